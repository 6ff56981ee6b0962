"""A finished run's folder read back through one guard: :func:`read_run`.

Every command that reads a run folder (``render``, ``bag``, ``compare``) reads it here, and
here only: each file is checked against what :data:`METRICS_FIELDS` and :func:`read_run`
declare before anything uses it, and any deviation is a :class:`RunFolderError` (a bad input:
one line, exit code 2) naming the file and the field, column or row. What is checked:

- the folder: no writer's claim (:data:`tt_mujoco.outputs.CLAIM_FILE`) in it, since outputs
  beside a claim are being written or were left by an interrupted writer;
- ``metrics.json``: UTF-8, strict JSON (no ``NaN``, no infinities, no number beyond a float,
  no key given twice), an object, and each declared field of the declared type where present
  (:data:`METRICS_FIELDS`); the vehicle's parameters are ``Params`` fields with allowed values;
- the time series (``timeseries.parquet`` or ``.csv``): readable, at least one row, every
  column a run of that train writes (:data:`tt_mujoco.sim.loop.timeseries.COLUMNS` and the
  trailers' columns), the states finite, time increasing, as many rows as ``steps`` says, and
  the axle spacing that ``plant_params`` implies (:func:`check_trace`);
- ``reference_path.parquet``, when the run kept it: at least two finite rows of ``x, y``;
- ``world.toml``, when the run kept it: a world file (:func:`tt_mujoco.world.world.read_world`).

A reader never writes inside a run folder: :func:`check_out` refuses an output there.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tt_mujoco.cliargs import BadInputError
from tt_mujoco.outputs import (
    CLAIM_FILE,
    METRICS_FILE,
    REFERENCE_FILE,
    JsonField,
    check_fields,
    enclosing_output,
    lookup,
    read_strict_json,
    read_timeseries,
    read_toml,
    run_timeseries_file,
    shown_json,
)
from tt_mujoco.sim.loop.timeseries import COLUMNS, train_columns
from tt_mujoco.vehicle.params import Params

__all__ = [
    "METRICS_FIELDS",
    "METRICS_FILE",
    "READ_COLUMNS",
    "STATE_COLUMNS",
    "FinishedRun",
    "RunFolderError",
    "check_out",
    "check_trace",
    "default_out",
    "params_from_config",
    "read_columns",
    "read_run",
    "reference_polyline_for",
]


class RunFolderError(BadInputError):
    """A run folder that is not what a finished run writes: exit code 2, naming the file, in
    one line (a library's message over several lines is joined)."""

    def __init__(self, message: str):
        super().__init__(
            "; ".join(line.strip() for line in str(message).splitlines() if line.strip())
        )


_TEXT = ((str,), "a string")
#: The fields of ``metrics.json`` that the readers use, where the run writes them; every other
#: key is a metric: a built-in one a number or null (:func:`_builtin_metrics_why`), a user's
#: a number, a string, null or a table of them, left to its reader.
METRICS_FIELDS = (
    JsonField("status", *_TEXT),
    JsonField("message", *_TEXT),
    JsonField("steps", (int,), "a whole number of steps >= 0"),
    JsonField("config", (dict,), "a table (the run's configuration)"),
    JsonField("config.scenario", (dict,), "a table (the run's scenario)"),
    *(JsonField(f"config.scenario.{k}", *_TEXT) for k in ("traj", "controller", "plant")),
    *(JsonField(f"config.scenario.{k}", *_TEXT) for k in ("target", "terrain", "world")),
    JsonField("config.scenario.reverse", (bool,), "true or false"),
    JsonField("config.plant_params", (dict,), "a table of the vehicle's parameters"),
    JsonField("config.params", (dict,), "a table of the vehicle's parameters"),
)
#: The time-series columns the readers use (with the trailers' columns of a train): every run
#: writes them (:data:`tt_mujoco.sim.loop.timeseries.COLUMNS`).
READ_COLUMNS = (
    *("t", "x", "y", "theta", "phi", "beta", "v", "omega", "x0", "y0", "theta0", "v0"),
    *("theta_l", "theta_r", "T_r", "T_l", "x_ref", "y_ref", "v_d", "omega_d"),
)
assert set(READ_COLUMNS) <= set(COLUMNS)
#: The time-series columns that hold the train's state: finite in every row a run keeps.
STATE_COLUMNS = ("t", "x", "y", "theta", "phi", "beta", "x0", "y0", "theta0")


@dataclass(frozen=True)
class FinishedRun:
    """A run folder that passed :func:`read_run`'s checks."""

    folder: Path
    metrics: Mapping
    params: Params
    timeseries: Mapping[str, np.ndarray]
    reference: np.ndarray
    #: Where :attr:`reference` came from (the run's own path file, or its reference point).
    reference_source: str
    world: object | None

    @property
    def config(self) -> Mapping:
        return self.metrics.get("config", {})

    @property
    def scenario(self) -> Mapping:
        return self.config.get("scenario", {})

    @property
    def status(self) -> str | None:
        return self.metrics.get("status")

    @property
    def message(self) -> str:
        return self.metrics.get("message", "")


def read_run(folder) -> FinishedRun:
    """Read and check a finished run's folder (see the module's docstring).

    Raises
    ------
    RunFolderError
        Naming the file and the field, column or row that is not a run's.
    """
    folder = Path(folder)
    try:
        metrics_file, ts_file = folder / METRICS_FILE, run_timeseries_file(folder)
        is_dir = folder.is_dir()
    except OSError as err:  # a name the file system refuses (too long)
        raise RunFolderError(f"{shown_json(str(folder))}: {err.strerror}") from None
    if not is_dir:
        raise RunFolderError(f"{str(folder)!r} is not a folder: give a finished run's folder")
    if (folder / CLAIM_FILE).exists() or (folder / CLAIM_FILE).is_symlink():
        raise RunFolderError(
            f"{folder / CLAIM_FILE} is there: the run in {str(folder)!r} is being written, or "
            f"its writer was interrupted; read it once it is finished (remove {CLAIM_FILE} "
            "only if no run is writing it)"
        )
    from tt_mujoco.world.builtin import KEPT_WORLD

    for file in (metrics_file, ts_file, folder / REFERENCE_FILE, folder / KEPT_WORLD):
        _refuse_unless_file(file, folder)
    missing = [str(f) for f in (metrics_file, ts_file) if not f.is_file()]
    if not ts_file.is_file():  # neither form of the time series
        missing[-1] = f"{ts_file.with_suffix('.parquet')} (or {ts_file.with_suffix('.csv').name})"
    if missing:
        raise RunFolderError(
            f"{' and '.join(missing)} not found: {folder} is not a finished run's folder"
        )
    metrics = _read_metrics(metrics_file)
    raw_params = metrics["config"].get("plant_params", metrics["config"].get("params"))
    if raw_params is None:
        raise RunFolderError(f"{metrics_file} has no config.plant_params or config.params")
    try:
        params = params_from_config(raw_params)
    except (ValueError, TypeError) as err:
        raise RunFolderError(f"{metrics_file}: config.plant_params: {err}") from None
    ts = _read_series(ts_file, params, metrics.get("steps"))
    problem = check_trace(params, ts)
    if problem:
        raise RunFolderError(f"{metrics_file}: {problem}")
    try:
        reference, source = reference_polyline_for(ts, folder)
    except (OSError, ValueError) as err:
        raise RunFolderError(f"{folder / REFERENCE_FILE}: {err}") from None
    return FinishedRun(folder, metrics, params, ts, reference, source, _world(folder, metrics))


def read_columns(n_trailers: int) -> tuple[str, ...]:
    """The columns :func:`read_run` requires of the time series of a train of ``n_trailers``."""
    return (*READ_COLUMNS, *train_columns(n_trailers))


def _read_metrics(path: Path) -> dict:
    try:
        doc = read_strict_json(path)
    except ValueError as err:
        raise RunFolderError(str(err)) from None
    if not isinstance(doc, dict):
        raise RunFolderError(
            f"{path} is not a run's metrics: it holds {shown_json(doc)}, not a table"
        )
    if "config" not in doc:
        raise RunFolderError(f"{path} is not a run's metrics: it has no config")
    why = check_fields(doc, METRICS_FIELDS) or _builtin_metrics_why(doc)
    if why:
        raise RunFolderError(f"{path}: {why}")
    return doc


def _refuse_unless_file(file: Path, folder: Path) -> None:
    """Refuse ``file`` of the run folder ``folder`` when something by its name is not a file
    (a folder, a device, a link to nothing): none is read, a device least of all."""
    if (file.exists() or file.is_symlink()) and not file.is_file():
        raise RunFolderError(
            f"{file} is not a file (a folder, a device, or a link to nothing): {folder} is "
            "not a finished run's folder"
        )


def _builtin_metrics_why(doc: Mapping) -> str:
    """Why one of the built-in metrics ``doc`` holds is not what every run writes there (a
    number, or null where it has none), or "": the readers compare and draw them."""
    from tt_mujoco.analysis.metric_names import metric_unit

    for key, value in doc.items():
        if metric_unit(key) is None or value is None:
            continue
        if isinstance(value, bool) or not isinstance(value, int | float):
            return f"{key} holds {shown_json(value)}, not a number or null (a built-in metric)"
    return ""


def _read_series(path: Path, params: Params, steps) -> dict[str, np.ndarray]:
    try:
        ts = read_timeseries(path)
    except (OSError, ValueError, TypeError, KeyError) as err:
        said = str(err)  # the readers' own messages name the file: not twice
        said = said if said.startswith(str(path)) else f"{path} is not a time series: {said}"
        raise RunFolderError(said) from None
    missing = [c for c in read_columns(params.n_trailers) if c not in ts]
    if missing:
        shown = ", ".join(missing[:6]) + (", ..." if len(missing) > 6 else "")
        raise RunFolderError(
            f"{path} lacks the column(s) {shown}: it is not the time series of a run of "
            f"{params.n_trailers} trailer(s)"
        )
    n = len(ts["t"])
    if n == 0:
        raise RunFolderError(f"{path} has no rows")
    if isinstance(steps, int) and n < steps:
        raise RunFolderError(
            f"{path} has {n} rows but metrics.json says the run took {steps} steps: the file is cut"
        )
    for name in (*STATE_COLUMNS, *train_columns(params.n_trailers)):
        bad = np.flatnonzero(~np.isfinite(ts[name]))
        if bad.size:
            row = int(bad[0])
            raise RunFolderError(
                f"{path}: row {row + 2} holds {float(ts[name][row])!r} in column {name!r}"
            )
    backwards = np.flatnonzero(np.diff(ts["t"]) <= 0.0)
    if backwards.size:
        row = int(backwards[0]) + 1
        raise RunFolderError(
            f"{path}: row {row + 2} has t = {float(ts['t'][row])!r}, not after the row "
            f"before's {float(ts['t'][row - 1])!r}: time must increase"
        )
    return ts


def _world(folder: Path, metrics: Mapping):
    from tt_mujoco.world.builtin import KEPT_WORLD, parse_world
    from tt_mujoco.world.world import WorldError, world_from_table

    name = lookup(metrics, "config.scenario.world", "none")
    kept = folder / KEPT_WORLD
    if name != "none" and kept.is_file():  # the copy the run kept, read once
        try:
            table = read_toml(kept, "the kept world")
        except ValueError as err:
            raise RunFolderError(str(err)) from None
        if not isinstance(table.get("name"), str):
            raise RunFolderError(f"{kept} is not the world a run kept: it has no name")
        try:
            return world_from_table(table, kept.stem)
        except WorldError as err:
            raise RunFolderError(f"{kept}: {err}") from None
    try:  # a run from before runs kept their world: what its name names now
        return parse_world(name)
    except (OSError, WorldError) as err:
        raise RunFolderError(f"{folder / METRICS_FILE}: config.scenario.world: {err}") from None


def check_out(out: Path, suffix: str | None = None, option: str = "--out") -> None:
    """Refuse the file ``out`` (given as ``option``) when it is a folder, when it would be
    written inside a run's folder (a finished run is a record, which a reader of it never
    changes), or, given ``suffix``, when its name does not end in it (what a viewer opening
    the file goes by)."""
    if suffix is not None and Path(out).suffix.lower() != suffix:
        raise BadInputError(f"{option} {out} is not allowed: it must end in {suffix}")
    if Path(out).is_dir():
        raise BadInputError(f"{option} {out} is not allowed: it is a folder; name a file")
    parent = enclosing_output(out)
    if parent is not None:
        raise BadInputError(
            f"{out} is inside the run folder {parent}, which a reader never writes into: "
            f"name a file elsewhere with {option}"
        )


def default_out(run_dir: Path, kind: str, suffix: str) -> Path:
    """Where a reader writes what it makes of ``run_dir`` unless told: beside the run folder,
    ``<run>.<kind><suffix>`` (``renders/run.follow.mp4`` for ``renders/run``)."""
    run_dir = Path(run_dir)
    if not run_dir.name:  # "." or ".."
        run_dir = run_dir.resolve()
    return run_dir.parent / f"{run_dir.name}.{kind}{suffix}"


def params_from_config(params: Mapping) -> Params:
    """``Params`` from ``metrics.json["config"]["plant_params"]`` (non-init fields such as
    ``steering`` are ignored; unknown names are an error)."""
    if not isinstance(params, Mapping):
        raise ValueError(f"it holds {shown_json(params)}, not a table of the vehicle's parameters")
    init = {f.name for f in dataclasses.fields(Params) if f.init}
    computed = {f.name for f in dataclasses.fields(Params) if not f.init}
    unknown = sorted(set(params) - init - computed)
    if unknown:
        raise ValueError(
            f"config params {unknown} are not Params fields; allowed: {', '.join(sorted(init))}"
        )
    return Params(**{k: v for k, v in params.items() if k in init})


def reference_polyline_for(ts: Mapping, run_dir=None) -> tuple[np.ndarray, str]:
    """A finished run's reference path, from what the run kept: its ``reference_path.parquet``
    (written by every run), else the recorded reference point ``(x_ref, y_ref)``. A path file
    the run was given (a CSV path) is never read again: it may have changed since.

    Returns the polyline and a note on where it came from.
    """
    if run_dir is not None:
        stored = Path(run_dir) / REFERENCE_FILE
        if stored.is_file():
            line = read_timeseries(stored)
            polyline = np.column_stack([line.get("x", ()), line.get("y", ())])
            if polyline.shape[0] < 2 or not np.all(np.isfinite(polyline)):
                raise ValueError(
                    f"{stored} is not a reference path: it needs at least 2 finite rows of x, y"
                )
            return polyline, f"the run's own {REFERENCE_FILE}"
    if "x_ref" not in ts or "y_ref" not in ts:
        raise ValueError("the run has no reference path: no reference_path.parquet, no x_ref/y_ref")
    return np.column_stack(
        [ts["x_ref"], ts["y_ref"]]
    ), "the recorded reference point (x_ref, y_ref)"


def check_trace(params: Params, ts: Mapping) -> str:
    """Why ``params`` cannot be the vehicle that recorded ``ts``, or "": the distance between
    the tractor's P and the trailer axle P0 is fixed by the hitch lengths and the articulation,
    ``|P - P0|^2 = L^2 + L0^2 + 2 L L0 cos(theta - theta0)`` (docs/model.md Section 2), which an
    edited L or L0 breaks (the video would draw the trailer off its own trace)."""
    needed = ("x", "y", "theta", "x0", "y0", "theta0")
    if not all(name in ts for name in needed) or len(ts["t"]) == 0:
        return ""
    try:
        L, L0 = float(params.L), float(params.L0)
    except OverflowError:
        return "its plant_params L or L0 is beyond a float"
    recorded = np.hypot(ts["x"] - ts["x0"], ts["y"] - ts["y0"])
    with np.errstate(over="ignore", invalid="ignore"):
        implied = np.sqrt(L * L + L0 * L0 + 2.0 * L * L0 * np.cos(ts["theta"] - ts["theta0"]))
        worst = float(np.max(np.abs(recorded - implied)))
    if not worst <= 1e-6:
        return (
            f"its plant_params (L={L:g} m, L0={L0:g} m) are not the vehicle of its time series: "
            f"the recorded axle spacing is off theirs by up to {worst * 1000:.3g} mm (was "
            "metrics.json edited?)"
        )
    return ""

"""The runs of a sweep: expansion into options with seeds, scenarios, and running one."""

from __future__ import annotations

import hashlib
import itertools
import json
import math
import time
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from tt_mujoco import watchdog
from tt_mujoco.controllers import controller_class
from tt_mujoco.registry import is_hook
from tt_mujoco.schema import Schema
from tt_mujoco.sim import SCHEMA, Scenario, build, simulate
from tt_mujoco.sim.simulate import checked_build
from tt_mujoco.sweep.options import (
    DICT_OPTIONS,
    LIST_OPTIONS,
    MAX_RUNS,
    SCENARIO_OPTIONS,
    BadSpecError,
    convert,
    trailer_option,
)
from tt_mujoco.sweep.spec import Axis, SweepSpec
from tt_mujoco.world.plan import StartError


# --- the runs ----------------------------------------------------------------------------------
def run_seed(sweep_seed: int, k: int) -> int:
    """The noise seed of repeat (grid) or sample (random) ``k``: spawn key (0, k)."""
    seq = np.random.SeedSequence(sweep_seed, spawn_key=(0, k))
    return int(seq.generate_state(1, dtype=np.uint32)[0])


def _draw(axis: Axis, rng: np.random.Generator):
    if axis.distribution:
        kind, a, b = axis.distribution
        if kind == "uniform":
            x = rng.uniform(a, b)
        elif kind == "loguniform":
            x = math.exp(rng.uniform(math.log(a), math.log(b)))
        else:
            x = rng.normal(a, b)
        return convert(axis.name, float(x))
    return axis.values[int(rng.integers(len(axis.values)))]


def input_files(options: Mapping) -> list[Path]:
    """The files a run reads besides the package: a CSV path, the files of hooks."""
    files = []
    values = []
    for opt in SCHEMA.options:
        if opt.file and isinstance(options.get(opt.name), str):
            values += options[opt.name].split(";") if opt.form == "repeat" else [options[opt.name]]
    for value in values:
        if not isinstance(value, str):
            continue
        text = value.strip()
        if text.lower().endswith(".csv"):
            files.append(Path(text))
        elif is_hook(text) and text.rsplit(":", 1)[0].endswith(".py"):
            files.append(Path(text.rsplit(":", 1)[0]))
    return files


def run_id(options: Mapping) -> str:
    """Stable key of a run: SHA-256 of its options as canonical JSON and of the content of every
    file it reads (:func:`input_files`), 16 hex digits. An edited CSV or controller file gives
    a new key, so a resumed sweep runs it again instead of reusing the old result."""
    text = json.dumps(options, sort_keys=True, separators=(",", ":"), allow_nan=False)
    digest = hashlib.sha256(text.encode())
    for path in input_files(options):
        try:
            digest.update(hashlib.sha256(path.read_bytes()).digest())
        except OSError:
            digest.update(b"missing")  # validation refuses the run with the file named
    return digest.hexdigest()[:16]


def expand(spec: SweepSpec, validate: bool = True) -> list[dict]:
    """The runs of a sweep, in table order.

    Returns
    -------
    list of dict
        ``{"index", "replicate", "run_id", "options"}``; ``options`` maps every given option
        (and always ``seed``) to this run's value, JSON-serialisable, and is what
        :func:`build_scenario` and :func:`run_one` take.

    Raises
    ------
    BadSpecError
        If a run's configuration is not valid (checked for every run before any is started).
    """
    explicit_seed = spec.axis("seed") is not None
    runs = []
    if spec.mode == "grid":
        n = math.prod(len(a.values) for a in spec.axes) * spec.repeats
        _check_count(n)
        points = itertools.product(*(a.values for a in spec.axes))
        for point in points:
            for j in range(spec.repeats):
                options = dict(zip((a.name for a in spec.axes), point, strict=True))
                if not explicit_seed:
                    options["seed"] = run_seed(spec.seed, j)
                runs.append((j, options))
    else:
        _check_count(spec.samples)
        for k in range(spec.samples):
            rng = np.random.default_rng(np.random.SeedSequence(spec.seed, spawn_key=(1, k)))
            options = {a.name: _draw(a, rng) for a in spec.axes}
            if not explicit_seed:
                options["seed"] = run_seed(spec.seed, k)
            runs.append((k, options))
    out = []
    seen: dict[str, int] = {}
    for index, (replicate, options) in enumerate(runs):
        rid = run_id(options)
        if rid in seen:
            raise BadSpecError(
                f"runs {seen[rid]} and {index} have the same configuration {options}: every run "
                "must differ (check the seed option)"
            )
        seen[rid] = index
        out.append({"index": index, "replicate": replicate, "run_id": rid, "options": options})
    if validate:
        validate_runs(out)
    return out


def _check_count(n: int) -> None:
    if n > MAX_RUNS:
        raise BadSpecError(f"the sweep has {n} runs: at most {MAX_RUNS} are allowed")


def build_scenario(options: Mapping) -> Scenario:
    """The :class:`~tt_mujoco.sim.Scenario` of one run's options.

    ``gain.<k>`` go into ``Scenario.gains`` (with ``gains`` as its preset); ``scale.<f>=x`` sets
    ``Scenario.plant_scale[f] = x``: the plant's mass or inertia times x while the controller
    keeps the nominal model (a per-parameter model mismatch, like ``param_scale`` for all of
    them). ``param.<f>=x`` sets ``Scenario.params[f] = x``: vehicle *and* nominal model.
    Without ``control_dt`` the control period is the ``timestep`` (as in
    ``python -m tt_mujoco.run``).
    """
    return Scenario(**scenario_values(options))


def scenario_values(options: Mapping, schema: Schema = SCHEMA) -> dict:
    """The checked values of one run's options, by field name (the schema's, plus the
    per-trailer options ``trailer<k>.<field>``, which become ``train``)."""
    values = schema.values({k: v for k, v in options.items() if not trailer_option(k)}, "")
    overrides = [(trailer_option(k), v) for k, v in options.items() if trailer_option(k)]
    if overrides:
        train = [{} for _ in range(max(k for (k, _), _ in overrides) - 1)]
        for (k, field), value in overrides:
            train[k - 2][field] = value
        values["train"] = train
    return values


def _resolved_gains(scenario: Scenario) -> tuple[str, dict]:
    values, preset = controller_class(scenario.controller).resolve_gains(scenario.gains)
    return preset, values


def validate_runs(runs: Sequence[dict]) -> None:
    """Every run through the one setup path (:func:`tt_mujoco.sim.build`), before any work
    (exit 2 on a bad one). Runs that differ only in their seed are checked once; a seed whose
    start has no plan (``traj="plan"``), or one the run cannot drive as asked
    (:class:`~tt_mujoco.world.plan.StartError`), is no fault of the configuration, which is
    checked with its next seed."""
    checked: set[str] = set()
    for run in runs:
        options = run["options"]
        key = json.dumps({k: v for k, v in options.items() if k != "seed"}, sort_keys=True)
        if key in checked:
            continue
        try:
            checked_build(build_scenario(options))
        except StartError:  # this seed's start has no plan (or one it cannot drive): a row
            continue  # of its own (run_one); the configuration is checked with the next seed
        except (ValueError, TypeError, OSError) as err:
            shown = {k: v for k, v in options.items() if k != "seed"}
            raise BadSpecError(f"run {run['index']} {shown}: {err}") from None
        checked.add(key)


def config_columns(run: Mapping) -> dict:
    """The configuration part of a run's row: its index, id and replicate, then
    :func:`scenario_columns`."""
    row = {"index": run["index"], "run_id": run["run_id"], "replicate": run["replicate"]}
    row.update(scenario_columns(run["options"]))
    return row


def scenario_columns(options: Mapping) -> dict:
    """The full Scenario of a run's options, the resolved eta and gains, and the
    ``scale.*``/``param.*`` factors given (the run's journal record keeps them, so a table is
    built without the files a run read, such as a controller that has gone since)."""
    scenario = build_scenario(options)
    row = {}
    for name in SCENARIO_OPTIONS:
        value = getattr(scenario, name)
        if name in LIST_OPTIONS:
            value = options.get(name, "none")
        elif name in DICT_OPTIONS and value is None:
            value = "off"
        row[name] = value if not isinstance(value, dict | list) else json.dumps(value)
    preset, gains = _resolved_gains(scenario)
    row["gains"] = preset
    row["eta_value"] = scenario.nominal_params().eta
    for k, v in gains.items():
        row[f"gain.{k}"] = v
    for k, v in options.items():
        if k.startswith(("scale.", "param.")) or trailer_option(k):
            row[k] = v
    return row


def _flatten_metrics(value, prefix: str = "", out: dict | None = None) -> dict:
    """Nested metrics (e.g. the per-fault report ``faults: [{..., window: {...}}]``) as flat
    columns ``faults.0.window.rmse_lateral``; numpy scalars as Python ones."""
    out = {} if out is None else out
    if isinstance(value, Mapping):
        for key, item in value.items():
            _flatten_metrics(item, f"{prefix}{key}.", out)
    elif isinstance(value, list | tuple):
        for i, item in enumerate(value):
            _flatten_metrics(item, f"{prefix}{i}.", out)
    else:
        out[prefix[:-1]] = value.item() if isinstance(value, np.generic) else value
    return out


def run_one(options: Mapping, hang_dir=None, run_id: str = "") -> dict:
    """Simulate one run; never raises for a run's failure (worker entry point).

    Parameters
    ----------
    options : mapping
        One run's options (see :func:`expand`).
    hang_dir : path, optional
        The sweep's folder for hang files: the run is watched there
        (:func:`tt_mujoco.watchdog.armed`) under ``run_id``, so that one that never returns
        to Python ends its worker, and the sweep records it.
    run_id : str

    Returns
    -------
    dict
        ``status`` ("ok", "jackknife", "diverged", ..., ``"no_plan"`` where the planner found
        no path from the run's start, ``"start_refused"`` where its plan cannot be driven as
        asked, or "error" when the run raised),
        ``message``, ``error`` (exception type and text, "" unless status is "error"),
        ``metrics`` (dict; empty on error) and ``run_wall_s`` (the whole run in this worker:
        setup, control loop and metrics).
    """

    start = time.perf_counter()
    try:
        config = scenario_columns(options)  # while every file the run reads is there
        # A Build: its user code was tried on the initial state by validate_runs, once per
        # configuration, before the sweep started; simulate(Scenario) would try it again.
        built = build(build_scenario(options))
        limit = built.wall_limit
        with watchdog.armed(limit, hang_dir, run_id):
            result = simulate(built)
        metrics = _flatten_metrics({k: v for k, v in result.metrics.items() if k != "status"})
        out = {"status": result.status, "message": result.message, "error": "", "metrics": metrics}
        out["config"] = config
    except StartError as err:  # this seed's start has no plan, or one it cannot drive
        out = {"status": err.status, "message": str(err), "error": "", "metrics": {}}
    except (Exception, SystemExit) as err:  # a run's crash is a row, not the sweep's end
        out = {
            "status": "error",
            "message": "",
            "error": f"{type(err).__name__}: {err}",
            "metrics": {},
        }
    out["run_wall_s"] = time.perf_counter() - start
    return out

"""``python -m tt_mujoco.sweep``: Monte Carlo runs and parameter sweeps, laptop to cluster.

A sweep is a set of *options* (the fields of :class:`tt_mujoco.sim.Scenario`, controller gains
``gain.<name>``, mass and inertia factors ``scale.<field>`` and absolute parameter overrides
``param.<field>``), each fixed or varied:

- **grid** (the default): the Cartesian product of every option's list of values, each point
  run ``repeats`` times;
- **random** (``samples=N``): N runs, each option drawn from its list (uniformly) or from a
  distribution (``uniform``, ``loguniform``, ``normal``).

Seeds. Every run's ``seed`` (the measurement-noise seed of :class:`~tt_mujoco.sim.Scenario`) comes
from the sweep seed through :class:`numpy.random.SeedSequence` with spawn key ``(0, k)``: ``k`` is
the repeat number in a grid (so every grid point sees the same noise realisations: common random
numbers, which makes comparisons between gains paired) and the sample number in random mode,
whose option values come from spawn key ``(1, k)``. A run is thus a pure function of its
configuration, and the table does not depend on the executor, the worker count or the order in
which runs finish. Giving ``seed`` as an option sets the runs' seeds directly instead.

Each run is keyed by ``run_id``, a hash of its configuration. Finished runs are appended to
``journal.jsonl`` (one JSON line each, flushed at once), so an interrupted sweep resumes with
``--resume`` without redoing them; a run whose configuration is unchanged is reused even when
the sweep grew (more values, more samples). At the end the sorted table ``runs.csv`` (one row per
run: its full configuration and every metric), ``summary.csv`` / ``summary.json`` (percentiles of
each metric over the runs that finished ``ok``, failure counts) and the figures
``histograms.png`` and ``scatter.png`` are written, each atomically.

Runs execute through a :mod:`concurrent.futures` executor: local worker processes
(``--workers N``), or Dask distributed (the ``dask`` extra) with ``--scheduler ADDRESS`` or
``--scheduler local`` for a ``LocalCluster``. A run that diverges, jackknifes or raises is a row
with its status and error, never lost. Exit codes: 0 the sweep finished (whatever its runs did),
2 bad sweep specification (one message), 130 interrupted (resumable).
"""

from __future__ import annotations

import argparse
import concurrent.futures as cf
import contextlib
import csv
import dataclasses
import hashlib
import importlib
import io
import itertools
import json
import math
import multiprocessing
import os
import signal
import sys
import time
import tomllib
from collections import deque
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from tt_mujoco.controllers import CONTROLLERS, controller_class
from tt_mujoco.controllers.base import resolve_gains
from tt_mujoco.outputs import atomic_write, free_name, save_figure
from tt_mujoco.registry import is_hook, normalise_hook
from tt_mujoco.sim import DISTURBANCE_MODES, PLANTS, TARGETS, Scenario, build
from tt_mujoco.vehicle.params import INERTIA_FIELDS, MASS_FIELDS, Params

__all__ = [
    "RESULT_COLUMNS",
    "WALL_COLUMNS",
    "Axis",
    "BadSpecError",
    "SweepResult",
    "SweepSpec",
    "build_scenario",
    "expand",
    "load_spec",
    "main",
    "parse_item",
    "parse_spec",
    "plot_summary",
    "read_table",
    "run_one",
    "run_sweep",
    "summarize",
]

EXIT_OK, EXIT_BAD_INPUT, EXIT_INTERRUPTED = 0, 2, 130

STARTS = ("on_path", "paper")
#: Scenario fields that are options, in the table's column order (``params`` is reached through
#: ``scale.*`` and ``param.*``; ``gains`` here is the preset name, single gains are ``gain.*``).
SCENARIO_OPTIONS = tuple(
    f.name for f in dataclasses.fields(Scenario) if f.name not in ("params", "plant_scale")
)
#: Scenario fields that hold a list of specs; a sweep value is one text, specs separated by ";"
#: ("none" for no spec), e.g. faults="payload:t=2,factor=1.5;dropout:t=5".
LIST_OPTIONS = tuple(f.name for f in dataclasses.fields(Scenario) if f.default_factory is list)
#: Scenario fields that are an optional dict of numbers (e.g. ``path_feedback``): ``NAME=on``
#: (the defaults, ``{}``) or ``off`` (None), and ``NAME.<key>=x`` for one entry (implies on).
DICT_OPTIONS = tuple(
    f.name
    for f in dataclasses.fields(Scenario)
    if f.name not in ("gains", "params", "plant_scale") and str(f.type).startswith("dict")
)
#: Fields of :class:`Params` that ``scale.<field>`` multiplies (docs/model.md Section 8
#: uncertainty).
SCALABLE = MASS_FIELDS + INERTIA_FIELDS
#: Fields of :class:`Params` that ``param.<field>`` may set (eta, friction and timestep are
#: Scenario options of their own).
SETTABLE = tuple(
    f.name
    for f in dataclasses.fields(Params)
    if f.init and f.name not in ("eta", "friction", "timestep")
)

#: Grid generators (expand to a list) and random distributions (random mode only).
GRID_GENERATORS = ("lin", "log", "range")
DISTRIBUTIONS = ("uniform", "loguniform", "normal")

#: Columns of the result part of a row that depend on the machine's load, not on the run.
WALL_COLUMNS = ("wall_time_s", "run_wall_s")
#: Result columns before the metrics.
RESULT_COLUMNS = ("status", "message", "error")
#: Metrics shown first in the printed summary and drawn in the histograms.
KEY_METRICS = (
    "rmse_lateral",
    "max_lateral",
    "rmse_v",
    "rmse_omega",
    "trailer_offtrack_max",
    "torque_saturation_fraction",
)
PERCENTILES = (5, 25, 50, 75, 95)
#: Largest sweep accepted: each run is at least a model compile, so more is a typo.
MAX_RUNS = 1_000_000

JOURNAL = "journal.jsonl"
TABLE = "runs.csv"
SPEC_FILE = "sweep.toml"
RENDERS = Path("renders")


class BadSpecError(ValueError):
    """A mistake in the sweep's specification: reported as one line, exit code 2."""


# --- option values ---------------------------------------------------------------------------
def _number(name: str, value, positive: bool = False) -> float:
    if isinstance(value, str):
        try:
            value = float(value)
        except ValueError:
            raise BadSpecError(f"{name}={value!r} is not allowed: it must be a number") from None
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise BadSpecError(f"{name}={value!r} is not allowed: it must be a finite number")
    if positive and value <= 0:
        raise BadSpecError(f"{name}={value!r} is not allowed: it must be > 0")
    return float(value)


def _integer(name: str, value) -> int:
    if isinstance(value, float) and value.is_integer():
        value = int(value)
    if isinstance(value, str):
        try:
            value = int(value)
        except ValueError:
            pass
    if isinstance(value, bool) or not isinstance(value, int) or value < 0:
        raise BadSpecError(f"{name}={value!r} is not allowed: it must be an integer >= 0")
    return value


def _choice(name: str, value, allowed: Sequence[str]) -> str:
    if value not in allowed:
        raise BadSpecError(
            f"{name}={value!r} is not allowed: use one of {', '.join(repr(a) for a in allowed)}"
        )
    return value


def _optional_number(name: str, value, positive: bool = False) -> float | None:
    if value is None or (isinstance(value, str) and value.strip().lower() == "none"):
        return None
    return _number(name, value, positive)


def _eta(name: str, value) -> float | str:
    if isinstance(value, str):
        key = value.strip().lower().replace("-", "_")
        if key in ("paper", "same_path"):
            return key
    return _number(name, value)


def _boolean(name: str, value, extra: str = "true or false") -> bool:
    if isinstance(value, bool):
        return value
    key = str(value).strip().lower()
    if key in ("true", "on", "yes", "1"):
        return True
    if key in ("false", "off", "no", "0", "none"):
        return False
    raise BadSpecError(f"{name}={value!r} is not allowed: use {extra}")


def _text(name: str, value) -> str:
    if not isinstance(value, str) or not value.strip():
        raise BadSpecError(f"{name}={value!r} is not allowed: it must be a non-empty string")
    return value.strip()


def convert(name: str, value):
    """Check and convert one value of option ``name`` (text from the command line, or a TOML
    value). Raises :class:`BadSpecError` naming the value and what is allowed."""
    if name == "controller" and not is_hook(value):
        return _choice(name, value, tuple(CONTROLLERS))  # the registry as it is now
    if name in ("controller", "traj", "disturbance_model"):
        # hook files are made absolute: the workers may run in another folder
        return normalise_hook(_text(name, value))
    if name == "target":
        return _choice(name, value, TARGETS)
    if name == "plant":
        return _choice(name, value, PLANTS)
    if name == "disturbance":
        return _choice(name, value, DISTURBANCE_MODES)
    if name == "start":
        return _choice(name, value, STARTS)
    if name == "gains":
        return _text(name, value)
    if name == "eta":
        return _eta(name, value)
    if name == "noise_snr_db":
        return _optional_number(name, value)
    if name == "duration":
        return _optional_number(name, value, positive=True)
    if name in ("param_scale", "timestep", "control_dt", "friction"):
        return _number(name, value, positive=True)
    if name == "seed":
        return _integer(name, value)
    if name.startswith(("gain.", "scale.")):
        return _number(name, value, positive=True)
    if name.startswith("param."):
        return _number(name, value)
    if name in LIST_OPTIONS:
        return _text(name, value)
    if name in DICT_OPTIONS:
        return "on" if _boolean(name, value, extra="'on' (defaults) or 'off'") else "off"
    if name.partition(".")[0] in DICT_OPTIONS:
        return _number(name, value)
    if name in SCENARIO_OPTIONS:  # a newer Scenario field: checked by the type of its default
        default = next(f.default for f in dataclasses.fields(Scenario) if f.name == name)
        if isinstance(default, bool):
            return _boolean(name, value)
        if isinstance(default, float):
            return _number(name, value)
        if isinstance(default, int) and not isinstance(default, bool):
            return _integer(name, value)
        if isinstance(default, str):
            return _text(name, value)
    raise BadSpecError(_unknown_option_message(name))


def _unknown_option_message(name: str) -> str:
    return (
        f"option {name!r} is not allowed: use one of {', '.join(SCENARIO_OPTIONS)}, "
        f"gain.<name> (a controller gain), scale.<field> (field one of {', '.join(SCALABLE)}: "
        f"Params default times the factor), param.<field> (field one of {', '.join(SETTABLE)})"
        + "".join(f" or {name}.<key>" for name in DICT_OPTIONS)
    )


def check_option_name(name: str) -> str:
    """Return ``name`` if it is an option, else raise :class:`BadSpecError` listing them."""
    if name in SCENARIO_OPTIONS:
        return name
    prefix, dot, rest = name.partition(".")
    if dot and rest:
        if prefix == "gain":
            return name  # checked against the controller's gains when the runs are expanded
        if prefix == "scale" and rest in SCALABLE:
            return name
        if prefix == "param" and rest in SETTABLE:
            return name
        if prefix in DICT_OPTIONS:
            return name  # its keys are checked by Scenario.validate when runs are expanded
    raise BadSpecError(_unknown_option_message(name))


# --- the specification -----------------------------------------------------------------------
@dataclass(frozen=True)
class Axis:
    """One option of a sweep: a list of values, or a distribution (random mode only).

    Attributes
    ----------
    name : str
        The option (e.g. ``"gain.k1_v"``).
    values : tuple
        The values (a single one for a fixed option); empty for a distribution.
    distribution : tuple
        ``(kind, a, b)`` with kind ``"uniform"`` (a <= x < b), ``"loguniform"`` (log x uniform
        in [log a, log b)) or ``"normal"`` (mean a, standard deviation b); empty for a list.
    """

    name: str
    values: tuple = ()
    distribution: tuple = ()

    @property
    def varies(self) -> bool:
        return bool(self.distribution) or len(self.values) > 1

    def to_toml(self):
        if self.distribution:
            kind, a, b = self.distribution
            return {kind: [a, b]}
        values = ["none" if v is None else v for v in self.values]
        return values[0] if len(values) == 1 else values


@dataclass(frozen=True)
class SweepSpec:
    """A whole sweep: its options (in order) and how they combine.

    Attributes
    ----------
    axes : tuple of Axis
    seed : int
        The sweep seed; every run's noise seed derives from it (see the module docstring).
    repeats : int
        Grid mode: runs per grid point (different derived seeds).
    samples : int or None
        Random mode when set: the number of runs.
    """

    axes: tuple[Axis, ...] = ()
    seed: int = 0
    repeats: int = 1
    samples: int | None = None

    @property
    def mode(self) -> str:
        return "random" if self.samples is not None else "grid"

    def axis(self, name: str) -> Axis | None:
        return next((a for a in self.axes if a.name == name), None)

    def to_toml(self) -> str:
        import tomli_w

        sweep = {"seed": self.seed, "repeats": self.repeats}
        if self.samples is not None:
            sweep["samples"] = self.samples
        doc = {"sweep": sweep, "options": {a.name: a.to_toml() for a in self.axes}}
        return tomli_w.dumps(doc)


def _round(x: float) -> float:
    # linspace/geomspace land on e.g. 0.9000000000000001; 12 significant digits give the value
    # the user meant, and the same text in every table.
    return float(f"{x:.12g}")


def _generator(name: str, kind: str, args: Sequence) -> Axis:
    """An axis from ``lin``/``log``/``range`` (lists) or a distribution."""
    if kind in DISTRIBUTIONS:
        if len(args) != 2:
            raise BadSpecError(
                f"{name}: {kind} takes 2 numbers ({kind}:A:B), got {len(args)}: {list(args)}"
            )
        a, b = (_number(name, x) for x in args)
        if kind in ("uniform", "loguniform") and not a < b:
            raise BadSpecError(f"{name}: {kind}:{a:g}:{b:g} needs A < B")
        if kind == "loguniform" and a <= 0:
            raise BadSpecError(f"{name}: loguniform:{a:g}:{b:g} needs 0 < A")
        if kind == "normal" and b <= 0:
            raise BadSpecError(f"{name}: normal:{a:g}:{b:g} needs a standard deviation > 0")
        for x in (a, b) if kind != "normal" else (a,):
            convert(name, x)  # e.g. a negative gain bound is wrong before anything is drawn
        return Axis(name, distribution=(kind, a, b))
    if kind == "range":
        if len(args) not in (2, 3):
            raise BadSpecError(f"{name}: range takes range:START:STOP[:STEP], got {list(args)}")
        ints = [_int_arg(name, x) for x in args]
        values = list(range(*ints))
        if not values:
            raise BadSpecError(f"{name}: range:{':'.join(map(str, ints))} is empty")
    else:  # lin, log
        if len(args) != 3:
            raise BadSpecError(f"{name}: {kind} takes {kind}:START:STOP:COUNT, got {list(args)}")
        a, b = _number(name, args[0]), _number(name, args[1])
        n = _int_arg(name, args[2])
        if n < 1:
            raise BadSpecError(f"{name}: {kind} COUNT={n} must be >= 1")
        if kind == "log" and not (a > 0 and b > 0):
            raise BadSpecError(f"{name}: log:{a:g}:{b:g}:{n} needs START and STOP > 0")
        points = np.linspace(a, b, n) if kind == "lin" else np.geomspace(a, b, n)
        values = [_round(float(x)) for x in points]
    return Axis(name, values=tuple(convert(name, v) for v in values))


def _int_arg(name: str, text) -> int:
    try:
        value = int(text)
    except (TypeError, ValueError):
        raise BadSpecError(f"{name}: {text!r} is not an integer") from None
    return value


def parse_item(item: str) -> Axis:
    """One command-line item ``OPTION=VALUES``.

    VALUES is a single value (fixed), a comma-separated list, ``lin:START:STOP:COUNT``
    (evenly spaced, ends included), ``log:START:STOP:COUNT`` (geometric),
    ``range:START:STOP[:STEP]`` (integers, STOP excluded, as Python's ``range``), or, with
    ``--samples``, ``uniform:A:B``, ``loguniform:A:B``, ``normal:MEAN:STD``. List-valued
    options (``faults``) take one value here, commas included.
    """
    name, eq, text = item.partition("=")
    name = name.strip()
    if not eq or not name:
        raise BadSpecError(
            f"{item!r} is not an option setting: write OPTION=VALUES, e.g. gain.k1_v=5,10,20"
        )
    check_option_name(name)
    text = text.strip()
    if not text:
        raise BadSpecError(f"{name}= has no value")
    if name in LIST_OPTIONS:
        # A fault spec has commas of its own: one value here; several in a TOML list.
        return Axis(name, values=(convert(name, text),))
    kind, colon, rest = text.partition(":")
    if colon and kind in GRID_GENERATORS + DISTRIBUTIONS:
        return _generator(name, kind, rest.split(":"))
    parts = [p.strip() for p in text.split(",")]
    return Axis(name, values=tuple(convert(name, p) for p in parts))


def _toml_axis(name: str, value) -> Axis:
    check_option_name(name)
    if isinstance(value, dict):
        if len(value) != 1 or next(iter(value)) not in GRID_GENERATORS + DISTRIBUTIONS:
            raise BadSpecError(
                f"{name} = {value!r} is not allowed: a table must be one of "
                f"{', '.join(f'{{{k} = [...]}}' for k in GRID_GENERATORS + DISTRIBUTIONS)}"
            )
        kind, args = next(iter(value.items()))
        if not isinstance(args, list):
            raise BadSpecError(f"{name} = {{{kind} = {args!r}}} needs a list of numbers")
        return _generator(name, kind, args)
    if isinstance(value, list):
        if not value:
            raise BadSpecError(f"{name} = [] has no values")
        return Axis(name, values=tuple(convert(name, v) for v in value))
    return Axis(name, values=(convert(name, value),))


def _flatten(table: Mapping, prefix: str = "") -> Iterable[tuple[str, object]]:
    """TOML ``gain.k1_v = 5`` is the nested table {gain: {k1_v: 5}}: back to dotted names.
    Tables with a generator's key (``{lin = [...]}``) are values, not nesting."""
    for key, value in table.items():
        name = f"{prefix}{key}"
        if isinstance(value, dict) and not (set(value) & set(GRID_GENERATORS + DISTRIBUTIONS)):
            yield from _flatten(value, f"{name}.")
        else:
            yield name, value


def load_spec(path: str | Path) -> SweepSpec:
    """Read a sweep specification from a TOML file.

    The file has a ``[sweep]`` table (``seed``, ``repeats``, ``samples``; all optional) and an
    ``[options]`` table: ``name = value`` (fixed), ``name = [v1, v2]`` (a list),
    ``name = {lin = [start, stop, count]}`` (also ``log``, ``range``, and for random mode
    ``uniform``, ``loguniform``, ``normal``). See ``examples/sweep_example.toml``.
    """
    path = Path(path)
    try:
        with open(path, "rb") as fh:
            doc = tomllib.load(fh)
    except OSError as err:
        raise BadSpecError(f"--config {str(path)!r} cannot be read: {err.strerror}") from None
    except tomllib.TOMLDecodeError as err:
        raise BadSpecError(f"--config {str(path)!r} is not valid TOML: {err}") from None
    unknown = sorted(set(doc) - {"sweep", "options"})
    if unknown:
        raise BadSpecError(
            f"--config {str(path)!r}: table(s) {unknown} are not allowed: use [sweep] and [options]"
        )
    sweep = doc.get("sweep", {})
    bad = sorted(set(sweep) - {"seed", "repeats", "samples"})
    if bad:
        raise BadSpecError(
            f"--config {str(path)!r}: [sweep] key(s) {bad} are not allowed: use seed, repeats, "
            "samples"
        )
    axes = [_toml_axis(name, value) for name, value in _flatten(doc.get("options", {}))]
    return _make_spec(axes, sweep.get("seed"), sweep.get("repeats"), sweep.get("samples"))


def _make_spec(axes: Sequence[Axis], seed, repeats, samples) -> SweepSpec:
    names = [a.name for a in axes]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise BadSpecError(f"option(s) {dup} given twice: give each option once")
    seed = 0 if seed is None else _integer("sweep seed", seed)
    repeats = 1 if repeats is None else _integer("repeats", repeats)
    if repeats < 1:
        raise BadSpecError(f"repeats={repeats!r} is not allowed: it must be an integer >= 1")
    if samples is not None:
        samples = _integer("samples", samples)
        if samples < 1:
            raise BadSpecError(f"samples={samples!r} is not allowed: it must be an integer >= 1")
    spec = SweepSpec(tuple(axes), seed, repeats, samples)
    if spec.mode == "grid":
        dists = [a.name for a in axes if a.distribution]
        if dists:
            raise BadSpecError(
                f"option(s) {dists} are random distributions: give --samples N (random "
                "sampling), or lists of values for a grid"
            )
        for a in axes:
            if len(set(map(repr, a.values))) != len(a.values):
                raise BadSpecError(f"{a.name} lists a value twice in a grid: {list(a.values)}")
    elif repeats != 1:
        raise BadSpecError(
            f"repeats={repeats} is for grids: in random mode every sample has its own seed; "
            "raise --samples instead"
        )
    seed_axis = spec.axis("seed")
    if seed_axis is not None and spec.mode == "grid" and repeats > 1:
        raise BadSpecError(
            "repeats > 1 with the option seed would run identical copies: give seeds as a list "
            "(e.g. seed=range:0:10) or repeats, not both"
        )
    return spec


def parse_spec(
    items: Sequence[str] = (),
    config: str | Path | None = None,
    seed: int | None = None,
    repeats: int | None = None,
    samples: int | None = None,
) -> SweepSpec:
    """A sweep from command-line items ``OPTION=VALUES``, an optional TOML file, and settings.

    Items override the file's options of the same name (and come after the file's in order);
    ``seed``/``repeats``/``samples`` override the file's ``[sweep]`` table.

    Raises
    ------
    BadSpecError
        (a ValueError) naming the bad option or value and what is allowed.
    """
    base = load_spec(config) if config is not None else SweepSpec()
    axes = {a.name: a for a in base.axes}
    for item in items:
        axis = parse_item(item)
        axes.pop(axis.name, None)
        axes[axis.name] = axis
    return _make_spec(
        list(axes.values()),
        base.seed if seed is None else seed,
        base.repeats if repeats is None else repeats,
        base.samples if samples is None else samples,
    )


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


def run_id(options: Mapping) -> str:
    """Stable key of a run: SHA-256 of its options as canonical JSON, 16 hex digits."""
    text = json.dumps(options, sort_keys=True, separators=(",", ":"), allow_nan=False)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def expand(spec: SweepSpec) -> list[dict]:
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
    _validate_runs(out)
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
    kwargs = {k: v for k, v in options.items() if k in SCENARIO_OPTIONS}
    for name in LIST_OPTIONS:
        if name in kwargs:
            text = kwargs[name].strip()
            kwargs[name] = [] if text.lower() == "none" else [p.strip() for p in text.split(";")]
    gains = {k[5:]: v for k, v in options.items() if k.startswith("gain.")}
    if gains:
        if "gains" in kwargs:
            gains["preset"] = kwargs["gains"]
        kwargs["gains"] = gains
    params = {}
    plant_scale = {}
    for k, v in options.items():
        if k.startswith("scale."):
            plant_scale[k[6:]] = v
        elif k.startswith("param."):
            params[k[6:]] = v
    for name in DICT_OPTIONS:
        entries = {k[len(name) + 1 :]: v for k, v in options.items() if k.startswith(name + ".")}
        switch = options.get(name)
        if switch == "off" and entries:
            raise ValueError(f"{name}=off contradicts {', '.join(map(str, entries))} set for it")
        if switch == "on" or entries:
            kwargs[name] = entries
        elif switch == "off":
            kwargs[name] = None
    if "timestep" in kwargs and "control_dt" not in kwargs:
        kwargs["control_dt"] = kwargs["timestep"]
    return Scenario(params=params, plant_scale=plant_scale, **kwargs)


def _resolved_gains(scenario: Scenario) -> tuple[str, dict]:
    cls = controller_class(scenario.controller)
    values, preset = resolve_gains(cls.name, cls.PRESETS, cls.DEFAULT_PRESET, scenario.gains)
    return preset, values


def _validate_runs(runs: Sequence[dict]) -> None:
    """Every run through the one setup path (:func:`tt_mujoco.sim.build`), before any work
    (exit 2 on a bad one). Runs that differ only in their seed are checked once."""
    checked: set[str] = set()
    for run in runs:
        options = run["options"]
        key = json.dumps({k: v for k, v in options.items() if k != "seed"}, sort_keys=True)
        if key in checked:
            continue
        try:
            build(build_scenario(options))
        except (ValueError, TypeError, OSError) as err:
            shown = {k: v for k, v in options.items() if k != "seed"}
            raise BadSpecError(f"run {run['index']} {shown}: {err}") from None
        checked.add(key)


def config_columns(run: Mapping) -> dict:
    """The configuration part of a run's row: the full Scenario, the resolved eta and gains,
    and the ``scale.*``/``param.*`` factors given."""
    options = run["options"]
    scenario = build_scenario(options)
    row = {"index": run["index"], "run_id": run["run_id"], "replicate": run["replicate"]}
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
        if k.startswith(("scale.", "param.")):
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


def run_one(options: Mapping) -> dict:
    """Simulate one run; never raises for a run's failure (worker entry point).

    Parameters
    ----------
    options : mapping
        One run's options (see :func:`expand`).

    Returns
    -------
    dict
        ``status`` ("ok", "jackknife", "diverged", or "error" when the run raised),
        ``message``, ``error`` (exception type and text, "" unless status is "error"),
        ``metrics`` (dict; empty on error) and ``run_wall_s`` (the whole run in this worker:
        setup, control loop and metrics).
    """
    from tt_mujoco.sim import simulate

    start = time.perf_counter()
    try:
        result = simulate(build_scenario(options))
        metrics = _flatten_metrics({k: v for k, v in result.metrics.items() if k != "status"})
        out = {"status": result.status, "message": result.message, "error": "", "metrics": metrics}
    except Exception as err:  # a run's crash is a row of the table, not the sweep's end
        out = {
            "status": "error",
            "message": "",
            "error": f"{type(err).__name__}: {err}",
            "metrics": {},
        }
    out["run_wall_s"] = time.perf_counter() - start
    return out


# --- journal and table -------------------------------------------------------------------------
def _read_journal(path: Path) -> dict[str, dict]:
    """Finished runs by run_id. A line cut by a kill is dropped (that run runs again)."""
    done = {}
    if not path.exists():
        return done
    with open(path, encoding="utf-8") as fh:
        for line in fh:
            try:
                record = json.loads(line)
                done[record["run_id"]] = record
            except (json.JSONDecodeError, KeyError, TypeError):
                continue
    return done


def _cell(value) -> str:
    if value is None:
        return ""
    if isinstance(value, float):
        return repr(value)  # full precision: tables from any executor compare exactly
    return str(value)


def build_rows(runs: Sequence[dict], done: Mapping[str, dict]) -> tuple[list[str], list[dict]]:
    """The table: header and one row per run (in run order) from the journal's records."""
    rows = []
    config_names: list[str] = []
    metric_names: list[str] = []
    for run in runs:
        record = done[run["run_id"]]
        row = config_columns(run)
        for name in row:
            if name not in config_names:
                config_names.append(name)
        row.update({k: record.get(k, "") for k in RESULT_COLUMNS})
        for name, value in record.get("metrics", {}).items():
            if name not in metric_names and name not in WALL_COLUMNS:
                metric_names.append(name)
            row[name] = value
        row["run_wall_s"] = record.get("run_wall_s")
        rows.append(row)
    header = config_names + list(RESULT_COLUMNS) + metric_names + list(WALL_COLUMNS)
    return header, rows


def table_csv(header: Sequence[str], rows: Sequence[Mapping]) -> str:
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(header)
    for row in rows:
        writer.writerow([_cell(row.get(name)) for name in header])
    return buf.getvalue()


def read_table(path: str | Path) -> list[dict[str, str]]:
    """A ``runs.csv`` as a list of rows (column -> text; empty text for missing values)."""
    with open(path, newline="", encoding="utf-8") as fh:
        return list(csv.DictReader(fh))


# --- summary and figures -------------------------------------------------------------------------
def _is_number(value) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def _numeric(rows: Sequence[Mapping], name: str) -> np.ndarray:
    """Column ``name`` as floats, NaN where a row has no number."""
    return np.array([float(v) if _is_number(v := r.get(name)) else math.nan for r in rows])


def summarize(header: Sequence[str], rows: Sequence[Mapping]) -> dict:
    """Counts by status and, per metric, statistics over the runs that finished ``ok``.

    Metrics of stopped runs cover only the time before the stop, so they would mix two
    populations; their number is in ``failed`` and ``by_status`` instead.

    Returns
    -------
    dict
        ``runs``, ``ok``, ``failed``, ``by_status`` (status -> count), ``errors`` (the first 5
        distinct error texts), ``metrics`` (name -> ``n``, ``mean``, ``std``, ``min``,
        ``p5``...``p95``, ``max``; NaN values skipped).
    """
    by_status: dict[str, int] = {}
    for row in rows:
        by_status[row["status"]] = by_status.get(row["status"], 0) + 1
    ok_rows = [r for r in rows if r["status"] == "ok"]
    errors = list(dict.fromkeys(r["error"] for r in rows if r.get("error")))[:5]
    start = header.index("error") + 1
    stats = {}
    for name in header[start:]:
        if not any(_is_number(r.get(name)) for r in rows):
            continue  # a text column (e.g. a fault's kind)
        x = _numeric(ok_rows, name)
        x = x[np.isfinite(x)]
        entry = {"n": int(x.size)}
        if x.size:
            entry.update(mean=float(x.mean()), std=float(x.std()), min=float(x.min()))
            for p, v in zip(PERCENTILES, np.percentile(x, PERCENTILES), strict=True):
                entry[f"p{p}"] = float(v)
            entry["max"] = float(x.max())
        stats[name] = entry
    return {
        "runs": len(rows),
        "ok": len(ok_rows),
        "failed": len(rows) - len(ok_rows),
        "by_status": dict(sorted(by_status.items())),
        "errors": errors,
        "metrics": stats,
    }


def summary_csv(summary: Mapping) -> str:
    keys = ["n", "mean", "std", "min", *(f"p{p}" for p in PERCENTILES), "max"]
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(["metric", *keys])
    for name, entry in summary["metrics"].items():
        writer.writerow([name, *(_cell(entry.get(k)) for k in keys)])
    return buf.getvalue()


def summary_text(summary: Mapping, metric_names: Sequence[str]) -> str:
    lines = [
        f"{summary['runs']} runs: {summary['ok']} ok, {summary['failed']} failed"
        + "".join(
            f", {count} {status}"
            for status, count in summary["by_status"].items()
            if status != "ok"
        )
    ]
    width = max([len(n) for n in metric_names] + [6])
    lines.append(f"{'metric':<{width}}  {'p5':>10} {'median':>10} {'p95':>10} {'max':>10}")
    for name in metric_names:
        e = summary["metrics"].get(name, {})
        if not e.get("n"):
            continue
        lines.append(
            f"{name:<{width}}  {e['p5']:>10.4g} {e['p50']:>10.4g} {e['p95']:>10.4g} "
            f"{e['max']:>10.4g}"
        )
    for err in summary["errors"]:
        lines.append(f"error: {err}")
    return "\n".join(lines)


def plot_summary(
    rows: Sequence[Mapping], spec: SweepSpec, out: Path, metric: str = "rmse_lateral"
) -> list[Path]:
    """``histograms.png`` (key metrics over the ok runs) and ``scatter.png`` (``metric``
    against each numeric option that varies; failed runs drawn as red crosses at the top)."""
    from matplotlib.figure import Figure

    ok = [r for r in rows if r["status"] == "ok"]
    failed = len(rows) - len(ok)
    names = [m for m in dict.fromkeys([*KEY_METRICS, metric]) if np.isfinite(_numeric(ok, m)).any()]
    names = names[:6]
    fig = Figure(figsize=(12, 6.5), layout="constrained")
    axs = fig.subplots(2, 3, squeeze=False).ravel()
    for ax, name in zip(axs, names, strict=False):
        x = _numeric(ok, name)
        x = x[np.isfinite(x)]
        ax.hist(x, bins=min(40, max(5, int(math.sqrt(x.size)) + 1)), color="tab:blue", alpha=0.8)
        med = float(np.median(x))
        ax.axvline(med, color="k", lw=1, ls="--", label=f"median {med:.3g}")
        ax.set_xlabel(name)
        ax.set_ylabel("runs")
        ax.legend(fontsize=8)
    for ax in axs[len(names) :]:
        ax.set_visible(False)
    fig.suptitle(f"{len(rows)} runs: {len(ok)} ok, {failed} failed (histograms of ok runs)")
    paths = [save_figure(fig, out / "histograms.png", 120)]

    axes = [a for a in spec.axes if a.varies and a.name != "seed" and _is_numeric(rows, a.name)]
    axes = axes[:6]
    y_all = _numeric(rows, metric)
    bad = np.array([r["status"] != "ok" for r in rows])
    finite = y_all[~bad & np.isfinite(y_all)]
    top = float(finite.max()) * 1.05 if finite.size else 1.0
    if axes:
        n_rows, n_cols = math.ceil(len(axes) / 3), min(3, len(axes))
        fig = Figure(figsize=(4.2 * n_cols, 3.6 * n_rows), layout="constrained")
        panels = fig.subplots(n_rows, n_cols, squeeze=False).ravel()
        # Fixed jitter spreads the runs of a grid value sideways (the same picture every time).
        jitter = np.random.default_rng(0).uniform(-1.0, 1.0, len(rows))
        for ax, axis in zip(panels, axes, strict=False):
            x = np.array([float(r[axis.name]) for r in rows])
            log = bool(np.all(x > 0) and x.max() >= 10 * x.min())
            if log:
                ax.set_xscale("log")
            u = np.log(x) if log else x  # jitter and medians where the axis is uniform
            levels = np.unique(u)
            xs = x
            if 1 < levels.size <= 12:
                half = 0.3 * float(np.diff(levels).min())
                u_jit = u + 0.5 * half * jitter
                xs = np.exp(u_jit) if log else u_jit
                for level in levels:  # the median of the ok runs at each grid value
                    y = y_all[(u == level) & ~bad & np.isfinite(y_all)]
                    if y.size:
                        ends = np.array([level - half, level + half])
                        ends = np.exp(ends) if log else ends
                        ax.plot(ends, [np.median(y)] * 2, color="k", lw=1.5)
            ax.scatter(xs[~bad], y_all[~bad], s=12, alpha=0.6, color="tab:blue", label="ok")
            if bad.any():
                top_row = np.full(bad.sum(), top)
                ax.scatter(xs[bad], top_row, marker="x", color="tab:red", label="failed")
            ax.set_xlabel(axis.name)
            ax.set_ylabel(metric)
            ax.legend(fontsize=8)
        for ax in panels[len(axes) :]:
            ax.set_visible(False)
    else:  # nothing numeric varies (e.g. seeds only): two metrics against each other
        fig = Figure(figsize=(5.5, 4.5), layout="constrained")
        ax = fig.subplots()
        other = "rmse_v" if metric != "rmse_v" else "rmse_omega"
        x_all = _numeric(rows, other)
        ax.scatter(x_all[~bad], y_all[~bad], s=12, alpha=0.6, color="tab:blue")
        ax.set_xlabel(other)
        ax.set_ylabel(metric)
    fig.suptitle(
        f"{metric} per run ({failed} failed runs drawn at the top in red; black: median per value)"
        if axes
        else f"{metric} per run ({failed} failed runs not drawn)"
    )
    paths.append(save_figure(fig, out / "scatter.png", 120))
    return paths


def _is_numeric(rows: Sequence[Mapping], name: str) -> bool:
    return all(_is_number(r.get(name)) for r in rows)


# --- execution ---------------------------------------------------------------------------------
@dataclass
class SweepResult:
    """What :func:`run_sweep` did.

    Attributes
    ----------
    out : Path
    header : list of str
    rows : list of dict
        The table, one dict per run (Python values).
    summary : dict
        See :func:`summarize`.
    reused : int
        Runs taken from the journal instead of being run.
    wall_s : float
        Wall time of this call.
    files : list of Path
    """

    out: Path
    header: list[str]
    rows: list[dict]
    summary: dict
    reused: int
    wall_s: float
    files: list[Path] = field(default_factory=list)


#: Imported once in the forkserver, so that no worker pays ~1 s of imports on its first run.
#: (Not this module: under ``python -m`` it is ``__main__`` and is imported by the workers.)
_PRELOAD = [
    "mujoco",
    "scipy.integrate",
    "tt_mujoco.sim",
    "tt_mujoco.sim.physics",
    "tt_mujoco.reference.targets",
    "tt_mujoco.analysis.metrics",
    "tt_mujoco.sim.faults",
    "controllers",
]


def _ignore_sigint() -> None:
    # Ctrl-C reaches the whole process group; only the parent should handle it (it cancels the
    # rest and stops the workers), or every worker prints a traceback.
    signal.signal(signal.SIGINT, signal.SIG_IGN)


class _Executors:
    """Opens the executor: a process pool, or a Dask client's concurrent.futures executor."""

    def __init__(self, workers: int, scheduler: str | None, initializer=None):
        self.workers = workers
        self.initializer = initializer
        self.scheduler = scheduler
        self.client = self.cluster = None
        self.pool: cf.Executor | None = None

    def open(self) -> cf.Executor:
        if self.scheduler is None:
            # forkserver: workers start from a clean preloaded process, not a fork of a parent
            # that may hold threads (the progress bar's, a Dask client's).
            if "forkserver" in multiprocessing.get_all_start_methods():
                ctx = multiprocessing.get_context("forkserver")
                ctx.set_forkserver_preload(_PRELOAD)
            else:  # Windows
                ctx = multiprocessing.get_context("spawn")
            self.pool = cf.ProcessPoolExecutor(
                max_workers=self.workers, mp_context=ctx, initializer=self.initializer
            )
            return self.pool
        try:
            from distributed import Client, LocalCluster
        except ImportError:
            raise BadSpecError(
                "--scheduler needs Dask distributed: pip install 'tt-mujoco[dask]'"
            ) from None
        if self.scheduler == "local":
            self.cluster = LocalCluster(
                n_workers=self.workers,
                threads_per_worker=1,
                processes=True,
                dashboard_address=":0",  # any free port: never clash with a running one
            )
            self.client = Client(self.cluster)
        else:
            try:
                self.client = Client(self.scheduler, timeout="20s")
            except (OSError, TimeoutError) as err:
                raise BadSpecError(
                    f"--scheduler {self.scheduler!r}: cannot connect to a Dask scheduler ({err})"
                ) from None
        # pure=False: a resubmitted run must run again, not return a cached failure
        self.pool = self.client.get_executor(pure=False)
        return self.pool

    def slots(self) -> int:
        if self.client is not None:
            return max(1, sum(self.client.nthreads().values()))
        return self.workers

    def reopen(self) -> cf.Executor:
        self.close(cancel=True)
        return self.open()

    def close(self, cancel: bool = False) -> None:
        if self.pool is not None:
            if cancel and isinstance(self.pool, cf.ProcessPoolExecutor):
                # Python 3.11 has no terminate_workers(): stop runs in flight instead of
                # waiting for them (their results would be dropped anyway).
                for proc in list(getattr(self.pool, "_processes", {}).values()):
                    with contextlib.suppress(Exception):
                        proc.terminate()
            if isinstance(self.pool, cf.ProcessPoolExecutor):
                self.pool.shutdown(wait=not cancel, cancel_futures=True)
            else:  # Dask's executor cancels what is pending on shutdown(wait=False)
                self.pool.shutdown(wait=not cancel)
            self.pool = None
        if self.client is not None:
            self.client.close()
            self.client = None
        if self.cluster is not None:
            self.cluster.close()
            self.cluster = None


def _progress(total: int, initial: int, quiet: bool):
    if quiet:
        return None
    from tqdm import tqdm

    return tqdm(
        total=total,
        initial=initial,
        unit="run",
        desc="sweep",
        dynamic_ncols=True,
        mininterval=0.5 if sys.stderr.isatty() else 30.0,
        file=sys.stderr,
    )


def _lock(out: Path):
    try:
        import fcntl
    except ImportError:  # Windows: no advisory lock, the user keeps one sweep per folder
        return contextlib.nullcontext()
    fh = open(out / ".lock", "w")  # held open (and locked) for the sweep's lifetime
    try:
        fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        fh.close()
        raise BadSpecError(f"--out {str(out)!r}: another sweep is running in it") from None
    return fh


def prepare_out(out: Path, resume: bool) -> None:
    """Make the output folder; refuse a used one unless resuming."""
    if out.exists() and (not out.is_dir() or any(out.iterdir())):
        if not resume:
            raise BadSpecError(
                f"--out {str(out)!r} already exists and is not empty: pass --resume to continue "
                "the sweep in it, or name a new folder"
            )
        if not (out / JOURNAL).exists() and not (out / SPEC_FILE).exists():
            raise BadSpecError(f"--out {str(out)!r} holds no sweep ({JOURNAL}) to resume")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise BadSpecError(f"--out {str(out)!r} cannot be made: {err.strerror}") from None


def run_sweep(
    spec: SweepSpec,
    out: str | Path,
    workers: int = 1,
    scheduler: str | None = None,
    resume: bool = False,
    quiet: bool = True,
    metric: str = "rmse_lateral",
    figures: bool = True,
    retry_errors: bool = False,
) -> SweepResult:
    """Run a sweep and write its table, summary and figures into ``out``.

    Parameters
    ----------
    spec : SweepSpec
    out : path
        Output folder: new or empty, or (``resume=True``) one holding an unfinished sweep.
    workers : int
        Local worker processes (``scheduler=None``), or the LocalCluster's workers
        (``scheduler="local"``); ignored for a remote scheduler.
    scheduler : str, optional
        None: a local process pool. ``"local"``: a Dask ``LocalCluster``. Otherwise the address
        of a running Dask scheduler, e.g. ``tcp://10.0.0.5:8786``.
    resume : bool
        Continue a sweep in ``out``: runs whose configuration is in its journal are not run.
    quiet : bool
        No progress bar.
    metric : str
        The metric of the scatter figure.
    figures : bool
        Write ``histograms.png`` and ``scatter.png``.
    retry_errors : bool
        With ``resume``: run again the runs whose status is "error" (a raised exception or a
        lost worker, perhaps transient); jackknifed and diverged runs are results and stay.

    Raises
    ------
    BadSpecError
        For a bad specification, output folder or scheduler, before any run starts.
    KeyboardInterrupt
        When interrupted; finished runs are in the journal, and ``resume=True`` continues.
    """
    t0 = time.perf_counter()
    out = Path(out)
    if not (isinstance(workers, int) and workers >= 1):
        raise BadSpecError(f"workers={workers!r} is not allowed: it must be an integer >= 1")
    runs = expand(spec)
    prepare_out(out, resume)
    with _lock(out):
        journal_path = out / JOURNAL
        done = _read_journal(journal_path)
        if retry_errors:
            done = {k: r for k, r in done.items() if r.get("status") != "error"}
        # Rewrite the journal without a line cut by a kill, so appends start on a fresh line.
        if journal_path.exists():
            atomic_write(journal_path, "".join(json.dumps(r) + "\n" for r in done.values()))
        atomic_write(out / SPEC_FILE, spec.to_toml())
        todo = deque(r for r in runs if r["run_id"] not in done)
        reused = len(runs) - len(todo)
        if todo:
            _execute(todo, done, journal_path, workers, scheduler, quiet, len(runs), reused)
        header, rows = build_rows(runs, done)
        atomic_write(out / TABLE, table_csv(header, rows))
        summary = summarize(header, rows)
        atomic_write(out / "summary.csv", summary_csv(summary))
        wall = time.perf_counter() - t0
        doc = {**summary, "mode": spec.mode, "seed": spec.seed, "wall_s": wall, "reused": reused}
        atomic_write(out / "summary.json", json.dumps(doc, indent=2) + "\n")
        files = [out / TABLE, out / "summary.csv", out / "summary.json"]
        if figures and rows:
            if metric not in header:
                print(
                    f"note: --metric {metric!r} is not a column; drawing rmse_lateral",
                    file=sys.stderr,
                )
                metric = "rmse_lateral"
            files += plot_summary(rows, spec, out, metric)
    return SweepResult(out, header, rows, summary, reused, time.perf_counter() - t0, files)


def _execute(todo, done, journal_path, workers, scheduler, quiet, total, reused) -> None:
    """Run ``todo`` through the executor, journalling each result as it arrives."""
    # The workers get the functions by reference to this module's import name: under
    # ``python -m tt_mujoco.sweep`` they would otherwise be ``__main__.run_one``, which a Dask
    # worker cannot import.
    worker = importlib.import_module("tt_mujoco.sweep")
    executors = _Executors(workers, scheduler, worker._ignore_sigint)
    executor = executors.open()
    bar = _progress(total, reused, quiet)
    failures = sum(1 for r in done.values() if r.get("status") != "ok")
    crashes: dict[str, int] = {}
    inflight: dict[cf.Future, dict] = {}
    slots, slots_checked = executors.slots(), time.monotonic()
    try:
        with open(journal_path, "a", encoding="utf-8") as journal:
            while todo or inflight:
                if executors.client is not None and time.monotonic() - slots_checked > 10:
                    slots, slots_checked = executors.slots(), time.monotonic()  # adaptive
                # A bounded window keeps memory flat for huge sweeps and makes Ctrl-C prompt.
                while todo and len(inflight) < 2 * slots + 2:
                    if any(r["run_id"] in crashes for r in inflight.values()):
                        break  # a suspect of a worker death runs alone (see _recover)
                    if todo[0]["run_id"] in crashes and inflight:
                        break
                    run = todo.popleft()
                    inflight[executor.submit(worker.run_one, run["options"])] = run
                finished, _ = cf.wait(inflight, return_when=cf.FIRST_COMPLETED)
                broken = []
                for fut in finished:
                    run = inflight.pop(fut)
                    try:
                        result = fut.result()
                    except cf.process.BrokenProcessPool:
                        broken.append(run)
                        continue
                    except Exception as err:  # e.g. Dask's KilledWorker after its retries
                        result = {
                            "status": "error",
                            "message": "",
                            "error": f"{type(err).__name__}: {err}",
                            "metrics": {},
                            "run_wall_s": None,
                        }
                    record = {"run_id": run["run_id"], "index": run["index"], **result}
                    journal.write(json.dumps(record) + "\n")
                    journal.flush()
                    done[run["run_id"]] = record
                    failures += result["status"] != "ok"
                    if bar is not None:
                        bar.update(1)
                        bar.set_postfix(failed=failures, refresh=False)
                if broken:
                    executor = _recover(executors, broken, inflight, todo, crashes, journal, done)
                    failures = sum(1 for r in done.values() if r.get("status") != "ok")
    except BaseException:
        executors.close(cancel=True)
        raise
    finally:
        if bar is not None:
            bar.close()
    executors.close()


def _recover(executors, broken, inflight, todo, crashes, journal, done) -> cf.Executor:
    """A worker process died (segfault, out of memory): every run in flight is suspect.

    Suspects run again one at a time; a run that was alone in flight when a worker died (or in
    flight at two deaths) is recorded as an error.
    """
    suspects = broken + list(inflight.values())
    inflight.clear()
    alone = len(suspects) == 1
    for run in reversed(suspects):
        crashes[run["run_id"]] = crashes.get(run["run_id"], 0) + 1
        if alone or crashes[run["run_id"]] >= 2:
            record = {
                "run_id": run["run_id"],
                "index": run["index"],
                "status": "error",
                "message": "",
                "error": "the worker process died during this run",
                "metrics": {},
                "run_wall_s": None,
            }
            journal.write(json.dumps(record) + "\n")
            journal.flush()
            done[run["run_id"]] = record
        else:
            todo.appendleft(run)
    return executors.reopen()


# --- command line ------------------------------------------------------------------------------
class _Parser(argparse.ArgumentParser):
    def error(self, message: str):  # argparse's own errors: exit code 2, one line
        raise BadSpecError(message)


_DICT_HELP = "".join(
    f"  {n:<16} on (its defaults), off, or {n}.<key>=x for one entry (implies on)\n"
    for n in DICT_OPTIONS
)
EPILOG = f"""\
options (OPTION=VALUES):
  Scenario fields: {", ".join(SCENARIO_OPTIONS)}
  gain.<name>      a controller gain, e.g. gain.k1_v (ISMC-STA), gain.kp_v (PID)
  scale.<field>    Params default times the factor; field one of {", ".join(SCALABLE)}
  param.<field>    a Params value; field one of {", ".join(SETTABLE)}
{_DICT_HELP}  faults           one fault spec per value, several in a run joined by ";" (e.g.
                   faults="payload:t=2,factor=1.5"); on the command line a single value,
                   several values as a list in a --config TOML file; "none" for no faults
VALUES:
  5                 fixed          5,10,20          a list
  lin:0.8:1.2:5     5 evenly spaced values, ends included
  log:1:100:3       geometric      range:0:10       integers 0..9
  uniform:A:B  loguniform:A:B  normal:MEAN:STD       random mode (--samples) only
example:
  python -m tt_mujoco.sweep traj=s_curve duration=10 noise_snr_db=20 \\
      gain.k1_v=5,10,20 scale.Mr=lin:0.8:1.2:3 --repeats 4 --workers 2 --out renders/sweep1
"""


def build_parser() -> argparse.ArgumentParser:
    p = _Parser(
        prog="python -m tt_mujoco.sweep",
        description=(
            "Run a grid or random sweep of closed-loop runs in parallel and write one table "
            "(runs.csv: configuration and metrics of every run), a summary and figures."
        ),
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("items", nargs="*", metavar="OPTION=VALUES", help="options (see below)")
    p.add_argument("--config", type=Path, metavar="FILE.toml", help="sweep specification file")
    p.add_argument("--repeats", type=int, default=None, help="grid: runs per point (default 1)")
    p.add_argument("--samples", type=int, default=None, help="random sampling: number of runs")
    p.add_argument("--seed", type=int, default=None, help="sweep seed (default 0)")
    p.add_argument(
        "--out",
        type=Path,
        default=None,
        metavar="DIR",
        help="output folder (default: a new folder under renders/)",
    )
    p.add_argument(
        "--resume",
        action="store_true",
        help="continue the sweep in --out (without options: with its saved spec)",
    )
    p.add_argument(
        "--retry-errors",
        action="store_true",
        help="with --resume: run again the runs that ended with status 'error'",
    )
    p.add_argument(
        "--workers", type=int, default=None, help="worker processes (default: the CPU count)"
    )
    p.add_argument(
        "--scheduler",
        default=None,
        metavar="ADDRESS",
        help="Dask scheduler address, or 'local' for a LocalCluster",
    )
    p.add_argument("--metric", default="rmse_lateral", help="metric of the scatter figure")
    p.add_argument("--no-figures", action="store_true", help="skip the PNG figures")
    p.add_argument("--dry-run", action="store_true", help="check the sweep and list its runs")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    return p


def _sigterm(signum, frame):
    raise KeyboardInterrupt  # a batch system's stop: same clean, resumable exit as Ctrl-C


def main(argv: list[str] | None = None) -> int:
    out = None
    try:
        args = build_parser().parse_args(argv)
        workers = args.workers if args.workers is not None else (os.cpu_count() or 1)
        if workers < 1:
            raise BadSpecError(f"--workers {workers} is not allowed: it must be >= 1")
        if args.resume and args.out is None:
            raise BadSpecError("--resume needs --out DIR, the folder of the sweep to continue")
        config = args.config
        if args.resume and not args.items and config is None:
            config = args.out / SPEC_FILE
            if not config.exists():
                raise BadSpecError(f"--out {str(args.out)!r} holds no {SPEC_FILE} to resume")
        spec = parse_spec(args.items, config, args.seed, args.repeats, args.samples)
        if not spec.axes and args.samples is None and args.repeats is None:
            raise BadSpecError(
                "nothing to sweep: give options as OPTION=VALUES, --repeats N, --samples N or "
                "--config FILE.toml (see --help)"
            )
        noise = spec.axis("noise_snr_db")
        if spec.mode == "grid" and spec.repeats > 1 and (noise is None or None in noise.values):
            print(
                "note: repeats differ only in the noise seed; runs without noise_snr_db are "
                "identical copies",
                file=sys.stderr,
            )
        if args.dry_run:
            runs = expand(spec)
            for run in runs:
                print(run["index"], run["run_id"], json.dumps(run["options"]))
            print(f"{len(runs)} runs ({spec.mode})")
            return EXIT_OK
        out = args.out
        if out is None:
            out = free_name(RENDERS / f"sweep-{time.strftime('%Y%m%d-%H%M%S')}")
        signal.signal(signal.SIGTERM, _sigterm)
        result = run_sweep(
            spec,
            out,
            workers=workers,
            scheduler=args.scheduler,
            resume=args.resume,
            quiet=args.quiet,
            metric=args.metric,
            figures=not args.no_figures,
            retry_errors=args.retry_errors,
        )
    except BadSpecError as err:
        print(f"error: {err}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        if out is not None:
            print(
                f"\ninterrupted: finished runs are in {out / JOURNAL}; continue with "
                f"python -m tt_mujoco.sweep --resume --out {out}",
                file=sys.stderr,
            )
        return EXIT_INTERRUPTED
    metric_names = [m for m in dict.fromkeys([*KEY_METRICS, args.metric])]
    print(summary_text(result.summary, metric_names))
    ran = len(result.rows) - result.reused
    rate = f", {ran / result.wall_s:.2f} runs/s" if ran else ""
    print(
        f"{len(result.rows)} runs ({result.reused} reused) in {result.wall_s:.1f} s{rate}; "
        f"wrote {', '.join(p.name for p in result.files)} to {result.out}/"
    )
    return EXIT_OK

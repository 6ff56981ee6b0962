"""The sweep's options: names, value checks and conversions, and the limits."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from pathlib import Path

from tt_mujoco.controllers import CONTROLLERS
from tt_mujoco.registry import closest, is_hook, normalise_hook
from tt_mujoco.sim import DISTURBANCE_MODES, PLANTS, TARGETS, Scenario
from tt_mujoco.sim.motors import ACTUATORS
from tt_mujoco.sim.scenario import ETA_SCHEDULES
from tt_mujoco.sim.terrain import parse_terrain
from tt_mujoco.sim.wind import parse_wind
from tt_mujoco.vehicle.params import (
    INERTIA_FIELDS,
    MASS_FIELDS,
    MAX_TRAILERS,
    SETTABLE_FIELDS,
    TRAILER_FIELDS,
)

STARTS = ("on_path", "paper")


#: Scenario fields that are options, in the table's column order (``params`` is reached through
#: ``scale.*`` and ``param.*``; ``gains`` here is the preset name, single gains are ``gain.*``).
SCENARIO_OPTIONS = tuple(
    f.name for f in dataclasses.fields(Scenario) if f.name not in ("params", "plant_scale", "train")
)


#: Per-trailer options of a train: ``trailer<k>.<field>`` for trailer k >= 2 (e.g.
#: ``trailer2.eta=0``, ``trailer3.L0=0.5``), with ``field`` one of these.
TRAILER_OPTION_FIELDS = (*TRAILER_FIELDS, "eta")


def trailer_option(name: str) -> tuple[int, str] | None:
    """``(k, field)`` of a per-trailer option name ``trailer<k>.<field>``, else None."""
    prefix, dot, field = name.partition(".")
    digits = prefix.removeprefix("trailer")
    if dot and prefix.startswith("trailer") and digits.isdigit() and field:
        return int(digits), field
    return None


#: Scenario fields that hold a list of specs; a sweep value is one text, specs separated by ";"
#: ("none" for no spec), e.g. faults="payload:t=2,factor=1.5;dropout:t=5".
LIST_OPTIONS = tuple(
    f.name for f in dataclasses.fields(Scenario) if f.default_factory is list and f.name != "train"
)


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
SETTABLE = SETTABLE_FIELDS


#: Options written as a spec text, each with its parser (the run keeps the parsed spelling).
SPEC_OPTIONS = {"terrain": parse_terrain, "wind": parse_wind}


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
def as_number(name: str, value, positive: bool = False) -> float:
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


def as_integer(name: str, value) -> int:
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
    return as_number(name, value, positive)


def _eta(name: str, value) -> float | str:
    if isinstance(value, str):
        key = value.strip().lower().replace("-", "_")
        if key in ("paper", "same_path"):
            return key
    return as_number(name, value)


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
    if name == "traj" and _text(name, value).lower().endswith(".csv"):
        return str(Path(_text(name, value)).resolve())  # the same file from any folder
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
    if name == "disturbance_limit":
        if isinstance(value, str) and value.strip().lower() in ("actuator", "none"):
            return value.strip().lower()
        return as_number(name, value, positive=True)
    if name == "noise_snr_db":
        return _optional_number(name, value)
    if name == "duration":
        return _optional_number(name, value, positive=True)
    if name in ("param_scale", "timestep", "control_dt", "friction"):
        return as_number(name, value, positive=True)
    if name == "seed":
        return as_integer(name, value)
    if name.startswith(("gain.", "scale.")):
        return as_number(name, value, positive=True)
    if name.startswith("param."):
        return as_number(name, value)
    if trailer_option(name) is not None:
        check_option_name(name)
        if trailer_option(name)[1] == "eta":
            return _eta(name, value)
        return as_number(name, value, positive=True)
    if name in LIST_OPTIONS:
        return _text(name, value)
    if name in DICT_OPTIONS:
        return "on" if _boolean(name, value, extra="'on' (defaults) or 'off'") else "off"
    if name.partition(".")[0] in DICT_OPTIONS:
        return as_number(name, value)
    if name == "eta_schedule":
        if isinstance(value, str) and value.strip().lower() in ETA_SCHEDULES:
            return value.strip().lower()
        return _boolean(name, value, extra=f"true, false or one of {', '.join(ETA_SCHEDULES)}")
    if name == "actuator":
        return _choice(name, value, ACTUATORS)
    if name in SPEC_OPTIONS:
        try:
            return SPEC_OPTIONS[name](_text(name, value)).spec()
        except ValueError as err:
            raise BadSpecError(str(err)) from None
    if name in SCENARIO_OPTIONS:  # a newer Scenario field: checked by the type of its default
        default = next(f.default for f in dataclasses.fields(Scenario) if f.name == name)
        if isinstance(default, bool):
            return _boolean(name, value)
        if isinstance(default, float):
            return as_number(name, value)
        if isinstance(default, int) and not isinstance(default, bool):
            return as_integer(name, value)
        if isinstance(default, str):
            return _text(name, value)
    raise BadSpecError(_unknown_option_message(name))


def _unknown_option_message(name: str) -> str:
    known = [
        *SCENARIO_OPTIONS,
        *(f"scale.{f}" for f in SCALABLE),
        *(f"param.{f}" for f in SETTABLE),
    ]
    close = closest(name, known)
    return (
        f"option {name!r} is not allowed"
        + (f" (did you mean {close!r}?)" if close else "")
        + f": use one of {', '.join(SCENARIO_OPTIONS)}, "
        f"gain.<name> (a controller gain), scale.<field> (field one of {', '.join(SCALABLE)}: "
        f"Params default times the factor), param.<field> (field one of {', '.join(SETTABLE)}), "
        f"trailer<k>.<field> (k in 2..{MAX_TRAILERS}, field one of "
        f"{', '.join(TRAILER_OPTION_FIELDS)})"
        + "".join(f" or {option}.<key>" for option in DICT_OPTIONS)
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
        trailer = trailer_option(name)
        if trailer is not None and 2 <= trailer[0] <= MAX_TRAILERS:
            if trailer[1] in TRAILER_OPTION_FIELDS:
                return name
    raise BadSpecError(_unknown_option_message(name))

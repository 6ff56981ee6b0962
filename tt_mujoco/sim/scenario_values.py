"""The parsers of the :class:`~tt_mujoco.sim.scenario.Scenario`'s own option values: each
``parse(value, label)`` returns the value checked (or its canonical form) or raises a
ValueError naming ``label``, the bad value and what is allowed (the schema's general parsers
are :mod:`tt_mujoco.schema_values`')."""

from __future__ import annotations

from tt_mujoco.registry import is_hook
from tt_mujoco.schema import boolean, choice, number, table, text
from tt_mujoco.schema_values import number_text, refuse
from tt_mujoco.sim.parts.faults import parse_fault
from tt_mujoco.sim.parts.ground import parse_patch
from tt_mujoco.vehicle.param_ranges import RANGES
from tt_mujoco.vehicle.params import MAX_TRAILERS, SETTABLE_FIELDS, Params

__all__ = [
    "ETA_SCHEDULES",
    "ETA_WORDS",
    "controller",
    "controller_names",
    "eta",
    "eta_schedule",
    "fault",
    "finite",
    "params",
    "patch",
    "path_names",
    "path_option",
    "positive",
    "spec",
    "trailers",
    "train",
    "world",
]

#: What ``Scenario.eta_schedule`` may name besides False / True.
ETA_SCHEDULES = ("curvature", "path")
#: ``eta`` words that schedule the plant's gain on the same-path model (``eta_schedule``).
ETA_WORDS = {"scheduled": "curvature", "path": "path"}


def _reraised(parse):
    """A parser from a module's own (``parse(value) -> record``), its message after the label."""

    def convert(value, label):
        try:
            return parse(value)
        except ValueError as err:
            raise ValueError(f"{label}: {err}") from None

    return convert


def spec(parse):
    def convert(value, label):
        if not isinstance(value, str):
            raise refuse(label, value, "give its text, e.g. 'flat'")
        try:
            return parse(value).spec()
        except ValueError as err:
            raise ValueError(str(err)) from None

    return convert


def world(value, label):
    from tt_mujoco.world.builtin import parse_world

    parse_world(value)  # a WorldError (a ValueError) naming what is wrong
    return text(value, label)


def controller_names() -> str:
    from tt_mujoco.controllers import CONTROLLERS  # the registry as it is when asked

    return "{" + ",".join((*CONTROLLERS, "HOOK")) + "}"


def path_names() -> str:
    from tt_mujoco.reference.paths import PATHS  # the registry as it is when asked

    return "{" + ",".join((*PATHS, "plan", "PATH.csv", "HOOK")) + "}"


def controller(value, label):
    from tt_mujoco.controllers import CONTROLLERS  # the registry as it is when asked

    name = text(value, label)
    if is_hook(name):
        return name
    return choice(*CONTROLLERS)(name, label)


finite = number()


def eta(value, label):
    if isinstance(value, str):
        key = value.strip().lower().replace("-", "_")
        if key in ("paper", "same_path", *ETA_WORDS):
            return key
    return number(words=("paper", "same_path", *ETA_WORDS))(value, label)


def eta_schedule(value, label):
    if isinstance(value, str) and value.strip().lower() in ETA_SCHEDULES:
        return value.strip().lower()
    try:
        return boolean(value, label)
    except ValueError:
        schedules = ", ".join(repr(e) for e in ETA_SCHEDULES)
        raise refuse(label, value, f"use False, True (curvature) or one of {schedules}") from None


def trailers(value, label):
    if isinstance(value, list):  # a file's [[trailers]]: one table per trailer behind the first
        if not all(isinstance(t, dict) for t in value):
            raise ValueError(
                f"{label}: trailers must be a number or an array of tables [[trailers]], one "
                "per trailer behind the first"
            )
        return [dict(t) for t in value]
    return number(1, MAX_TRAILERS, integer=True)(value, label)


def train(value, label):
    if not isinstance(value, list | tuple) or not all(isinstance(t, dict) for t in value):
        raise refuse(label, value, "give a list of tables")
    return [dict(t) for t in value]


def path_option(value, label):
    if isinstance(value, str) and value.strip():
        number = number_text(value)
        return value.strip() if number is None else number
    return finite(value, label)


def fault(value, label):
    return _reraised(lambda v: parse_fault(v).to_dict())(value, label)


def patch(value, label):
    return _reraised(lambda v: parse_patch(v).spec())(value, label)


positive = number(0, low_open=True)

# Bounded numbers: every number a run takes has a stated range, wide enough for any study and
# short of where the arithmetic breaks (10**(-snr/20) overflowing, a time past time_t, ...).
#: A factor on masses or inertias.
scale_factor = number(1e-3, 1e3)
#: A friction coefficient (Params' range).
friction = number(*RANGES["friction"][:2], unit=RANGES["friction"][2])
#: A measurement noise's signal-to-noise ratio, from noise 100 times the signal to none.
snr_db = number(-40, 200, optional=True, unit="dB")
#: A bound on a disturbance torque (or one of its words).
torque_bound = number(0, 1e6, low_open=True, words=("actuator", "none"), unit="N m")
#: A gain of a feedback loop (1/m, 1/s).
loop_gain = number(0, 1e4)
#: The initial articulation (deg), the Scenario checks it against the jackknife.
articulation_deg = number(-180, 180, unit="deg")
#: A wall-clock limit (s): up to 10 days.
wall_limit = number(0, 864000, low_open=True, unit="s")
_param_table = table(finite, SETTABLE_FIELDS)


def params(value, label):
    """Overrides of :class:`Params` fields, checked by Params itself."""
    out = _param_table(value, label)
    try:
        Params(**out)
    except ValueError as err:
        raise ValueError(f"{label}: {err}") from None
    return out


params.names = _param_table.names  # the allowed entries, as a table's parser has them

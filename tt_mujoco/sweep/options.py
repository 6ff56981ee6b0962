"""The sweep's options: names, value checks and conversions, and the limits."""

from __future__ import annotations

import math
from pathlib import Path

from tt_mujoco.registry import closest
from tt_mujoco.schema import Schema
from tt_mujoco.schema_values import check_typed, number, number_text
from tt_mujoco.sim import SCHEMA
from tt_mujoco.vehicle.params import MAX_TRAILERS, TRAILER_FIELDS

#: Scenario fields that are options, in the table's column order (``params`` is reached through
#: ``scale.*`` and ``param.*``; ``gains`` here is the preset name, single gains are ``gain.*``).
SCENARIO_OPTIONS = tuple(o.name for o in SCHEMA.options if o.axis)


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
LIST_OPTIONS = tuple(o.name for o in SCHEMA.options if o.form == "repeat")


#: Scenario fields that are a table of numbers that may be off (e.g. ``path_feedback``):
#: ``NAME=on`` (the defaults, ``{}``) or ``off`` (None), and ``NAME.<key>=x`` for one entry
#: (implies on).
DICT_OPTIONS = tuple(o.name for o in SCHEMA.options if o.entry and o.form == "switch")
#: Tables of any names reached entry by entry as ``NAME.<key>`` besides the gains.
ENTRY_OPTIONS = tuple(
    o.name
    for o in SCHEMA.options
    if o.entry and o.axis and SCHEMA.entry_names(o) is None and o.entry != "gain"
)


#: Fields of :class:`Params` that ``scale.<field>`` multiplies (docs/model.md Section 8
#: uncertainty) and that ``param.<field>`` may set: the entries of the schema's tables.
TABLE_ENTRIES = {o.entry: SCHEMA.entry_names(o) for o in SCHEMA.options if o.entry and not o.axis}
SCALABLE = TABLE_ENTRIES["scale"]
SETTABLE = TABLE_ENTRIES["param"]


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
        text, value = value, number_text(value)
        if value is None:
            raise BadSpecError(f"{name}={text!r} is not allowed: it must be a number")
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise BadSpecError(f"{name}={value!r} is not allowed: it must be a finite number")
    if positive and value <= 0:
        raise BadSpecError(f"{name}={value!r} is not allowed: it must be > 0")
    return float(value)


def as_integer(name: str, value) -> int:
    """An integer >= 0 that a TOML file holds (the schema's own integer check)."""
    try:
        return number(0, integer=True)(value, name)
    except ValueError as err:
        raise BadSpecError(str(err)) from None


def convert(name: str, value, schema: Schema = SCHEMA, *, typed: bool = True):
    """Check and convert one value of option ``name`` (text from the command line with
    ``typed=False``, or a TOML value) by the option schema; raises :class:`BadSpecError`
    naming the value and what is allowed.

    The value is kept in a sweep's own spelling, one JSON value per option: a list of specs as
    its text, a table that may be off as "on" or "off", a table's entry (``gain.k1_v``) as its
    number.
    """
    name = check_option_name(name, schema)
    trailer = trailer_option(name)
    try:
        if trailer is not None:
            checked = (
                schema["eta"].parse(value, name)
                if trailer[1] == "eta"
                else as_number(name, value, positive=True)
            )
            if typed:
                check_typed(value, checked, name)
            return checked
        parsed = schema.values({name: value}, "", typed=typed)
    except ValueError as err:
        raise BadSpecError(str(err)) from None
    field, checked = next(iter(parsed.items()))
    if field != name and schema.entry_option(name) is not None:
        key = name.partition(".")[2]
        return checked[key] if isinstance(checked, dict) else checked
    if field in LIST_OPTIONS:
        return value.strip() if isinstance(value, str) else ";".join(map(str, checked))
    if field in DICT_OPTIONS:
        return "off" if checked is None else "on"
    if schema[field].file and isinstance(checked, str) and checked.lower().endswith(".csv"):
        return str(Path(checked).resolve())  # the same file from any folder
    return checked


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
        + "".join(f" or {option}.<key>" for option in ENTRY_OPTIONS)
    )


def check_option_name(name: str, schema: Schema = SCHEMA) -> str:
    """The option's name in a sweep (a field's name for any of its keys: ``noise_snr`` is
    ``noise_snr_db``), else raise :class:`BadSpecError` listing them."""
    key = name.replace("-", "_")
    for opt in schema.options:
        if key in opt.keys and opt.axis:
            return opt.name
    _, dot, rest = name.partition(".")
    if dot and rest:
        table_option = schema.entry_option(name)
        names = None if table_option is None else schema.entry_names(table_option)
        if names is not None and rest in names:
            return f"{table_option.entry}.{rest}"
        if table_option is not None and names is None:
            return name  # gains and the tables' keys are checked when runs are expanded
        trailer = trailer_option(name)
        if trailer is not None and 2 <= trailer[0] <= MAX_TRAILERS:
            if trailer[1] in TRAILER_OPTION_FIELDS:
                return name
    raise BadSpecError(_unknown_option_message(name))

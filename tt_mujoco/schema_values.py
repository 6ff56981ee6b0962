"""The parsers of an option's value (:attr:`tt_mujoco.schema.Option.parse`): each checks and
converts a value given as text (the command line, a sweep axis) or as a TOML value, and raises
a ``ValueError`` naming the key and what is allowed."""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Mapping, Sequence
from decimal import Decimal, InvalidOperation
from pathlib import Path
from typing import Any

import numpy as np

from tt_mujoco.registry import closest, is_hook, normalise_hook, shown

__all__ = [
    "boolean",
    "check_typed",
    "choice",
    "number",
    "number_text",
    "optional_table",
    "refuse",
    "resolve_file",
    "spec_list",
    "table",
    "text",
]


#: The largest integer a TOML file holds (a signed 64-bit integer).
TOML_INT_MAX = 2**63 - 1


def refuse(label: str, value, allowed: str) -> ValueError:
    """The error of a value that is not allowed: the key, the value, what is allowed."""
    return ValueError(f"{label}={shown(value)} is not allowed: {allowed}")


# --- parsers -----------------------------------------------------------------------------------
def _interval(low, high, low_open, high_open, unit) -> str:
    if low is not None and high is not None:
        text = f"in {'(' if low_open else '['}{low:g}, {high:g}{')' if high_open else ']'}"
    elif low is not None:
        text = f"{'>' if low_open else '>='} {low:g}"
    elif high is not None:
        text = f"{'<' if high_open else '<='} {high:g}"
    else:
        return "a finite number" + (f" ({unit})" if unit else "")
    return f"a finite number {text}" + (f" {unit}" if unit else "")


def number(
    low=None,
    high=None,
    *,
    low_open=False,
    high_open=False,
    integer=False,
    optional=False,
    unit="",
    words=(),
):
    """A parser of a number in an interval; ``optional``: "none" is None; ``words``: texts
    allowed besides numbers (kept in lower case)."""
    if integer:
        # what a TOML file (config.toml, a sweep's) can hold, so every integer round-trips
        high = TOML_INT_MAX if high is None else min(high, TOML_INT_MAX)
        allowed = f"an integer in [{low}, {'2**63 - 1' if high == TOML_INT_MAX else high}]"
    else:
        allowed = _interval(low, high, low_open, high_open, unit)
    if words:
        allowed = f"{', '.join(repr(w) for w in words)} or {allowed}"
    if optional:
        allowed += " (or none)"

    def parse(value, label):
        if optional and (value is None or (isinstance(value, str) and value.strip() == "none")):
            return None
        if isinstance(value, str) and value.strip().lower() in words:
            return value.strip().lower()
        x = value
        if isinstance(x, np.integer | np.floating):  # a NumPy scalar (np.linspace's): its value
            x = x.item()
        if isinstance(x, str):
            x = number_text(x, integer)
            if x is None:
                raise refuse(label, value, f"it must be {allowed}")
        if integer and isinstance(x, float) and x.is_integer():
            x = int(x)
        ok_type = int if integer else int | float
        if isinstance(x, bool) or not isinstance(x, ok_type) or not math.isfinite(x):
            raise refuse(label, value, f"it must be {allowed}")
        if (low is not None and (x < low or (low_open and x == low))) or (
            high is not None and (x > high or (high_open and x == high))
        ):
            raise refuse(label, value, f"it must be {allowed}")
        return x if integer else float(x)

    return parse


def number_text(text: str, integer: bool = False):
    """The number a text spells, as a TOML file would hold it (None: not a number): ASCII only
    (Python's ``int("３")`` is 3), and an integer may be spelt as a whole float, ``3.0`` or
    ``3e0``, as a TOML float holding a whole number is taken; read exactly, so a whole number
    beyond a float's 53 bits is not rounded to another."""
    text = text.strip()
    if not text.isascii():
        return None
    try:
        return int(text) if integer else float(text)
    except ValueError:
        if not integer:
            return None
    try:
        exact = Decimal(text)
    except InvalidOperation:
        return None
    # far beyond any option's range: not made into an integer of a billion digits
    if not exact.is_finite() or exact.adjusted() > 20 or exact != exact.to_integral_value():
        return None
    return int(exact)


def choice(*allowed):
    """A parser of one of ``allowed`` texts, with a "did you mean" for a near miss."""

    def parse(value, label):
        if value in allowed:
            return value
        close = closest(str(value), [str(a) for a in allowed])
        hint = f" (did you mean {close!r}?)" if close else ""
        raise refuse(label, value, f"use one of {', '.join(repr(a) for a in allowed)}{hint}")

    return parse


def text(value, label):
    """A parser of a non-empty text (kept stripped); a path object (``pathlib.Path``) is its
    text, as Python code gives a file (``Scenario(traj=Path("my.csv"))``)."""
    if isinstance(value, os.PathLike):
        value = os.fspath(value)
    if not isinstance(value, str) or not value.strip():
        raise refuse(label, value, "it must be a non-empty string")
    return value.strip()


_TRUE = ("true", "on", "yes", "1")
_FALSE = ("false", "off", "no", "0")


def boolean(value, label):
    """A parser of true/false (also on/off, yes/no, 1/0 as text); a number is not a truth
    value (``video = 1`` is refused, where text ``"1"`` from the command line is true)."""
    if isinstance(value, bool | np.bool_):
        return bool(value)
    if not isinstance(value, str):
        raise refuse(label, value, "use true or false")
    key = value.strip().lower()
    if key in _TRUE:
        return True
    if key in _FALSE:
        return False
    raise refuse(label, value, "use true or false")


def check_typed(given, parsed, label: str) -> None:
    """Refuse text given where the option's value is a number or true/false.

    Only the command line (and a sweep's command-line axes) gives values as text; a TOML file,
    a sweep file, the Python API and the Gym env give them with their types, so
    ``video = "yes"`` or ``duration = "1"`` there is a mistake to name, not to guess. ``given``
    is what was given, ``parsed`` what its option's parser made of it; tables are walked
    entry by entry.
    """
    if isinstance(given, Mapping) and isinstance(parsed, Mapping):
        for key, item in given.items():
            if key in parsed:
                check_typed(item, parsed[key], f"{label}.{key}")
        return
    if isinstance(given, str) and isinstance(parsed, bool | int | float):
        kind = "true or false" if isinstance(parsed, bool) else "a number"
        raise refuse(label, given, f"it is text where {kind} is wanted: write it without quotes")


def spec_list(check_one: Callable[[Any, str], Any]):
    """A parser of a list of specs: a list, or one text with specs separated by ";" ("none"
    for no spec); each spec through ``check_one``."""

    def parse(value, label):
        if isinstance(value, str):
            stripped = value.strip()
            items = [] if stripped.lower() in ("", "none") else stripped.split(";")
        elif isinstance(value, list | tuple):
            items = list(value)
        else:
            raise refuse(label, value, "give a list of specs")
        return [check_one(item.strip() if isinstance(item, str) else item, label) for item in items]

    return parse


def table(entry_parse, names: Sequence[str] | None = None):
    """A parser of a table ``{NAME: value}`` (each value through ``entry_parse``; ``names``:
    the allowed names, None for any identifier)."""

    def parse(value, label):
        if not isinstance(value, Mapping):
            raise refuse(label, value, "give a table of NAME = value")
        out = {}
        for key, item in value.items():
            if names is not None and key not in names:
                close = closest(str(key), list(names))
                hint = f" (did you mean {close!r}?)" if close else ""
                raise ValueError(
                    f"{label}: {key!r} is not allowed{hint}: use one of {', '.join(names)}"
                )
            if names is None and not (isinstance(key, str) and key.isidentifier()):
                raise ValueError(f"{label}: {key!r} is not allowed: a name is an identifier")
            out[key] = entry_parse(item, f"{label}.{key}")
        return out

    parse.names = tuple(names) if names is not None else None  # the allowed entries
    return parse


def optional_table(entry_parse):
    """A parser of a table that may be off: ``None``/false/"off" is off, true/"on" is the
    defaults (``{}``), a table gives its entries."""
    inner = table(entry_parse)

    def parse(value, label):
        if value is None:
            return None
        if isinstance(value, Mapping):
            return inner(value, label)
        try:
            on = boolean(value, label)
        except ValueError:
            raise refuse(label, value, "use on (the defaults), off, or a table of gains") from None
        return {} if on else None

    return parse


def resolve_file(value, base: Path | None):
    """A file or hook value resolved against ``base`` (None: the current folder)."""
    if isinstance(value, list):
        return [resolve_file(v, base) for v in value]
    if not isinstance(value, str):
        return value
    if value.lower().endswith((".csv", ".toml")):  # a path's table, a world's file
        path = Path(value)
        return str(path if path.is_absolute() else ((base or Path.cwd()) / path).absolute())
    if is_hook(value):
        return normalise_hook(value, base.absolute() if base is not None else None)
    return value

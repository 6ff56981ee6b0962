"""A sweep's specification: axes of values or distributions, from the command line or TOML."""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import tomli_w

from tt_mujoco.outputs import read_toml
from tt_mujoco.schema_values import check_typed, number_text
from tt_mujoco.sweep.options import (
    DISTRIBUTIONS,
    GRID_GENERATORS,
    LIST_OPTIONS,
    MAX_RUNS,
    BadSpecError,
    as_integer,
    as_number,
    check_option_name,
    convert,
)


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
        a, b = (as_number(name, x) for x in args)
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
        if len(range(*ints)) > MAX_RUNS:  # len() of a range allocates nothing
            raise BadSpecError(f"{name}: range has more than the {MAX_RUNS} runs allowed")
        values = list(range(*ints))
        if not values:
            raise BadSpecError(f"{name}: range:{':'.join(map(str, ints))} is empty")
    else:  # lin, log
        if len(args) != 3:
            raise BadSpecError(f"{name}: {kind} takes {kind}:START:STOP:COUNT, got {list(args)}")
        a, b = as_number(name, args[0]), as_number(name, args[1])
        n = _int_arg(name, args[2])
        if n < 1:
            raise BadSpecError(f"{name}: {kind} COUNT={n} must be >= 1")
        if n > MAX_RUNS:  # before anything is allocated
            raise BadSpecError(f"{name}: {kind} COUNT={n} is more than the {MAX_RUNS} runs allowed")
        if kind == "log" and not (a > 0 and b > 0):
            raise BadSpecError(f"{name}: log:{a:g}:{b:g}:{n} needs START and STOP > 0")
        points = np.linspace(a, b, n) if kind == "lin" else np.geomspace(a, b, n)
        values = [_round(float(x)) for x in points]
    return Axis(name, values=tuple(convert(name, v) for v in values))


def _int_arg(name: str, text) -> int:
    """An integer argument of a generator (a COUNT, range's START:STOP:STEP), from text or a
    TOML number; 2.5 or true is refused, not cut to 2 or taken as 1."""
    if isinstance(text, float) and text.is_integer():
        return int(text)
    if isinstance(text, int) and not isinstance(text, bool):
        return text
    value = number_text(text, integer=True) if isinstance(text, str) else None
    if value is not None:
        return value
    raise BadSpecError(f"{name}: {text!r} is not an integer")


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
    name = check_option_name(name)
    text = text.strip()
    if not text:
        raise BadSpecError(f"{name}= has no value")
    if name in LIST_OPTIONS:
        # A fault spec has commas of its own: one value here; several in a TOML list.
        return Axis(name, values=(convert(name, text, typed=False),))
    kind, colon, rest = text.partition(":")
    if colon and kind in GRID_GENERATORS + DISTRIBUTIONS:
        return _generator(name, kind, rest.split(":"))
    parts = [p.strip() for p in text.split(",")]
    return Axis(name, values=tuple(convert(name, p, typed=False) for p in parts))


def _toml_axis(name: str, value) -> Axis:
    name = check_option_name(name)
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
        doc = read_toml(path, "--config")
    except ValueError as err:
        raise BadSpecError(str(err)) from None
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
    for key, value in sweep.items():  # a TOML file's numbers are typed: "3" is a mistake
        try:
            check_typed(value, as_integer(key, value), f"--config {str(path)!r}: [sweep] {key}")
        except ValueError as err:
            raise BadSpecError(str(err)) from None
    axes = [_toml_axis(name, value) for name, value in _flatten(doc.get("options", {}))]
    return _make_spec(axes, sweep.get("seed"), sweep.get("repeats"), sweep.get("samples"))


def _make_spec(axes: Sequence[Axis], seed, repeats, samples) -> SweepSpec:
    names = [a.name for a in axes]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise BadSpecError(f"option(s) {dup} given twice: give each option once")
    seed = 0 if seed is None else as_integer("sweep seed", seed)
    repeats = 1 if repeats is None else as_integer("repeats", repeats)
    if repeats < 1:
        raise BadSpecError(f"repeats={repeats!r} is not allowed: it must be an integer >= 1")
    if samples is not None:
        samples = as_integer("samples", samples)
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
    given = {}
    for item in items:
        axis = parse_item(item)
        if axis.name in given:  # the same command line: which one was meant?
            raise BadSpecError(
                f"{given[axis.name]!r} and {item!r} both give option {axis.name!r}: give it once "
                "(its values as one list, e.g. NAME=1,2,3)"
            )
        given[axis.name] = item
        axes.pop(axis.name, None)
        axes[axis.name] = axis
    return _make_spec(
        list(axes.values()),
        base.seed if seed is None else seed,
        base.repeats if repeats is None else repeats,
        base.samples if samples is None else samples,
    )

"""The option schema: every option of a run declared once, every interface derived from it.

An :class:`Option` carries a field's default, help text, unit, allowed values and the one
function that checks and converts a value of it (:attr:`Option.parse`). :class:`Schema` is a
set of options; :data:`tt_mujoco.sim.scenario.SCHEMA` is the :class:`~tt_mujoco.sim.Scenario`'s,
read from its dataclass fields (each declared with :func:`option`). From a schema come

* the command line's options (:meth:`Schema.add_arguments`),
* the values of a TOML table, a sweep's options or keyword arguments (:meth:`Schema.values`),
  with the same checks and the same "did you mean" for a misspelt key,
* the resolved file form written to a run's ``config.toml`` (:meth:`Schema.file_form`).

A value given as text (the command line, a sweep axis) or as a TOML value goes through the same
``parse``, which raises ``ValueError`` naming the key and what is allowed.
"""

from __future__ import annotations

import argparse
import copy
import dataclasses
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from tt_mujoco.cliargs import StoreConstOnce, StoreOnce, set_once
from tt_mujoco.registry import closest, shown
from tt_mujoco.schema_values import (
    boolean,
    check_typed,
    choice,
    number,
    number_text,
    optional_table,
    refuse,
    resolve_file,
    spec_list,
    table,
    text,
)

__all__ = [
    "Option",
    "Schema",
    "boolean",
    "check_typed",
    "choice",
    "name_value",
    "number",
    "option",
    "optional_table",
    "spec_list",
    "table",
    "table_of",
    "text",
]

#: The forms an option takes on the command line.
FORMS = ("value", "switch", "repeat", "table")


def table_of(pairs, flag: str) -> dict:
    """``NAME=VALUE`` entries of a repeatable option (``--param``, ``--path-option``, ...) as a
    table: a name given again with another value is refused, naming both, rather than the
    last one winning in silence (the same value again is allowed, as for any option).

    Raises
    ------
    ValueError
        The name set twice.
    """
    table = {}
    for name, value in pairs:
        if name in table and table[name] != value:
            raise ValueError(
                f"{flag} {name}={table[name]!r} and {flag} {name}={value!r} both set {name!r}, "
                "which cannot be both: give it once"
            )
        table[name] = value
    return table


@dataclass(frozen=True)
class Option:
    """One option: what it is, its default, and how a value of it is checked.

    Parameters
    ----------
    name : str
        The field it sets (a :class:`~tt_mujoco.sim.Scenario` field, or a run's output option).
    default : object
        Its value when not given.
    help : str
        One line for ``--help`` and the docs.
    parse : callable
        ``parse(value, label) -> value``: a text (command line, sweep) or a TOML value checked
        and converted, or ``ValueError`` naming ``label``; a converted value passes unchanged.
    unit : str
        SI unit of a number ("" if none).
    flags : tuple of str
        The command-line spellings, the first shown (default ``--name`` with ``-`` for ``_``).
    form : str
        On the command line: "value" (``--x V``), "switch" (``--x`` / ``--no-x``), "repeat"
        (``--x V`` again and again, a list) or "table" (``--x NAME=VALUE``, repeatable).
    entry : str or None
        Of a table: the name of one entry in a flat key ``ENTRY.NAME`` (a sweep's ``param.Mr``).
    merge : bool
        Of a table: a later source (the command line over a file) adds entries key by key
        instead of replacing the table.
    file : bool
        The value names a file or a hook ``file.py:Name``: a relative one is resolved against
        the folder of the source that gave it.
    cli : bool
        Whether the command line has it.
    consts : tuple of (str, object)
        Extra flags that each set one value (``--no-disturbance`` is disturbance "none").
    metavar : str, callable or None
        The value's name in ``--help``; a callable gives it when the parser is built (the
        names a registry holds then, ``{ismc_sta,pid,...,HOOK}``).
    choices : tuple
        The allowed values, where they are a short list (for ``--help`` and hints).
    axis : bool
        Whether a sweep varies the whole option as one axis; a table of named entries (the
        vehicle's parameters) is swept entry by entry instead, as ``ENTRY.NAME``.
    needs : (str, callable) or None
        ``(other, acts)``: the option does something only where ``acts(value of other)``;
        a command line that gives both otherwise is refused
        (:func:`tt_mujoco.config.check_needs`).
    """

    name: str
    default: Any
    help: str
    parse: Callable[[Any, str], Any]
    unit: str = ""
    flags: tuple[str, ...] = ()
    form: str = "value"
    entry: str | None = None
    merge: bool = False
    file: bool = False
    cli: bool = True
    consts: tuple[tuple[str, Any], ...] = ()
    metavar: str | Callable[[], str] | None = None
    choices: tuple = ()
    axis: bool = True
    needs: tuple[str, Callable[[Any], bool]] | None = None

    def __post_init__(self):
        if self.form not in FORMS:
            raise ValueError(f"form={self.form!r} is not allowed: use one of {FORMS}")

    @property
    def cli_flags(self) -> tuple[str, ...]:
        """The command-line spellings of the option."""
        return self.flags or ("--" + self.name.replace("_", "-"),)

    @property
    def keys(self) -> tuple[str, ...]:
        """Its keys in a file or a mapping: the field name and every long flag, ``_`` for
        ``-``."""
        names = [self.name]
        for flag in (*self.cli_flags, *(f for f, _ in self.consts)):
            key = flag.removeprefix("--").replace("-", "_")
            if key not in names:
                names.append(key)
        return tuple(names)

    def default_value(self):
        """A fresh copy of the default (a table or list is never shared)."""
        return copy.deepcopy(self.default)


def option(default=None, parse=None, help="", *, default_factory=None, **details):
    """A dataclass field declared as an :class:`Option` (its name is the field's)."""
    declared = Option(
        name="",
        default=default_factory() if default_factory is not None else default,
        help=help,
        parse=parse,
        **details,
    )
    metadata = {"option": declared}
    if default_factory is not None:
        return dataclasses.field(default_factory=default_factory, metadata=metadata)
    return dataclasses.field(default=default, metadata=metadata)


# --- the schema --------------------------------------------------------------------------------
@dataclass(frozen=True)
class Schema:
    """A set of options, each found by its name or any of its keys."""

    options: tuple[Option, ...]

    @classmethod
    def of(cls, record) -> Schema:
        """The schema of a dataclass whose fields are declared with :func:`option`."""
        found = []
        for f in dataclasses.fields(record):
            declared = f.metadata.get("option")
            if declared is not None:
                found.append(dataclasses.replace(declared, name=f.name))
        return cls(tuple(found))

    def __add__(self, other: Schema) -> Schema:
        return Schema(self.options + other.options)

    def with_option(self, extra: Option) -> Schema:
        """This schema and one more option."""
        return Schema((*self.options, extra))

    def only(self, *names: str) -> Schema:
        """The options named, in this schema's order."""
        return Schema(tuple(o for o in self.options if o.name in names))

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(o.name for o in self.options)

    def __getitem__(self, name: str) -> Option:
        for o in self.options:
            if o.name == name:
                return o
        raise KeyError(name)

    def defaults(self) -> dict:
        """Every option's default (fresh copies)."""
        return {o.name: o.default_value() for o in self.options}

    def _key_map(self) -> dict[str, tuple[Option, Any]]:
        """Each accepted key: (its option, the const it stands for, or a marker)."""
        keys: dict[str, tuple[Option, Any]] = {}
        for o in self.options:
            for key in o.keys:
                keys.setdefault(key, (o, _PLAIN))
            if o.form == "switch":
                for flag in o.cli_flags:
                    keys.setdefault("no_" + flag.removeprefix("--").replace("-", "_"), (o, _NOT))
            for flag, const in o.consts:
                keys[flag.removeprefix("--").replace("-", "_")] = (o, const)
        return keys

    def key_names(self) -> list[str]:
        """Every accepted key, flat entries ``ENTRY.NAME`` shown as ``ENTRY.<name>``."""
        names = list(self._key_map())
        names += [f"{o.entry or o.name}.<name>" for o in self.options if o.entry]
        return names

    def unknown(self, key: str, where: str) -> ValueError:
        """The message for a key no option has, with the nearest one."""
        known = [k for k in self._key_map() if not k.startswith("no_")]
        close = closest(key, known)
        hint = f" (did you mean {close!r}?)" if close else ""
        return ValueError(
            f"{where}: unknown key {key!r}{hint}; allowed keys are {', '.join(sorted(known))}"
        )

    def entry_names(self, opt: Option) -> tuple[str, ...] | None:
        """The allowed entries of a table option, None where any name is allowed."""
        return getattr(opt.parse, "names", None)

    def entry_option(self, key: str) -> Option | None:
        """The table option of a flat key ``ENTRY.NAME`` (``param.Mr``, ``path_feedback.k_y``)."""
        prefix, dot, rest = key.partition(".")
        if not (dot and rest):
            return None
        for o in self.options:
            if o.entry and prefix in (o.entry, o.name):
                return o
        return None

    def values(
        self, given: Mapping, where: str, base: Path | None = None, *, typed: bool = True
    ) -> dict:
        """The checked values of ``given`` (a TOML table, a sweep's options, keyword
        arguments), by field name.

        Keys are field names or long flags (``noise_snr`` as ``noise_snr_db``; a switch's
        ``no_x = true`` is ``x = false``); a table's entries may also come as flat keys
        ``ENTRY.NAME``. Files are resolved against ``base``. ``typed``: the values come with
        their types (TOML, keyword arguments), so text where a number or true/false is wanted
        is refused (:func:`~tt_mujoco.schema_values.check_typed`); False for text (a sweep's
        command-line axes).

        Raises
        ------
        ValueError
            An unknown key (with the nearest), a key given twice, or a bad value; the
            message starts with ``where``.
        """
        keys = self._key_map()
        out: dict = {}
        seen: dict[str, str] = {}
        entries: dict[str, dict] = {}
        for raw_key, value in given.items():
            key = str(raw_key).replace("-", "_")
            if key not in keys:
                table_option = self.entry_option(key)
                if table_option is None:
                    raise self.unknown(str(raw_key), where)
                entries.setdefault(table_option.name, {})[key.partition(".")[2]] = value
                continue
            opt, const = keys[key]
            if opt.name in seen:
                raise ValueError(
                    f"{where + ': ' if where else ''}keys {seen[opt.name]!r} and {raw_key!r} "
                    "name the same option: keep one"
                )
            seen[opt.name] = str(raw_key)
            label = f"{where}: {raw_key}" if where else str(raw_key)
            if const is _PLAIN:
                parsed = opt.parse(value, label)
                if typed:
                    check_typed(value, parsed, label)
            else:
                on = boolean(value, label)
                if typed:
                    check_typed(value, on, label)
                if const is _NOT:  # ``no_video = true`` is ``--no-video``
                    parsed = opt.parse(not on, label)
                elif on:
                    parsed = const
                else:
                    raise refuse(label, value, f"use true (it means {opt.name} = {const!r})")
            if opt.file:
                parsed = resolve_file(parsed, base)
            out[opt.name] = parsed
        for name, found in entries.items():
            opt = self[name]
            label = f"{where}: {opt.entry or name}" if where else (opt.entry or name)
            current = out.get(name)
            if current is None or not isinstance(current, Mapping):
                if isinstance(current, str):  # a preset name, kept beside its entries
                    found = {"preset": current, **found}
                elif name in out and current is None:
                    raise ValueError(
                        f"{label}: {name}=off contradicts {', '.join(map(str, found))} set for it"
                    )
                current = {}
            parsed = opt.parse(found, label)
            if typed:
                check_typed(found, parsed, label)
            out[name] = {**current, **parsed}
        return out

    def merged(self, *layers: Mapping) -> dict:
        """Defaults, then each layer over the one before: tables with ``merge`` key by key,
        everything else replaced."""
        out = self.defaults()
        for layer in layers:
            for name, value in layer.items():
                opt = self[name]
                if opt.merge and isinstance(out.get(name), Mapping) and isinstance(value, Mapping):
                    out[name] = {**out[name], **value}
                else:
                    out[name] = value
        return out

    # --- the command line -------------------------------------------------------------------
    def add_arguments(self, group) -> None:
        """Add every option with ``cli`` to an argparse parser or group.

        Each option stores its parsed value under its field name and only when given (the
        default is ``argparse.SUPPRESS``): what the command line set is ``vars(namespace)``.
        """
        for opt in self.options:
            if not opt.cli:
                continue
            flags = opt.cli_flags
            shown_default = _shown_default(opt)
            metavar = opt.metavar() if callable(opt.metavar) else opt.metavar
            help_text = opt.help + (f" [{opt.unit}]" if opt.unit else "")
            help_text += f" (default: {shown_default})" if shown_default else ""
            common = dict(dest=opt.name, default=argparse.SUPPRESS, help=help_text)
            if opt.form == "switch":
                group.add_argument(*flags, action=_Switch, option=opt, **common)
            elif opt.form == "repeat":
                group.add_argument(
                    *flags,
                    action="append",
                    type=_cli_type(opt, lambda v, label: v),
                    metavar=metavar,
                    **common,
                )
            elif opt.form == "table":
                group.add_argument(
                    *flags,
                    action="append",
                    type=_entry_type(flags[0]),
                    metavar=metavar or "NAME=VALUE",
                    **common,
                )
            else:
                if metavar is None and opt.choices:
                    metavar = "{" + ",".join(map(str, opt.choices)) + "}"
                group.add_argument(
                    *flags,
                    type=_cli_type(opt, opt.parse),
                    metavar=metavar,
                    action=StoreOnce,
                    **common,
                )
            for flag, const in opt.consts:
                group.add_argument(
                    flag,
                    dest=opt.name,
                    action=StoreConstOnce,
                    const=const,
                    default=argparse.SUPPRESS,
                    help=f"same as {flags[0]} {const}",
                )

    def from_command_line(self, namespace: argparse.Namespace) -> dict:
        """The checked values the command line gave, by field name (files resolved against the
        current folder)."""
        given = {k: v for k, v in vars(namespace).items() if k in self.names}
        out = {}
        for name, value in given.items():
            opt = self[name]
            label = opt.cli_flags[0]
            if opt.form == "table":
                value = table_of(value, label)
            if opt.form in ("repeat", "table"):
                value = opt.parse(value, label)
            if opt.file:
                value = resolve_file(value, None)
            out[name] = value
        return out

    # --- the documentation -----------------------------------------------------------------
    def markdown_table(self) -> str:
        """Every option as a row of a Markdown table (the docs' options page)."""
        rows = [
            "| option | command line | default | unit | what it sets |",
            "|---|---|---|---|---|",
        ]
        for opt in self.options:
            name = f"`{opt.name}`"
            if opt.entry:
                name += f", `{opt.entry}.<name>`"
            if opt.cli:
                flags = [f"`{f}`" for f in opt.cli_flags]
                if opt.form == "switch":
                    flags = [f"`{f}`, `--no-{f[2:]}`" for f in opt.cli_flags]
                flags += [f"`{f}`" for f, _ in opt.consts]
                line = ", ".join(flags)
                line += " (repeatable)" if opt.form in ("repeat", "table") else ""
            else:
                line = "files, sweeps, Python"
            default = "" if opt.default in (None, [], {}) else f"`{_plain(opt.default)}`"
            text = opt.help.replace("|", "\\|")
            if opt.choices and opt.form == "value":
                text += ". One of " + ", ".join(f"`{c}`" for c in opt.choices) + "."
            rows.append(f"| {name} | {line} | {default} | {opt.unit} | {text} |")
        return "\n".join(rows) + "\n"

    # --- the file form ---------------------------------------------------------------------
    def file_form(self, values: Mapping) -> dict:
        """``values`` as TOML-ready keys (field names): None is left out where it is the
        default and written false where it switches a default table off."""
        out = {}
        for opt in self.options:
            if opt.name not in values:
                continue
            value = values[opt.name]
            if value is None:
                if opt.default is not None:
                    out[opt.name] = False
                continue
            out[opt.name] = _plain(value)
        return out


_PLAIN = object()
_NOT = object()


def _plain(value):
    if isinstance(value, Path):
        return str(value)
    if isinstance(value, float) and not math.isfinite(value):
        raise ValueError(f"cannot write {value!r} to TOML")
    if isinstance(value, Mapping):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    return value


def _shown_default(opt: Option) -> str:
    value = opt.default
    if opt.form == "switch":
        return "on" if value not in (None, False) else "off"
    if value is None or value in ([], {}) or isinstance(value, Mapping | list):
        return ""
    return f"{value:g}" if isinstance(value, float) else str(value)


def _cli_type(opt: Option, parse):
    def convert(text: str):
        try:
            return parse(text, opt.cli_flags[0])
        except ValueError as err:
            raise argparse.ArgumentTypeError(_without_label(str(err), opt.cli_flags[0])) from None

    convert.__name__ = opt.name  # argparse names the type in some messages
    return convert


def _without_label(message: str, flag: str) -> str:
    # argparse already starts with "argument --flag:"; keep the value as typed and the rule.
    head = f"{flag}="
    return message.removeprefix(head) if message.startswith(head) else message


def name_value(text: str, flag: str, example: str = "R=2") -> tuple[str, str]:
    """``(NAME, VALUE)`` of one ``NAME=VALUE`` item of a repeatable option (every command's:
    ``--param``, ``--path-option``, ``--columns``, ``--topics``, ...), both stripped.

    Raises
    ------
    ValueError
        No ``=``, or an empty name or value, naming the item and the form ``example`` shows.
    """
    name, sep, value = str(text).partition("=")
    name, value = name.strip(), value.strip()
    if not sep or not name or not value:
        raise ValueError(
            f"{flag} {shown(text)} is not allowed: write NAME=VALUE, e.g. {flag} {example}"
        )
    return name, value


def _entry_type(flag: str):
    def convert(text: str):
        try:
            name, value = name_value(text, flag)
        except ValueError as err:
            raise argparse.ArgumentTypeError(str(err).removeprefix(f"{flag} ")) from None
        number = number_text(value)
        return name, value if number is None else number

    return convert


class _Switch(argparse.BooleanOptionalAction):
    """``--x`` / ``--no-x``, storing what the option's parse makes of true or false."""

    def __init__(self, option_strings, dest, option: Option, **kwargs):
        self._option = option
        super().__init__(option_strings, dest, **kwargs)

    def __call__(self, parser, namespace, values, option_string=None):
        on = not option_string.startswith("--no-")
        set_once(parser, namespace, self.dest, option_string, self._option.parse(on, option_string))

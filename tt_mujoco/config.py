"""Scenario files: every option of ``python -m tt_mujoco.run`` from a TOML file.

A config file holds the run's options under their long names with ``_`` for ``-`` (``traj``,
``noise_snr``, ``control_dt``, ...; ``-`` is accepted too), plus three tables::

    traj = "s_curve"
    controller = "pid"
    noise_snr = 20.0
    video = false
    [params]            # Params overrides, as --param NAME=VALUE
    Mr = 7.5
    [gains]             # or gains = "paper_6_2"; as --gains
    k1_v = 12.0
    [[faults]]          # as --fault KIND:key=value,...  (see tt_mujoco.sim.faults)
    kind = "dropout"
    t = 2.0

Options given on the command line override the file (``params`` key by key; ``--fault``
replaces the file's faults). Relative CSV paths in a file are relative to the file's folder.
Unknown keys, wrong types and bad values are refused with the key and the file named.

``run`` writes the resolved options (file, command line and defaults) to ``config.toml`` in
its output folder, so ``--config RUN_DIR/config.toml`` repeats the run exactly. Not written:
``out`` (a repeat needs a new folder), ``config``, and how the run was watched (``viewer``,
``quiet``).
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import tomllib
from pathlib import Path

import tomli_w

from tt_mujoco.registry import closest, existing_file, normalise_hook, shown
from tt_mujoco.sim.faults import parse_fault
from tt_mujoco.vehicle.params import Params

__all__ = [
    "CONFIG_FILE",
    "FileOptions",
    "dump_config",
    "load_config",
    "options_from_file",
    "resolved_options",
]

CONFIG_FILE = "config.toml"
#: Options that are never read from a file: the file itself, where outputs go, and the
#: repeatable command-line forms of the [params] and [[faults]] tables.
NOT_READ = ("config", "out", "help", "param", "fault", "path_option")
#: Options read from a file but not written to a run's config.toml: how a run is watched.
NOT_WRITTEN = ("viewer", "quiet")
#: Tables handled here rather than by one argparse option.
TABLES = ("params", "faults", "gains", "path_options")


@dataclasses.dataclass
class FileOptions:
    """What a config file sets: argparse defaults, Params overrides and fault specs."""

    defaults: dict
    params: dict
    faults: list | None


def load_config(path) -> dict:
    """Read a TOML file into a dict.

    Raises
    ------
    ValueError
        The file is missing, unreadable or not valid TOML (the message has the line).
    """
    file = existing_file(path, "config file")
    try:
        with file.open("rb") as handle:
            return tomllib.load(handle)
    except tomllib.TOMLDecodeError as err:
        raise ValueError(f"config file {str(path)!r} is not valid TOML: {err}") from None
    except RecursionError:
        raise ValueError(
            f"config file {str(path)!r} is nested too deeply: a scenario file is flat keys and "
            "a few tables"
        ) from None
    except (OSError, UnicodeDecodeError) as err:
        raise ValueError(f"config file {str(path)!r} cannot be read: {err}") from None


def _actions(parser: argparse.ArgumentParser) -> dict[str, argparse.Action]:
    return {
        a.dest: a
        for a in parser._actions  # argparse has no public accessor for its options
        if a.dest not in NOT_READ and a.dest != argparse.SUPPRESS
    }


def _is_flag(action: argparse.Action) -> bool:
    return action.nargs == 0  # store_true/false, BooleanOptionalAction


def _convert(key: str, value, action: argparse.Action, where: str):
    """A file value for ``action``, through the same checks as the command line."""
    if _is_flag(action):
        if not isinstance(value, bool):
            raise ValueError(f"{where}: {key}={value!r} is not allowed: use true or false")
        return value
    if isinstance(value, bool) or not isinstance(value, str | int | float):
        raise ValueError(
            f"{where}: {key}={value!r} is not allowed: give a string or a number, as on the "
            f"command line ({'/'.join(action.option_strings)})"
        )
    text = value if isinstance(value, str) else repr(value)
    if action.type is not None:
        try:
            converted = action.type(text)
        except (argparse.ArgumentTypeError, ValueError, TypeError) as err:
            raise ValueError(f"{where}: {key}={shown(value)} is not allowed: {err}") from None
    else:
        converted = text
    if action.choices is not None and converted not in action.choices:
        raise ValueError(
            f"{where}: {key}={value!r} is not allowed: use one of "
            f"{', '.join(repr(c) for c in action.choices)}"
        )
    return converted


def _unknown_key(key: str, known, where: str) -> ValueError:
    close = closest(key, known)
    hint = f" (did you mean {close!r}?)" if close else ""
    return ValueError(
        f"{where}: unknown key {key!r}{hint}; allowed keys are {', '.join(sorted(known))}"
    )


def _relative_hook(spec: str, source) -> str:
    """A ``file.py:Name`` hook in a config file is relative to the file's folder."""
    return normalise_hook(spec, Path(source).parent.absolute())


def options_from_file(
    table: dict, parser: argparse.ArgumentParser, source, param_names
) -> FileOptions:
    """Check a loaded config table against ``parser``'s options.

    Parameters
    ----------
    table : dict
        From :func:`load_config`.
    parser : argparse.ArgumentParser
        The ``run`` parser: its option names, types and choices are the allowed keys.
    source : str or Path
        The file, for messages and for resolving relative CSV paths.
    param_names : iterable of str
        Allowed keys of the ``[params]`` table.

    Raises
    ------
    ValueError
        Unknown key, wrong type or bad value; the message names the key and the file.
    """
    where = f"config file {str(source)!r}"
    actions = _actions(parser)
    known = set(actions) | set(TABLES)
    defaults, params, faults = {}, {}, None
    # Every long option name is a key (``noise_snr`` and ``noise_snr_db`` both name the option
    # whose destination is ``noise_snr_db``); giving one option twice is refused. A flag's
    # negative form means what it says on the command line: ``no_video = true`` is
    # ``--no-video``, i.e. ``video = false``.
    aliases = {
        opt[2:].replace("-", "_"): a.dest
        for a in actions.values()
        for opt in a.option_strings
        if opt.startswith("--")
    }
    negative = {
        opt[2:].replace("-", "_")
        for a in actions.values()
        if isinstance(a, argparse.BooleanOptionalAction)
        for opt in a.option_strings
        if opt.startswith("--no-")
    }
    seen: dict[str, str] = {}
    for raw_key, value in table.items():
        key = raw_key.replace("-", "_")
        negated = key in negative
        key = aliases.get(key, key)
        if key in seen:
            raise ValueError(
                f"{where}: keys {seen[key]!r} and {raw_key!r} name the same option: keep one"
            )
        seen[key] = raw_key
        if key in NOT_READ:
            raise ValueError(
                f"{where}: key {raw_key!r} is not allowed in a config file: "
                + (
                    "use the [params] table or [[faults]] array instead"
                    if key in ("param", "fault")
                    else f"give --{key} on the command line"
                )
            )
        if key not in known:
            raise _unknown_key(raw_key, known, where)
        if key == "params":
            if not isinstance(value, dict):
                raise ValueError(f"{where}: params must be a table [params] of NAME = number")
            allowed = set(param_names)
            for name, number in value.items():
                if name not in allowed:
                    raise _unknown_key(name, allowed, f"{where} [params]")
                if isinstance(number, bool) or not isinstance(number, int | float):
                    raise ValueError(
                        f"{where} [params]: {name}={number!r} is not allowed: it must be a number"
                    )
                params[name] = number
            try:
                Params(**params)  # the same checks as --param, with the file named
            except ValueError as err:
                raise ValueError(f"{where} [params]: {err}") from None
        elif key == "faults":
            if not isinstance(value, list) or not all(isinstance(f, dict) for f in value):
                raise ValueError(
                    f"{where}: faults must be an array of tables [[faults]] with kind, t, ..."
                )
            try:
                faults = [parse_fault(f).to_dict() for f in value]
            except ValueError as err:
                raise ValueError(f"{where}: {err}") from None
        elif key == "path_options":
            if not isinstance(value, dict) or not all(
                isinstance(v, str | int | float) and not isinstance(v, bool) for v in value.values()
            ):
                raise ValueError(
                    f"{where}: path_options must be a table [path_options] of NAME = value"
                )
            defaults["path_option"] = [
                (k, float(v) if not isinstance(v, str) else v) for k, v in value.items()
            ]
        elif key == "metric":
            items = value if isinstance(value, list) else [value]
            if not all(isinstance(m, str) and m.strip() for m in items):
                raise ValueError(f"{where}: metric={value!r} is not allowed: give hook names")
            defaults["metric"] = [_relative_hook(m, source) for m in items]
        elif key == "trailers" and isinstance(value, list):
            if not all(isinstance(t, dict) for t in value):
                raise ValueError(
                    f"{where}: trailers must be a number or an array of tables [[trailers]], "
                    "one per trailer behind the first"
                )
            try:
                Params(**params).with_trailers(len(value) + 1, value)
            except ValueError as err:
                raise ValueError(f"{where} [[trailers]]: {err}") from None
            defaults["trailers"] = len(value) + 1
            defaults["train"] = [dict(t) for t in value]
        elif key == "gains":
            if not isinstance(value, str | dict):
                raise ValueError(
                    f"{where}: gains={value!r} is not allowed: give a preset name or a table"
                )
            defaults["gains"] = value
        else:
            converted = _convert(key, value, actions[key], where)
            if negated:
                converted = not converted
            if key == "traj" and converted.lower().endswith(".csv"):
                csv = Path(converted)
                if not csv.is_absolute():
                    csv = (Path(source).parent / csv).absolute()
                converted = str(csv)
            elif key in ("traj", "controller", "disturbance_model"):
                converted = _relative_hook(converted, source)
            defaults[key] = converted
    return FileOptions(defaults=defaults, params=params, faults=faults)


def _plain(value):
    if isinstance(value, Path):
        return str(value)
    if isinstance(value, float) and not math.isfinite(value):
        raise ValueError(f"cannot write {value!r} to TOML")
    return value


def resolved_options(args: argparse.Namespace, parser, params: dict, faults: list) -> dict:
    """The options a run actually used, in file form (see the module docstring).

    Options left at None (``duration``, ``noise_snr``, ``gains``) are left out: absent means
    the same default. A CSV path is made absolute so the file works from any folder.
    """
    out = {}
    for dest in _actions(parser):
        if dest in NOT_WRITTEN:
            continue
        value = getattr(args, dest, None)
        if value is None:
            continue
        if dest == "traj" and str(value).lower().endswith(".csv"):
            value = str(Path(value).absolute())
        elif dest in ("traj", "controller", "disturbance_model"):
            value = normalise_hook(value)
        elif dest == "metric":
            value = [normalise_hook(m) for m in value]
        out[dest] = _plain(value)
    if getattr(args, "path_option", None):
        out["path_options"] = {k: _plain(v) for k, v in args.path_option}
    if params:
        out["params"] = {k: _plain(v) for k, v in params.items()}
    train = getattr(args, "train", None)
    if train:
        # The array form: one table per trailer behind the first (empty: a copy of trailer 1).
        tables = [dict(t) for t in train] + [{}] * (args.trailers - 1 - len(train))
        out["trailers"] = [{k: _plain(v) for k, v in t.items()} for t in tables]
    if faults:
        out["faults"] = [{k: _plain(v) for k, v in f.items()} for f in faults]
    return out


def dump_config(options: dict) -> str:
    """TOML text of ``options`` with a header saying how to repeat the run."""
    header = (
        "# Resolved options of a tt_mujoco run (config file, command line and defaults).\n"
        "# Repeat it with: python -m tt_mujoco.run --config THIS_FILE [--out NEW_DIR]\n"
    )
    plain = {k: v for k, v in options.items() if not isinstance(v, dict | list)}
    tables = {k: v for k, v in options.items() if isinstance(v, dict | list)}
    return header + tomli_w.dumps(plain) + ("\n" + tomli_w.dumps(tables) if tables else "")

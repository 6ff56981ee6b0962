"""Scenario files: every option of ``python -m tt_mujoco.run`` from a TOML file.

A config file holds a run's options by the names of the :class:`~tt_mujoco.sim.Scenario`'s
fields or of the command line's long options, ``_`` for ``-`` (``traj``, ``noise_snr`` or
``noise_snr_db``, ``control_dt``, ...; ``-`` is accepted too), plus tables::

    traj = "s_curve"
    controller = "pid"
    noise_snr = 20.0
    video = false
    [params]            # Params overrides, as --param NAME=VALUE
    Mr = 7.5
    [gains]             # or gains = "paper_6_2"; as --gains
    k1_v = 12.0
    [[faults]]          # as --fault KIND:key=value,...  (see tt_mujoco.sim.parts.faults)
    kind = "dropout"
    t = 2.0

The keys and their checks are the option schema's (:mod:`tt_mujoco.schema`), the same as the
command line's and a sweep's. Options given on the command line override the file (``params``
key by key; ``--fault`` replaces the file's faults). Relative CSV and hook files in a file are
relative to the file's folder. Unknown keys, wrong types and bad values are refused with the
key and the file named.

``run`` writes the resolved options (file, command line and defaults) to ``config.toml`` in its
output folder, by field name, so ``--config RUN_DIR/config.toml`` repeats the run exactly. Not
written: ``out`` (a repeat needs a new folder), ``config``, and how the run was watched
(``viewer``, ``quiet``).
"""

from __future__ import annotations

from pathlib import Path

import tomli_w

from tt_mujoco.cliargs import BadInputError
from tt_mujoco.outputs import read_toml
from tt_mujoco.registry import existing_file
from tt_mujoco.schema import Schema

__all__ = ["CONFIG_FILE", "dump_config", "load_config", "read_options"]

CONFIG_FILE = "config.toml"
#: Keys that are never read from a file: the file itself and where outputs go.
NOT_READ = ("config", "out", "help")


def load_config(path) -> dict:
    """Read a TOML file into a dict.

    Raises
    ------
    ValueError
        The file is missing, unreadable or not valid TOML (the message has the line).
    """
    existing_file(path, "config file")
    return read_toml(path, "config file")


def read_options(table: dict, source, schema: Schema) -> dict:
    """The checked values of a loaded config table, by field name.

    Parameters
    ----------
    table : dict
        From :func:`load_config`.
    source : str or Path
        The file: named in messages; relative files in it are relative to its folder.
    schema : tt_mujoco.schema.Schema
        The options allowed (``tt_mujoco.run.RUN_SCHEMA``: the scenario's and the outputs').

    Raises
    ------
    ValueError
        Unknown key (with the nearest), wrong type or bad value; the message names the key and
        the file.
    """
    where = f"config file {str(source)!r}"
    for key in table:
        if str(key).replace("-", "_") in NOT_READ:
            raise ValueError(
                f"{where}: key {key!r} is not allowed in a config file: give --{key} on the "
                "command line"
            )
    return schema.values(table, where, base=Path(source).parent.absolute())


def dump_config(options: dict) -> str:
    """TOML text of ``options`` with a header saying how to repeat the run."""
    header = (
        "# Resolved options of a tt_mujoco run (config file, command line and defaults).\n"
        "# Repeat it with: python -m tt_mujoco.run --config THIS_FILE [--out NEW_DIR]\n"
    )
    plain = {k: v for k, v in options.items() if not isinstance(v, dict | list)}
    tables = {k: v for k, v in options.items() if isinstance(v, dict | list)}
    return header + tomli_w.dumps(plain) + ("\n" + tomli_w.dumps(tables) if tables else "")


def check_needs(schema: Schema, given: dict, values: dict, where: str) -> None:
    """Refuse a command line (``where``) that gives an option and, with it, another option's
    value under which the first does nothing (:attr:`~tt_mujoco.schema.Option.needs`:
    ``--no-disturbance --disturbance-model x`` would run no disturbance, the model unused);
    ``values`` are the resolved options. A command line that changes a file's option is an
    override, not a conflict; and a file may hold an option that does nothing (the
    ``config.toml`` a run writes holds every option), so files are not checked."""
    for opt in schema.options:
        if opt.needs is None or opt.name not in given:
            continue
        other, acts = opt.needs
        if other in given and not acts(values[other]):
            raise BadInputError(
                f"{where} gives {_as_given(opt, given[opt.name])} and "
                f"{_as_given(schema[other], values[other])}, under which it does nothing: "
                "drop one of them"
            )


def _as_given(opt, value) -> str:
    """``value`` of ``opt`` as a command line spells it (a switch by its flag)."""
    flag = opt.cli_flags[0]
    if opt.form == "switch":
        return flag if value not in (None, False) else "--no-" + flag.removeprefix("--")
    return f"{flag} {value!r}"

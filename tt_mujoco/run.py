"""``python -m tt_mujoco.run``: one closed-loop run, with metrics, time series, plots and video.

Exit codes (docs/model.md Section 11): 0 done; 2 bad input (one message, no traceback, nothing
written); 3 the run diverged, jackknifed or hit an obstacle (the message gives the time and
state; everything computed up to then is still written); 70 a bug of ours (one line naming the
file its traceback went to: :func:`tt_mujoco.guard.command`); 130 interrupted (Ctrl-C, or the
live viewer closed): files already written are complete, and ``metrics.json``, written last,
is absent.

Options can come from a TOML file (``--config FILE``, see :mod:`tt_mujoco.config`); the
command line overrides it, and every run writes its resolved options to ``config.toml`` so
that ``--config RUN_DIR/config.toml`` repeats it exactly. ``--viewer`` shows the run live in
MuJoCo's passive viewer (:mod:`tt_mujoco.viz.viewer`).

Outputs are written atomically (a temporary file, then a rename) into a new folder, never an
existing non-empty one; ``metrics.json`` is written last, so its presence marks a complete run.
"""

from __future__ import annotations

import argparse
import functools
import sys
import time
from pathlib import Path
from typing import NamedTuple

from tt_mujoco import config as config_mod
from tt_mujoco import guard, sim, watchdog
from tt_mujoco.analysis.metrics import DEFAULT_SUMMARY_KEYS, metric_name, summary_table
from tt_mujoco.cliargs import BadInputError, Parser
from tt_mujoco.controllers import controller_class
from tt_mujoco.defaults import (
    CONTROLLER,
    EXIT_BAD_INPUT,
    EXIT_DIVERGED,
    EXIT_INTERRUPTED,
    EXIT_OK,
)
from tt_mujoco.outputs import claim_folder, release_folder
from tt_mujoco.progress import progress_bar
from tt_mujoco.run_endings import (
    abandon,
    best_candidate_drawn,
    exited_early,
    fail,
    hung,
    interrupted,
    killed,
    rows_unwritable,
)
from tt_mujoco.run_outputs import (
    CHECKPOINT_FILE,
    OUTPUTS,
    figure_rows,
    figure_worker,
    write_outputs,
)
from tt_mujoco.schema import Schema
from tt_mujoco.sim import SCHEMA, Scenario

__all__ = [
    "OUTPUTS",
    "RUN_SCHEMA",
    "Invocation",
    "build_parser",
    "main",
    "options_from_argv",
    "write_outputs",
]

RENDERS = Path("renders")
#: Output options read from a file but not written to a run's config.toml: how it was watched.
NOT_WRITTEN = ("quiet", "viewer", "live", "live_realtime")
#: Every option of the command: the scenario's and the outputs'.
RUN_SCHEMA = SCHEMA + OUTPUTS
#: Whether the simulation runs in a watched child (:mod:`tt_mujoco.watchdog`): only when this
#: module is the command (``python -m tt_mujoco.run``), never when ``main`` is called from
#: Python, whose process is the caller's.
WATCHED = False


def build_parser(schema: Schema | None = None) -> argparse.ArgumentParser:
    """The command's parser: ``--config``, the options of ``schema`` (default
    :data:`RUN_SCHEMA`: the scenario's, then the outputs'), and ``--out``."""
    schema = RUN_SCHEMA if schema is None else schema
    p = Parser(
        prog="python -m tt_mujoco.run",
        description=(
            "Run one closed-loop tracking scenario of the off-axle tractor-trailer on the MuJoCo "
            "plant or the analytic reduced model, and write metrics.json, timeseries.parquet, "
            "config.toml, plots and a video into a new folder."
        ),
    )
    p.add_argument(
        "--config",
        type=Path,
        default=None,
        metavar="FILE",
        help="read options from this TOML file (e.g. a previous run's config.toml); "
        "options given here override it",
    )
    outputs = Schema(tuple(o for o in schema.options if o.name in OUTPUTS.names))
    scenario = Schema(tuple(o for o in schema.options if o.name not in OUTPUTS.names))
    scenario.add_arguments(p.add_argument_group("scenario"))
    o = p.add_argument_group("outputs")
    o.add_argument(
        "--out",
        type=Path,
        default=None,
        metavar="DIR",
        help="output folder (must not exist or be empty); default: a new folder under renders/",
    )
    outputs.add_arguments(o)
    return p


def usage(width: int = 100) -> str:
    """The command's usage as ``--help`` prints it at ``width`` columns: the synopsis
    docs/getting-started.md shows (``tests/test_docs.py`` keeps it the parser's)."""
    parser = build_parser()
    parser.formatter_class = functools.partial(argparse.HelpFormatter, width=width)
    return parser.format_usage()


class Invocation(NamedTuple):
    """What a command line (with its ``--config`` file) asks for."""

    scenario: Scenario
    #: The output options (:data:`OUTPUTS`), by name.
    outputs: dict
    #: ``--out`` and ``--config``.
    args: argparse.Namespace

    def file_form(self) -> dict:
        """The resolved options in file form: what ``config.toml`` holds."""
        written = {k: v for k, v in self.outputs.items() if k not in NOT_WRITTEN}
        return RUN_SCHEMA.file_form({**self.scenario.to_dict(), **written})


def options_from_argv(argv, schema: Schema | None = None) -> dict:
    """Every option's value a command line stands for: the command line over its ``--config``
    file over the defaults, by field name, with ``config`` and ``out`` besides.

    Raises
    ------
    tt_mujoco.cliargs.BadInputError
        A bad option (the message names it).
    ValueError
        A bad config file (the message names the file and the key).
    """
    schema = RUN_SCHEMA if schema is None else schema
    args = build_parser(schema).parse_args(argv)
    given = schema.from_command_line(args)
    from_file = {}
    if args.config is not None:
        from_file = config_mod.read_options(
            config_mod.load_config(args.config), args.config, schema
        )
        if "gains" in from_file and "gains" not in given:
            controller = given.get("controller", from_file.get("controller", CONTROLLER))
            _check_gains(controller, from_file["gains"], f"config file {str(args.config)!r}")
    merged = schema.merged(from_file, given)
    config_mod.check_needs(schema, given, merged, "the command line")
    return {**merged, "config": args.config, "out": args.out}


def _parse(argv) -> Invocation:
    """Command line over config file over defaults, through :data:`RUN_SCHEMA`."""
    values = options_from_argv(argv)
    scenario = Scenario(**{name: values[name] for name in SCHEMA.names})
    args = argparse.Namespace(config=values["config"], out=values["out"])
    return Invocation(scenario, {name: values[name] for name in OUTPUTS.names}, args)


def scenario_from_argv(argv) -> Scenario:
    """The :class:`~tt_mujoco.sim.Scenario` a command line (``--config FILE`` included) stands
    for, as ``python -m tt_mujoco.run`` builds it.

    Raises
    ------
    tt_mujoco.cliargs.BadInputError
        A bad option or config file (the message names it).
    """
    return _parse(list(argv)).scenario


def _check_gains(controller: str, gains, where: str) -> None:
    """Gains from a file are checked against the controller now, so the message names the file."""
    try:
        controller_class(controller).resolve_gains(gains)
    except ValueError as err:
        raise BadInputError(f"{where} [gains]: {err}") from None


def _output_dir(out: Path | None, scenario: Scenario) -> tuple[Path, bool]:
    """A new folder named after the run, or the user's ``--out`` if new or empty."""
    stem = Path(scenario.traj.rpartition(":")[0] or scenario.traj).stem
    base = RENDERS / (
        f"{stem}-{Path(scenario.controller.rpartition(':')[2]).stem}-{scenario.target}-"
        f"{scenario.plant}-{time.strftime('%Y%m%d-%H%M%S')}"
    )
    return claim_folder(out, base)


def _progress_bar(total_label: str, quiet: bool):
    if quiet:
        return None, None

    bar = progress_bar(100, total_label, "%")

    def update(done: int, total: int) -> None:
        pct = int(100 * done / max(total, 1))
        if pct > bar.n:
            bar.update(pct - bar.n)

    return update, bar


@guard.command
def main(argv: list[str] | None = None) -> int:
    # Ctrl-C and a batch system's SIGTERM reach it as the same clean exit, told from a
    # KeyboardInterrupt a user's code raises itself (tt_mujoco.guard.command installs them)
    try:
        return _main(argv)
    except KeyboardInterrupt:  # before a folder exists (start-up); later ones are handled inside
        return fail("interrupted: nothing was written", EXIT_INTERRUPTED)


class _RunSetup(NamedTuple):
    """What the command has checked and made before its run: the build, the output options,
    the folder's ``config.toml``, the live view (if any) and the claimed folder."""

    built: object
    shown: dict
    config_toml: str
    live: object
    out: Path
    created: bool


def _main(argv: list[str] | None) -> int:
    try:
        invocation = _parse(argv)  # --help ends here: the simulation is not imported for it
    except (BadInputError, ValueError) as err:
        return fail(str(err))
    except OSError as err:  # a name the file system refuses (too long, not encodable, ...)
        return _file_system_refused(err)
    # Forked before anything else starts (no thread yet): matplotlib loads meanwhile.
    figures = figure_worker(invocation.scenario, invocation.outputs)
    setup = None
    try:
        setup = _set_up(invocation)
    finally:
        if figures is not None and not isinstance(setup, _RunSetup):
            figures.cancel()  # refused, or interrupted: nothing to draw
    if isinstance(setup, int):
        return setup
    if WATCHED and setup.live is None:  # from here on, the run in a watched child
        out, limit = setup.out, setup.built.wall_limit
        controller = setup.built.scenario.controller
        watchdog.supervise(
            limit,
            lambda traceback, interrupt: hung(out, limit, controller, traceback, interrupt),
            lambda signum: killed(out, signum),
            lambda code: exited_early(out, code),
        )
    result = _simulate(setup, figures)
    if isinstance(result, int):
        return result
    return _write(setup, result, figures)


def _set_up(invocation: Invocation) -> _RunSetup | int:
    """Everything simulate checks, before an output folder exists (simulate reuses the
    build), then the live view and the folder; an exit code for what is refused."""
    from tt_mujoco.sim.simulate import checked_build
    from tt_mujoco.vehicle import reduced
    from tt_mujoco.viz import viewer as viewer_mod

    try:
        scenario, shown = invocation.scenario, invocation.outputs
        if shown["mcap"]:
            _check_mcap()
        built = checked_build(scenario)
        config_toml = config_mod.dump_config(invocation.file_form())
        live = _live_view(built, shown)
        try:
            out, created = _output_dir(invocation.args.out, scenario)
        except BaseException:
            if live is not None:  # no run: no server left listening
                live.close()
            raise
    except (BadInputError, ValueError, reduced.SingularityError) as err:  # OutputError too
        return fail(str(err) + best_candidate_drawn(err, invocation.outputs["plots"]))
    except OSError as err:  # a name the file system refuses (too long, not encodable, ...)
        return _file_system_refused(err)
    except viewer_mod.ViewerUnavailable as err:
        return fail(str(err))
    return _RunSetup(built, shown, config_toml, live, out, created)


def _live_view(built, shown: dict):
    """MuJoCo's viewer (``--viewer``), the Foxglove server (``--live``), or None."""
    from tt_mujoco.viz import viewer as viewer_mod

    scenario = built.scenario
    if shown["viewer"]:
        if shown["live"]:
            raise BadInputError("--live and --viewer are not allowed together: choose one")
        if scenario.plant != "mujoco":
            raise BadInputError(
                f"--viewer shows the MuJoCo plant; --plant {scenario.plant!r} has no "
                "MuJoCo model to show (use --plant mujoco)"
            )
        viewer_mod.check_display()
        return viewer_mod.LiveViewer(reference=built.path.dense())
    if not shown["live"]:
        return None
    from tt_mujoco.viz.foxglove_live import FoxgloveLive, LiveError

    try:
        live = FoxgloveLive(
            built.plant_params,
            built.path.dense(),
            built.world,
            port=shown["live"],
            realtime=shown["live_realtime"],
        )
    except LiveError as err:
        raise BadInputError(str(err)) from None
    if not shown["quiet"]:
        print(f"live: Foxglove, connect to ws://localhost:{live.port}", file=sys.stderr)
    return live


def _simulate(setup: _RunSetup, figures):
    """The run, handed as it ends to ``figures`` (its figures' worker, or None); or the exit
    code of a run that produced no result."""
    from tt_mujoco.vehicle import reduced
    from tt_mujoco.viz import viewer as viewer_mod

    built, shown, live, out, created = (
        setup.built,
        setup.shown,
        setup.live,
        setup.out,
        setup.created,
    )
    # The figures' worker draws while the metrics are computed and the files written.
    on_rows = None if figures is None else figure_rows(figures, built)
    update, bar = _progress_bar("simulating", shown["quiet"] or shown["viewer"])
    try:
        # Rows reach the disk every 8192 steps while the run goes on: a killed run keeps them.
        checkpoint = out / CHECKPOINT_FILE
        try:
            result = sim.simulate(
                built, progress=update, on_step=live, checkpoint=checkpoint, on_rows=on_rows
            )
        except BaseException:
            if figures is not None:  # no figures to draw: the worker ends
                figures.cancel()
            raise
    except (BadInputError, ValueError, reduced.SingularityError) as err:
        return abandon(out, created, live, str(err), EXIT_BAD_INPUT)
    except viewer_mod.ViewerUnavailable as err:
        return abandon(out, created, live, str(err), EXIT_BAD_INPUT)
    except viewer_mod.ViewerClosed as err:
        return abandon(out, created, live, f"{err}: run abandoned", EXIT_INTERRUPTED)
    except KeyboardInterrupt:
        return interrupted(out, created, live)
    except OSError as err:  # the rows on their way to the disk: a full disk, a quota
        return rows_unwritable(out, created, live, err)
    finally:
        watchdog.disarm()  # the outputs that follow are not the simulation's time
        if bar is not None:
            bar.close()
    return result


def _write(setup: _RunSetup, result, figures) -> int:
    """The run's folder written, its summary printed; the command's exit code."""
    out, live = setup.out, setup.live
    try:
        written, notes = write_outputs(result, out, setup.shown, setup.config_toml, figures)
    except (OSError, KeyboardInterrupt) as err:  # a full disk, a quota, a vanished folder
        if live is not None:
            live.close()
        release_folder(out)  # the missing metrics.json labels the folder incomplete
        if isinstance(err, KeyboardInterrupt):
            return fail(
                f"interrupted while writing outputs: the files in {out}/ are complete, but "
                "metrics.json was not written, so the run's outputs are incomplete",
                EXIT_INTERRUPTED,
            )
        return fail(
            f"the outputs cannot be written to {out}/: {err.strerror}; the files there are "
            "complete, but metrics.json is missing, so the run's outputs are incomplete",
            EXIT_BAD_INPUT,
        )
    release_folder(out)  # complete: metrics.json is written
    _print_summary(result, out, written, notes)
    if live is not None:
        live.wait_closed()
    if not result.ok:
        return fail(f"the run stopped: {result.message}", EXIT_DIVERGED)
    return EXIT_OK


def _check_mcap() -> None:
    """``--mcap`` needs the mcap extra: said before the run, not after it."""
    from importlib.util import find_spec

    if find_spec("mcap_ros2") is None:
        raise BadInputError(
            "mcap=True needs the mcap extra to write run.mcap: pip install 'tt-mujoco[mcap]'"
        )


def _file_system_refused(err: OSError) -> int:
    name = str(err.filename or "")
    shown = name if len(name) <= 80 else name[:77] + "..."
    return fail(f"{shown!r}: {err.strerror}")


def steering_shown(s: Scenario) -> str:
    """The trailers' steering as ``config.toml`` names it, with the gains it gives:
    ``eta=same_path (-0.142857)``, ``eta=path schedule``, ``3 trailers, eta=paper (3, 3, 3)``."""
    kind = s.eta_schedule_kind
    if kind is not None:
        shown = f"eta={kind} schedule"
    else:
        etas = s.nominal_params().etas
        gains = ", ".join(f"{e:.6g}" for e in etas)
        shown = f"eta={s.eta} ({gains})" if isinstance(s.eta, str) else f"eta={gains}"
    n = s.plant_params().n_trailers
    return shown if n == 1 else f"{n} trailers, {shown}"


def _print_summary(result, out: Path, written, notes) -> None:

    from tt_mujoco.sim.parts import faults

    s = result.scenario
    print(
        f"{s.traj} | {s.controller} | {s.target} target | {s.plant} plant | {steering_shown(s)}"
        f" | disturbance={s.disturbance}"
        + ("" if s.terrain == "flat" else f" | terrain={s.terrain}")
        + (f" | backing up: {result.metrics['reversing']}" if s.reverse else "")
        + f" | status={result.status}"
    )
    # A train adds its worst trailer, and every trailer's off-tracking.
    train = [k for k in result.metrics if k.startswith("trailer_") and k[8].isdigit()]
    train = [k for k in train if k.endswith("offtrack_rms")]
    train += ["train_offtrack_rms_worst", "train_phi_max_abs_deg"]
    extra = [*train, *(metric_name(spec) for spec in s.metrics)]
    keys = [k for k in (*DEFAULT_SUMMARY_KEYS, *extra, "wall_time_s") if k in result.metrics]
    print(summary_table(result.metrics, keys=keys))
    for fault in result.metrics.get("faults", []):
        w = fault["window"]
        where = f"s={fault['s']:g} m" if "s" in fault else f"t={fault['t']:g} s"
        if w is None:
            print(
                f"fault {fault['kind']} at {where}: not reached, the run stopped at "
                f"t={result.metrics['sim_time_s']:.3f} s ({result.status})"
            )
            continue
        if "t_acted" in fault:
            where += f" (t={fault['t_acted']:.3f} s)"
        print(
            f"fault {fault['kind']} at {where}, until {faults.RECOVERY_S:g} s after its end: "
            f"max|e_v| {w['max_abs_v']:.4g} m/s, max|e_omega| {w['max_abs_omega']:.4g} rad/s, "
            f"max lateral {w['max_lateral']:.4g} m"
        )
    for note in notes:
        print(f"note: {note}")
    print(f"wrote {len(written)} files to {out}/")


if __name__ == "__main__":
    WATCHED = watchdog.available()  # the command itself: its run goes on in a watched child
    guard.end(main())

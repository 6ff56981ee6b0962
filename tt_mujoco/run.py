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
import shutil
import signal
import sys
import tempfile
import time
from collections.abc import Mapping
from pathlib import Path
from typing import NamedTuple

from tt_mujoco import config as config_mod
from tt_mujoco import guard, sim, watchdog
from tt_mujoco.analysis.metrics import DEFAULT_SUMMARY_KEYS, metric_name, summary_table
from tt_mujoco.cliargs import BadInputError, Parser
from tt_mujoco.config import CONFIG_FILE
from tt_mujoco.controllers import controller_class
from tt_mujoco.defaults import (
    CAMERAS,
    CONTROLLER,
    EXIT_BAD_INPUT,
    EXIT_BUG,
    EXIT_DIVERGED,
    EXIT_INTERRUPTED,
    EXIT_OK,
)
from tt_mujoco.outputs import (
    REFERENCE_FILE,
    atomic_write,
    claim_folder,
    publish_new,
    release_folder,
    remove_if_empty,
    write_json,
    write_timeseries,
)
from tt_mujoco.progress import progress_bar
from tt_mujoco.schema import Option, Schema, boolean, choice, number
from tt_mujoco.sim import COLUMNS, SCHEMA, Scenario
from tt_mujoco.sim.loop.timeseries import UNITS, train_columns, unit_of

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
#: Prefix of the hidden folder, private to one run, where figures and video are made before
#: they are moved into the output folder.
STAGING = ".partial-"
#: Formats of the time-series file (``timeseries.<format>``).
TIMESERIES_FORMATS = ("parquet", "csv")
#: The command's options besides the scenario: what it writes and how the run is watched.
OUTPUTS = Schema(
    (
        Option("video", True, "write video.mp4", boolean, form="switch"),
        Option("plots", True, "write PNG figures", boolean, form="switch"),
        Option(
            "camera",
            "follow",
            "video camera",
            choice(*CAMERAS),
            choices=CAMERAS,
        ),
        Option("fps", 30.0, "video frame rate", number(0, 240, low_open=True), unit="1/s"),
        Option(
            "timeseries_format",
            "parquet",
            "timeseries.parquet (compact, columnar; pandas and polars read it) or "
            "timeseries.csv (text, full precision)",
            choice(*TIMESERIES_FORMATS),
            choices=TIMESERIES_FORMATS,
        ),
        Option(
            "mcap",
            False,
            "also write run.mcap: the run as ROS 2 messages for Foxglove and ROS 2's bag tools "
            "(the mcap extra; python -m tt_mujoco.bag converts a finished run)",
            boolean,
            form="switch",
        ),
        Option(
            "live",
            0,
            "serve the run live to Foxglove at ws://localhost:PORT (0: no; the mcap extra)",
            number(0, 65535, integer=True),
            metavar="PORT",
        ),
        Option(
            "live_realtime",
            True,
            "with --live: pace the run to real time (else as fast as it runs)",
            boolean,
            form="switch",
        ),
        Option("quiet", False, "no progress bar", boolean, form="switch"),
        Option(
            "viewer",
            False,
            "show the run live in MuJoCo's viewer (needs a display; MuJoCo plant only)",
            boolean,
            form="switch",
        ),
    )
)
#: Output options read from a file but not written to a run's config.toml: how it was watched.
NOT_WRITTEN = ("quiet", "viewer", "live", "live_realtime")
#: Every option of the command: the scenario's and the outputs'.
RUN_SCHEMA = SCHEMA + OUTPUTS
#: The rows of a run in progress (raw logged columns), removed once the time series is written.
CHECKPOINT_FILE = "timeseries.partial.arrows"
#: Whether the simulation runs in a watched child (:mod:`tt_mujoco.watchdog`): only when this
#: module is the command (``python -m tt_mujoco.run``), never when ``main`` is called from
#: Python, whose process is the caller's.
WATCHED = False
#: The traceback of the user's code that stopped a run (status "failed").
ERROR_LOG = "error.log"


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
    return {**schema.merged(from_file, given), "config": args.config, "out": args.out}


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


def write_outputs(
    result,
    out: Path,
    shown: Mapping | None = None,
    config_toml: str | None = None,
    figures=None,
):
    """Write ``config.toml`` (if given), the time series, figures, video and, last,
    ``metrics.json`` into ``out``.

    Every file appears complete or not at all: text files through a temporary file and a
    rename; figures and video are made in a hidden staging folder and renamed into ``out``.
    An interruption therefore leaves complete files and no ``metrics.json``.

    Parameters
    ----------
    result : Result
        The run's (:func:`tt_mujoco.sim.simulate`).
    out : Path
        Its folder, claimed.
    shown : mapping, optional
        The output options by name (:data:`OUTPUTS`: ``video``, ``plots``, ``camera``, ...);
        those not given take their defaults.
    config_toml : str, optional
        The run's ``config.toml``.
    figures : RunFigures, optional
        Workers forked for the figures when the run started
        (:class:`tt_mujoco.viz.run_figures.RunFigures`); made here if not given.

    Returns
    -------
    (list of Path, list of str)
        The files written and the run's notes.
    """
    shown = {**OUTPUTS.defaults(), **(shown or {})}
    notes = list(result.notes)  # how the run ran (the loop, backing up), then the outputs'
    written, world = _write_data_files(result, out, shown, config_toml)
    plots, video = shown["plots"], shown["video"]
    if len(result.timeseries["t"]) < 2 and (plots or video):
        # A run that stopped at its first step has one sample: nothing to draw.
        notes.append("figures and video skipped: the run has fewer than 2 samples")
        plots = video = False
    if not plots and figures is not None:
        figures.cancel()
        figures = None
    staging = Path(tempfile.mkdtemp(dir=out, prefix=STAGING))  # this run's own
    try:
        if plots:  # drawn by a forked worker while the video renders here
            if figures is None:
                from tt_mujoco.viz.run_figures import RunFigures

                figures = RunFigures()
            if not figures.asked:
                params = result.scenario.plant_params()
                figures.draw(result.timeseries, result.reference_polyline, params, world)
        if video:
            made, note = _render_video(result, staging, shown, world)
            written += [publish_new(made, out / "video.mp4")] if made is not None else []
            notes += [note] if note is not None else []
        if figures is not None:
            pngs = figures.result()
            figures = None
            for name, png in pngs.items():
                (staging / name).write_bytes(png)
                written.append(publish_new(staging / name, out / name))
    finally:
        if figures is not None:
            figures.cancel()
        shutil.rmtree(staging, ignore_errors=True)
    doc = {
        **result.metrics,
        "message": result.message,
        "notes": notes,
        "config": result.config,
    }
    write_json(out / "metrics.json", doc, strict=True)
    written.append(out / "metrics.json")
    return written, notes


def _write_data_files(result, out: Path, shown: Mapping, config_toml: str | None):
    """``config.toml``, the error log, the reference path, the time series, the world and the
    MCAP file: ``(written, world)``."""
    written = []
    if config_toml is not None:
        atomic_write(out / CONFIG_FILE, config_toml)
        written.append(out / CONFIG_FILE)
    if result.details is not None:  # the traceback of the user code that stopped the run
        atomic_write(out / ERROR_LOG, result.details)
        written.append(out / ERROR_LOG)
    # The run's own reference path: render and compare read it, not a file that may change.
    line = result.reference_polyline
    write_timeseries(out / REFERENCE_FILE, {"x": line[:, 0], "y": line[:, 1]}, ("x", "y"), UNITS)
    written.append(out / REFERENCE_FILE)
    ts_file = out / f"timeseries.{shown['timeseries_format']}"
    extra = train_columns(result.scenario.plant_params().n_trailers)
    extra += tuple(name for name in result.timeseries if name.startswith("ctrl_"))
    units = {**UNITS, **{name: unit_of(name) or "" for name in extra}}
    write_timeseries(ts_file, result.timeseries, (*COLUMNS, *extra), units)
    (out / CHECKPOINT_FILE).unlink(missing_ok=True)  # the complete file replaces it
    written.append(ts_file)
    world = None
    if result.scenario.world != "none":  # its copy: re-rendering reads it, not the file
        from tt_mujoco.world.builtin import KEPT_WORLD, kept_world_toml, parse_world

        world = parse_world(result.scenario.world)
        atomic_write(out / KEPT_WORLD, kept_world_toml(world))
        written.append(out / KEPT_WORLD)
    if shown["mcap"]:
        from tt_mujoco.bag import BAG_FILE, write_bag

        scenario = result.scenario
        written.append(
            write_bag(
                result.timeseries,
                result.reference_polyline,
                scenario.plant_params(),
                out / BAG_FILE,
                bool(scenario.reverse),
                world,
            )
        )
    return written, world


def _render_video(result, staging: Path, shown: Mapping, world):
    """The run's video into ``staging``: ``(path, None)``, or ``(None, note)`` where no
    OpenGL renders it (the results are not lost for it)."""
    from tt_mujoco.viz import render

    try:
        info, outcome = render.run_labels(result.config["scenario"], result.status, result.message)
        path = render.render_video(
            result.timeseries,
            result.scenario.plant_params(),
            result.reference_polyline,
            staging / "video.mp4",
            camera=shown["camera"],
            fps=shown["fps"],
            progress=not shown["quiet"],
            info=info,
            outcome=outcome,
            terrain=result.scenario.terrain,
            world=world,
        )
    except render.RenderUnavailable as err:
        return None, f"video skipped: {err}"
    return Path(path), None


def _progress_bar(total_label: str, quiet: bool):
    if quiet:
        return None, None

    bar = progress_bar(100, total_label, "%")

    def update(done: int, total: int) -> None:
        pct = int(100 * done / max(total, 1))
        if pct > bar.n:
            bar.update(pct - bar.n)

    return update, bar


def _fail(message: str, code: int = EXIT_BAD_INPUT) -> int:
    print(f"error: {message}", file=sys.stderr)
    return code


@guard.command
def main(argv: list[str] | None = None) -> int:
    # Ctrl-C and a batch system's SIGTERM: the same clean exit, told from a KeyboardInterrupt
    # a user's code raises itself (tt_mujoco.guard)
    guard.interrupts_from_signals()
    try:
        return _main(argv)
    except KeyboardInterrupt:  # before a folder exists (start-up); later ones are handled inside
        return _fail("interrupted: nothing was written", EXIT_INTERRUPTED)


def _main(argv: list[str] | None) -> int:
    try:
        invocation = _parse(argv)  # --help ends here: the simulation is not imported for it
    except (BadInputError, ValueError) as err:
        return _fail(str(err))
    except OSError as err:  # a name the file system refuses (too long, not encodable, ...)
        return _file_system_refused(err)
    from tt_mujoco.sim.build import build
    from tt_mujoco.sim.probe import check_user_code
    from tt_mujoco.vehicle import reduced
    from tt_mujoco.viz import viewer as viewer_mod

    try:
        scenario, args, shown = invocation.scenario, invocation.args, invocation.outputs
        # Everything simulate checks, before an output folder exists; simulate reuses it.
        if shown["mcap"]:
            _check_mcap()
        built = build(scenario)
        check_user_code(built)
        config_toml = config_mod.dump_config(invocation.file_form())
        live = None
        if shown["viewer"]:
            if scenario.plant != "mujoco":
                raise BadInputError(
                    f"--viewer shows the MuJoCo plant; --plant {scenario.plant!r} has no "
                    "MuJoCo model to show (use --plant mujoco)"
                )
            viewer_mod.check_display()
            live = viewer_mod.LiveViewer(reference=built.path.dense())
        if shown["live"]:
            if live is not None:
                raise BadInputError("--live and --viewer are not allowed together: choose one")
            from tt_mujoco.viz.foxglove_live import FoxgloveLive, LiveError
            from tt_mujoco.world.builtin import parse_world

            try:
                live = FoxgloveLive(
                    built.plant_params,
                    built.path.dense(),
                    parse_world(scenario.world),
                    port=shown["live"],
                    realtime=shown["live_realtime"],
                )
            except LiveError as err:
                raise BadInputError(str(err)) from None
            if not shown["quiet"]:
                print(f"live: Foxglove, connect to ws://localhost:{live.port}", file=sys.stderr)
        try:
            out, created = _output_dir(args.out, scenario)
        except BaseException:
            if live is not None:  # no run: no server left listening
                live.close()
            raise
    except (BadInputError, ValueError, reduced.SingularityError) as err:  # OutputError too
        return _fail(str(err))
    except OSError as err:  # a name the file system refuses (too long, not encodable, ...)
        return _file_system_refused(err)
    except viewer_mod.ViewerUnavailable as err:
        return _fail(str(err))

    if WATCHED and live is None:  # from here on, the run in a watched child
        limit = built.wall_limit
        watchdog.supervise(
            limit,
            lambda traceback, interrupt: _hung(
                out, limit, scenario.controller, traceback, interrupt
            ),
            lambda signum: _killed(out, signum),
            lambda code: _exited_early(out, code),
        )
    # Forked now (before any thread starts), the figures' worker imports matplotlib while the
    # simulation runs, and draws while the metrics are computed.
    figures, on_rows = _figure_worker(built) if shown["plots"] and live is None else (None, None)
    update, bar = _progress_bar("simulating", shown["quiet"] or shown["viewer"])
    try:
        # Rows reach the disk every 8192 steps while the run goes on: a killed run keeps them.
        checkpoint = out / CHECKPOINT_FILE
        try:
            result = sim.simulate(
                built, progress=update, on_step=live, checkpoint=checkpoint, on_rows=on_rows
            )
        except BaseException:
            if figures is not None:  # no figures to draw: the workers end
                figures.cancel()
            raise
    except (BadInputError, ValueError, reduced.SingularityError) as err:
        return _abandon(out, created, live, str(err), EXIT_BAD_INPUT)
    except viewer_mod.ViewerUnavailable as err:
        return _abandon(out, created, live, str(err), EXIT_BAD_INPUT)
    except viewer_mod.ViewerClosed as err:
        return _abandon(out, created, live, f"{err}: run abandoned", EXIT_INTERRUPTED)
    except KeyboardInterrupt:
        return _interrupted(out, created, live)
    except OSError as err:  # the rows on their way to the disk: a full disk, a quota
        return _rows_unwritable(out, created, live, err)
    finally:
        watchdog.disarm()  # the outputs that follow are not the simulation's time
        if bar is not None:
            bar.close()
    try:
        written, notes = write_outputs(result, out, shown, config_toml, figures)
    except OSError as err:  # a full disk, a quota, a vanished folder
        if live is not None:
            live.close()
        release_folder(out)
        return _fail(
            f"the outputs cannot be written to {out}/: {err.strerror}; the files there are "
            "complete, but metrics.json is missing, so the run's outputs are incomplete",
            EXIT_BAD_INPUT,
        )
    except KeyboardInterrupt:
        if live is not None:
            live.close()
        release_folder(out)  # the missing metrics.json labels the folder incomplete
        return _fail(
            f"interrupted while writing outputs: the files in {out}/ are complete, but "
            "metrics.json was not written, so the run's outputs are incomplete",
            EXIT_INTERRUPTED,
        )
    release_folder(out)  # complete: metrics.json is written
    _print_summary(result, out, written, notes)
    if live is not None:
        live.wait_closed()
    if not result.ok:
        return _fail(f"the run stopped: {result.message}", EXIT_DIVERGED)
    return EXIT_OK


def _figure_worker(built):
    """The run's figure worker (:class:`tt_mujoco.viz.run_figures.RunFigures`), forked before
    the simulation, and the ``on_rows`` that hands it the time series as the run ends (a run
    of fewer than 2 samples has none to draw)."""
    from tt_mujoco.viz.run_figures import RunFigures

    figures = RunFigures()
    world = None
    if built.scenario.world != "none":
        from tt_mujoco.world.builtin import parse_world

        world = parse_world(built.scenario.world)

    def on_rows(ts, reference_polyline) -> None:
        if len(ts["t"]) >= 2:
            figures.draw(ts, reference_polyline, built.plant_params, world)

    return figures, on_rows


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
    return _fail(f"{shown!r}: {err.strerror}")


def _abandon(out: Path, created: bool, live, message: str, code: int) -> int:
    """A run that produced no result: close the viewer, remove the folder made for it."""
    if live is not None:
        live.close()
    (out / CHECKPOINT_FILE).unlink(missing_ok=True)
    if created:
        remove_if_empty(out)
    nothing = "nothing was written" if not out.exists() or not any(out.iterdir()) else ""
    return _fail(f"{message}{'; ' + nothing if nothing else ''}", code)


def _rows_unwritable(out: Path, created: bool, live, err: OSError) -> int:
    """The rows the run wrote as it went could not reach the disk (it is full, a quota): one
    line, exit 2, the rows that did kept; none reached it: nothing left behind."""
    t = _kept_rows(out).get("t", ())
    why = f"the run's rows cannot be written to {out}/: {err.strerror}"
    if len(t) == 0:
        return _abandon(out, created, live, f"{why}; none reached it", EXIT_BAD_INPUT)
    if live is not None:
        live.close()
    release_folder(out)
    kept = f"the {len(t)} rows that reached it are kept in {out / CHECKPOINT_FILE}"
    return _fail(
        f"{why}; {kept}; the folder has no metrics.json, so it is labelled incomplete",
        EXIT_BAD_INPUT,
    )


def _kept_rows(out: Path) -> dict:
    from tt_mujoco.sim.loop.checkpoint import read_checkpoint

    try:
        return read_checkpoint(out / CHECKPOINT_FILE)
    except (OSError, ValueError):
        return {}


def _hung(out: Path, limit: float, controller: str, traceback: str, interrupt: bool) -> int:
    """The watchdog killed a run stuck in code that never returned to Python
    (:mod:`tt_mujoco.watchdog`), past its time limit or an interrupt: keep its rows and its
    traceback, say where it hung."""
    site = watchdog.hang_site(traceback)
    if traceback:
        atomic_write(out / ERROR_LOG, traceback)
    t = _kept_rows(out).get("t", ())
    rows = (
        f"the {len(t)} rows computed to t={t[-1]:.3f} s are kept in {out / CHECKPOINT_FILE}"
        if len(t)
        else "no rows had reached the disk"
    )
    release_folder(out)
    why = (
        "interrupted, the run did not stop"
        if interrupt
        else f"the run passed its time limit of {limit:g} s (wall clock; --time-limit)"
    )
    return _fail(
        f"{why} in code that never returned to Python (a compiled law's own loop, or a call "
        f"into C; the controller: {controller}), at {site}; it was stopped; {rows}; its "
        f"traceback is in {out / ERROR_LOG}; the folder has no metrics.json, so it is labelled "
        "incomplete",
        EXIT_INTERRUPTED if interrupt else EXIT_DIVERGED,
    )


def _killed(out: Path, signum: int) -> int:
    """The run's process was killed by a signal it did not handle (a crash in C code, the
    out-of-memory killer): a bug or the machine, said in one line, the rows kept."""
    t = _kept_rows(out).get("t", ())
    name = signal.Signals(signum).name if signum in signal.Signals._value2member_map_ else signum
    release_folder(out)
    return _fail(
        f"the simulation's process was killed by {name} (a crash in compiled code, or the "
        f"machine ran out of memory): the {len(t)} rows that reached the disk are kept in "
        f"{out / CHECKPOINT_FILE}; if it happens again, please report it",
        EXIT_BUG,
    )


def _exited_early(out: Path, code: int) -> int:
    """The run's process ended by itself while the simulation went on, with exit ``code``:
    not through any of the project's ways out (a user's code calling ``os._exit``, a library
    calling ``exit()`` in C); the rows kept, exit 3."""
    t = _kept_rows(out).get("t", ())
    release_folder(out)
    return _fail(
        f"the simulation's process ended by itself with exit code {code} before the run was "
        f"over (user code calling os._exit, or a library calling exit() in C): the {len(t)} "
        f"rows that reached the disk are kept in {out / CHECKPOINT_FILE}; the folder has no "
        "metrics.json, so it is labelled incomplete",
        EXIT_DIVERGED,
    )


def _interrupted(out: Path, created: bool, live) -> int:
    """Ctrl-C or SIGTERM during the simulation: keep the rows computed, say where they are."""
    partial = out / CHECKPOINT_FILE
    t = _kept_rows(out).get("t", ())
    if len(t) == 0:
        return _abandon(out, created, live, "interrupted before the first row", EXIT_INTERRUPTED)
    if live is not None:
        live.close()
    return _fail(
        f"interrupted at t={t[-1]:.3f} s: the {len(t)} rows computed are kept in {partial} "
        "(read them with tt_mujoco.sim.loop.checkpoint.read_checkpoint or "
        "pyarrow.ipc.open_stream); "
        "the folder has no metrics.json, so it is labelled incomplete",
        EXIT_INTERRUPTED,
    )


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
    sys.exit(main())

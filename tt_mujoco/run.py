"""``python -m tt_mujoco.run``: one closed-loop run, with metrics, time series, plots and video.

Exit codes (docs/model.md Section 11): 0 done; 2 bad input (one message, no traceback, nothing
written); 3 the run diverged or jackknifed (the message gives the time and state; everything
computed up to then is still written); 130 interrupted (Ctrl-C, or the live viewer closed):
files already written are complete, and ``metrics.json``, written last, is absent.

Options can come from a TOML file (``--config FILE``, see :mod:`tt_mujoco.config`); the
command line overrides it, and every run writes its resolved options to ``config.toml`` so
that ``--config RUN_DIR/config.toml`` repeats it exactly. ``--viewer`` shows the run live in
MuJoCo's passive viewer (:mod:`tt_mujoco.viz.viewer`).

Outputs are written atomically (a temporary file, then a rename) into a new folder, never an
existing non-empty one; ``metrics.json`` is written last, so its presence marks a complete run.
"""

from __future__ import annotations

import argparse
import json
import shutil
import signal
import sys
import tempfile
import threading
import time
from pathlib import Path

from tt_mujoco import config as config_mod
from tt_mujoco import sim
from tt_mujoco.analysis.metrics import DEFAULT_SUMMARY_KEYS, metric_name, summary_table
from tt_mujoco.cliargs import BadInputError, Parser, finite, integer_at_least, positive
from tt_mujoco.config import CONFIG_FILE
from tt_mujoco.controllers import CONTROLLERS, controller_class
from tt_mujoco.controllers.base import resolve_gains
from tt_mujoco.defaults import (
    CONTROLLER,
    DISTURBANCE_MODEL,
    EXIT_BAD_INPUT,
    EXIT_DIVERGED,
    EXIT_INTERRUPTED,
    EXIT_OK,
    TIME_LIMIT_S,
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
from tt_mujoco.sim import COLUMNS, DISTURBANCE_MODES, PLANTS, TARGETS, Scenario, build
from tt_mujoco.sim.checkpoint import read_checkpoint
from tt_mujoco.sim.faults import RECOVERY_S, parse_fault
from tt_mujoco.sim.motors import ACTUATORS
from tt_mujoco.sim.probe import check_user_code
from tt_mujoco.sim.terrain import parse_terrain
from tt_mujoco.sim.timeseries import UNITS, train_columns, unit_of
from tt_mujoco.sim.wind import parse_wind
from tt_mujoco.vehicle import reduced
from tt_mujoco.vehicle.params import SETTABLE_FIELDS
from tt_mujoco.viz import plots as plots_mod
from tt_mujoco.viz import render
from tt_mujoco.viz import viewer as viewer_mod

__all__ = ["build_parser", "main", "write_outputs"]

RENDERS = Path("renders")
#: Params fields settable with --param / [params] (eta, timestep and friction have options).
PARAM_NAMES = SETTABLE_FIELDS
#: Prefix of the hidden folder, private to one run, where figures and video are made before
#: they are moved into the output folder.
STAGING = ".partial-"
#: Formats of the time-series file (``timeseries.<format>``).
TIMESERIES_FORMATS = ("parquet", "csv")
#: ``--eta`` words that schedule the plant's gain (Scenario.eta_schedule) on the same_path model.
ETA_OPTION_SCHEDULES = {"scheduled": "curvature", "path": "path"}
#: The rows of a run in progress (raw logged columns), removed once the time series is written.
CHECKPOINT_FILE = "timeseries.partial.arrows"
#: The traceback of the user's code that stopped a run (status "failed").
ERROR_LOG = "error.log"


def parse_param(text: str) -> tuple[str, float]:
    name, sep, value = text.partition("=")
    name = name.strip()
    if not sep or name not in PARAM_NAMES:
        raise argparse.ArgumentTypeError(
            f"--param {text!r} is not allowed: write NAME=VALUE with NAME one of "
            f"{', '.join(PARAM_NAMES)}"
        )
    try:
        return name, float(value)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"--param {text!r} is not allowed: {value.strip()!r} is not a number"
        ) from None


def _disturbance_limit(text: str) -> str | float:
    if text.strip().lower() in ("actuator", "none"):
        return text.strip().lower()
    return positive("--disturbance-limit")(text)


def _spec(parse):
    """An argparse type for an option written as a spec text (``--wind``, ``--terrain``): the
    parsed value's own spelling of it, or the parser's message."""

    def convert(text: str) -> str:
        try:
            return parse(text).spec()
        except ValueError as err:
            raise argparse.ArgumentTypeError(str(err)) from None

    return convert


def _path_option(text: str) -> tuple[str, float | str]:
    name, sep, value = text.partition("=")
    name, value = name.strip(), value.strip()
    if not sep or not name.isidentifier() or not value:
        raise argparse.ArgumentTypeError(
            f"--path-option {text!r} is not allowed: write NAME=VALUE, e.g. R=2 or cruise=0.5"
        )
    try:
        return name, float(value)
    except ValueError:
        return name, value


def build_parser() -> argparse.ArgumentParser:
    p = Parser(
        prog="python -m tt_mujoco.run",
        description=(
            "Run one closed-loop tracking scenario of the off-axle tractor-trailer on the MuJoCo "
            "plant or the analytic reduced model, and write metrics.json, timeseries.parquet, "
            "config.toml, plots and a video into a new folder."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    p.add_argument(
        "--config",
        type=Path,
        default=None,
        metavar="FILE",
        help="read options from this TOML file (e.g. a previous run's config.toml); "
        "options given here override it",
    )
    g = p.add_argument_group("scenario")
    g.add_argument(
        "--traj",
        default="s_curve",
        help="reference path: cycloid, s_curve, circle, a CSV file with header x,y[,v], or a "
        "hook package.module:NAME / path/to/file.py:NAME (a ReferencePath or a factory)",
    )
    g.add_argument(
        "--path-option",
        action="append",
        type=_path_option,
        default=None,
        metavar="NAME=VALUE",
        help="a shape option of the path (s_curve/circle: R, cruise, ramp_time; CSV: "
        "max_curvature, smoothing, cruise, ramp_time; a hook: its keyword arguments); "
        "repeatable",
    )
    g.add_argument(
        "--controller",
        default=CONTROLLER,
        help=f"{', '.join(CONTROLLERS)}, or a hook package.module:Class / "
        "path/to/file.py:Class (a tt_mujoco.controllers.Controller subclass)",
    )
    g.add_argument(
        "--gains",
        default=None,
        help="controller gain preset (ismc_sta: paper_6_1 or paper_6_2) or JSON overrides, "
        "e.g. '{\"k1_v\": 12}'",
    )
    g.add_argument(
        "--target",
        default="dynamic",
        choices=TARGETS,
        help="dynamic: omega_d = kappa(s) v (paper eq. 34); static: fixed functions of time",
    )
    g.add_argument("--plant", default="mujoco", choices=PLANTS)
    g.add_argument(
        "--eta",
        default="same_path",
        help="passive steering gain: paper (3, jackknifes forward), same_path "
        "((L-L0)/(L+L0) = -1/7), scheduled (the exact same-path gain for the local "
        "curvature, updated every step), path (each trailer's gain eta_k(s) from the path's "
        "geometry, at its own arc length; |eta| <= 3), or a number",
    )
    g.add_argument(
        "--reverse",
        action=argparse.BooleanOptionalAction,
        default=False,
        help="drive the path backwards, trailer first (where eta > 1 is stable)",
    )
    g.add_argument(
        "--hitch-feedback",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="reversing without --path-feedback: the leading trailer's axle tracks the path "
        "and a cascade on the hitch angles sets the tractor's yaw rate "
        "(tt_mujoco.controllers.backing); --no-hitch-feedback leaves the hitches to themselves",
    )
    g.add_argument(
        "--path-feedback",
        action=argparse.BooleanOptionalAction,
        default=False,
        help="outer loop: lateral and heading errors feed the yaw-rate target "
        "(tt_mujoco.reference.feedback; k_y = k_psi = 4)",
    )
    g.add_argument(
        "--no-disturbance",
        dest="disturbance",
        action="store_const",
        const="none",
        default=argparse.SUPPRESS,  # the default is --disturbance-mode's
        help="switch off the paper's disturbance (same as --disturbance-mode none)",
    )
    g.add_argument(
        "--disturbance-mode",
        dest="disturbance",
        default="matched",
        choices=DISTURBANCE_MODES,
        help="matched: wheel torques g^-1 Delta; wrench: force and moment on the chassis "
        "(can exceed traction); none",
    )
    g.add_argument(
        "--disturbance-model",
        default=DISTURBANCE_MODEL,
        help="the disturbance Delta(t): paper, or a hook package.module:Name / file.py:Name",
    )
    g.add_argument(
        "--disturbance-limit",
        type=_disturbance_limit,
        default="actuator",
        help="bound on each wheel's matched disturbance torque: actuator (the torque limit), "
        "none (the paper's unbounded g^-1 Delta) or a number in N m",
    )
    g.add_argument(
        "--metric",
        action="append",
        default=None,
        metavar="HOOK",
        help="an extra metric fn(timeseries, path) added to metrics.json: a registered name or "
        "a hook package.module:fn / path/to/file.py:fn (repeatable)",
    )
    g.add_argument(
        "--noise-snr-db",
        "--noise-snr",
        type=finite("--noise-snr-db"),
        default=None,
        metavar="DB",
        help="Gaussian measurement noise on v and omega at this SNR (dB); none by default",
    )
    g.add_argument(
        "--param-scale",
        type=positive("--param-scale"),
        default=1.0,
        metavar="F",
        help="scale the plant's masses and inertias (the controller keeps the nominal model)",
    )
    g.add_argument(
        "--param",
        action="append",
        type=parse_param,
        default=None,
        metavar="NAME=VALUE",
        help="override a vehicle parameter of both plant and controller model, e.g. Mr=7.5 "
        "(repeatable; see tt_mujoco.vehicle.params.Params)",
    )
    g.add_argument(
        "--duration",
        type=positive("--duration"),
        default=None,
        metavar="S",
        help="run length in s, at most 600 (default: the path's own duration)",
    )
    g.add_argument(
        "--seed",
        type=integer_at_least("--seed", 0),
        default=0,
        help="seed for the measurement noise",
    )
    g.add_argument(
        "--start",
        default="on_path",
        choices=("on_path", "paper"),
        help="on_path: start in the reference's initial state (pose and speed); paper: the "
        "paper's initial condition, at rest (on the cycloid at its pose (0, 0, pi/4))",
    )
    g.add_argument(
        "--trailers",
        type=int,
        default=1,
        metavar="N",
        help="number of trailers, 1 to 8: trailers 2..N copy trailer 1 and steer with their "
        "own gain of the --eta preset (a config file's [[trailers]] tables override them)",
    )
    g.add_argument(
        "--phi0-deg",
        "--phi0",
        type=finite("--phi0-deg"),
        default=0.0,
        metavar="DEG",
        help="initial articulation phi (deg), short of the jackknife",
    )
    g.add_argument(
        "--time-limit",
        dest="time_limit_s",
        type=positive("--time-limit"),
        default=TIME_LIMIT_S,
        help=f"wall-clock limit of the run (s; default {TIME_LIMIT_S:g}): a run still going "
        "then stops, its rows kept (exit code 3)",
    )
    g.add_argument(
        "--friction",
        type=positive("--friction"),
        default=1.0,
        help="tyre friction coefficient",
    )
    g.add_argument(
        "--actuator",
        choices=ACTUATORS,
        default="ideal",
        help="ideal: the wheels get the commanded torque; dc_motor: a DC motor per wheel with "
        "its lag and current and voltage limits (Params motor_*, set with --param)",
    )
    g.add_argument(
        "--sensor-delay",
        type=finite("--sensor-delay"),
        default=0.0,
        metavar="S",
        help="the sensors' delay (s, a multiple of the control period, shorter than the run)",
    )
    g.add_argument(
        "--ground",
        action="append",
        default=None,
        metavar="band:S0:S1:MU|rect:X0:Y0:X1:Y1:MU",
        help="a patch of other friction (repeatable): a stretch of the path or a rectangle of "
        "the floor; MuJoCo plant only",
    )
    g.add_argument(
        "--wind",
        type=_spec(parse_wind),
        default="none",
        metavar="SPEED[:DIRECTION_DEG[:GUST_STD]]",
        help="wind blowing toward DIRECTION_DEG (m/s, deg from +x, gusts' std in m/s); "
        "MuJoCo plant only",
    )
    g.add_argument(
        "--terrain",
        type=_spec(parse_terrain),
        default="flat",
        metavar="flat|slope:GRADE_DEG[:HEADING_DEG]",
        help="the ground: flat, or a constant grade rising along HEADING_DEG (default 0, +x); "
        "MuJoCo plant only",
    )
    g.add_argument(
        "--timestep",
        type=positive("--timestep"),
        default=0.001,
        help="physics step (s), in [1e-5, 0.01]",
    )
    g.add_argument(
        "--control-dt",
        type=positive("--control-dt"),
        default=None,
        help="control period (s), a multiple of the timestep, at most 0.05; default: the timestep",
    )
    g.add_argument(
        "--fault",
        action="append",
        default=None,
        metavar="KIND:K=V,...",
        help="inject a fault (repeatable; replaces a config file's faults): "
        "payload:t=S[,factor=1.5] | dropout:t=S[,duration=0.1] | "
        "actuator:t=S[,duration=1,scale=0.3,wheel=both|right|left]",
    )
    o = p.add_argument_group("outputs")
    o.add_argument(
        "--out",
        type=Path,
        default=None,
        metavar="DIR",
        help="output folder (must not exist or be empty); default: a new folder under renders/",
    )
    o.add_argument(
        "--video", action=argparse.BooleanOptionalAction, default=True, help="write video.mp4"
    )
    o.add_argument(
        "--plots", action=argparse.BooleanOptionalAction, default=True, help="write PNG figures"
    )
    o.add_argument(
        "--camera", default="follow", choices=("follow", "overview"), help="video camera"
    )
    o.add_argument("--fps", type=positive("--fps"), default=30.0, help="video frame rate")
    o.add_argument(
        "--timeseries-format",
        default="parquet",
        choices=TIMESERIES_FORMATS,
        help="timeseries.parquet (compact, columnar; pandas and polars read it) or "
        "timeseries.csv (text, full precision)",
    )
    o.add_argument(
        "--quiet", action=argparse.BooleanOptionalAction, default=False, help="no progress bar"
    )
    o.add_argument(
        "--viewer",
        action=argparse.BooleanOptionalAction,
        default=False,
        help="show the run live in MuJoCo's viewer (needs a display; MuJoCo plant only)",
    )
    return p


def _parse(argv) -> tuple[argparse.Namespace, argparse.ArgumentParser, dict, list]:
    """Command line over config file over defaults; returns (args, parser, params, faults)."""

    parser = build_parser()
    args = parser.parse_args(argv)
    params, faults = {}, []
    if args.config is not None:
        table = config_mod.load_config(args.config)
        found = config_mod.options_from_file(table, parser, args.config, PARAM_NAMES)
        parser.set_defaults(**found.defaults)
        args = parser.parse_args(argv)
        if "gains" in found.defaults and args.gains == found.defaults["gains"]:
            _check_gains(args.controller, args.gains, f"config file {str(args.config)!r} [gains]")
        params = dict(found.params)
        faults = found.faults or []
    params.update(dict(args.param or []))
    if args.fault is not None:
        faults = list(args.fault)
    faults = [parse_fault(f).to_dict() for f in faults]
    gains = args.gains
    if isinstance(gains, str) and gains.strip().startswith("{"):
        try:
            gains = json.loads(gains)
        except json.JSONDecodeError as err:
            raise BadInputError(f"--gains {args.gains!r} is not valid JSON: {err.msg}") from None
        if not isinstance(gains, dict):
            raise BadInputError(f"--gains {args.gains!r} is not a JSON object")
    args.gains = gains
    if args.control_dt is None:
        args.control_dt = args.timestep
    return args, parser, params, faults


def scenario_from_argv(argv) -> Scenario:
    """The :class:`~tt_mujoco.sim.Scenario` a command line (``--config FILE`` included) stands
    for, as ``python -m tt_mujoco.run`` builds it.

    Raises
    ------
    tt_mujoco.cliargs.BadInputError
        A bad option or config file (the message names it).
    """
    args, _, params, faults = _parse(list(argv))
    return _scenario(args, params, faults)


def _check_gains(controller: str, gains, where: str) -> None:
    """Gains from a file are checked against the controller now, so the message names the file."""
    try:
        cls = controller_class(controller)
        resolve_gains(cls.name, cls.PRESETS, cls.DEFAULT_PRESET, gains)
    except ValueError as err:
        raise BadInputError(f"{where}: {err}") from None


def _scenario(args, params: dict, faults: list) -> Scenario:
    path_options = dict(args.path_option or [])
    traj = args.traj
    if traj.lower().endswith(".csv"):
        traj = str(Path(traj))
    eta = args.eta
    eta_schedule = ETA_OPTION_SCHEDULES.get(eta.strip().lower()) if isinstance(eta, str) else None
    if eta_schedule:
        eta = "same_path"  # the nominal model's gain; the plant's follows the schedule
    else:
        eta_schedule = False
    try:
        eta = float(eta)
    except ValueError:
        pass
    return Scenario(
        traj=traj,
        controller=args.controller,
        gains=args.gains,
        target=args.target,
        plant=args.plant,
        eta=eta,
        disturbance=args.disturbance,
        noise_snr_db=args.noise_snr_db,
        param_scale=args.param_scale,
        duration=args.duration,
        seed=args.seed,
        timestep=args.timestep,
        control_dt=args.control_dt,
        start=args.start,
        friction=args.friction,
        params=dict(params),
        phi0_deg=args.phi0_deg,
        faults=list(faults),
        eta_schedule=eta_schedule,
        reverse=bool(args.reverse),
        path_feedback={} if args.path_feedback else None,
        hitch_feedback={} if args.hitch_feedback else None,
        disturbance_model=args.disturbance_model,
        disturbance_limit=args.disturbance_limit,
        path_options=dict(path_options),
        metrics=list(args.metric or []),
        trailers=args.trailers,
        train=list(getattr(args, "train", None) or []),
        time_limit_s=args.time_limit_s,
        terrain=args.terrain,
        actuator=args.actuator,
        sensor_delay=args.sensor_delay,
        wind=args.wind,
        ground=list(args.ground or []),
    )


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
    video: bool,
    plots: bool,
    camera: str,
    fps: float,
    quiet,
    config_toml: str | None = None,
    timeseries_format: str = "parquet",
):
    """Write ``config.toml`` (if given), the time series, figures, video and, last,
    ``metrics.json`` into ``out``.

    Every file appears complete or not at all: text files through a temporary file and a
    rename; figures and video are made in a hidden staging folder and renamed into ``out``.
    An interruption therefore leaves complete files and no ``metrics.json``.
    """
    written = []
    notes = []
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
    ts_file = out / f"timeseries.{timeseries_format}"
    extra = train_columns(result.scenario.plant_params().n_trailers)
    extra += tuple(name for name in result.timeseries if name.startswith("ctrl_"))
    units = {**UNITS, **{name: unit_of(name) or "" for name in extra}}
    write_timeseries(ts_file, result.timeseries, (*COLUMNS, *extra), units)
    (out / CHECKPOINT_FILE).unlink(missing_ok=True)  # the complete file replaces it
    written.append(ts_file)
    if len(result.timeseries["t"]) < 2 and (plots or video):
        # A run that stopped at its first step has one sample: nothing to draw.
        notes.append("figures and video skipped: the run has fewer than 2 samples")
        plots = video = False
    staging = Path(tempfile.mkdtemp(dir=out, prefix=STAGING))  # this run's own
    try:
        if plots:
            made = plots_mod.plot_run(
                result.timeseries,
                result.reference_polyline,
                staging,
                params=result.scenario.plant_params(),
            )
            written += [publish_new(Path(f), out / Path(f).name) for f in made]
        if video:
            try:
                info, outcome = render.run_labels(
                    result.config["scenario"], result.status, result.message
                )
                path = render.render_video(
                    result.timeseries,
                    result.scenario.plant_params(),
                    result.reference_polyline,
                    staging / "video.mp4",
                    camera=camera,
                    fps=fps,
                    progress=not quiet,
                    info=info,
                    outcome=outcome,
                )
                written.append(publish_new(Path(path), out / "video.mp4"))
            except render.RenderUnavailable as err:  # no GL must not lose the results
                notes.append(f"video skipped: {err}")
    finally:
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


def _sigterm(signum, frame):
    raise KeyboardInterrupt  # a batch system's stop: the same clean exit as Ctrl-C


def main(argv: list[str] | None = None) -> int:
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGTERM, _sigterm)
    try:
        return _main(argv)
    except KeyboardInterrupt:  # before a folder exists (start-up); later ones are handled inside
        return _fail("interrupted: nothing was written", EXIT_INTERRUPTED)


def _main(argv: list[str] | None) -> int:
    try:
        args, parser, params, faults = _parse(argv)
        scenario = _scenario(args, params, faults)
        # Everything simulate checks, before an output folder exists; simulate reuses it.
        built = build(scenario)
        check_user_code(built)
        config_toml = config_mod.dump_config(
            config_mod.resolved_options(args, parser, params, faults)
        )
        live = None
        if args.viewer:
            if scenario.plant != "mujoco":
                raise BadInputError(
                    f"--viewer shows the MuJoCo plant; --plant {scenario.plant!r} has no "
                    "MuJoCo model to show (use --plant mujoco)"
                )
            viewer_mod.check_display()
            live = viewer_mod.LiveViewer(reference=built.path.dense())
        out, created = _output_dir(args.out, scenario)
    except (BadInputError, ValueError, reduced.SingularityError) as err:  # OutputError too
        return _fail(str(err))
    except OSError as err:  # a name the file system refuses (too long, not encodable, ...)
        name = str(err.filename or "")
        shown = name if len(name) <= 80 else name[:77] + "..."
        return _fail(f"{shown!r}: {err.strerror}")
    except viewer_mod.ViewerUnavailable as err:
        return _fail(str(err))

    update, bar = _progress_bar("simulating", args.quiet or args.viewer)
    try:
        # Rows reach the disk every 8192 steps while the run goes on: a killed run keeps them.
        checkpoint = out / CHECKPOINT_FILE
        result = sim.simulate(built, progress=update, on_step=live, checkpoint=checkpoint)
    except (BadInputError, ValueError, reduced.SingularityError) as err:
        return _abandon(out, created, live, str(err), EXIT_BAD_INPUT)
    except viewer_mod.ViewerUnavailable as err:
        return _abandon(out, created, live, str(err), EXIT_BAD_INPUT)
    except viewer_mod.ViewerClosed as err:
        return _abandon(out, created, live, f"{err}: run abandoned", EXIT_INTERRUPTED)
    except KeyboardInterrupt:
        return _interrupted(out, created, live)
    finally:
        if bar is not None:
            bar.close()
    try:
        written, notes = write_outputs(
            result,
            out,
            video=args.video,
            plots=args.plots,
            camera=args.camera,
            fps=args.fps,
            quiet=args.quiet,
            config_toml=config_toml,
            timeseries_format=args.timeseries_format,
        )
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


def _abandon(out: Path, created: bool, live, message: str, code: int) -> int:
    """A run that produced no result: close the viewer, remove the folder made for it."""
    if live is not None:
        live.close()
    (out / CHECKPOINT_FILE).unlink(missing_ok=True)
    if created:
        remove_if_empty(out)
    nothing = "nothing was written" if not out.exists() or not any(out.iterdir()) else ""
    return _fail(f"{message}{'; ' + nothing if nothing else ''}", code)


def _interrupted(out: Path, created: bool, live) -> int:
    """Ctrl-C or SIGTERM during the simulation: keep the rows computed, say where they are."""
    partial = out / CHECKPOINT_FILE
    try:
        rows = read_checkpoint(partial)
    except (OSError, ValueError):
        rows = {}
    t = rows.get("t", ())
    if len(t) == 0:
        return _abandon(out, created, live, "interrupted before the first row", EXIT_INTERRUPTED)
    if live is not None:
        live.close()
    return _fail(
        f"interrupted at t={t[-1]:.3f} s: the {len(t)} rows computed are kept in {partial} "
        "(read them with tt_mujoco.sim.checkpoint.read_checkpoint or pyarrow.ipc.open_stream); "
        "the folder has no metrics.json, so it is labelled incomplete",
        EXIT_INTERRUPTED,
    )


def _print_summary(result, out: Path, written, notes) -> None:

    s = result.scenario
    etas = s.nominal_params().etas
    gains = ", ".join(f"{e:.4g}" for e in etas)
    shown = f"eta={etas[0]:g}" if len(etas) == 1 else f"{len(etas)} trailers, eta_k={gains}"
    print(
        f"{s.traj} | {s.controller} | {s.target} target | {s.plant} plant | {shown} | "
        f"disturbance={s.disturbance}"
        + ("" if s.terrain == "flat" else f" | terrain={s.terrain}")
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
        if w is None:
            print(
                f"fault {fault['kind']} at t={fault['t']:g} s: not reached, the run stopped at "
                f"t={result.metrics['sim_time_s']:.3f} s ({result.status})"
            )
            continue
        print(
            f"fault {fault['kind']} at t={fault['t']:g} s, until {RECOVERY_S:g} s after its end: "
            f"max|e_v| {w['max_abs_v']:.4g} m/s, max|e_omega| {w['max_abs_omega']:.4g} rad/s, "
            f"max lateral {w['max_lateral']:.4g} m"
        )
    for note in notes:
        print(f"note: {note}")
    print(f"wrote {len(written)} files to {out}/")


if __name__ == "__main__":
    sys.exit(main())

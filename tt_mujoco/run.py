"""``python -m tt_mujoco.run``: one closed-loop run, with metrics, time series, plots and video.

Exit codes (SPEC Section 11): 0 done; 2 bad input (one message, no traceback); 3 the run
diverged or jackknifed (the message gives the time and state; everything computed up to then
is still written).
"""

from __future__ import annotations

import argparse
import csv
import io
import json
import math
import os
import sys
import time
from pathlib import Path

import numpy as np

from tt_mujoco.sim import COLUMNS, DISTURBANCE_MODES, PLANTS, TARGETS, Scenario

__all__ = ["build_parser", "main", "write_outputs"]

RENDERS = Path("renders")
CONTROLLERS = ("ismc_sta", "pid", "fbl")
EXIT_OK, EXIT_BAD_INPUT, EXIT_DIVERGED = 0, 2, 3

SUMMARY_KEYS = (
    "rmse_v",
    "max_abs_v",
    "rmse_omega",
    "max_abs_omega",
    "rmse_lateral",
    "max_lateral",
    "rmse_position",
    "max_position",
    "trailer_rmse_lateral",
    "trailer_offtrack_rms",
    "eq_violation_max",
    "slip_lateral_max",
    "torque_saturation_fraction",
    "steps",
    "sim_time_s",
    "wall_time_s",
)


class BadInputError(Exception):
    """A user's mistake: reported as one line, exit code 2."""


class _Parser(argparse.ArgumentParser):
    def error(self, message: str):  # argparse's own errors: same exit code, no usage dump
        raise BadInputError(message)


def _snr(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"--noise-snr {text!r} is not a number: give the SNR in dB, e.g. 20"
        ) from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"--noise-snr {text!r} must be a finite number of dB")
    return value


def _positive(name: str):
    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{name} {text!r} is not a number") from None
        if not (math.isfinite(value) and value > 0):
            raise argparse.ArgumentTypeError(f"{name} {text!r} must be a finite number > 0")
        return value

    return parse


def _seed(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"--seed {text!r} is not an integer >= 0") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"--seed {text!r} is not an integer >= 0")
    return value


def build_parser() -> argparse.ArgumentParser:
    p = _Parser(
        prog="python -m tt_mujoco.run",
        description=(
            "Run one closed-loop tracking scenario of the off-axle tractor-trailer on the MuJoCo "
            "plant or the analytic reduced model, and write metrics.json, timeseries.csv, plots "
            "and a video into a new folder."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    g = p.add_argument_group("scenario")
    g.add_argument(
        "--traj",
        default="s_curve",
        help="reference path: cycloid, s_curve, circle, or a CSV file with header x,y[,v]",
    )
    g.add_argument("--controller", default="ismc_sta", choices=CONTROLLERS)
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
        "(-(L0-L)/(2 L0)), or a number",
    )
    g.add_argument(
        "--no-disturbance", action="store_true", help="switch off the paper's disturbance"
    )
    g.add_argument(
        "--disturbance-mode",
        default="matched",
        choices=[m for m in DISTURBANCE_MODES if m != "none"],
        help="matched: wheel torques g^-1 Delta; wrench: force and moment on the chassis",
    )
    g.add_argument(
        "--noise-snr",
        type=_snr,
        default=None,
        metavar="DB",
        help="Gaussian measurement noise on v and omega at this SNR (dB); none by default",
    )
    g.add_argument(
        "--param-scale",
        type=_positive("--param-scale"),
        default=1.0,
        metavar="F",
        help="scale the plant's masses and inertias (the controller keeps the nominal model)",
    )
    g.add_argument(
        "--duration",
        type=_positive("--duration"),
        default=None,
        metavar="S",
        help="run length in s (default: the path's own duration)",
    )
    g.add_argument("--seed", type=_seed, default=0, help="seed for the measurement noise")
    g.add_argument(
        "--start",
        default="on_path",
        choices=("on_path", "paper"),
        help="cycloid only: start on the path, or at the paper's pose (0, 0, pi/4)",
    )
    g.add_argument(
        "--friction", type=_positive("--friction"), default=1.0, help="tyre friction coefficient"
    )
    g.add_argument(
        "--timestep", type=_positive("--timestep"), default=0.001, help="physics step (s)"
    )
    g.add_argument(
        "--control-dt",
        type=_positive("--control-dt"),
        default=None,
        help="control period (s), a multiple of the timestep; default: the timestep",
    )
    o = p.add_argument_group("outputs")
    o.add_argument(
        "--out",
        type=Path,
        default=None,
        metavar="DIR",
        help="output folder (must not exist or be empty); default: a new folder under renders/",
    )
    o.add_argument("--no-video", action="store_true", help="skip the MP4")
    o.add_argument("--no-plots", action="store_true", help="skip the PNG figures")
    o.add_argument(
        "--camera", default="follow", choices=("follow", "overview"), help="video camera"
    )
    o.add_argument("--fps", type=_positive("--fps"), default=30.0, help="video frame rate")
    o.add_argument("--quiet", action="store_true", help="no progress bar")
    return p


def _scenario(args) -> Scenario:
    gains = args.gains
    if gains is not None and gains.strip().startswith("{"):
        try:
            gains = json.loads(gains)
        except json.JSONDecodeError as err:
            raise BadInputError(f"--gains {args.gains!r} is not valid JSON: {err.msg}") from None
    traj = args.traj
    if traj.lower().endswith(".csv"):
        traj = str(Path(traj))
    return Scenario(
        traj=traj,
        controller=args.controller,
        gains=gains,
        target=args.target,
        plant=args.plant,
        eta=args.eta,
        disturbance="none" if args.no_disturbance else args.disturbance_mode,
        noise_snr_db=args.noise_snr,
        param_scale=args.param_scale,
        duration=args.duration,
        seed=args.seed,
        timestep=args.timestep,
        control_dt=args.control_dt if args.control_dt is not None else args.timestep,
        start=args.start,
        friction=args.friction,
    )


def _output_dir(out: Path | None, scenario: Scenario) -> Path:
    """A new, writable, empty folder; never one with files in it."""
    if out is None:
        stem = Path(scenario.traj).stem if scenario.traj.endswith(".csv") else scenario.traj
        base = RENDERS / (
            f"{stem}-{scenario.controller}-{scenario.target}-{scenario.plant}-"
            f"{time.strftime('%Y%m%d-%H%M%S')}"
        )
        out = base
        i = 2
        while out.exists():
            out = base.with_name(f"{base.name}-{i}")
            i += 1
    elif out.exists() and (not out.is_dir() or any(out.iterdir())):
        raise BadInputError(
            f"--out {str(out)!r} already exists and is not empty: outputs are never overwritten; "
            "name a new folder"
        )
    try:
        out.mkdir(parents=True, exist_ok=True)
        probe = out / ".write-test"
        probe.write_text("")
        probe.unlink()
    except OSError as err:
        raise BadInputError(f"--out {str(out)!r} cannot be written: {err.strerror}") from None
    return out


def _atomic_write(path: Path, data: str | bytes) -> None:
    tmp = path.with_name(f".{path.name}.tmp-{os.getpid()}")
    if isinstance(data, str):
        tmp.write_text(data)
    else:
        tmp.write_bytes(data)
    os.replace(tmp, path)


def _json_default(obj):
    if isinstance(obj, np.floating | np.integer):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, Path):
        return str(obj)
    raise TypeError(f"not JSON serialisable: {type(obj).__name__}")


def timeseries_csv(ts: dict) -> str:
    """The time series as CSV text, every float with full precision (repr)."""
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(COLUMNS)
    cols = [ts[c] for c in COLUMNS]
    for row in zip(*cols, strict=True):
        writer.writerow([repr(float(v)) for v in row])
    return buf.getvalue()


def read_timeseries(path: Path) -> dict[str, np.ndarray]:
    """Read a ``timeseries.csv`` back into column arrays."""
    data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    with open(path) as fh:
        header = fh.readline().strip().split(",")
    return {name: data[:, i] for i, name in enumerate(header)}


def write_outputs(result, out: Path, video: bool, plots: bool, camera: str, fps: float, quiet):
    """Write the time series, figures, video and (last) metrics.json into ``out``."""
    written = []
    _atomic_write(out / "timeseries.csv", timeseries_csv(result.timeseries))
    written.append(out / "timeseries.csv")
    notes = []
    if plots:
        try:
            from tt_mujoco import plots as plots_mod

            written += plots_mod.plot_run(result.timeseries, result.reference_polyline, out)
        except ImportError:
            notes.append("plots skipped: tt_mujoco.plots is not available")
    if video:
        try:
            from tt_mujoco import render

            path = render.render_video(
                result.timeseries,
                result.scenario.plant_params(),
                result.reference_polyline,
                out / "video.mp4",
                camera=camera,
                fps=fps,
                progress=not quiet,
            )
            written.append(path)
        except ImportError:
            notes.append("video skipped: tt_mujoco.render is not available")
        except Exception as err:  # a missing GL backend must not lose the run's results
            if type(err).__name__ != "RenderUnavailable":
                raise
            notes.append(f"video skipped: {err}")
    doc = {
        **result.metrics,
        "message": result.message,
        "notes": notes,
        "config": result.config,
    }
    _atomic_write(out / "metrics.json", json.dumps(doc, indent=2, default=_json_default) + "\n")
    written.append(out / "metrics.json")
    return written, notes


def _progress_bar(total_label: str, quiet: bool):
    if quiet:
        return None, None
    from tqdm import tqdm

    bar = tqdm(total=100, desc=total_label, unit="%", leave=False, disable=None)

    def update(done: int, total: int) -> None:
        pct = int(100 * done / max(total, 1))
        if pct > bar.n:
            bar.update(pct - bar.n)

    return update, bar


def main(argv: list[str] | None = None) -> int:
    from tt_mujoco import reduced, sim

    try:
        args = build_parser().parse_args(argv)
        scenario = _scenario(args)
        scenario.validate()
        scenario.nominal_params()  # parameter errors before any folder is made
        out = _output_dir(args.out, scenario)
    except (BadInputError, ValueError) as err:
        print(f"error: {err}", file=sys.stderr)
        return EXIT_BAD_INPUT

    update, bar = _progress_bar("simulating", args.quiet)
    try:
        result = sim.simulate(scenario, progress=update)
    except (BadInputError, ValueError, reduced.SingularityError) as err:
        if bar is not None:
            bar.close()
        _cleanup_empty(out)
        print(f"error: {err}", file=sys.stderr)
        return EXIT_BAD_INPUT
    if bar is not None:
        bar.close()
    written, notes = write_outputs(
        result,
        out,
        video=not args.no_video,
        plots=not args.no_plots,
        camera=args.camera,
        fps=args.fps,
        quiet=args.quiet,
    )
    _print_summary(result, out, written, notes)
    if not result.ok:
        print(f"error: the run stopped: {result.message}", file=sys.stderr)
        return EXIT_DIVERGED
    return EXIT_OK


def _cleanup_empty(out: Path) -> None:
    try:
        if out.is_dir() and not any(out.iterdir()):
            out.rmdir()
    except OSError:
        pass


def _print_summary(result, out: Path, written, notes) -> None:
    from tt_mujoco.metrics import summary_table

    s = result.scenario
    print(
        f"{s.traj} | {s.controller} | {s.target} target | {s.plant} plant | "
        f"eta={result.config['nominal_params']['eta']:g} | disturbance={s.disturbance} | "
        f"status={result.status}"
    )
    print(summary_table(result.metrics, keys=[k for k in SUMMARY_KEYS if k in result.metrics]))
    for note in notes:
        print(f"note: {note}")
    print(f"wrote {len(written)} files to {out}/")


if __name__ == "__main__":
    sys.exit(main())

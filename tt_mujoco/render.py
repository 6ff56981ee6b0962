"""``python -m tt_mujoco.render RUN_DIR``: re-render a finished run's video from its time series."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from tt_mujoco import guard
from tt_mujoco.outputs import read_timeseries, run_timeseries_file
from tt_mujoco.viz.render import (
    CAMERAS,
    RenderUnavailable,
    check_trace,
    params_from_config,
    reference_polyline_for,
    render_video,
    run_labels,
)
from tt_mujoco.world.builtin import run_world


def _check_rows(ts, steps) -> str:
    """Why a time series cannot be rendered as the run it claims to be, or ""."""
    n = len(ts.get("t", ()))
    if isinstance(steps, int) and n < steps:
        return f"has {n} rows but metrics.json says the run took {steps} steps: the file is cut"
    for name in ("t", "x", "y", "theta", "phi", "beta", "x0", "y0", "theta0"):
        if name in ts:
            bad = np.flatnonzero(~np.isfinite(ts[name]))
            if bad.size:
                return f"row {int(bad[0]) + 2} holds {float(ts[name][bad[0]])!r} in column {name!r}"
    return ""


@guard.command
def main(argv: list[str] | None = None) -> int:
    """``python -m tt_mujoco.render RUN_DIR``: re-render a finished run's video.

    Exit codes: 0 written; 2 bad input (missing files, bad options, output exists); 1 no
    OpenGL backend works here.
    """
    parser = argparse.ArgumentParser(
        prog="python -m tt_mujoco.render",
        description="Re-render a finished run (RUN_DIR/timeseries.parquet or .csv and "
        "RUN_DIR/metrics.json) "
        "as an H.264 MP4. Never overwrites a file.",
    )
    parser.add_argument("run_dir", type=Path, metavar="RUN_DIR")
    parser.add_argument("--camera", choices=CAMERAS, default="follow")
    parser.add_argument("--width", type=int, default=640)
    parser.add_argument("--height", type=int, default=480)
    parser.add_argument("--fps", type=float, default=30.0)
    parser.add_argument("--out", type=Path, default=None, help="default RUN_DIR/video.mp4")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    args = parser.parse_args(argv)

    def fail(message: str, code: int = 2) -> int:
        print(f"tt_mujoco.render: {message}", file=sys.stderr)
        return code

    run_dir: Path = args.run_dir
    out = args.out if args.out is not None else run_dir / "video.mp4"
    if out.exists():
        hint = "" if args.out is not None else "; name a new file with --out FILE"
        return fail(f"{out} exists and is never overwritten{hint}")
    ts_path = run_timeseries_file(run_dir)
    metrics_path = run_dir / "metrics.json"
    for needed in (ts_path, metrics_path):
        if not needed.is_file():
            return fail(f"{needed} not found: RUN_DIR must be a finished run's folder")
    try:
        doc = json.loads(metrics_path.read_text())
        if not isinstance(doc, dict) or not isinstance(doc.get("config", {}), dict):
            return fail(f"{metrics_path} is not a run's metrics (a JSON object with a config)")
        config = doc.get("config", {})
        # The simulation loop records the plant's parameters as "plant_params" (the vehicle
        # that moved) and the path in its scenario; the plain "params"/"traj" also work.
        raw_params = config.get("plant_params", config.get("params"))
        if raw_params is None:
            return fail(f"{metrics_path} has no config.plant_params or config.params")
        params = params_from_config(raw_params)
        ts = read_timeseries(ts_path)
        problem = _check_rows(ts, doc.get("steps"))
        if problem:
            return fail(f"{ts_path}: {problem}")
        problem = check_trace(params, ts)
        if problem:
            return fail(f"{metrics_path}: {problem}")
        polyline, source = reference_polyline_for(ts, run_dir)
        print(f"reference path: {source}", file=sys.stderr)
        info, outcome = run_labels(
            config.get("scenario", {}), doc.get("status"), str(doc.get("message", ""))
        )
        render_video(
            ts,
            params,
            polyline,
            out,
            width=args.width,
            height=args.height,
            fps=args.fps,
            camera=args.camera,
            progress=not args.no_progress,
            info=info,
            outcome=outcome,
            terrain=config.get("scenario", {}).get("terrain", "flat"),
            world=run_world(run_dir, config.get("scenario", {}).get("world", "none")),
        )
    except (ValueError, FileExistsError, json.JSONDecodeError) as exc:
        return fail(str(exc))
    except OSError as exc:  # an --out the file system refuses
        return fail(f"{out}: {exc.strerror}")
    except RenderUnavailable as exc:
        return fail(f"rendering unavailable: {exc}", code=1)
    print(out)
    return 0


if __name__ == "__main__":
    sys.exit(main())

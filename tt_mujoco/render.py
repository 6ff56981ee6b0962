"""``python -m tt_mujoco.render RUN_DIR``: re-render a finished run's video from its time series."""

from __future__ import annotations

import sys
from pathlib import Path

from tt_mujoco import guard
from tt_mujoco.cliargs import Parser
from tt_mujoco.runfolder import check_out, default_out, read_run
from tt_mujoco.viz.render import (
    CAMERAS,
    RenderUnavailable,
    RunScene,
    VideoFormat,
    render_video,
    run_labels,
)


@guard.command
def main(argv: list[str] | None = None) -> int:
    """``python -m tt_mujoco.render RUN_DIR``: re-render a finished run's video.

    Exit codes: 0 written; 2 bad input (missing files, bad options, output exists); 1 no
    OpenGL backend works here.
    """
    parser = Parser(
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
    parser.add_argument(
        "--out",
        type=Path,
        default=None,
        help="a new file outside the run folder (default: RUN_DIR.CAMERA.mp4 beside it)",
    )
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    args = parser.parse_args(argv)

    def fail(message: str, code: int = 2) -> int:
        print(f"error: {message}", file=sys.stderr)
        return code

    run_dir: Path = args.run_dir
    out = args.out if args.out is not None else default_out(run_dir, args.camera, ".mp4")
    try:
        if out.exists() or out.is_symlink():
            hint = "" if args.out is not None else "; name a new file with --out FILE"
            return fail(f"{out} exists and is never overwritten{hint}")
        check_out(out, ".mp4")
        video = VideoFormat(args.width, args.height, args.fps, args.camera)
        run = read_run(run_dir)
        info, outcome = run_labels(run.scenario, run.status, run.message)
        scene = RunScene(
            run.params,
            run.reference,
            info=info,
            terrain=run.scenario.get("terrain", "flat"),
            world=run.world,
        )
        print(f"reference path: {run.reference_source}", file=sys.stderr)
        render_video(run.timeseries, scene, out, video, outcome, progress=not args.no_progress)
    except (ValueError, FileExistsError) as exc:  # RunFolderError and BadInputError included
        return fail(str(exc))
    except OSError as exc:  # an --out the file system refuses
        return fail(f"{out}: {exc.strerror}")
    except RenderUnavailable as exc:
        return fail(f"rendering unavailable: {exc}", code=1)
    print(out)
    return 0


if __name__ == "__main__":
    guard.end(main())

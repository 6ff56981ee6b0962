"""Rendering speed: milliseconds per frame for both cameras, and the MP4 encode time.

    python benchmarks/bench_render.py [--frames 150] [--width 640 --height 480] [--rounds 3]

A frame is everything :meth:`tt_mujoco.viz.render.RunRenderer.render_frame` does: pose the vehicle
(mj_kinematics), build the scene with the path and traces, render offscreen, read the pixels
back and draw the text overlay. Encoding is timed separately, on frames held in memory, with
the same ffmpeg (imageio-ffmpeg's), once with mediapy's default settings and once with those of
:func:`tt_mujoco.viz.render.render_video` (the encoder's CPU, the file's size and the decoded
picture's PSNR); in a real render the encoder runs in its own process, beside the rendering.
The series is the reduced model under constant torques (10 s), so the numbers do not depend on
the simulation loop. On a shared machine the load average is printed with the results: the
minimum over rounds is the best estimate of the cost, the median of what a user sees.
"""

from __future__ import annotations

import argparse
import os
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from tt_mujoco.vehicle.params import Params
from tt_mujoco.viz import demo, render


def time_frames(renderer: render.RunRenderer, frames: int, rounds: int) -> list[float]:
    """Milliseconds per frame of ``rounds`` passes over the first ``frames`` frames."""
    for k in range(min(5, renderer.n_frames)):  # warm up: first-use costs of the GL context
        renderer.render_frame(k)
    out = []
    for _ in range(rounds):
        start = time.perf_counter()
        for k in range(frames):
            renderer.render_frame(k)
        out.append(1e3 * (time.perf_counter() - start) / frames)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--frames", type=int, default=150)
    parser.add_argument("--width", type=int, default=640)
    parser.add_argument("--height", type=int, default=480)
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()

    start = time.perf_counter()
    backend = render.select_gl_backend()
    print(
        f"GL backend: {backend} (MUJOCO_GL={os.environ.get('MUJOCO_GL', '<unset>')}), "
        f"selected in {time.perf_counter() - start:.2f} s"
    )
    print(f"load average before: {os.getloadavg()[0]:.2f} on {os.cpu_count()} CPUs")

    ts, polyline = demo.open_loop_timeseries(duration=10.0, dt=0.01)
    size = f"{args.width}x{args.height}"
    kept = None
    for camera in render.CAMERAS:
        with render.RunRenderer(
            ts,
            render.RunScene(Params(), polyline),
            render.VideoFormat(args.width, args.height, 30, camera),
        ) as renderer:
            frames = min(args.frames, renderer.n_frames)
            ms = time_frames(renderer, frames, args.rounds)
            print(
                f"{camera:9s} {size}: {min(ms):5.1f} ms/frame min, "
                f"{statistics.median(ms):5.1f} median over {args.rounds} x {frames} frames"
            )
            if kept is None:
                kept = [renderer.render_frame(k) for k in range(frames)]

    import imageio_ffmpeg
    import mediapy

    mediapy.set_ffmpeg(imageio_ffmpeg.get_ffmpeg_exe())
    with tempfile.TemporaryDirectory() as tmp:
        # mediapy's own default (x264's "medium" preset at quantiser 20) against the renderer's
        # setting, on the same frames: the encoder's CPU (its own process), the file, and the
        # picture decoded against the frames given (PSNR).
        source = np.stack(kept).astype(float)
        settings = {
            "default": {},
            f"{render.H264_PRESET}": {
                "qp": render.H264_QP,
                "ffmpeg_args": ["-preset", render.H264_PRESET],
            },
        }
        for name, options in settings.items():
            out = Path(tmp) / f"encode-{name}.mp4"
            before, start = os.times(), time.perf_counter()
            with mediapy.VideoWriter(out, shape=kept[0].shape[:2], fps=30, **options) as writer:
                for image in kept:
                    writer.add_image(image)
            seconds, after = time.perf_counter() - start, os.times()
            cpu = after.children_user + after.children_system
            cpu -= before.children_user + before.children_system
            decoded = imageio_ffmpeg.read_frames(str(out))
            height, width = next(decoded)["size"][::-1]
            got = np.stack([np.frombuffer(f, np.uint8).reshape(height, width, 3) for f in decoded])
            mse = float(np.mean((got[: len(source)].astype(float) - source) ** 2))
            print(
                f"encode    {size} {name:9s}: {len(kept)} frames in {seconds:.2f} s, encoder "
                f"CPU {1e3 * cpu / len(kept):.1f} ms/frame, {out.stat().st_size / 1e3:.0f} kB, "
                f"PSNR {10 * np.log10(255.0**2 / mse):.1f} dB"
            )
        start = time.perf_counter()
        video = render.render_video(
            ts,
            render.RunScene(Params(), polyline),
            Path(tmp) / "full.mp4",
            render.VideoFormat(args.width, args.height, 30, "follow"),
            progress=False,
        )
        seconds = time.perf_counter() - start
        n = len(render.frame_schedule(ts["t"], 30)[0])
        print(
            f"render_video follow {size}, {ts['t'][-1]:.0f} s run: {n} frames in {seconds:.2f} s "
            f"({1e3 * seconds / n:.1f} ms/frame incl. setup and encoding), "
            f"{video.stat().st_size / 1e3:.0f} kB"
        )
    print(f"load average after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()

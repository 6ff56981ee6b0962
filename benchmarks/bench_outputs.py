"""The main command with its video and figures against the same command without them.

    python benchmarks/bench_outputs.py [--pairs 3]

Runs ``python -m tt_mujoco.run --traj s_curve --quiet`` (the README's main command: video and
four figures) and the same with ``--no-video --no-plots`` one after the other, ``--pairs``
times, and prints each whole-process wall time and the ratio of each pair (the machine's speed
drifts: a ratio taken pair by pair holds when the absolute times do not). It also times the
video alone (``--no-plots``) and the figures alone (``--no-video``) once each, to show what
overlaps: the figures are drawn in a forked process while the video renders.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

MAIN = [sys.executable, "-m", "tt_mujoco.run", "--traj", "s_curve", "--quiet"]


def wall(extra: list[str], tmp: Path, name: str) -> float:
    """Whole-process seconds of the main command with ``extra``, into a new folder."""
    start = time.perf_counter()
    subprocess.run([*MAIN, *extra, "--out", str(tmp / name)], check=True, stdout=subprocess.DEVNULL)
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--pairs", type=int, default=3)
    args = parser.parse_args()
    print(f"load average before: {os.getloadavg()[0]:.2f} on {os.cpu_count()} CPUs")
    with tempfile.TemporaryDirectory() as folder:
        tmp = Path(folder)
        wall([], tmp, "warm-up")  # the compiled kernel and the OS's file cache, once
        ratios = []
        for i in range(args.pairs):
            full = wall([], tmp, f"full-{i}")
            bare = wall(["--no-video", "--no-plots"], tmp, f"bare-{i}")
            ratios.append(full / bare)
            print(
                f"pair {i + 1}: with video and figures {full:.2f} s, without {bare:.2f} s, "
                f"ratio {full / bare:.2f}"
            )
        print(f"median ratio {statistics.median(ratios):.2f} over {args.pairs} pairs")
        video = wall(["--no-plots"], tmp, "video")
        figures = wall(["--no-video"], tmp, "figures")
        print(f"video alone {video:.2f} s, figures alone {figures:.2f} s")
    print(f"load average after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()

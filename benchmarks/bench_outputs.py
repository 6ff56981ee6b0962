"""The main command with its video and figures against the same command without them.

    python benchmarks/bench_outputs.py [--pairs 3]

Runs ``python -m tt_mujoco.run --traj s_curve --quiet`` (the README's main command: video and
four figures) and the same with ``--no-video --no-plots`` one after the other, ``--pairs``
times, and prints each whole-process wall time and the ratio of each pair (the machine's speed
drifts: a ratio taken pair by pair holds when the absolute times do not). It also times the
video alone (``--no-plots``) and the figures alone (``--no-video``) once each, to show what
overlaps: the figures are drawn in a forked process while the video renders. Beside each wall
time it prints the CPU seconds the command and its children used (the renderer's threads and
the encoder included): the CPU the video and figures add, over the machine's cores, is the
least wall time they can add however they overlap.
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

MAIN = [sys.executable, "-m", "tt_mujoco.run", "--traj", "s_curve", "--quiet"]


def _children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def wall(extra: list[str], tmp: Path, name: str) -> tuple[float, float]:
    """Whole-process wall and CPU seconds of the main command with ``extra``, into a new
    folder."""
    cpu, start = _children_cpu(), time.perf_counter()
    subprocess.run([*MAIN, *extra, "--out", str(tmp / name)], check=True, stdout=subprocess.DEVNULL)
    return time.perf_counter() - start, _children_cpu() - cpu


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--pairs", type=int, default=3)
    args = parser.parse_args()
    print(f"load average before: {os.getloadavg()[0]:.2f} on {os.cpu_count()} CPUs")
    with tempfile.TemporaryDirectory() as folder:
        tmp = Path(folder)
        wall([], tmp, "warm-up")  # the compiled kernel and the OS's file cache, once
        ratios, added_cpu, bares = [], [], []
        for i in range(args.pairs):
            full, full_cpu = wall([], tmp, f"full-{i}")
            bare, bare_cpu = wall(["--no-video", "--no-plots"], tmp, f"bare-{i}")
            ratios.append(full / bare)
            added_cpu.append(full_cpu - bare_cpu)
            bares.append(bare)
            print(
                f"pair {i + 1}: with video and figures {full:.2f} s ({full_cpu:.2f} s CPU), "
                f"without {bare:.2f} s ({bare_cpu:.2f} s CPU), ratio {full / bare:.2f}"
            )
        print(f"median ratio {statistics.median(ratios):.2f} over {args.pairs} pairs")
        cores = os.cpu_count() or 1
        least = statistics.median(added_cpu) / cores
        print(
            f"the video and figures add {statistics.median(added_cpu):.2f} s of CPU (median): "
            f"on {cores} cores at least {least:.2f} s of wall, a ratio of at least "
            f"{1 + least / statistics.median(bares):.2f} to the median run without them"
        )
        video, video_cpu = wall(["--no-plots"], tmp, "video")
        figures, figures_cpu = wall(["--no-video"], tmp, "figures")
        print(
            f"video alone {video:.2f} s ({video_cpu:.2f} s CPU), figures alone {figures:.2f} s "
            f"({figures_cpu:.2f} s CPU)"
        )
    print(f"load average after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()

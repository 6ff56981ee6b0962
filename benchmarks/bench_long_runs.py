"""A run's cost against its length: wall time and peak memory grow with the simulated time.

Run: ``python benchmarks/bench_long_runs.py [--longest]``. Each run is the CLI as users run it,
``python -m tt_mujoco.run --traj circle --duration D --no-video --no-plots``, in a fresh
process; the wall time is the whole process's and the peak memory its maximum resident set
(``os.wait4``). It prints, for D = 60 s and 240 s of the circle (20 laps: the metrics then
measure against a path that overlaps itself):

- the wall-time ratio 240 s / 60 s (linear: 4);
- the growth of the peak memory from 60 s to 240 s against the growth of the time series' own
  bytes (float64 columns, rows x columns x 8): how many times the extra rows' size the extra
  memory is.

``--longest`` also runs the longest run the caps allow (600 s) on every built-in path and prints
each wall time. Ratios are taken in one run of this script, so a busy machine moves both alike.
"""

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from tt_mujoco.outputs import read_timeseries


def cli_run(traj: str, duration: float, out: Path) -> tuple[float, float, int, int]:
    """(wall s, peak resident MB, rows, columns) of one CLI run in a fresh process."""
    cmd = [sys.executable, "-m", "tt_mujoco.run", "--traj", traj, "--duration", str(duration)]
    cmd += ["--no-video", "--no-plots", "--quiet", "--out", str(out)]
    start = time.perf_counter()
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL)
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - start
    if os.waitstatus_to_exitcode(status) != 0:
        raise SystemExit(f"{cmd}: exit {os.waitstatus_to_exitcode(status)}")
    ts = read_timeseries(out / "timeseries.parquet")
    return wall, usage.ru_maxrss / 1024.0, len(ts["t"]), len(ts)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--longest", action="store_true", help="also 600 s on every built-in path")
    args = p.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        cli_run("circle", 5.0, Path(tmp) / "warm")  # the compiled code's cache, filled
        results = {}
        for duration in (60.0, 240.0):
            results[duration] = cli_run("circle", duration, Path(tmp) / f"circle-{duration:g}")
            wall, peak, rows, _ = results[duration]
            print(f"circle {duration:5.0f} s: {rows} rows, wall {wall:.2f} s, peak {peak:.0f} MB")
        (w1, m1, r1, c1), (w2, m2, r2, _) = results[60.0], results[240.0]
        print(f"wall-time ratio 240 s / 60 s: {w2 / w1:.2f} (linear: 4.00)")
        grown = (r2 - r1) * c1 * 8 / 2**20
        print(
            f"peak memory grew {m2 - m1:.0f} MB for {grown:.0f} MB more time series: "
            f"{(m2 - m1) / grown:.2f} times its bytes"
        )
        if args.longest:
            for traj in ("s_curve", "cycloid", "circle"):
                wall, peak, rows, _ = cli_run(traj, 600.0, Path(tmp) / f"{traj}-600")
                print(f"{traj:8s} 600 s: {rows} rows, wall {wall:.1f} s, peak {peak:.0f} MB")


if __name__ == "__main__":
    main()

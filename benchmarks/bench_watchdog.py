"""What the watchdog costs a single command: the README's main command without video or
figures, whole process, each run in a new process, watched (the default) against
``TT_MUJOCO_WATCHDOG=0`` (one process), taken in pairs so that the machine's drift moves both.

Run: ``python benchmarks/bench_watchdog.py [--pairs N]``.
"""

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

COMMAND = [sys.executable, "-m", "tt_mujoco.run", "--no-video", "--no-plots", "--quiet"]


def whole(out: Path, watched: bool) -> float:
    env = {**os.environ, "TT_MUJOCO_WATCHDOG": "1" if watched else "0"}
    shutil.rmtree(out, ignore_errors=True)
    start = time.perf_counter()
    subprocess.run([*COMMAND, "--out", str(out)], env=env, check=True, capture_output=True)
    return time.perf_counter() - start


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--pairs", type=int, default=15)
    args = p.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "run"
        whole(out, True), whole(out, False)  # warm the file cache and the compiled code's
        watched, alone = [], []
        for _ in range(args.pairs):
            watched.append(whole(out, True))
            alone.append(whole(out, False))
    ratios = [w / a for w, a in zip(watched, alone, strict=True)]
    print(f"main command, whole process, median of {args.pairs} pairs:")
    print(f"  watched (the default)        {statistics.median(watched):.3f} s")
    print(f"  one process (WATCHDOG=0)     {statistics.median(alone):.3f} s")
    print(f"  watched / one process        {statistics.median(ratios):.3f}")


if __name__ == "__main__":
    main()

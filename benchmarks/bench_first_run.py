"""The first run after an install against later ones: is the compile out of the user's way?

Run: ``python benchmarks/bench_first_run.py [--tries N]``. Each try times, in new processes,
the main command without video (``python -m tt_mujoco.run --traj s_curve --no-video
--no-plots``): once with a new, empty compiled-code cache (``TT_MUJOCO_CACHE``), then, once the
background compile that run started has filled it, once more (a warm run); then once with the
Python loop (``TT_MUJOCO_COMPILED=0``), and once from a copy of the package whose kernel source
differs by a comment (another checkout, byte-compiled as an install leaves it, meeting a cache
that holds only this checkout's kernel). It prints each try's wall times and the medians, over
the tries, of the empty-cache and the stale-cache run against the same try's warm run: the
machine is shared, and a run's time moves by tenths of a second from one minute to the next.
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

from tt_mujoco.sim.loop import compiled

ROOT = Path(__file__).resolve().parents[1]


def timed_run(env: dict, out: Path, cwd: Path | None = None) -> float:
    cmd = [sys.executable, "-m", "tt_mujoco.run", "--traj", "s_curve", "--no-video"]
    cmd += ["--no-plots", "--quiet", "--out", str(out)]
    start = time.perf_counter()
    subprocess.run(cmd, env=env, check=True, stdout=subprocess.DEVNULL, cwd=cwd)
    return time.perf_counter() - start


def other_checkout(tmp: Path) -> Path:
    """A copy of the package and its models whose kernel source differs by a comment."""
    checkout = tmp / "checkout"
    for name in ("tt_mujoco", "models"):
        shutil.copytree(ROOT / name, checkout / name, ignore=shutil.ignore_patterns("__pycache__"))
    kernel = checkout / "tt_mujoco" / "sim" / "_kernel.py"
    kernel.write_text(kernel.read_text() + "\n# another checkout\n")
    subprocess.run([sys.executable, "-m", "compileall", "-q", str(checkout)], check=True)
    return checkout


def wait_for_compiles(cache: Path) -> None:
    """Wait until no background compile is filling a folder of ``cache``."""
    folders = (cache / "numba").glob("*")
    while any(compiled.compile_in_progress(folder) for folder in folders):
        time.sleep(1.0)
        folders = (cache / "numba").glob("*")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--tries", type=int, default=3, help="tries, each a new cache (default 3)")
    args = p.parse_args()
    cold, stale = [], []
    with tempfile.TemporaryDirectory() as tmp:
        checkout = other_checkout(Path(tmp))
        for j in range(args.tries):
            cache = Path(tmp) / f"cache-{j}"
            env = {**os.environ, "TT_MUJOCO_CACHE": str(cache)}
            env.pop("TT_MUJOCO_COMPILE_NOW", None)
            first = timed_run(env, Path(tmp) / f"first-{j}")
            wait_for_compiles(cache)  # the one the first run started
            warm = timed_run(env, Path(tmp) / f"warm-{j}")
            python = timed_run({**env, "TT_MUJOCO_COMPILED": "0"}, Path(tmp) / f"python-{j}")
            other = {**env, "PYTHONPATH": str(checkout)}
            other_wall = timed_run(other, Path(tmp) / f"other-{j}", cwd=checkout)
            wait_for_compiles(cache)  # the one that run started
            cold.append(first / warm)
            stale.append(other_wall / warm)
            print(
                f"try {j + 1}: empty cache {first:.2f} s, warm {warm:.2f} s, Python loop "
                f"{python:.2f} s, another checkout's stale cache {other_wall:.2f} s",
                flush=True,
            )
    print(
        f"median over {args.tries} tries, against the same try's warm run: empty cache "
        f"{statistics.median(cold):.2f}x, stale cache {statistics.median(stale):.2f}x"
    )


if __name__ == "__main__":
    main()

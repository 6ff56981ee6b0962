"""The first run after an install against later ones: is the compile out of the user's way?

Run: ``python benchmarks/bench_first_run.py``. It runs the main command without video
(``python -m tt_mujoco.run --traj s_curve --no-video --no-plots``) three times with a new, empty
compiled-code cache (``TT_MUJOCO_CACHE``), waiting after each for the background compile the
first one starts, then once with the Python loop (``TT_MUJOCO_COMPILED=0``), then once from a copy
of the package whose kernel source differs by a comment (another checkout, byte-compiled as an
install leaves it, meeting a cache that holds only this checkout's kernel), and prints each wall
time.
"""

import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from tt_mujoco.sim import compiled

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
    with tempfile.TemporaryDirectory() as tmp:
        env = {**os.environ, "TT_MUJOCO_CACHE": str(Path(tmp) / "cache")}
        env.pop("TT_MUJOCO_COMPILE_NOW", None)
        for label in ("first run (empty cache)", "second run", "third run"):
            print(f"{label:28s} {timed_run(env, Path(tmp) / label.split()[0]):.2f} s")
            wait_for_compiles(Path(tmp) / "cache")  # the one the first run started
        python = {**env, "TT_MUJOCO_COMPILED": "0"}
        print(f"{'Python loop':28s} {timed_run(python, Path(tmp) / 'python'):.2f} s")
        checkout = other_checkout(Path(tmp))
        other = {**env, "PYTHONPATH": str(checkout)}
        wall = timed_run(other, Path(tmp) / "other", cwd=checkout)
        print(f"{'another checkout, stale cache':28s} {wall:.2f} s")
        wait_for_compiles(Path(tmp) / "cache")  # the one that run started, before cleaning up


if __name__ == "__main__":
    main()

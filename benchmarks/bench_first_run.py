"""The first run after an install against later ones: is the compile out of the user's way?

Run: ``python benchmarks/bench_first_run.py``. It runs the main command without video
(``python -m tt_mujoco.run --traj s_curve --no-video --no-plots``) three times with a new, empty
compiled-code cache (``TT_MUJOCO_CACHE``), waiting between runs for the background compile the
first one starts, then once with the Python loop (``TT_MUJOCO_COMPILED=0``), and prints each wall
time.
"""

import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def timed_run(env: dict, out: Path) -> float:
    cmd = [sys.executable, "-m", "tt_mujoco.run", "--traj", "s_curve", "--no-video"]
    cmd += ["--no-plots", "--quiet", "--out", str(out)]
    start = time.perf_counter()
    subprocess.run(cmd, env=env, check=True, stdout=subprocess.DEVNULL)
    return time.perf_counter() - start


def main() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        env = {**os.environ, "TT_MUJOCO_CACHE": str(Path(tmp) / "cache")}
        env.pop("TT_MUJOCO_COMPILE_NOW", None)
        for label in ("first run (empty cache)", "second run", "third run"):
            print(f"{label:28s} {timed_run(env, Path(tmp) / label.split()[0]):.2f} s")
            time.sleep(10)  # the background compile the first run started
        python = {**env, "TT_MUJOCO_COMPILED": "0"}
        print(f"{'Python loop':28s} {timed_run(python, Path(tmp) / 'python'):.2f} s")


if __name__ == "__main__":
    main()

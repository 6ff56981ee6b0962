"""Single commands as a user runs them: each a fresh process, against what it cannot beat.

Run: ``python benchmarks/bench_cold_start.py [--tries N]``. After one warm-up round (so that the
compiled-code cache holds the kernel and the plain law, as on any run after the first), each
try runs, one after the other in new processes:

- ``python -c "import numpy, mujoco"``: what any MuJoCo program pays before its first line;
- ``python -m tt_mujoco.run --help``;
- the README's main command without video (``--traj s_curve --no-video``), and the same with
  ``--no-plots``; its episode's physics floor, MuJoCo's C rollout of the run's own inputs on one
  thread (``bench_cli.floor``, checked to end in the run's final state), is timed in this
  process from that run's time series. It runs the chunk loop's machine code, loaded without
  numba (``tt_mujoco/sim/loop/machine_code.py``);
- the same run with the Python loop forced (``TT_MUJOCO_COMPILED=0``), whose ``wall_time_s``
  the chosen route's should not exceed;
- a long run, 40 s on the circle (``--traj circle --duration 40``, 40,001 steps), against the
  same run in the Python loop and its own C floor;
- that long run with ``--controller examples/kanayama.py:kanayama_law`` (a plain-number law,
  its machine code loaded from the cache like the loop's) against the built-in law's;
- the main run with a train of three trailers (``--trailers 3``) against its own C floor.

Each figure is the median over the tries of a ratio taken within one try: the machine is shared,
and whole-process times drift by tenths of a second from one minute to the next.
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from bench_cli import floor  # the episode's C rollout, checked against the run

from tt_mujoco.outputs import read_timeseries

ROOT = Path(__file__).resolve().parents[1]
MAIN = ["--traj", "s_curve", "--no-video", "--quiet"]
LONG = ["--traj", "circle", "--duration", "40", "--no-video", "--no-plots", "--quiet"]
LAW = ["--controller", f"{ROOT}/examples/kanayama.py:kanayama_law"]
#: The main run with a train of three trailers (issue 52's third cold case).
TRAIN = ["--trailers", "3"]


#: What a shell here may set that a user's does not: a compile forced into the run, and no
#: bytecode written (every module compiled from source in every process: the warm-up round
#: writes the package's, as a user's first run, or pip's install, does).
NOT_A_USERS = ("TT_MUJOCO_COMPILE_NOW", "PYTHONDONTWRITEBYTECODE")


def user_env(**extra) -> dict:
    """The environment a user's shell gives (:data:`NOT_A_USERS` dropped)."""
    env = {k: v for k, v in os.environ.items() if k not in NOT_A_USERS}
    return {**env, **extra}


def timed(cmd: list[str], env: dict | None = None) -> float:
    """Wall seconds of ``cmd`` as a new process."""
    start = time.perf_counter()
    subprocess.run(cmd, env=env or user_env(), check=True, stdout=subprocess.DEVNULL)
    return time.perf_counter() - start


def run(argv: list[str], out: Path, env: dict | None = None) -> tuple[float, float]:
    """(whole-process seconds, the run's ``wall_time_s``) of ``python -m tt_mujoco.run``."""
    whole = timed([sys.executable, "-m", "tt_mujoco.run", *argv, "--out", str(out)], env)
    return whole, json.loads((out / "metrics.json").read_text())["wall_time_s"]


def one_try(tmp: Path, j: int) -> dict:
    py = sys.executable
    importing = timed([py, "-c", "import numpy, mujoco"])
    helping = timed([py, "-m", "tt_mujoco.run", "--help"])
    plots, _ = run(MAIN, tmp / f"plots-{j}")
    main_whole, main_loop = run([*MAIN, "--no-plots"], tmp / f"main-{j}")
    series = read_timeseries(tmp / f"main-{j}" / "timeseries.parquet")
    c_floor = floor(["--traj", "s_curve"], series)
    python_env = user_env(TT_MUJOCO_COMPILED="0")
    _, python_loop = run([*MAIN, "--no-plots"], tmp / f"python-{j}", python_env)
    long_whole, long_loop = run(LONG, tmp / f"long-{j}")
    long_series = read_timeseries(tmp / f"long-{j}" / "timeseries.parquet")
    long_floor = floor(["--traj", "circle", "--duration", "40"], long_series)
    _, long_python = run(LONG, tmp / f"long-python-{j}", python_env)
    law_whole, law_loop = run([*LONG, *LAW], tmp / f"law-{j}")
    _, train_loop = run([*MAIN, "--no-plots", *TRAIN], tmp / f"train-{j}")
    train_series = read_timeseries(tmp / f"train-{j}" / "timeseries.parquet")
    train_floor = floor(["--traj", "s_curve", *TRAIN], train_series)
    figures = {
        "import numpy, mujoco (s)": importing,
        "C floor of the main episode (s)": c_floor,
        "--help / import": helping / importing,
        "main command, no video / (import + floor)": plots / (importing + c_floor),
        "main command, no video, no plots / (import + floor)": main_whole / (importing + c_floor),
        "main run's wall_time_s: floor / loop": c_floor / main_loop,
        "main run's wall_time_s / the forced Python loop's": main_loop / python_loop,
        "40 s run's wall_time_s: floor / loop": long_floor / long_loop,
        "40 s run's wall_time_s / the forced Python loop's": long_loop / long_python,
        "40 s run, whole process / (import + floor)": long_whole / (importing + long_floor),
        "40 s kanayama_law, whole process / the built-in law's": law_whole / long_whole,
        "40 s kanayama_law's wall_time_s: floor / loop": long_floor / law_loop,
        "main run, 3 trailers, wall_time_s: floor / loop": train_floor / train_loop,
    }
    print(
        f"try {j + 1}: import {importing:.3f} s, --help {helping:.3f} s, main {plots:.2f} s "
        f"(no plots {main_whole:.2f} s, its loop {main_loop:.3f} s, forced Python loop "
        f"{python_loop:.3f} s, floor {c_floor:.3f} s); 40 s run {long_whole:.2f} s (loop "
        f"{long_loop:.3f} s, Python loop {long_python:.3f} s, floor {long_floor:.3f} s), "
        f"kanayama_law {law_whole:.2f} s (loop {law_loop:.3f} s); 3 trailers: loop "
        f"{train_loop:.3f} s, floor {train_floor:.3f} s",
        flush=True,
    )
    return figures


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--tries", type=int, default=5, help="tries after the warm-up (default 5)")
    args = p.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        tmp = Path(folder)
        from tt_mujoco.sim.loop import compiled

        # Each fills the cache if it lacks its entry, by a background compile: waited for.
        for argv, name in ((LONG, "warm-main"), ([*MAIN, "--no-plots", *TRAIN], "warm-train")):
            run(argv, tmp / name)
            while compiled.compile_in_progress(compiled._cache_dir()):
                time.sleep(1.0)
        run([*LONG, *LAW], tmp / "warm-law")  # compiles the law once
        tries = [one_try(tmp, j) for j in range(args.tries)]
    print(f"medians over {args.tries} tries:")
    for name in tries[0]:
        print(f"  {name:<55} {statistics.median(t[name] for t in tries):8.3f}")


if __name__ == "__main__":
    main()

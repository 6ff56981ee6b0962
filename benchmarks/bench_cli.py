"""Runs through the CLI against their physics floor: MuJoCo's C rollout of their own inputs.

Run: ``python benchmarks/bench_cli.py [--repeats N] [CASE ...]``. For each case (a command line
of ``python -m tt_mujoco.run``, with ``--no-video --no-plots``), in this one process:

1. runs it once through :func:`tt_mujoco.run.main` to warm the process (the compiled code is
   loaded once per process), then ``--repeats`` times ``--tries`` times more, each run
   followed at once by its yardstick (below): each figure is the median of ``--tries`` such
   pairs' ratios, so that a burst of load on a shared machine moves a pair, not the figure;
2. takes the episode's inputs from its own ``timeseries.parquet`` (the wheel torques ``T_r,
   T_l`` and the matched disturbance ``dist_T_r, dist_T_l`` of every control step, held over its
   physics steps) and replays them from the run's initial state with ``mujoco.rollout`` on one
   thread: MuJoCo is deterministic, so the rollout ends in the run's final state (checked, bit
   for bit), and its cost is the physics of that episode and nothing else;
3. prints the CLI's simulation time (``wall_time_s`` of ``metrics.json``: the loop as the user
   runs it), the whole ``main()`` call's, the rollout's, and the ratio floor / loop (1.0: the
   loop costs nothing beyond MuJoCo's own stepping). The reduced-plant case prints its loop's
   speed against the MuJoCo case's instead (it has no MuJoCo floor), and the path-scheduled
   case (``--eta path``) and the wind case against the same command in the Python loop
   (``TT_MUJOCO_COMPILED=0``) and the main case's loop: the path schedule's axles' targets are
   set from the hitches before every physics step and the wind pushes the bodies, which a
   rollout of the logged inputs cannot replay.

Ratios are taken in one process, so a busy machine moves both sides alike.
"""

import argparse
import contextlib
import io
import json
import math
import os
import statistics
import tempfile
import time
from pathlib import Path
from typing import NamedTuple

os.environ.setdefault("TT_MUJOCO_COMPILE_NOW", "1")  # compile here, not in the background

import mujoco
import numpy as np
from mujoco import rollout

from tt_mujoco import run
from tt_mujoco.outputs import read_timeseries
from tt_mujoco.sim import build

ROOT = Path(__file__).resolve().parents[1]
CASES = {
    "main": ["--traj", "s_curve"],
    "train3": ["--traj", "s_curve", "--trailers", "3", "--no-disturbance"],
    "kanayama": [
        "--traj",
        "s_curve",
        "--controller",
        f"{ROOT}/examples/kanayama.py:KanayamaTracker",
    ],
    "kanayama_law": [
        "--traj",
        "s_curve",
        "--controller",
        f"{ROOT}/examples/kanayama.py:kanayama_law",
    ],
    # a user's reversing law that reads the path (examples/backing_law.py): no hitch cascade
    "backing_law": [
        "--traj",
        "s_curve",
        "--reverse",
        "--controller",
        f"{ROOT}/examples/backing_law.py:backing_law",
    ],
    # the built-ins added as a module or class and a registry line (docs/extending.md): a law
    # that sees the path, a path read from fine cells, a disturbance's form the step computes
    "pure_pursuit": ["--traj", "s_curve", "--controller", "pure_pursuit"],
    "clothoid": ["--traj", "clothoid"],
    "rolling": ["--traj", "s_curve", "--disturbance-model", "rolling"],
    "reduced": ["--traj", "s_curve", "--plant", "reduced"],
    "path": ["--traj", "s_curve", "--eta", "path"],
    "reverse": ["--traj", "s_curve", "--reverse", "--trailers", "2"],
    "delay": ["--traj", "s_curve", "--sensor-delay", "0.01"],
    "wind": ["--traj", "s_curve", "--wind", "8:90:2"],
    # a user's path and a user's disturbance, which the compiled step calls back
    "user_path": ["--traj", f"{ROOT}/examples/user_parts.py:slalom"],
    "user_disturbance": [
        "--traj",
        "s_curve",
        "--disturbance-model",
        f"{ROOT}/examples/user_parts.py:headwind_gusts",
    ],
}
#: Cases whose physics a rollout of the logged inputs cannot replay: the path schedule sets its
#: axles' targets from the hitches before every physics step, and the wind pushes the bodies
#: (forces the time series does not log); they are timed against the Python loop instead.
NO_ROLLOUT = ("path", "wind")
QUIET = ["--no-video", "--no-plots", "--quiet"]
#: What the rollout's control vector holds: the actuators' ctrl, then qfrc_applied.
CONTROL_SPEC = mujoco.mjtState.mjSTATE_CTRL | mujoco.mjtState.mjSTATE_QFRC_APPLIED
FULL = mujoco.mjtState.mjSTATE_FULLPHYSICS


def cli_run(argv: list[str], out: Path) -> tuple[float, float, dict]:
    """(whole main() seconds, the run's simulation seconds, its time series); the run's
    metrics are kept in :data:`LAST_METRICS`."""
    start = time.perf_counter()
    with contextlib.redirect_stdout(io.StringIO()):  # the summary table
        code = run.main([*argv, *QUIET, "--out", str(out)])
    whole = time.perf_counter() - start
    if code != 0:
        raise SystemExit(f"{argv}: exit {code}")
    metrics = json.loads((out / "metrics.json").read_text())
    LAST_METRICS.clear()
    LAST_METRICS.update(metrics)
    return whole, metrics["wall_time_s"], read_timeseries(out / "timeseries.parquet")


#: The metrics of the last run of :func:`cli_run`.
LAST_METRICS: dict = {}


def floor(argv: list[str], ts: dict) -> float:
    """Seconds of ``mujoco.rollout`` (one thread) of the run's inputs; checks that it ends in
    the run's last logged state."""
    built = build(run.scenario_from_argv([*argv, *QUIET]))
    plant = built.new_plant()
    m, d = plant.model, plant.data
    state = np.empty(mujoco.mj_stateSize(m, FULL))
    mujoco.mj_getState(m, d, state, FULL)
    n = len(ts["t"]) - 1  # control steps advanced: the last row is measured, not applied
    per_step = np.zeros((n, m.nu + m.nv))
    per_step[:, plant._act_r] = ts["T_r"][:n]
    per_step[:, plant._act_l] = ts["T_l"][:n]
    per_step[:, m.nu + plant._wheel_r] = ts["dist_T_r"][:n]
    per_step[:, m.nu + plant._wheel_l] = ts["dist_T_l"][:n]
    control = np.repeat(per_step, built.substeps, axis=0)[None]
    data = mujoco.MjData(m)
    warm = d.qacc_warmstart.copy()[None]
    start = time.perf_counter()
    states, _ = rollout.rollout(
        m, data, state[None], control, control_spec=CONTROL_SPEC, initial_warmstart=warm
    )
    seconds = time.perf_counter() - start
    mujoco.mj_setState(m, d, states[0, -1], FULL)
    last = plant.measure()
    for name in ("x", "y", "theta", "phi", "v", "omega"):
        if getattr(last, name) != ts[name][-1]:
            raise SystemExit(f"{argv}: the rollout does not reproduce the run ({name})")
    return seconds


class Pair(NamedTuple):
    """One run of a case and its yardstick."""

    #: the run's loop and its whole ``main()`` call (s), and its control steps
    loop: float
    whole: float
    steps: int
    #: the C rollout's time over the loop's (the Python loop's over the loop's for a case no
    #: rollout replays; NaN for the reduced plant), and the rollout's time (s; else NaN)
    ratio: float
    floor: float


def _pair(case: str, argv: list[str], out: Path) -> Pair:
    """A run of ``case`` and, right after it, its yardstick."""
    whole, loop, ts = cli_run(argv, out)
    steps = len(ts["t"]) - 1
    if case == "reduced":
        return Pair(loop, whole, steps, math.nan, math.nan)
    if case in NO_ROLLOUT:
        os.environ["TT_MUJOCO_COMPILED"] = "0"
        try:
            python_loop = cli_run(argv, out.with_name(out.name + "-python"))[1]
        finally:
            os.environ.pop("TT_MUJOCO_COMPILED")
        return Pair(loop, whole, steps, python_loop / loop, math.nan)
    c_floor = floor(argv, ts)
    return Pair(loop, whole, steps, c_floor / loop, c_floor)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("cases", nargs="*", metavar="CASE", help=f"of {list(CASES)} (default: all)")
    p.add_argument("--repeats", type=int, default=2, help="figures per case (default 2)")
    p.add_argument(
        "--tries", type=int, default=5, help="pairs (run, yardstick) a figure is the median of"
    )
    args = p.parse_args()
    loops = {}
    with tempfile.TemporaryDirectory() as tmp:
        for case in args.cases or CASES:
            argv = CASES[case]
            first = cli_run(argv, Path(tmp) / f"{case}-warm")[0]
            # the first run of a case in this process loads the kernel (a plain law compiles)
            line = f"{case:9s} first run in the process: main() {first:.3f} s"
            if "--reverse" in argv:  # what backing up achieved: the leading axle's error
                rms = LAST_METRICS["trailer_rmse_lateral"]
                line += f" ({LAST_METRICS['status']}, trailer axle {rms * 1000:.1f} mm rms)"
            print(line, flush=True)
            for i in range(args.repeats):
                # --tries pairs, each a run and right after it its yardstick (the rollout of its
                # inputs, or the Python loop): the figure is the median of the pairs' ratios, so
                # that a burst of load on a shared machine moves one pair, not the figure
                pairs = [
                    _pair(case, argv, Path(tmp) / f"{case}-{i}-{j}") for j in range(args.tries)
                ]
                loop = statistics.median(pair.loop for pair in pairs)
                whole = statistics.median(pair.whole for pair in pairs)
                steps = pairs[0].steps
                loops.setdefault(case, []).append(steps / loop)
                line = (
                    f"{case:9s} run {i + 1}, median of {args.tries}: {steps} steps, "
                    f"loop {loop:.3f} s ({steps / loop:,.0f} steps/s), main() {whole:.3f} s"
                )
                ratio = statistics.median(pair.ratio for pair in pairs)
                if case == "reduced":
                    if "main" in loops:
                        line += f"; {steps / loop / loops['main'][i]:.1f}x the MuJoCo loop"
                elif case in NO_ROLLOUT:
                    line += f"; {ratio:.1f}x the Python loop"
                    if "main" in loops:
                        line += f", at {steps / loop / loops['main'][i]:.2f} of the main case's"
                else:
                    c_floor = statistics.median(pair.floor for pair in pairs)
                    line += f"; C rollout {c_floor:.3f} s; loop at {ratio:.2f} of it"
                print(line, flush=True)


if __name__ == "__main__":
    main()

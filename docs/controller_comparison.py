"""The paper's controller comparison (Table 3) with the baselines, and beyond it.

    python docs/controller_comparison.py [--plants mujoco reduced] [--cases ...] \
        > docs/controller_comparison.md

Eight controllers: the paper's ISMC-STA, PID and FBL (PID and FBL with the paper's gains,
"paper_6_2"; ISMC-STA with Table 3's comparison set "paper_6_2" in Table 3's case and the
paper's Section 6.1 set elsewhere), the boundary-layer sliding mode SMC, and the Stanley-type
tracker, the pure-pursuit tracker, the gain-scheduled LQR and the NMPC (their default gains).
Four cases: Table 3's own (cycloid, the paper's disturbance), the S-curve and the circle without
disturbance, and backing up the S-curve without disturbance (for the controllers that reverse;
ISMC-STA, PID, FBL and SMC then drive the hitch cascade's yaw-rate target). One trailer, the
same-path gain, dynamic target, seed 0, both plants.

Columns: Table 3's four (rmse and max of e_v, e_omega), the tractor's cross-track rms and the
position error rms (mm), how the run ended, and the cost of a control step: the median of the
controller's ``compute`` over the run (us), and for the NMPC the median solve (ms, once per
sample period), and the real-time factor (simulated over wall-clock time of the run, the step
compiled and the controller's ``compute``, timed, called back from it at every step; the
pure-pursuit law is a plain-number law that sees the path, which runs compiled with the step,
so its step column says "compiled"). Timings
are this machine's; every other figure is the same on every machine up to round-off.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time

import numpy as np

from tt_mujoco.sim import Scenario, build, simulate
from tt_mujoco.sim.loop.stepper import Stepper
from tt_mujoco.sim.probe import check_user_code
from tt_mujoco.sim.simulate import finish, run_episode

CONTROLLERS = {
    "ISMC-STA": {"controller": "ismc_sta"},
    "PID": {"controller": "pid", "gains": "paper_6_2"},
    "FBL": {"controller": "fbl", "gains": "paper_6_2"},
    "SMC": {"controller": "smc"},
    "Stanley": {"controller": "stanley"},
    "pure pursuit": {"controller": "pure_pursuit"},
    "LQR": {"controller": "lqr"},
    "NMPC": {"controller": "nmpc"},
}
TABLE_3 = "cycloid, paper disturbance (Table 3)"
CASES = {
    TABLE_3: {"traj": "cycloid"},
    "S-curve, no disturbance": {"traj": "s_curve", "disturbance": "none"},
    "circle, no disturbance": {"traj": "circle", "disturbance": "none"},
    "S-curve backing up, no disturbance": {
        "traj": "s_curve",
        "disturbance": "none",
        "reverse": True,
    },
}
HEADER = (
    "| controller | plant | rmse e_v | rmse e_omega | max e_v | max e_omega | cross-track rms "
    "(mm) | position rms (mm) | ended | step (us, median) | NMPC solve (ms, median) | "
    "real-time factor |"
)


def timed_run(scenario: Scenario):
    """``(result, compute times in s)``: :func:`tt_mujoco.sim.simulate` with the controller's
    ``compute`` timed (a subclass of the controller, whose Python ``compute`` the loop calls at
    every step: a built-in law's too)."""
    built = build(scenario)
    check_user_code(built)
    stepper = Stepper(built)
    stepper.reset(np.random.default_rng(scenario.seed))
    controller = built.new_controller()
    controller.reset()
    times = []
    inner = type(controller).compute

    def compute(self, t, measurement, reference):
        start = time.perf_counter()
        out = inner(self, t, measurement, reference)
        times.append(time.perf_counter() - start)
        return out

    controller.__class__ = type(
        type(controller).__name__, (type(controller),), {"compute": compute}
    )
    start = time.perf_counter()
    status, message = run_episode(stepper, controller)
    result = finish(built, stepper, controller, status, message, time.perf_counter() - start)
    return result, times


def row(case: str, controller: str, plant: str) -> list[str] | None:
    """One table row, or None where the controller does not drive the case (reversing)."""
    kw = {**CASES[case], **CONTROLLERS[controller]}
    if case == TABLE_3 and controller == "ISMC-STA":
        kw["gains"] = "paper_6_2"  # Table 3's comparison set; elsewhere the paper's 6.1 set
    scenario = Scenario(plant=plant, **kw)
    try:
        result, times = timed_run(scenario)
    except ValueError as err:
        if "driving forward only" in str(err):
            return None
        raise
    m = result.metrics
    ended = m["status"] if m["status"] == "ok" else f"{m['status']} at {m['sim_time_s']:.2f} s"
    cells = [controller, plant]
    cells += [f"{m[key]:.4f}" for key in ("rmse_v", "rmse_omega", "max_abs_v", "max_abs_omega")]
    cells += [f"{1e3 * m['cross_track_rms']:.1f}", f"{1e3 * m['rmse_position']:.1f}", ended]
    solve = m.get("controller", {}).get("solve_ms_median")
    # a plain-number law that sees the path runs compiled: its compute is never called back
    step = f"{1e6 * statistics.median(times):.1f}" if times else "compiled"
    cells += [step, "" if solve is None else f"{solve:.1f}"]
    cells.append(f"{m['sim_time_s'] / m['wall_time_s']:.1f}")
    return cells


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--plants", nargs="+", default=["mujoco", "reduced"])
    parser.add_argument("--cases", nargs="+", default=list(CASES), choices=list(CASES))
    args = parser.parse_args(argv)
    # the compiled loop loads, and a plain-number law compiles, once a process: not in a row
    for kw in CONTROLLERS.values():
        for case in args.cases:
            for plant in args.plants:
                try:
                    simulate(Scenario(plant=plant, duration=0.2, **{**CASES[case], **kw}))
                except ValueError:  # a law that drives forward only, backing up
                    pass
    print("# Controller comparison: Table 3 and beyond\n")
    print("Written by `python docs/controller_comparison.py > docs/controller_comparison.md`")
    print("(see its docstring); `tests/test_controller_comparison.py` re-runs sample rows.\n")
    for case in args.cases:
        print(f"## {case}\n")
        print(HEADER)
        print("|" + "---|" * HEADER.count(" | ") + "---|")
        for name in CONTROLLERS:
            for plant in args.plants:
                cells = row(case, name, plant)
                if cells is not None:
                    print("| " + " | ".join(cells) + " |")
                    sys.stdout.flush()
        print()
    return 0


if __name__ == "__main__":
    sys.exit(main())

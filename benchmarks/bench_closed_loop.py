"""Closed-loop speed: the simulation loop against bare stepping of the same model.

Run: ``python benchmarks/bench_closed_loop.py``. Prints, for a 10 s s_curve run (ISMC-STA,
dynamic target, paper disturbance, no video) at a 1 ms step, the loop's wall time and steps/s
on each plant, next to bare MuJoCo stepping, and the per-step cost of each part of the loop.
"""

import itertools
import time
import timeit

import mujoco
from tt_mujoco.controllers import make_controller, reduced_model

from tt_mujoco.reference.targets import make_target
from tt_mujoco.sim import Scenario, simulate
from tt_mujoco.sim.physics import Vehicle
from tt_mujoco.vehicle import reduced
from tt_mujoco.vehicle.params import Params


def best_of(fn, repeats=3):
    return min(fn() for _ in range(repeats))


def loop_seconds(plant: str) -> float:
    return simulate(Scenario(traj="s_curve", duration=10.0, plant=plant)).wall_time_s


def bare_seconds(steps: int) -> float:
    veh = Vehicle(Params())
    veh.set_state(v=0.5)
    m, d = veh.model, veh.data
    start = time.perf_counter()
    for _ in range(steps):
        mujoco.mj_step(m, d)
    return time.perf_counter() - start


def per_call_us(stmt, number=20000) -> float:
    return 1e6 * min(timeit.repeat(stmt, number=number, repeat=5)) / number


if __name__ == "__main__":
    steps = 10000
    bare = best_of(lambda: bare_seconds(steps))
    print(f"bare MuJoCo stepping (one mj_step call a step): {steps / bare:,.0f} steps/s")
    for plant in ("mujoco", "reduced"):
        wall = best_of(lambda plant=plant: loop_seconds(plant))
        print(
            f"closed loop, {plant:7s} plant: 10 s s_curve in {wall:.3f} s wall, "
            f"{steps / wall:,.0f} steps/s ({bare / wall:.0%} of bare stepping)"
        )
    p = Params()
    veh = Vehicle(p)
    veh.set_state(v=0.5)
    ctrl = make_controller("ismc_sta", reduced_model(p))
    setup = make_target("s_curve", kind="dynamic")
    target = setup.target
    print("per-step parts (us):")
    step_us = per_call_us(lambda: mujoco.mj_step(veh.model, veh.data))
    print(f"  mj_step (free rolling)  {step_us:6.2f}")
    print(f"  measure                 {per_call_us(veh.measure):6.2f}")
    print(f"  target.update           {per_call_us(lambda: target.update(1.0, 0.001, 0.5)):6.2f}")
    # A new articulation angle every call, as in a run: the reduced model memoises the last one.
    angles = itertools.cycle([0.05 + 1e-6 * i for i in range(1000)])
    step_us = per_call_us(lambda: ctrl.step(0.001, next(angles), 0.5, 0.1, 0.5, 0.1, 0.0, 0.0))
    print(f"  controller step         {step_us:6.2f}")
    print(
        "  matched disturbance     "
        f"{per_call_us(lambda: reduced.matched_torque(0.05, 3.5, 1.0, p)):6.2f}"
    )

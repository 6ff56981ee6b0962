"""Physics steps per second of the bare model (no controller), one core.

Run: ``python benchmarks/bench_step.py``. Prints steps/s for the default timestep and for
2 ms, stepping the vehicle forward under constant torques for 10 simulated seconds.
"""

import time

import mujoco

from tt_mujoco.sim.parts.physics import Vehicle
from tt_mujoco.vehicle.params import Params


def bare_rate(p: Params, sim_seconds: float = 10.0, repeats: int = 3) -> float:
    best = 0.0
    for _ in range(repeats):
        veh = Vehicle(p)
        veh.set_state(v=0.5)
        veh.set_torque(0.3, 0.25)
        n = int(round(sim_seconds / p.timestep))
        start = time.perf_counter()
        mujoco.mj_step(veh.model, veh.data, nstep=n)
        best = max(best, n / (time.perf_counter() - start))
    return best


def python_loop_rate(p: Params, sim_seconds: float = 10.0) -> float:
    """One mj_step call per step from Python, as a closed loop does."""
    veh = Vehicle(p)
    veh.set_state(v=0.5)
    veh.set_torque(0.3, 0.25)
    m, d = veh.model, veh.data
    n = int(round(sim_seconds / p.timestep))
    start = time.perf_counter()
    for _ in range(n):
        mujoco.mj_step(m, d)
    return n / (time.perf_counter() - start)


if __name__ == "__main__":
    print(f"mujoco {mujoco.__version__}")
    for dt in (0.001, 0.002):
        p = Params(timestep=dt)
        print(
            f"timestep {dt * 1e3:.0f} ms: bare {bare_rate(p):,.0f} steps/s (nstep in C), "
            f"{python_loop_rate(p):,.0f} steps/s (one mj_step call per step)"
        )

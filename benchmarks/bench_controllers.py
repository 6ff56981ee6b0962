"""Microseconds per ``Controller.step`` for each controller (no assertions).

Run: ``python benchmarks/bench_controllers.py [--number N] [--repeat R]``.

Three timings per controller: the whole step with the nominal reduced model
(:func:`controllers.reduced_model`, as the simulation loop uses it), the step with a constant
stand-in model (the controller's own arithmetic), and the model adapter alone. The best of
``--repeat`` runs is reported: the minimum is the least disturbed by other processes.
"""

from __future__ import annotations

import argparse
import timeit

from tt_mujoco.controllers import make_controller, reduced_model

from tt_mujoco.vehicle.params import Params

# A representative operating point: turning, small articulation, a small tracking error.
PHI, V, OMEGA = 0.1, 0.52, 0.28
V_D, OMEGA_D, V_D_DOT, OMEGA_D_DOT = 0.5, 0.3, 0.1, -0.05
DT = 0.001
#: The laws ``make_controller`` builds outside a run; the path trackers (Stanley, LQR, NMPC)
#: need a path, and docs/controller_comparison.md times them inside their runs.
VELOCITY_LAWS = ("ismc_sta", "pid", "fbl")


def constant_model(phi, v, omega):
    """Stand-in with the paper's phi = 0 input matrix (docs/model.md Section 4 check values)."""
    return 0.01, -0.02, 0.3759, 0.3759, 0.3893, -0.3893


def best_us(fn, number: int, repeat: int) -> float:
    return min(timeit.repeat(fn, number=number, repeat=repeat)) / number * 1e6


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--number", type=int, default=20000, help="calls per timing run")
    parser.add_argument("--repeat", type=int, default=5, help="timing runs (best is reported)")
    args = parser.parse_args()

    model = reduced_model(Params())
    model_us = best_us(lambda: model(PHI, V, OMEGA), args.number, args.repeat)
    print(f"reduced_model adapter alone: {model_us:6.2f} us/call")
    print(f"{'controller':<10} {'step (reduced model)':>22} {'step (constant model)':>22}")
    for name in VELOCITY_LAWS:
        row = []
        for m in (model, constant_model):
            ctrl = make_controller(name, m)
            step = ctrl.step
            step(DT, PHI, V, OMEGA, V_D, OMEGA_D, V_D_DOT, OMEGA_D_DOT)  # past the first call

            def call(step=step):
                step(DT, PHI, V, OMEGA, V_D, OMEGA_D, V_D_DOT, OMEGA_D_DOT)

            row.append(best_us(call, args.number, args.repeat))
        print(f"{name:<10} {row[0]:>19.2f} us {row[1]:>19.2f} us")


if __name__ == "__main__":
    main()

"""The paper's robustness claims against physical causes instead of the abstract Delta(t).

    python docs/robustness_study.py > docs/robustness_study.md

The paper stands in for the world with Delta_1(t) = 3.5 + sin(0.3 t) + 0.5 cos(2 t) and
Delta_2(t) = 1.5 sin(0.3 t) + 0.5 cos(5 t) (its Section 6), and names friction, actuator
dynamics and payloads as its future work. Here each controller runs, on the MuJoCo plant with one
same-path trailer, the cycloid and the S-curve (dynamic target) under:

- no disturbance, and the paper's Delta(t) (matched wheel torques, the default);
- the grade whose pull on a free body is Delta_1's constant 3.5 m/s^2 (20.9 deg), rising along
  the path's start tangent (docs/model.md Section 16), without Delta(t);
- a gusty wind across the path's start, 10 m/s with gusts of 3 m/s (Section 18), without
  Delta(t);
- an ice band (friction 0.1) over the second metre of the path;
- a DC motor per wheel with a 20 ms lag and a 20 A current limit (10 N m at the wheel;
  Section 17);
- a 20 ms measurement delay;
- the trailer's mass and yaw inertia times 1.5 from the middle of the run on (the fault
  ``payload``: t = 2 s on the 4.7 s cycloid, 5 s on the 13.8 s S-curve).

Printed per run: the tractor's cross-track rms (mm), rmse of e_v (m/s) and e_omega (rad/s), the
share of steps at the torque limit, and how the run ended.
"""

from __future__ import annotations

import argparse
import sys

from tt_mujoco.paper.robustness import CONTROLLERS, GRADE_DEG, PATHS, cases
from tt_mujoco.sim import Scenario, simulate

__all__ = ["CONTROLLERS", "GRADE_DEG", "PATHS", "cases", "main", "row"]


def row(path: str, case: str, controller: str) -> list[str]:
    """One table row: the run's figures, formatted."""
    scenario = Scenario(traj=path, **cases(path)[case], **CONTROLLERS[controller])
    m = simulate(scenario).metrics
    ended = m["status"] if m["status"] == "ok" else f"{m['status']} at {m['sim_time_s']:.2f} s"
    return [
        controller,
        f"{1e3 * m['cross_track_rms']:.1f}",
        f"{m['rmse_v']:.4f}",
        f"{m['rmse_omega']:.4f}",
        f"{100 * m['torque_saturation_fraction']:.0f} %",
        ended,
    ]


HEADER = "| controller | cross-track rms (mm) | rmse e_v | rmse e_omega | at torque limit | ended |"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--paths", nargs="+", default=list(PATHS), choices=PATHS)
    args = parser.parse_args(argv)
    print("# Robustness against physical causes\n")
    print("Written by `python docs/robustness_study.py > docs/robustness_study.md` (its")
    print("docstring says what runs); `tests/test_robustness_study.py` re-runs sample rows.\n")
    for path in args.paths:
        for case in cases(path):
            print(f"## {path}: {case}\n")
            print(HEADER)
            print("|---|---|---|---|---|---|")
            for name in CONTROLLERS:
                print("| " + " | ".join(row(path, case, name)) + " |")
                sys.stdout.flush()
            print()
    return 0


if __name__ == "__main__":
    sys.exit(main())

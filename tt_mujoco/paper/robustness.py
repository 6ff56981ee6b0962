"""The robustness study: the paper's claims against physical causes instead of Delta(t).

The paper stands in for the world with Delta_1(t) = 3.5 + sin(0.3 t) + 0.5 cos(2 t) and
Delta_2(t) = 1.5 sin(0.3 t) + 0.5 cos(5 t) (its Section 6) and names friction, actuator dynamics
and payloads as future work. The study runs each controller, on the MuJoCo plant with one
same-path trailer, on the cycloid and the S-curve (dynamic target) under each of
:func:`cases`: no disturbance; the paper's Delta(t); the grade whose pull on a free body is
Delta_1's 3.5 m/s^2 (20.9 deg) rising along the path's start; a gusty wind across the start;
an ice band; DC motors with a 20 ms lag and a 20 A limit; a 20 ms sensor delay; a payload
step. ``python -m tt_mujoco.paper`` runs it (its report's table), and
``python docs/robustness_study.py`` prints the full figures of every run.
"""

from __future__ import annotations

import math

from tt_mujoco.paper.values import fmt, metric_of
from tt_mujoco.reference.paths import get_path
from tt_mujoco.sim.parts.terrain import GRAVITY

__all__ = ["CONTROLLERS", "GRADE_DEG", "PATHS", "cases", "robustness_markdown", "run_key"]

#: The grade equivalent to Delta_1's bias: g sin(a) = 3.5 m/s^2.
GRADE_DEG = math.degrees(math.asin(3.5 / GRAVITY))
PATHS = ("cycloid", "s_curve")
#: When the payload comes on: about the middle of each run (4.7 s and 13.8 s long).
PAYLOAD_T = {"cycloid": 2.0, "s_curve": 5.0}
CONTROLLERS = {
    "ISMC-STA": {"controller": "ismc_sta"},
    "PID": {"controller": "pid"},
    "FBL": {"controller": "fbl"},
    "Stanley": {"controller": "stanley"},
    "LQR": {"controller": "lqr"},
    "NMPC": {"controller": "nmpc"},
}


def cases(path: str) -> dict[str, dict]:
    """Case name -> Scenario fields, for ``path``."""
    start_heading = math.degrees(get_path(path).pose_at(0.0)[2])  # 67.5 deg, 0 deg
    grade = f"slope:{GRADE_DEG:.1f}:{start_heading:g}"
    motor = {"motor_lag": 0.02, "motor_current_limit": 20.0}
    payload = PAYLOAD_T[path]
    return {
        "no disturbance": {"disturbance": "none"},
        "paper Delta(t)": {},
        f"grade {GRADE_DEG:.1f} deg": {"disturbance": "none", "terrain": grade},
        "gusty wind 10 m/s": {"disturbance": "none", "wind": f"10:{start_heading + 90:g}:3"},
        "ice band (mu 0.1) at 1-2 m": {"disturbance": "none", "ground": ["band:1:2:0.1"]},
        "DC motor, 20 ms, 20 A": {"disturbance": "none", "actuator": "dc_motor", "params": motor},
        "20 ms sensor delay": {"disturbance": "none", "sensor_delay": 0.02},
        f"payload x1.5 at {payload:g} s": {
            "disturbance": "none",
            "faults": [f"payload:t={payload:g},factor=1.5"],
        },
    }


def run_key(path: str, case: str, controller: str) -> str:
    """The paper suite's key of one run of the study."""
    return f"robust:{path}:{case}:{controller}@mujoco"


def robustness_markdown(records) -> list[str]:
    """The report's tables: per path, the tractor's cross-track rms (mm) of every controller in
    every case, or how the run ended when it did not finish."""
    out = [
        "### Robustness against physical causes (MuJoCo, cross-track rms in mm)",
        "",
        "Each case replaces the paper's Delta(t) by one physical cause (docs/robustness_study.md "
        "has every figure of every run).",
        "",
    ]
    for path in PATHS:
        out += [f"{path}:", "", "| case | " + " | ".join(CONTROLLERS) + " |"]
        out.append("|---|" + "---|" * len(CONTROLLERS))
        for case in cases(path):
            cells = []
            for name in CONTROLLERS:
                key = run_key(path, case, name)
                rec = records.get(key) or {}
                status = rec.get("status", "not run")
                if status == "ok":
                    cells.append(fmt(1e3 * metric_of(records, key, "cross_track_rms"), 3))
                elif status in ("not run", "error"):
                    cells.append(status)
                else:
                    t = metric_of(records, key, "sim_time_s")
                    cells.append(f"{status} at {fmt(t, 3)} s")
            out.append(f"| {case} | " + " | ".join(cells) + " |")
        out.append("")
    return out

"""Every path x controller x target on both plants, under the paper's disturbance.

Run: ``python benchmarks/closed_loop_grid.py`` (about a minute). Prints one row per run:
status and the main metrics (docs/model.md Section 11). ISMC-STA uses the paper's Section 6.2
comparison gains (as in Table 3); eta is the project default, same_path.
"""

import itertools

from tt_mujoco.sim import Scenario, simulate

KEYS = (
    "rmse_v",
    "rmse_omega",
    "rmse_lateral",
    "rmse_position",
    "max_position",
    "trailer_offtrack_rms",
    "slip_lateral_max",
    "torque_saturation_fraction",
)

if __name__ == "__main__":
    print("| path | controller | target | plant | status | " + " | ".join(KEYS) + " |")
    print("|" + "---|" * (5 + len(KEYS)))
    for path, ctrl, target, plant in itertools.product(
        ("cycloid", "s_curve", "circle"),
        ("ismc_sta", "pid", "fbl"),
        ("dynamic", "static"),
        ("mujoco", "reduced"),
    ):
        gains = "paper_6_2" if ctrl == "ismc_sta" else None
        r = simulate(Scenario(traj=path, controller=ctrl, gains=gains, target=target, plant=plant))
        values = " | ".join(f"{r.metrics[k]:.4f}" for k in KEYS)
        print(f"| {path} | {ctrl} | {target} | {plant} | {r.status} | {values} |")

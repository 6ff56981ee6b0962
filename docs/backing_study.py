"""Backing up with the hitch cascade: every path, plant and train size (docs/model.md Section 14).

    python docs/backing_study.py [--plants mujoco reduced] [--trailers 1 2 3]

One run per case (``--reverse`` with the defaults: ISMC-STA tracking the cascade's yaw rate,
the train starting on the path at its end); without disturbance, and with the paper's for one
trailer. Prints the leading axle's cross-track rms and max (mm), every hitch's largest angle
(deg), the tractor's cross-track rms (mm) and how the run ended.
"""

from __future__ import annotations

import argparse

from tt_mujoco.sim import Scenario, simulate

PATHS = ("s_curve", "circle", "cycloid")


def row(path: str, plant: str, n: int, disturbance: str) -> list[str]:
    """One table row: the run's figures, formatted."""
    m = simulate(
        Scenario(traj=path, plant=plant, trailers=n, reverse=True, disturbance=disturbance)
    ).metrics
    sfx = "" if n == 1 else f"_{n}"
    rms = m["trailer_rmse_lateral" if n == 1 else f"trailer{sfx}_rmse_lateral"]
    worst = m["trailer_max_lateral" if n == 1 else f"trailer{sfx}_max_lateral"]
    phis = [m["phi_max_abs_deg"]] + [m[f"trailer_{k}_phi_max_abs_deg"] for k in range(2, n + 1)]
    ended = m["status"] if m["status"] == "ok" else f"{m['status']} at {m['sim_time_s']:.2f} s"
    return [
        path,
        plant,
        str(n),
        disturbance,
        f"{1e3 * rms:.1f}",
        f"{1e3 * worst:.1f}",
        " / ".join(f"{phi:.0f}" for phi in phis),
        f"{1e3 * m['cross_track_rms']:.1f}",
        ended,
    ]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--plants", nargs="+", default=["mujoco", "reduced"])
    parser.add_argument("--trailers", nargs="+", type=int, default=[1, 2, 3])
    args = parser.parse_args(argv)
    head = ["path", "plant", "N", "disturbance", "leading axle cross-track rms (mm)", "max (mm)"]
    head += ["max abs phi_k (deg)", "tractor cross-track rms (mm)", "run"]
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for path in PATHS:
        for plant in args.plants:
            for n in args.trailers:
                for disturbance in ("none", "matched") if n == 1 else ("none",):
                    print("| " + " | ".join(row(path, plant, n, disturbance)) + " |", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

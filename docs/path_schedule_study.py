"""Off-tracking of every trailer, forward, under four steerings: docs/model.md Section 13.

    python docs/path_schedule_study.py [--plants mujoco reduced] [--trailers 1 2 3]
        [--disturbance none matched] [--paths circle cycloid s_curve] [--torque-limit N_M]
        [--driven-path-gain K] [--reverse]

For each path (circle, cycloid, S-curve), plant, train size and disturbance, one closed-loop run
(ISMC-STA, dynamic target, from rest) with plain trailers (eta = 0), the same-path limit gains,
the curvature schedule (``--eta scheduled``) and the path schedule (``--eta path``). Prints each
trailer's maximum and rms off-tracking (its axle to the path the unit ahead drove, mm), the
tractor's cross-track rms (mm), the share of steps at the torque limit, and how the run ended.
``--torque-limit`` bounds the wheel torques below the paper's 15 N m, ``--driven-path-gain`` sets
the path schedule's feedback to the tractor's path (0: the table's steering alone; docs/model.md
Section 13). ``--reverse`` backs each path up from its end, the last trailer leading (the hitch
cascade, docs/model.md Section 14): each unit's off-tracking is then against the path the unit
ahead of it in the motion drove (the tractor behind trailer 1, trailer k behind trailer k + 1),
and the leading axle's cross-track to the reference path is given, rms and max.
"""

from __future__ import annotations

import argparse
import sys

from tt_mujoco.sim import Scenario, simulate

PATHS = ("circle", "cycloid", "s_curve")
STEERINGS = {
    "plain": {"eta": 0.0},
    "same_path": {"eta": "same_path"},
    "curvature": {"eta": "same_path", "eta_schedule": "curvature"},
    "path": {"eta": "same_path", "eta_schedule": "path"},
}


def row(
    path: str,
    plant: str,
    n: int,
    disturbance: str,
    steering: str,
    torque_limit: float | None = None,
    driven_path_gain: float | None = None,
    reverse: bool = False,
) -> list[str]:
    """One table row: the run's figures, formatted."""
    params = {} if torque_limit is None else {"torque_limit": torque_limit}
    options = {} if driven_path_gain is None else {"driven_path_gain": driven_path_gain}
    if reverse:
        options["reverse"] = True
    scenario = Scenario(
        traj=path,
        plant=plant,
        trailers=n,
        disturbance=disturbance,
        params=params,
        **options,
        **STEERINGS[steering],
    )
    m = simulate(scenario).metrics
    if reverse:  # behind trailer 1 (the tractor), then behind trailers 2..N
        keys = ["trailer_offtrack"] + [f"trailer_{k}_offtrack" for k in range(1, n)]
    else:
        keys = ["trailer_offtrack"] + [f"trailer_{k}_offtrack" for k in range(2, n + 1)]
    worst = " / ".join(f"{1e3 * m[f'{key}_max']:.1f}" for key in keys)
    rms = " / ".join(f"{1e3 * m[f'{key}_rms']:.1f}" for key in keys)
    ended = m["status"] if m["status"] == "ok" else f"{m['status']} at {m['sim_time_s']:.2f} s"
    saturated = f"{100 * m['torque_saturation_fraction']:.0f} %"
    if reverse:
        lead = (m["leading_cross_track_rms"], m["leading_cross_track_max"])
        cross = " / ".join(f"{1e3 * x:.1f}" for x in lead)
    else:
        cross = f"{1e3 * m['cross_track_rms']:.1f}"
    return [path, plant, str(n), disturbance, steering, worst, rms, cross, saturated, ended]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--plants", nargs="+", default=["mujoco", "reduced"])
    parser.add_argument("--trailers", nargs="+", type=int, default=[1, 2, 3])
    parser.add_argument("--disturbance", nargs="+", default=["none"])
    parser.add_argument("--paths", nargs="+", default=list(PATHS))
    parser.add_argument("--torque-limit", type=float, default=None, help="wheel torque bound (N m)")
    parser.add_argument("--driven-path-gain", type=float, default=None, help="feedback gain (1/m)")
    parser.add_argument("--reverse", action="store_true", help="back the paths up")
    args = parser.parse_args(argv)
    head = ["path", "plant", "N", "disturbance", "steering", "max (mm)", "rms (mm)"]
    if args.reverse:
        head += ["leading axle cross-track rms / max (mm)", "torque at limit", "run"]
    else:
        head += ["tractor cross-track rms (mm)", "torque at limit", "run"]
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for path in args.paths:
        for plant in args.plants:
            for disturbance in args.disturbance:
                for n in args.trailers:
                    for steering in STEERINGS:
                        cells = row(
                            path,
                            plant,
                            n,
                            disturbance,
                            steering,
                            args.torque_limit,
                            args.driven_path_gain,
                            args.reverse,
                        )
                        print("| " + " | ".join(cells) + " |")
                        sys.stdout.flush()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

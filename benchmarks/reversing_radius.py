"""How tight a circle the hitch cascade backs a train around, by the number of trailers.

    python benchmarks/reversing_radius.py [--trailers 1 2 3] [--radii 2.0 1.5 1.05 0.8]

Each case backs the train around a circle of radius R (``--traj circle --reverse``) for 30 s
on the MuJoCo plant, with the paper's disturbance and 20 dB measurement noise, the last axle
leading on the path (the hitch cascade, tt_mujoco.controllers.backing). It prints how the
leading axle followed the circle (cross-track rms and largest, after the start), the largest
hitch angle and the share of steps with a motor at its limit. A maneuver's planner
(tt_mujoco.world.plan) turns at a least radius per train, and falls back to
``TIGHT_RADIUS_SHARE`` of it where no plan at the least radius is clear: this is what that
fallback stands on. A steady circle is the easy case; a plan's turns start and end abruptly.
"""

from __future__ import annotations

import argparse

import tt_mujoco
from tt_mujoco.vehicle.params import Params
from tt_mujoco.world.plan import TIGHT_RADIUS_SHARE, least_radius


def backed_circle(trailers: int, radius: float) -> dict:
    """The metrics of backing a train of ``trailers`` around a circle of ``radius`` (m)."""
    scenario = tt_mujoco.Scenario(
        traj="circle",
        path_options={"R": radius},
        reverse=True,
        trailers=trailers,
        duration=30.0,
        noise_snr_db=20.0,
    )
    return tt_mujoco.simulate(scenario).metrics


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trailers", type=int, nargs="+", default=[1, 2, 3])
    parser.add_argument("--radii", type=float, nargs="+", default=[2.0, 1.5, 1.2, 1.05, 0.8])
    args = parser.parse_args(argv)
    trains = {n: Params().with_trailers(n) if n > 1 else Params() for n in args.trailers}
    least = ", ".join(f"N={n} {least_radius(p):g} m" for n, p in trains.items())
    print(f"least radius of a plan: {least}; its fallback {TIGHT_RADIUS_SHARE:g} of it")
    print("N  R (m)  status     lead rms (mm)  lead max (mm)  hitch max (deg)  saturated")
    for n in args.trailers:
        for radius in args.radii:
            m = backed_circle(n, radius)
            hitch = m.get("train_phi_max_abs_deg", m["phi_max_abs_deg"])
            print(
                f"{n}  {radius:5.2f}  {m['status']:<9}  {1e3 * m['leading_cross_track_rms']:13.1f}"
                f"  {1e3 * m['leading_cross_track_max']:13.1f}  {hitch:15.1f}"
                f"  {m['torque_saturation_fraction']:9.3f}",
                flush=True,
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""How much of the motors the paper's disturbance takes, by the number of trailers.

    python benchmarks/disturbance_budget.py [--trailers 1 2 3] [--phi-deg 0 10 20]

The paper's Delta(t) (docs/model.md Section 8) is an acceleration; it enters as the matched
wheel torques ``g_nominal(phi)^-1 Delta(t)``, which grow with the train's mass and inertia and,
through ``1 / cos(beta)``, with the hitch angle. For each train and each hitch angle (every
trailer at it) this prints the largest torque one wheel takes over a period of Delta (its
slowest term, 0.3 rad/s, repeats every 21 s; sampled for 63 s at 1 ms) and its share of the
actuator limit: what is left is all the controller has to drive the train and reject the rest.
"""

from __future__ import annotations

import argparse
import math
import sys

import numpy as np

from tt_mujoco.sim.parts.disturbances import paper_disturbance_of
from tt_mujoco.vehicle import reduced, train
from tt_mujoco.vehicle.params import Params


def largest_wheel_torque(p: Params, phi: float) -> float:
    """The largest |T| one wheel takes to add Delta(t) at hitch angle ``phi`` (every trailer)."""
    largest = 0.0
    for t in np.arange(0.0, 63.0, 1e-3):
        a_v, a_omega = paper_disturbance_of(float(t))
        if p.n_trailers == 1:
            torques = reduced.matched_torque(phi, a_v, a_omega, p)
        else:
            torques = train.matched_torque((phi,) * p.n_trailers, a_v, a_omega, p)
        largest = max(largest, abs(torques[0]), abs(torques[1]))
    return largest


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trailers", type=int, nargs="+", default=[1, 2, 3])
    parser.add_argument("--phi-deg", type=float, nargs="+", default=[0.0, 10.0, 20.0])
    args = parser.parse_args(argv)
    for n in args.trailers:
        p = Params().with_trailers(n) if n > 1 else Params()
        cells = []
        for phi_deg in args.phi_deg:
            torque = largest_wheel_torque(p, math.radians(phi_deg))
            share = 100.0 * torque / p.torque_limit
            cells.append(f"phi {phi_deg:g} deg: {torque:.2f} N m ({share:.0f} %)")
        print(f"N = {n}, limit {p.torque_limit:g} N m per wheel: " + "; ".join(cells))
    return 0


if __name__ == "__main__":
    sys.exit(main())

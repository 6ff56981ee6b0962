"""Each unit's footprint: the rectangle on the floor that nothing may touch.

A unit is the tractor (unit 0, its frame at the axle midpoint P, heading theta) or trailer k
(unit k, its frame at its axle midpoint P0_k, heading its body's theta0_k). Its footprint is a
rectangle in that frame, ``x`` in ``[rear, front]`` along the heading and ``|y| <= half``:

- the tractor reaches from its hitch ``O_1`` (``x = -L_1``) to the front of its chassis
  (``0.75 L_1``, the chassis of :func:`tt_mujoco.vehicle.mjcf.vehicle_xml`);
- trailer k reaches from its hitch ``O_k`` (``x = L0_k``) back past its chassis
  (``-0.25 L0_k``) and, when a trailer follows, to that trailer's hitch (``-L_(k+1)``);
- both are as wide as the wheels (``d / 2 + r`` each side), and a trailer's rectangle keeps
  ``d / 2 + r`` behind and ahead of its axle, so its steered wheels stay inside at any angle.

The geometric check of a world (:mod:`tt_mujoco.world.contact`) and the MuJoCo scene's
collision boxes (``vehicle_xml(footprints=...)``) both take the rectangles from here.
"""

from __future__ import annotations

import numpy as np

from tt_mujoco.vehicle.params import Params

__all__ = ["FOOTPRINT_BITS", "FOOTPRINT_COLUMNS", "OBSTACLE_BITS", "footprints", "unit_names"]

#: ``(contype, conaffinity)`` of a unit's footprint box in the MuJoCo scene and of a world's
#: obstacle: each meets only the other (never the wheels, the floor or another unit).
FOOTPRINT_BITS, OBSTACLE_BITS = (2, 0), (0, 2)

#: The columns of :func:`footprints`: the rectangle's rear and front ends along the unit's
#: heading and its half width (m), in the unit's frame.
FOOTPRINT_COLUMNS = ("rear", "front", "half")


def footprints(p: Params) -> np.ndarray:
    """The footprint of every unit of ``p`` (tractor first), ``(N + 1, 3)`` by
    :data:`FOOTPRINT_COLUMNS`."""
    trailers = p.trailers
    half = 0.5 * p.d + p.r
    rows = [(-trailers[0].L, max(0.75 * trailers[0].L, half), half)]
    for k, t in enumerate(trailers):
        follower = trailers[k + 1].L if k + 1 < len(trailers) else 0.0
        rows.append((-max(0.25 * t.L0, half, follower), max(t.L0, half), half))
    return np.array(rows, dtype=float)


def unit_names(n_trailers: int) -> tuple[str, ...]:
    """The units' names as messages and metrics give them: ``tractor``, ``trailer 1``, ..."""
    return ("tractor", *(f"trailer {k}" for k in range(1, n_trailers + 1)))

"""The clearance check every planned path passes (a candidate of :mod:`tt_mujoco.world.plan`,
an edge of :mod:`tt_mujoco.world.roadmap`): every unit of the train, placed by the path's axle
chain, against every obstacle and the world's bounds, at samples along the tractor's path."""

from __future__ import annotations

import math

import numpy as np

from tt_mujoco.vehicle.params import Params
from tt_mujoco.vehicle.path_schedule import axle_chain
from tt_mujoco.world import contact
from tt_mujoco.world.part import outside_bounds

__all__ = ["CHAIN_BISECTIONS", "COARSE", "STEP", "clearance_along"]

#: The spacing of the samples a path is checked at (m), and every how many of them a first
#: look is taken.
STEP, COARSE = 0.05, 8
#: The bisections that place each axle on a candidate path for its clearance check: its
#: bracket (under 2 m for the trains planned for) shrinks below 1e-7 m, far inside the margin.
CHAIN_BISECTIONS = 24


def clearance_along(
    path,
    p: Params,
    record,
    step: float = STEP,
    below: float = -math.inf,
    bounds=None,
    blocked: dict | None = None,
    s_from: float = 0.0,
) -> tuple[float, float]:
    """``(gap, reached)``: the least gap between any unit of ``p`` and any obstacle of a
    world's ``record`` (:func:`~tt_mujoco.world.part.world_record`) with the tractor at arc
    lengths ``step`` apart along ``path``, every unit on the path's axle chain, and the
    fraction of the samples looked at. With ``below``, it stops at the first sample whose gap
    is under it, looking first at every :data:`COARSE`-th sample (a path that fails is most
    often told there, and those samples are among the others), and gaps of ``below`` or more
    are not told apart (the gap is then ``below``); ``blocked`` (a dict) then receives where:
    the ``unit`` (index, tractor 0), the ``obstacle`` (index, None: outside the bounds) and
    the tractor's ``x``, ``y`` and every unit's ``poses`` there. With ``bounds`` (x_min,
    x_max, y_min, y_max), a sample with an axle outside them has the gap -inf. The tractor is
    placed from arc length ``s_from`` on (a leg that stops short of the path's start,
    :attr:`Leg.stop_s`)."""
    cap = math.inf if below == -math.inf else below
    if not record.sizes.size and bounds is None:
        return math.inf, 1.0
    span = path.length - s_from
    s = np.linspace(s_from, path.length, max(2, math.ceil(span / step) + 1))
    lengths = [(t.L, t.L0) for t in p.trailers]
    poses = np.zeros((p.n_trailers + 1, 3))

    def gaps(arcs):
        """Each sample's least gap, the unit and the obstacle (None: out of bounds)."""
        x, y, heading = path.pose(arcs)
        chain = axle_chain(path, arcs, lengths, CHAIN_BISECTIONS)
        for i in range(len(arcs)):
            poses[0] = x[i], y[i], heading[i]
            for k, axle in enumerate(chain, start=1):
                poses[k] = axle["x"][i], axle["y"][i], axle["theta"][i]
            if bounds is not None and outside_bounds(bounds, poses):
                yield i, -math.inf, 0, None
                continue
            if not record.sizes.size:
                yield i, math.inf, 0, None
                continue
            gap, unit, obstacle = contact.clearance_of(
                poses,
                record.boxes,
                record.polygons,
                record.sizes,
                record.circles,
                record.corners,
                cap,
            )
            yield i, gap, int(unit), int(obstacle)

    def told(gap, unit, obstacle):
        if blocked is not None:
            blocked.update(
                unit=unit, obstacle=obstacle, x=poses[0][0], y=poses[0][1], poses=poses.copy()
            )
        return gap

    if below > -math.inf:
        for i, gap, unit, obstacle in gaps(s[::COARSE]):
            if gap < below:
                return told(gap, unit, obstacle), i * COARSE / len(s)
    least = math.inf
    for i, gap, unit, obstacle in gaps(s):
        least = min(least, gap)
        if least < below:
            return told(least, unit, obstacle), (i + 1) / len(s)
    return least, 1.0

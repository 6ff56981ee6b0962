"""How close the units are to a world's obstacles: the step's contact check, in plain numbers.

Every shape is a convex polygon on the floor, its vertices counter-clockwise in the rows of a
``(V, 2)`` array (an obstacle: :mod:`tt_mujoco.world.world`; a unit's footprint:
:func:`unit_corners_of`). :func:`gap_of` is the signed distance between two of them: their
Euclidean distance when apart, zero when they touch, and minus the least depth of their overlap
along an edge's normal when they overlap (the separating-axis test). The closed loop's step
(:mod:`tt_mujoco.sim.loop.closed_loop`) calls :func:`clearance_of` on the true state of every
control step, on either plant, and stops the run at the first step whose clearance is not
positive; numba compiles these functions from this source.
"""

from __future__ import annotations

import math

__all__ = ["clearance_of", "gap_of", "point_segment_distance", "unit_corners_of"]


def unit_corners_of(x: float, y: float, heading: float, box, out) -> None:
    """The corners of a unit's footprint ``box = (rear, front, half)`` (m, in the unit's frame:
    :func:`tt_mujoco.vehicle.footprint.footprints`) at pose ``(x, y, heading)``, counter-
    clockwise into the ``(4, 2)`` array ``out``."""
    c, s = math.cos(heading), math.sin(heading)
    rear, front, half = box[0], box[1], box[2]
    out[0, 0], out[0, 1] = x + c * front + s * half, y + s * front - c * half
    out[1, 0], out[1, 1] = x + c * front - s * half, y + s * front + c * half
    out[2, 0], out[2, 1] = x + c * rear - s * half, y + s * rear + c * half
    out[3, 0], out[3, 1] = x + c * rear + s * half, y + s * rear - c * half


def point_segment_distance(px: float, py: float, ax: float, ay: float, bx: float, by: float):
    """The distance from point ``(px, py)`` to the segment from ``(ax, ay)`` to ``(bx, by)``."""
    ex, ey = bx - ax, by - ay
    length2 = ex * ex + ey * ey
    u = 0.0 if length2 == 0.0 else ((px - ax) * ex + (py - ay) * ey) / length2
    u = 0.0 if u < 0.0 else (1.0 if u > 1.0 else u)
    return math.hypot(px - ax - u * ex, py - ay - u * ey)


def _separation_of(a, na: int, b, nb: int) -> float:
    """The largest gap between convex polygon ``b`` and ``a`` along ``a``'s outward edge
    normals (positive: an edge of ``a`` separates them)."""
    best = -math.inf
    for i in range(na):
        j = i + 1 if i + 1 < na else 0
        ex, ey = a[j, 0] - a[i, 0], a[j, 1] - a[i, 1]
        length = math.hypot(ex, ey)
        nx, ny = ey / length, -ex / length  # outward for counter-clockwise vertices
        edge = nx * a[i, 0] + ny * a[i, 1]
        nearest = math.inf
        for m in range(nb):
            nearest = min(nearest, nx * b[m, 0] + ny * b[m, 1])
        best = max(best, nearest - edge)
    return best


def gap_of(a, na: int, b, nb: int, enough: float = math.inf) -> float:
    """The signed distance between convex polygons ``a`` and ``b`` (their first ``na`` and
    ``nb`` rows, counter-clockwise): their distance when apart, else minus the least depth of
    their overlap along an edge normal (zero when they touch). When an edge already separates
    them by ``enough`` or more, that separation (a lower bound of the distance) instead."""
    separation = max(_separation_of(a, na, b, nb), _separation_of(b, nb, a, na))
    if separation <= 0.0 or separation >= enough:
        return separation
    distance = math.inf
    for i in range(na):
        for j in range(nb):
            k = j + 1 if j + 1 < nb else 0
            d = point_segment_distance(a[i, 0], a[i, 1], b[j, 0], b[j, 1], b[k, 0], b[k, 1])
            distance = min(distance, d)
    for j in range(nb):
        for i in range(na):
            k = i + 1 if i + 1 < na else 0
            d = point_segment_distance(b[j, 0], b[j, 1], a[i, 0], a[i, 1], a[k, 0], a[k, 1])
            distance = min(distance, d)
    return distance


def clearance_of(
    poses, boxes, polygons, sizes, circles, corners, cap: float = math.inf
) -> tuple[float, int, int]:
    """``(clearance, unit, obstacle)``: the least :func:`gap_of` between any unit's footprint
    (unit ``u`` at ``poses[u] = (x, y, heading)`` with box ``boxes[u]``) and any obstacle
    (``polygons[o]``'s first ``sizes[o]`` rows, within the circle ``circles[o] = (x, y,
    radius)``), and the pair it is between; ``corners`` is a ``(4, 2)`` scratch array. Gaps of
    ``cap`` or more are not told apart: the clearance is then ``cap`` and the pair ``(-1, -1)``.
    An obstacle that cannot come closer than the least gap so far is not looked at closer:
    its circle is farther, or an edge separates it by more."""
    best, unit, obstacle = cap, -1, -1
    for u in range(len(boxes)):
        box = boxes[u]
        x, y, heading = poses[u, 0], poses[u, 1], poses[u, 2]
        unit_corners_of(x, y, heading, box, corners)
        middle = 0.5 * (box[0] + box[1])
        cx, cy = x + middle * math.cos(heading), y + middle * math.sin(heading)
        radius = math.hypot(0.5 * (box[1] - box[0]), box[2])
        for o in range(len(sizes)):
            circle = circles[o]
            reach = math.hypot(cx - circle[0], cy - circle[1]) - radius - circle[2]
            if reach >= best:
                continue
            gap = gap_of(corners, 4, polygons[o], sizes[o], best)
            if gap < best:
                best, unit, obstacle = gap, u, o
    return best, unit, obstacle

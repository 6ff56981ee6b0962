"""The path and the vehicle as a plain-number law sees them (:mod:`tt_mujoco.controllers.plain`,
``plain_law(..., path=True)``).

The law is given two more arguments:

- ``path``: the run's path as a table, sampled every :data:`PATH_SPACING` m of arc length
  from ``s = 0`` to its end (rows :data:`PATH_ROWS`); a law reads it through
  :func:`path_pose_at` and :func:`path_nearest`, never by index;
- ``vehicle``: the vehicle as the controller knows it (its nominal parameters), by name
  (:data:`VEHICLE_FIELDS`): the first trailer's ``L``, ``L0`` and ``eta``, the last
  trailer's ``L_last``, ``L0_last`` and ``eta_last``, the wheels' radius ``r`` and track
  ``d`` (m), ``n_trailers``, and the run's ``direction`` of travel (+1 forward, -1 backing up).

Both functions are plain numbers on arrays: the kernel compiles them with the law (it
registers them, :mod:`tt_mujoco.sim.loop.kernel_sources`), and the Python loop runs the same text,
so both loops give the same numbers. Between samples the position is linear (the chord of 5
mm of a 0.5 m radius strays 6 um from the arc), the heading and the curvature too.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from tt_mujoco.analysis.nearest import segment_distance2_of

__all__ = [
    "LAW_LIBRARY",
    "PATH_ROWS",
    "PATH_SPACING",
    "VEHICLE_FIELDS",
    "path_nearest",
    "path_pose_at",
    "path_table",
    "vehicle_values",
]

#: The rows of a law's path table: arc length s (m), the position x, y (m), the heading theta
#: (rad) and the curvature kappa (1/m) at each sample, and the segment to the next sample
#: (dx, dy, and 1 / its squared length; 0 after the last).
PATH_ROWS = ("s", "x", "y", "theta", "kappa", "dx", "dy", "inv_len2")
#: Arc length between the table's samples (m).
PATH_SPACING = 0.005
#: A law's ``vehicle`` record, by name.
VEHICLE_FIELDS = (
    *("L", "L0", "eta", "L_last", "L0_last", "eta_last"),
    *("r", "d", "n_trailers", "direction"),
)


class _Segments(NamedTuple):
    """The table's segments as :func:`~tt_mujoco.analysis.nearest.segment_distance2_of`
    reads them."""

    sx: np.ndarray
    sy: np.ndarray
    dx: np.ndarray
    dy: np.ndarray
    inv_len2: np.ndarray


def path_table(path, spacing: float = PATH_SPACING) -> np.ndarray:
    """The table of ``path`` (a :class:`~tt_mujoco.reference.path_base.ReferencePath`) that a
    law reads: shape ``(len(PATH_ROWS), n)``, samples ``spacing`` apart (the last at the
    path's end)."""
    n = max(2, math.ceil(path.length / spacing) + 1)
    s = np.linspace(0.0, path.length, n)
    x, y, theta = (np.asarray(a, dtype=float) for a in path.pose(s))
    table = np.zeros((len(PATH_ROWS), n))
    table[0], table[1], table[2] = s, x, y
    table[3] = np.unwrap(theta)
    table[4] = path.curvature(s)
    table[5, :-1], table[6, :-1] = np.diff(x), np.diff(y)
    length2 = table[5, :-1] ** 2 + table[6, :-1] ** 2
    table[7, :-1] = np.where(length2 > 0.0, 1.0 / np.where(length2 > 0.0, length2, 1.0), 0.0)
    table.setflags(write=False)  # a law reads its path; a write raises, as numba's is refused
    return table


def vehicle_values(params, reverse: bool) -> tuple[float, ...]:
    """The values of :data:`VEHICLE_FIELDS` for the nominal ``params`` and the run's direction."""
    first, last = params.trailers[0], params.trailers[-1]
    return (
        *(float(first.L), float(first.L0), float(first.eta)),
        *(float(last.L), float(last.L0), float(last.eta)),
        *(float(params.r), float(params.d), float(params.n_trailers), -1.0 if reverse else 1.0),
    )


def path_pose_at(path, s):
    """The path's pose and curvature at arc length ``s`` (m; held at the ends beyond them):
    ``(x, y, theta, kappa)``."""
    n = path.shape[1]
    spacing = path[0, 1] - path[0, 0]
    u = min(max(s, 0.0), path[0, n - 1]) / spacing
    i = min(int(u), n - 2)
    t = u - i
    x = path[1, i] + t * path[5, i]
    y = path[2, i] + t * path[6, i]
    theta = path[3, i] + t * (path[3, i + 1] - path[3, i])
    kappa = path[4, i] + t * (path[4, i + 1] - path[4, i])
    return x, y, theta, kappa


def path_nearest(path, px, py, s_near, reach):
    """The point of the path nearest to ``(px, py)``, searched within ``reach`` m of arc
    length around ``s_near`` (``reach <= 0``: the whole path; ties go to the lower s):
    ``(s, x, y, theta, kappa, lateral)``, where ``lateral`` (m) is the point's signed distance
    from the path, positive to the left of the direction of increasing s.

    A law that keeps the last s in its state and searches ``reach`` around it (a few
    decimetres) costs a few hundred samples a step however long the path, and never jumps to
    another lap of a path that crosses itself.
    """
    n = path.shape[1]
    spacing = path[0, 1] - path[0, 0]
    lo, hi = 0, n - 2
    if reach > 0.0:
        lo = min(max(int((s_near - reach) / spacing), 0), n - 2)
        hi = max(min(int((s_near + reach) / spacing) + 1, n - 2), lo)
    segments = _Segments(path[1], path[2], path[5], path[6], path[7])
    best_d2, best_k, best_t = math.inf, lo, 0.0
    for k in range(lo, hi + 1):
        d2, t = segment_distance2_of(px, py, segments, k, 0.0, 1.0)
        if d2 < best_d2:
            best_d2, best_k, best_t = d2, k, t
    x, y, theta, kappa = path_pose_at(path, path[0, best_k] + best_t * spacing)
    lateral = math.cos(theta) * (py - y) - math.sin(theta) * (px - x)
    return path[0, best_k] + best_t * spacing, x, y, theta, kappa, lateral


#: What a law may call on its path (the kernel registers them with numba).
LAW_LIBRARY = (path_pose_at, path_nearest)

"""When a track of points is a path: the one rule by which a polyline drops repeated points
and a metric decides whether the point a follower tracks ever moved."""

from __future__ import annotations

import numpy as np

__all__ = ["MIN_SEGMENT", "moves", "new_vertices"]

#: Consecutive vertices closer than this (m) are one vertex of a polyline: a shorter
#: segment's squared length can underflow to 0 (a standing vehicle drifting by 1e-170 m).
MIN_SEGMENT = 1e-12


def new_vertices(points: np.ndarray) -> np.ndarray:
    """Which of the points (N, 2) start a new vertex of their polyline: the first, and each
    farther than :data:`MIN_SEGMENT` from the one before."""
    keep = np.ones(points.shape[0], dtype=bool)
    keep[1:] = np.hypot(*(points[1:] - points[:-1]).T) > MIN_SEGMENT
    return keep


def moves(points) -> bool:
    """Whether a track of points (N, 2) makes a polyline (two vertices or more): whether the
    point it follows ever moved."""
    points = np.asarray(points, dtype=float)
    return points.shape[0] >= 2 and int(np.count_nonzero(new_vertices(points))) >= 2

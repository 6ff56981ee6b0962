"""Distances, sides and off-tracking of points against a path, measured exactly on its
polyline (:class:`tt_mujoco.analysis.geometry.Polyline`)."""

from __future__ import annotations

import numpy as np

from tt_mujoco.analysis.geometry import Polyline
from tt_mujoco.analysis.tracks import moves

__all__ = ["as_polyline", "distance_to_polyline", "signed_lateral_error", "trailer_offtrack"]


def as_polyline(polyline) -> Polyline:
    """``polyline`` as a :class:`~tt_mujoco.analysis.geometry.Polyline` (itself, if it is one)."""
    return polyline if isinstance(polyline, Polyline) else Polyline(polyline)


def distance_to_polyline(points, polyline) -> np.ndarray:
    """Distance from each point to the nearest point of a polyline's segments (metres).

    Parameters
    ----------
    points : array_like, shape (N, 2) or (2,)
    polyline : array_like, shape (M, 2), or Polyline
        Build a :class:`Polyline` once to query the same path repeatedly.

    Returns
    -------
    ndarray, shape (N,) (a scalar for a single point); NaN for non-finite points.
    """
    return as_polyline(polyline).project(points).distance


def signed_lateral_error(
    points, polyline, *, extend_ends: bool = False, interior_only: bool = False
) -> tuple[np.ndarray, np.ndarray]:
    """Signed distance to a path and the arc length of the nearest path point.

    Parameters
    ----------
    points : array_like, shape (N, 2) or (2,)
        Query points (metres), e.g. the tractor axle midpoint P over a run.
    polyline : array_like, shape (M, 2), or Polyline
        The path, vertices in the direction of travel.
    extend_ends : bool
        Continue the first and last segments as rays (see :meth:`Polyline.project`).
    interior_only : bool
        If True, the signed distance is NaN where the nearest path point is not strictly inside
        the path (arc length <= 0 or >= the path's length): there the distance is mostly
        along-track (e.g. the trailer behind the path's start). :func:`compute_metrics` uses
        this for the trailer's lateral error.

    Returns
    -------
    signed_distance : ndarray, shape (N,)
        Distance to the path, positive when the point is left of the direction of travel.
    arc_length : ndarray, shape (N,)
        Path length from the path's start to the nearest path point.
    """
    line = as_polyline(polyline)
    proj = line.project(points, extend_ends=extend_ends)
    if not interior_only:
        return proj.signed_distance, proj.arc_length
    # Exact comparisons: a foot clamped to the start has arc length 0.0, one clamped to the end
    # has arc_length[-2] + 1.0 * length[-1], the same sum that built the total length.
    inside = (proj.arc_length > 0.0) & (proj.arc_length < line.length)
    return np.where(inside, proj.signed_distance, np.nan), proj.arc_length


def trailer_offtrack(
    tractor_xy, trailer_xy, window: float | None = None, path: Polyline | None = None
) -> np.ndarray:
    """Distance from the following axle (P0 driving forward) to the path its leading axle (P)
    has driven: the off-tracking, sample by sample (docs/metrics.md).

    Sample i counts once the follower has passed the leader's starting point and is not ahead
    of the leader:

    - *passed the start*: the follower has travelled at least its initial spacing from the
      leader's start, measured along the leader's start direction (so a leader that wiggles by
      1e-6 m at the start, or rolls back a little, cannot make the initial spacing count as
      off-tracking), and its nearest point on the driven path lies beyond the path's first
      point;
    - *recent path only*: the driven path is searched over its last ``window`` metres (default
      three times the initial spacing), so a path driven earlier (the previous lap, the other
      loop of a figure-eight) never serves;
    - *not ahead*: the nearest point lies before the leader's current position.

    Other samples are NaN.

    Parameters
    ----------
    tractor_xy, trailer_xy : array_like, shape (N, 2)
        Leader and follower at the same samples; finite. (Reversing, pass the trailer as the
        leader.)
    window : float, optional
        Length (m) of the recent driven path that serves a sample.
    path : Polyline, optional
        ``Polyline(tractor_xy)``, when the caller measures several followers against one
        leader (built here otherwise).

    Returns
    -------
    ndarray, shape (N,)
        Off-tracking distance (m); NaN where a sample does not count (see above).
    """
    p = np.asarray(tractor_xy, dtype=float)
    p0 = np.asarray(trailer_xy, dtype=float)
    if p.ndim != 2 or p.shape[1] != 2 or p0.shape != p.shape:
        raise ValueError(
            f"tractor_xy and trailer_xy must both have shape (N, 2), got {p.shape} and {p0.shape}"
        )
    out = np.full(p.shape[0], np.nan)
    if not moves(p):
        return out  # the tractor never moved: P0 cannot have passed its start
    spacing = float(np.hypot(*(p[0] - p0[0])))
    # The leader's start direction, from its first move of a tenth of the spacing (not from
    # its first sample, which may wiggle): the follower passes the start after travelling the
    # spacing's component along it.
    moved = np.flatnonzero(np.hypot(*(p - p[0]).T) >= 0.1 * spacing)
    along = spacing
    if spacing > 0.0 and moved.size:
        heading = p[moved[0]] - p[0]
        along = max(0.0, float(np.dot(p[0] - p0[0], heading) / np.hypot(*heading)))
    if window is None:
        window = 3.0 * spacing if spacing > 0.0 else np.inf
    path = Polyline(p) if path is None else path
    count = path.vertex_index  # segments driven up to each sample
    driven = path.arc_length[count]
    first = np.searchsorted(path.arc_length, driven - window, side="right") - 1
    first = np.clip(first, 0, np.maximum(count - 1, 0)).astype(np.int64)
    proj = path.project(p0, segment_count=count, segment_first=first)
    step = np.hypot(*np.diff(p0, axis=0).T)
    travelled = np.concatenate([[0.0], np.cumsum(step)])
    # Exact comparisons: a foot clamped to the window's first vertex has that vertex's arc
    # length, one clamped to the leader's position the same sum that built driven[i].
    inside = (proj.arc_length > path.arc_length[first]) & (proj.arc_length < driven)
    counted = inside & (travelled >= along) & (count > 0)
    out[counted] = proj.distance[counted]
    return out

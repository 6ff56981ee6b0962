"""The nearest segment of a polyline to a point, in plain numbers: the search the compiled
kernel runs over a time series (:func:`nearest_segments_of`), the one formula of a point's
distance to a segment (:func:`segment_distance2_of`), and the table of segments and bounds
they read (:class:`SegmentTable`, made by :class:`tt_mujoco.analysis.geometry.Polyline`).

Every function here takes numbers and arrays only, so that numba compiles it as it stands
(:mod:`tt_mujoco.sim.loop.kernel_sources` lists them) and Python runs the same text.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

__all__ = [
    "CHUNK",
    "Best",
    "PolylineProjection",
    "SegmentTable",
    "nearest_segment_of",
    "nearest_segments_of",
    "segment_distance2_of",
    "segment_windows",
]

#: Segments per chunk, and chunks per group, of both searches: a time series' search mostly
#: searches again the one or two chunks an earlier search kept, the fewer segments the better.
CHUNK = 8


class SegmentTable(NamedTuple):
    """A polyline's segments and their bounds as plain arrays: what the compiled projection
    reads. Segment ``k`` starts at ``(sx, sy)[k]`` and runs ``(dx, dy)[k]``; chunk ``c`` holds
    segments ``c * CHUNK`` to ``c * CHUNK + CHUNK - 1``, all within ``chord_reach[c]`` of its
    chord, the segment from ``(chord_x, chord_y)[c]`` along ``(chord_dx, chord_dy)[c]`` (its
    first vertex to its last); group ``g`` holds chunks ``g * CHUNK`` to ``g * CHUNK + CHUNK
    - 1`` inside the circle ``(group_cx, group_cy, group_r)[g]``."""

    sx: np.ndarray
    sy: np.ndarray
    dx: np.ndarray
    dy: np.ndarray
    inv_len2: np.ndarray
    chord_x: np.ndarray
    chord_y: np.ndarray
    chord_dx: np.ndarray
    chord_dy: np.ndarray
    chord_inv_len2: np.ndarray
    chord_reach: np.ndarray
    group_cx: np.ndarray
    group_cy: np.ndarray
    group_r: np.ndarray


def segment_distance2_of(px, py, table, segments, lower, upper):
    """Squared distance from ``(px, py)`` to segment ``segments`` of ``table`` (the segment from
    ``(sx, sy)`` along ``(dx, dy)``), and the foot's parameter ``t``, clamped to ``[lower,
    upper]`` (``[0, 1]``; an end ray takes an infinite bound). One index or an index array
    alike: the one formula of every projection, the vectorised search's too."""
    dx, dy = table.dx[segments], table.dy[segments]
    rx = px - table.sx[segments]
    ry = py - table.sy[segments]
    t = np.minimum(np.maximum((rx * dx + ry * dy) * table.inv_len2[segments], lower), upper)
    rx = rx - t * dx
    ry = ry - t * dy
    return rx * rx + ry * ry, t


def _better(d2, seg, best_d2, best_seg) -> bool:
    """Nearer, or as near with a lower segment index: one nearest point however it is found."""
    return d2 < best_d2 or (d2 == best_d2 and seg < best_seg)


def _beyond(distance2, r, best_distance) -> bool:
    """Whether everything within ``r`` of a centre ``sqrt(distance2)`` away lies farther than
    ``best_distance``."""
    reach = r + best_distance
    return distance2 > reach * reach * (1.0 + 1e-9)


def _chord_distance2(px, py, table, c):
    """Squared distance to chunk ``c``'s chord, which the chunk strays from by at most
    ``chord_reach[c]``: a bound tighter than a circle around the chunk for a point beside a
    smooth path, whose neighbouring chunks a circle would keep."""
    rx, ry = px - table.chord_x[c], py - table.chord_y[c]
    dx, dy = table.chord_dx[c], table.chord_dy[c]
    t = min(max((rx * dx + ry * dy) * table.chord_inv_len2[c], 0.0), 1.0)
    rx -= t * dx
    ry -= t * dy
    return rx * rx + ry * ry


def _scan(px, py, a, b, extend, table, best):
    """Segments ``a`` to ``b - 1`` against the best ``(d2, segment, t)`` so far; with
    ``extend`` the end segments are rays, which :func:`_rays` tries."""
    if extend:
        a, b = max(a, 1), min(b, table.sx.shape[0] - 1)
    best_d2, best_seg, best_t = best
    for s in range(a, b):
        d2, t = segment_distance2_of(px, py, table, s, 0.0, 1.0)
        if _better(d2, s, best_d2, best_seg):
            best_d2, best_seg, best_t = d2, s, t
    return best_d2, best_seg, best_t


def _rays(px, py, lo, hi, extend, table):
    """The best ``(d2, segment, t)`` of the end segments in segments ``lo`` to ``hi - 1``,
    continued as rays (none unless ``extend``), which no chunk's bound covers."""
    n_seg = table.sx.shape[0]
    best = (np.inf, -1, 0.0)
    if extend:
        for s in (0, n_seg - 1):
            if lo <= s < hi:
                low = -np.inf if s == 0 else 0.0
                high = np.inf if s == n_seg - 1 else 1.0
                d2, t = segment_distance2_of(px, py, table, s, low, high)
                if _better(d2, s, best[0], best[1]):
                    best = (d2, s, t)
    return best


def nearest_segment_of(px, py, lo, hi, extend, table, warm, kept):
    """The nearest of segments ``lo`` to ``hi - 1`` to one point.

    Exact: it starts from the chunk of segment ``warm`` (the previous sample's nearest, for a
    time series), then searches every other group whose circle is not beyond the best so far,
    and in it every chunk whose chord bound (:func:`_chord_distance2`) is not. ``extend``
    continues the polyline's first and last segments as rays, which no bound covers, so those
    are tried first. Ties go to the lower segment index.

    Returns ``(d2, segment, t, n_kept, lower)``: the chunks it searched are ``kept[:n_kept]``,
    and every other segment of the window (the rays aside) lies at least ``lower`` away (inf
    when it set none aside).
    """
    best = _rays(px, py, lo, hi, extend, table)
    first_chunk = warm // CHUNK
    a, b = max(lo, first_chunk * CHUNK), min(hi, first_chunk * CHUNK + CHUNK)
    best = _scan(px, py, a, b, extend, table, best)
    kept[0], n_kept = first_chunk, 1
    lower = np.inf
    reach = np.sqrt(best[0])
    c_lo, c_hi = lo // CHUNK, (hi - 1) // CHUNK + 1
    for g in range(c_lo // CHUNK, (c_hi - 1) // CHUNK + 1):
        gx, gy = px - table.group_cx[g], py - table.group_cy[g]
        distance2 = gx * gx + gy * gy
        if _beyond(distance2, table.group_r[g], reach):
            lower = min(lower, np.sqrt(distance2) - table.group_r[g])
            continue
        for c in range(max(c_lo, g * CHUNK), min(c_hi, g * CHUNK + CHUNK)):
            if c == first_chunk:
                continue
            distance2 = _chord_distance2(px, py, table, c)
            if _beyond(distance2, table.chord_reach[c], reach):
                lower = min(lower, np.sqrt(distance2) - table.chord_reach[c])
                continue
            a, b = max(lo, c * CHUNK), min(hi, c * CHUNK + CHUNK)
            best = _scan(px, py, a, b, extend, table, best)
            kept[n_kept] = c
            n_kept += 1
            reach = np.sqrt(best[0])
    return best[0], best[1], best[2], n_kept, lower


def nearest_segments_of(points, window, extend, table, out):
    """Every point's nearest segment (:func:`nearest_segment_of`) into ``out = (d2, seg, t)``,
    for ``points = (px, py)`` and ``window = (lo, hi)``, arrays over the points: a time series,
    searched the way it moves.

    Each search starts from the previous point's nearest segment, and certifies the points that
    follow while they stay near where it was made: the segments it set aside lay at least
    ``lower`` from there and its nearest ``reach``, so a point ``moved`` away is at most ``reach
    + moved`` from that nearest segment and at least ``lower - moved`` from those set aside.
    While ``2 moved < lower - reach`` (less a rounding margin of 1e-9 of the coordinates and
    distances), and the window keeps that nearest segment, loses none below and gains at most a
    chunk's worth above (a window that slides forward, as the off-tracking's does), the chunks
    the search kept and what the window gained since hold the point's nearest segment: the same
    segment, found the same way, as a search of its own would find.
    """
    (px, py), (lo, hi), (d2, seg, t) = points, window, out
    kept = np.empty(table.chord_x.shape[0], np.int64)
    n_kept, slack, margin = 0, -np.inf, 0.0
    at_x, at_y, searched_lo, searched_hi, nearest = 0.0, 0.0, 0, 0, -1
    warm = lo[0] if px.shape[0] else 0
    for i in range(px.shape[0]):
        x, y, a, b = px[i], py[i], lo[i], hi[i]
        moved = np.hypot(x - at_x, y - at_y)
        gained = b - searched_hi
        certified = 0 <= gained <= CHUNK and searched_lo <= a <= nearest < b
        if certified and 2.0 * moved + margin < slack:
            # the rays, the chunks it kept, and what the window gained since (some of it in a
            # kept chunk: scanned twice, it finds the same)
            best = _rays(x, y, a, b, extend, table)
            for j in range(n_kept):
                first, end = kept[j] * CHUNK, kept[j] * CHUNK + CHUNK
                best = _scan(x, y, max(a, first), min(b, end), extend, table, best)
            d2[i], seg[i], t[i] = _scan(x, y, searched_hi, b, extend, table, best)
        else:
            d2[i], seg[i], t[i], n_kept, lower = nearest_segment_of(
                x, y, a, b, extend, table, max(warm, a), kept
            )
            reach = np.sqrt(d2[i])
            slack = lower - reach
            margin = 1e-9 * (abs(x) + abs(y) + reach + (lower if lower < np.inf else 0.0))
            at_x, at_y, searched_lo, searched_hi, nearest = x, y, a, b, seg[i]
        warm = seg[i]


def segment_windows(
    n: int, n_seg: int, segment_count, segment_first
) -> tuple[np.ndarray, np.ndarray]:
    """``(limit, first)``: the segments of ``n_seg`` that serve each of ``n`` points
    (:meth:`tt_mujoco.analysis.geometry.Polyline.project`'s ``segment_count`` and
    ``segment_first``), checked."""
    if segment_count is None:
        limit = np.full(n, n_seg, dtype=np.int64)
    else:
        limit = np.asarray(segment_count)
        if limit.shape != (n,) or not np.issubdtype(limit.dtype, np.integer):
            raise ValueError(
                f"segment_count must be an integer array of shape ({n},), got dtype "
                f"{limit.dtype} and shape {limit.shape}"
            )
        if np.any((limit < 0) | (limit > n_seg)):
            raise ValueError(
                f"segment_count must lie in [0, {n_seg}], got values in "
                f"[{limit.min()}, {limit.max()}]"
            )
        limit = limit.astype(np.int64)
    first = np.zeros(n, dtype=np.int64)
    if segment_first is not None:
        first = np.asarray(segment_first)
        if first.shape != (n,) or not np.issubdtype(first.dtype, np.integer):
            raise ValueError(f"segment_first must be an integer array of shape ({n},)")
        if np.any((first < 0) | ((first >= limit) & (limit > 0))):
            raise ValueError("segment_first must lie in [0, segment_count)")
        first = first.astype(np.int64)
    return limit, first


class Best:
    """Best projection found so far for each query point (mutable work arrays)."""

    def __init__(self, n: int) -> None:
        self.d2 = np.full(n, np.inf)
        self.seg = np.full(n, -1, dtype=np.int64)
        self.t = np.zeros(n)


class PolylineProjection(NamedTuple):
    """Nearest points of a set of query points on a polyline (arrays over the query points).

    ``distance`` is the Euclidean distance to the foot point ``foot`` (shape (..., 2)).
    ``signed_distance`` is ``distance`` with the sign of the side: positive left of the path's
    direction of travel (vertex order), negative right. ``arc_length`` is the path length from the
    first vertex to the foot. ``segment`` is the index of the segment holding the foot, in the
    polyline's de-duplicated vertices (:attr:`Polyline.vertices`). Rows whose query point is not
    finite hold NaN (and segment -1).
    """

    distance: np.ndarray
    signed_distance: np.ndarray
    arc_length: np.ndarray
    foot: np.ndarray
    segment: np.ndarray

"""Exact, vectorised point-to-polyline projection: distances, sides, arc lengths.

Distances to a path are distances to its polyline: the nearest point on any segment, not only on
the vertices. :class:`Polyline` does this exactly and vectorised: a k-d tree over short stretches
of the path proposes candidate segments, exact projection onto those picks the nearest, and a
distance bound certifies that no segment outside the candidates can be nearer. Points that fail
the bound are retried with more candidates, then searched exhaustively over the chunks of the
path that the bound cannot exclude. The result is therefore exact (to rounding), including for
points near a vertex of a sharply curving path; no point is left to a heuristic. The distances,
sides and off-tracking measured with it are :mod:`tt_mujoco.analysis.offtrack`'s.
"""

from __future__ import annotations

import numpy as np

from tt_mujoco.analysis.kdtree import kd_tree_class
from tt_mujoco.analysis.nearest import (
    CHUNK,
    Best,
    PolylineProjection,
    SegmentTable,
    segment_distance2_of,
    segment_windows,
)
from tt_mujoco.analysis.tracks import new_vertices

__all__ = [
    "Polyline",
    "PolylineProjection",
    "prepare_search",
    "use_compiled_projection",
]

# Tree entries asked for per point in successive queries; points the distance bound does not
# settle go on to the next query, then to the chunk search. With 4 pieces per entry, 8 entries
# settle points up to ~15 segment lengths from a smooth path, 32 up to ~250. Chosen by timing
# 20,000 points against a 2,000-segment cycloid at lateral scatter from 1 cm to far: (8, 32)
# with 4 pieces was the fastest at every scatter but the nearest, where single pieces tie;
# larger first queries cost more on near points (query time grows with k).
_CANDIDATE_ROUNDS = (8, 32)
# Consecutive pieces per tree entry: a coarser tree certifies farther points with the same k.
_GROUP_PIECES = 4
# Point-segment pairs evaluated at once: 256 kB per work array stays in cache and in the
# allocator's pool (measured: whole 20,000 x 16 arrays were 3-4x slower than blocks).
_WORK_BLOCK = 1 << 15
# The chunk search works on blocks of at most this many point-segment pairs (bounds the memory).
_SEARCH_BLOCK = 1 << 20
# Query points handed to the chunk search at once (bounds the pairs and lists it makes).
_POINT_BLOCK = 1 << 14
# A window of at most this many chunks is enumerated; a longer one is asked of the chunk tree.
_WINDOW_CHUNKS = 512


#: The compiled :func:`tt_mujoco.analysis.nearest.nearest_segments_of`, once
#: :mod:`tt_mujoco.sim.loop.compiled` has loaded its kernel in this process (None: the vectorised
#: search below serves alone).
_COMPILED = None


def use_compiled_projection(project_points) -> None:
    """Let :meth:`Polyline.project` run ``project_points((px, py), (lo, hi), extend, table,
    (d2, seg, t))``, the compiled :func:`~tt_mujoco.analysis.nearest.nearest_segments_of` (same
    numbers); it returns False when it could not run, and the vectorised search serves instead.
    None: none."""
    global _COMPILED
    _COMPILED = project_points


def prepare_search() -> None:
    """Import what the vectorised search needs (SciPy's k-d tree): a worker forked ahead of
    its work (the run's figures) pays for it before the work comes."""
    kd_tree_class()


class Polyline:
    """A planar polyline prepared for fast, exact nearest-point queries.

    Parameters
    ----------
    vertices : array_like, shape (M, 2)
        Finite vertices in path order (metres). Consecutive repeats (within
        :data:`~tt_mujoco.analysis.tracks.MIN_SEGMENT`) are dropped (a standing vehicle logs
        the same point many times); at least two distinct points are required.

    Attributes
    ----------
    vertices : ndarray, shape (K, 2)
        The vertices without consecutive repeats.
    vertex_index : ndarray of int, shape (M,)
        For each given vertex, its index in :attr:`vertices`.
    arc_length : ndarray, shape (K,)
        Path length from the first vertex to each vertex.
    length : float
        Total path length.
    """

    def __init__(self, vertices) -> None:
        given = np.asarray(vertices, dtype=float)
        if given.ndim != 2 or given.shape[1] != 2 or given.shape[0] < 2:
            raise ValueError(
                f"polyline must have shape (M, 2) with M >= 2 vertices, got shape {given.shape}"
            )
        if not np.all(np.isfinite(given)):
            bad = int(np.flatnonzero(~np.all(np.isfinite(given), axis=1))[0])
            raise ValueError(
                f"polyline vertices must be finite, got {given[bad].tolist()} at row {bad}"
            )
        keep = new_vertices(given)
        kept = int(np.count_nonzero(keep))
        if kept < 2:
            raise ValueError(
                f"polyline must contain at least two distinct points, got {given.shape[0]} "
                f"copies of {given[0].tolist()}"
            )
        self.vertices = given.copy() if kept == given.shape[0] else given[keep]
        self.vertex_index = np.cumsum(keep) - 1
        starts = self.vertices[:-1]
        self._starts = starts
        self._deltas = self.vertices[1:] - starts
        seg_lengths = np.hypot(self._deltas[:, 0], self._deltas[:, 1])
        self._seg_lengths = seg_lengths
        self._sx, self._sy = starts[:, 0].copy(), starts[:, 1].copy()
        self._dx, self._dy = self._deltas[:, 0].copy(), self._deltas[:, 1].copy()
        self._inv_len2 = 1.0 / (seg_lengths * seg_lengths)
        # Unit tangents as x and y arrays: the projection gathers them per point.
        self._tx, self._ty = self._dx / seg_lengths, self._dy / seg_lengths
        self.arc_length = np.concatenate(([0.0], np.cumsum(seg_lengths)))
        self.length = float(self.arc_length[-1])
        self._vertex_tx, self._vertex_ty = self._make_vertex_tangents()
        self._build_search()

    def _make_trees(self) -> None:
        """The vectorised search's k-d trees, made on its first use (the compiled search needs
        neither): one over the chunk centres, and one over short stretches of path.

        The path is cut into pieces no longer than ``spacing`` (long segments into several
        pieces, so one long straight does not weaken the bound for the whole path), and runs of
        ``_GROUP_PIECES`` consecutive pieces form groups. Each group lies inside a circle (centre
        c, radius R, around its bounding box); the tree holds the centres. A segment whose
        groups' centres are all at least D from a query point is at least ``D - R_max`` away.
        The spacing is the median segment length, but at least ``length / (2 * n_segments)``, so
        there are at most 3 pieces per segment.
        """
        if self._tree is not None:
            return
        cKDTree = kd_tree_class()  # only where the vectorised search runs

        n_seg = self.n_segments
        spacing = max(float(np.median(self._seg_lengths)), self.length / (2.0 * n_seg))
        pieces = np.maximum(1, np.ceil(self._seg_lengths / spacing).astype(np.int64))
        segment_of_piece = np.repeat(np.arange(n_seg), pieces)
        first_piece = np.cumsum(pieces) - pieces
        within = np.arange(segment_of_piece.size) - np.repeat(first_piece, pieces)
        seg_start = self._starts[segment_of_piece]
        seg_delta = self._deltas[segment_of_piece]
        piece_start = seg_start + (within / pieces[segment_of_piece])[:, None] * seg_delta
        piece_end = seg_start + ((within + 1) / pieces[segment_of_piece])[:, None] * seg_delta
        # Groups of _GROUP_PIECES consecutive pieces, each in a circle around its bounding box.
        n_pieces = segment_of_piece.size
        n_groups = -(-n_pieces // _GROUP_PIECES)
        piece_of = np.minimum(
            np.arange(n_groups)[:, None] * _GROUP_PIECES + np.arange(_GROUP_PIECES),
            n_pieces - 1,
        )
        corners = np.concatenate([piece_start[piece_of], piece_end[piece_of]], axis=1)
        centre = 0.5 * (corners.min(axis=1) + corners.max(axis=1))
        offset = corners - centre[:, None, :]
        radius = np.sqrt(np.max(np.einsum("ijk,ijk->ij", offset, offset), axis=1))
        self._group_segments = segment_of_piece[piece_of]
        self._group_radius_max = float(radius.max())
        self._chunk_tree = cKDTree(self._chunk_centre)
        self._tree = cKDTree(centre)

    def _compiled_search(self, pts, pending, window, extend_ends: bool, best: Best):
        """The compiled search of the ``pending`` points (``window``: each point's first and
        limit segments) into ``best``; the points it left (all of them where it failed)."""
        first, limit = window
        # Every point searched (the usual time series): no gathers, no scatter.
        every = pending.size == pts.shape[0]
        at = slice(None) if every else pending
        px, py = np.ascontiguousarray(pts[at, 0]), np.ascontiguousarray(pts[at, 1])
        m = pending.size
        d2, seg, t = np.empty(m), np.empty(m, np.int64), np.empty(m)
        if not _COMPILED((px, py), (first[at], limit[at]), extend_ends, self.table, (d2, seg, t)):
            return pending
        if every:
            best.d2, best.seg, best.t = d2, seg, t
        else:
            best.d2[pending], best.seg[pending], best.t[pending] = d2, seg, t
        return pending[:0]

    def _windowed_search(self, pts, pending, window, extend_ends: bool, best: Best):
        """The points of short windows searched directly (the tree holds the whole path, whose
        other laps crowd out the window's candidates); the points left."""
        first, limit = window
        lo_chunk, hi_chunk = self._window_chunks(limit, first)
        direct = pending[hi_chunk[pending] - lo_chunk[pending] <= _WINDOW_CHUNKS]
        if not direct.size:
            return pending
        # The tree's nearest groups inside a point's window give it a distance to beat: the
        # chunk tree then finds the few chunks nearer than it, where enumerating every chunk
        # of the window would cost the window's length for every point.
        k = min(_CANDIDATE_ROUNDS[0], self._tree.n)
        group_dist, group_idx = self._tree.query(pts[direct], k=k)
        group_dist = group_dist.reshape(direct.size, -1)
        candidates = self._group_segments[group_idx].reshape(direct.size, -1)
        self._try(pts[direct], direct, candidates, limit[direct], extend_ends, best, first[direct])
        # The tree's bound holds for every segment, in the window or not: a point whose best
        # usable candidate is within it is settled (the rays, which the bound does not cover,
        # are for extend_ends, which a windowed search goes on to check).
        if k < self._tree.n and not extend_ends:
            bound = group_dist[:, -1] - self._group_radius_max
            unsettled = direct[np.sqrt(best.d2[direct]) > bound]
        else:
            unsettled = direct
        self._chunk_search(pts, unsettled, limit, extend_ends, best, first)
        return np.setdiff1d(pending, direct, assume_unique=True)

    def _chunk_chords(self, xs: np.ndarray, ys: np.ndarray) -> tuple[np.ndarray, ...]:
        """Each chunk's chord (its first vertex to its last: start, direction, 1 / length^2, 0
        for a closed chunk) and how far its vertices, hence its segments, stray from it (a
        segment lies in the convex hull of its ends, and the distance to the chord is convex),
        widened by 1e-12 of the path's extent against rounding in the bound. ``xs``, ``ys``:
        the chunks' vertices, one chunk a column."""
        start_x, start_y = xs[0], ys[0]
        chord_x, chord_y = xs[-1] - start_x, ys[-1] - start_y
        length2 = chord_x * chord_x + chord_y * chord_y
        inv_length2 = np.divide(1.0, length2, out=np.zeros_like(length2), where=length2 > 0.0)
        rel_x, rel_y = xs - start_x, ys - start_y
        t = np.clip((rel_x * chord_x + rel_y * chord_y) * inv_length2, 0.0, 1.0)
        off_x, off_y = rel_x - t * chord_x, rel_y - t * chord_y
        stray = np.sqrt(np.max(off_x * off_x + off_y * off_y, axis=0))
        slack = 1e-12 * float(np.max(np.abs(self.vertices)))
        columns = (start_x, start_y, chord_x, chord_y, inv_length2)
        return (*(np.ascontiguousarray(c) for c in columns), stray * (1.0 + 1e-9) + slack)

    @property
    def n_segments(self) -> int:
        """Number of segments (``len(vertices) - 1``)."""
        return self._starts.shape[0]

    def _make_vertex_tangents(self) -> tuple[np.ndarray, np.ndarray]:
        """Direction (x and y arrays) used for the side of points whose foot is a vertex.

        At an interior vertex it is the sum of the two adjacent unit tangents: for any point whose
        nearest path point is that vertex, the cross product with this sum is negative on the
        outside of the turn and positive on the inside for a left turn (and the reverse for a
        right turn), so the sign is right even beyond a hairpin, where the two adjacent segments
        alone disagree. A complete reversal (sum 0) falls back to the incoming tangent.
        """
        tangents = []
        summed_x, summed_y = self._tx[:-1] + self._tx[1:], self._ty[:-1] + self._ty[1:]
        norm = np.hypot(summed_x, summed_y)
        reversal = norm < 1e-12
        norm = np.where(reversal, 1.0, norm)
        for t, summed in ((self._tx, summed_x), (self._ty, summed_y)):
            inner = np.where(reversal, t[:-1], summed / norm)
            tangents.append(np.concatenate((t[:1], inner, t[-1:])))
        return tangents[0], tangents[1]

    def _build_search(self) -> None:
        """Chunk circles: runs of ``CHUNK`` consecutive segments, each inside a circle around
        its vertices' bounding box (a segment lies in the convex hull of its end points), and
        groups of ``CHUNK`` chunks inside circles around theirs. A chunk or group whose circle
        is farther than a known distance cannot hold the nearest point: the compiled search
        walks these, and the vectorised one prunes its exact search with the chunks'.
        """
        n_seg = self.n_segments
        n_chunks = -(-n_seg // CHUNK)
        self._chunk_first = np.arange(n_chunks) * CHUNK
        vertex_of = np.minimum(
            np.arange(CHUNK + 1)[:, None] + self._chunk_first, self.vertices.shape[0] - 1
        )
        # The chunks' vertices, one chunk a column, x and y apart: reduced across the few rows,
        # each reduction runs along the chunks.
        xs, ys = self.vertices[:, 0][vertex_of], self.vertices[:, 1][vertex_of]
        centre_x = 0.5 * (xs.min(axis=0) + xs.max(axis=0))
        centre_y = 0.5 * (ys.min(axis=0) + ys.max(axis=0))
        off_x, off_y = xs - centre_x, ys - centre_y
        self._chunk_centre = centre = np.column_stack((centre_x, centre_y))
        self._chunk_radius = np.sqrt(np.max(off_x * off_x + off_y * off_y, axis=0))
        self._chunk_radius_max = float(self._chunk_radius.max())
        self._tree = self._chunk_tree = None  # made by _make_trees when the vectorised search runs
        # Groups of CHUNK chunks, each inside a circle around its chunks' circles.
        n_groups = -(-n_chunks // CHUNK)
        chunk_of = np.minimum(np.arange(n_groups)[:, None] * CHUNK + np.arange(CHUNK), n_chunks - 1)
        reach_lo = (centre - self._chunk_radius[:, None])[chunk_of].min(axis=1)
        reach_hi = (centre + self._chunk_radius[:, None])[chunk_of].max(axis=1)
        group_centre = 0.5 * (reach_lo + reach_hi)
        group_radius = np.max(
            np.hypot(*(centre[chunk_of] - group_centre[:, None, :]).transpose(2, 0, 1))
            + self._chunk_radius[chunk_of],
            axis=1,
        )
        self.table = SegmentTable(
            self._sx,
            self._sy,
            self._dx,
            self._dy,
            self._inv_len2,
            *self._chunk_chords(xs, ys),
            np.ascontiguousarray(group_centre[:, 0]),
            np.ascontiguousarray(group_centre[:, 1]),
            group_radius,
        )

    def project(
        self, points, *, extend_ends: bool = False, segment_count=None, segment_first=None
    ) -> PolylineProjection:
        """Nearest point on the polyline for each query point.

        Parameters
        ----------
        points : array_like, shape (N, 2) or (2,)
            Query points (metres). Non-finite rows give NaN results.
        extend_ends : bool
            If False (default) the path ends at its end vertices, so a point beyond an end is
            measured to that vertex. If True the first and last segments continue as rays: a point
            beyond an end is measured perpendicular to the extension, and its ``arc_length`` is
            negative (before the start) or exceeds :attr:`length` (after the end). An outer
            path-feedback loop wants this; the metrics do not.
        segment_count : array_like of int, shape (N,), optional
            Only the first ``segment_count[i]`` segments of :attr:`vertices` serve query point
            i (a path known up to some time). 0 means "the first vertex only". The end extension
            then applies only to segment 0 and, if available, the last segment.
        segment_first : array_like of int, shape (N,), optional
            Segments before ``segment_first[i]`` do not serve query point i (a window on a path
            that may pass the same place twice, e.g. laps). Must be below ``segment_count``.

        Returns
        -------
        PolylineProjection
            Arrays of shape (N,) (feet (N, 2)); scalars (foot (2,)) for a single (2,) point.
        """
        pts = np.asarray(points, dtype=float)
        single = pts.ndim == 1
        if single:
            pts = pts[None, :]
        if pts.ndim != 2 or pts.shape[1] != 2:
            raise ValueError(f"points must have shape (N, 2) or (2,), got shape {np.shape(points)}")
        n = pts.shape[0]
        limit, first = segment_windows(n, self.n_segments, segment_count, segment_first)
        best = Best(n)
        finite = np.all(np.isfinite(pts), axis=1)

        # Points that may only see the first vertex.
        only_start = finite & (limit == 0)
        if np.any(only_start):
            diff = pts[only_start] - self.vertices[0]
            best.d2[only_start] = np.einsum("ij,ij->i", diff, diff)
            best.seg[only_start] = 0

        pending = np.flatnonzero(finite & (limit > 0))
        window = (first, limit)
        if _COMPILED is not None and pending.size:
            pending = self._compiled_search(pts, pending, window, extend_ends, best)
        if pending.size:
            self._make_trees()
        if segment_first is not None and pending.size:
            pending = self._windowed_search(pts, pending, window, extend_ends, best)
        for k in _CANDIDATE_ROUNDS:
            if pending.size == 0 or k >= self._tree.n:
                break
            group_dist, group_idx = self._tree.query(pts[pending], k=k)
            candidates = self._group_segments[group_idx].reshape(pending.size, -1)
            if extend_ends:
                # The rays are not covered by the tree's distance bound: always try them.
                ends = np.broadcast_to(np.array([0, self.n_segments - 1]), (pending.size, 2))
                candidates = np.concatenate([candidates, ends], axis=1)
            self._try(
                pts[pending], pending, candidates, limit[pending], extend_ends, best, first[pending]
            )
            # Every segment outside the candidate groups is at least this far away.
            bound = group_dist[:, -1] - self._group_radius_max
            pending = pending[np.sqrt(best.d2[pending]) > bound]
        if pending.size:
            self._chunk_search(pts, pending, limit, extend_ends, best, first)
        return self._assemble(pts, finite, best, single)

    def _segment_distance2(
        self, px: np.ndarray, py: np.ndarray, candidates: np.ndarray, extend_ends: bool
    ) -> tuple[np.ndarray, np.ndarray]:
        """Squared distance from point i to segment ``candidates[i, j]``, and the foot parameter.

        ``px``, ``py`` have shape (P,), ``candidates`` (P, C). Plain x/y arrays: several times
        faster than gathering (P, C, 2) blocks.
        """
        if extend_ends:
            lower = np.where(candidates == 0, -np.inf, 0.0)
            upper = np.where(candidates == self.n_segments - 1, np.inf, 1.0)
        else:
            lower, upper = 0.0, 1.0
        return segment_distance2_of(px[:, None], py[:, None], self.table, candidates, lower, upper)

    def _try(
        self,
        pts: np.ndarray,
        rows: np.ndarray,
        candidates: np.ndarray,
        limit: np.ndarray,
        extend_ends: bool,
        best: Best,
        first: np.ndarray,
    ) -> None:
        """Project ``pts[i]`` onto segments ``candidates[i]``; keep what beats ``best[rows[i]]``.

        ``rows`` may repeat (several candidate sets for one point); ``limit`` and ``first`` (the
        window of usable segments) are per row of ``pts``.
        """
        n_rows, width = candidates.shape
        px = np.ascontiguousarray(pts[:, 0])
        py = np.ascontiguousarray(pts[:, 1])
        d2_min = np.empty(n_rows)
        seg_min = np.empty(n_rows, dtype=np.int64)
        t_min = np.empty(n_rows)
        step = max(1, _WORK_BLOCK // width)
        for lo in range(0, n_rows, step):
            part = slice(lo, lo + step)
            cand = candidates[part]
            d2, t = self._segment_distance2(px[part], py[part], cand, extend_ends)
            d2[(cand >= limit[part, None]) | (cand < first[part, None])] = np.inf
            # The nearest, and of equally near ones the lowest segment (nearest_segment_of's).
            tied = d2 == d2.min(axis=1)[:, None]
            col = np.argmin(np.where(tied, cand, np.iinfo(np.int64).max), axis=1)
            i = np.arange(cand.shape[0])
            d2_min[part], seg_min[part], t_min[part] = d2[i, col], cand[i, col], t[i, col]
        if rows.size > 1 and np.any(rows[1:] <= rows[:-1]):
            # Repeated rows: keep each point's nearest (the lowest segment on ties).
            order = np.lexsort((seg_min, d2_min, rows))
            rows, d2_min, seg_min, t_min = rows[order], d2_min[order], seg_min[order], t_min[order]
            first = np.ones(rows.size, dtype=bool)
            first[1:] = rows[1:] != rows[:-1]
            rows, d2_min, seg_min, t_min = rows[first], d2_min[first], seg_min[first], t_min[first]
        held, held_seg = best.d2[rows], best.seg[rows]
        better = (d2_min < held) | ((d2_min == held) & (seg_min < held_seg))
        rows = rows[better]
        best.d2[rows] = d2_min[better]
        best.seg[rows] = seg_min[better]
        best.t[rows] = t_min[better]

    def _chunk_search(
        self,
        pts: np.ndarray,
        pending: np.ndarray,
        limit: np.ndarray,
        extend_ends: bool,
        best: Best,
        first: np.ndarray,
    ) -> None:
        """Exact search over every chunk of a point's usable segments (``first`` to ``limit``)
        whose bounding circle is not beyond the best so far.

        The chunks are found without looking at all of them, so the cost grows with the points,
        not with points times path (a path driven in many laps, a long run's driven path): a
        point asks the chunk tree for the circles within its distance so far (one without,
        whose window held no tree candidate, takes the nearest of its window's chunk starts).
        """
        offsets = np.arange(CHUNK)
        budget = max(1, _SEARCH_BLOCK // CHUNK)
        for lo in range(0, pending.size, _POINT_BLOCK):
            idx = pending[lo : lo + _POINT_BLOCK]
            pair_point, pair_chunk = self._chunk_pairs(
                pts[idx], limit[idx], first[idx], best.d2[idx]
            )
            # Blocks of whole points (a point's pairs are never split: ties resolve as in one
            # pass), each about _SEARCH_BLOCK segment tests.
            bounds = np.searchsorted(pair_point, np.arange(idx.size + 1))
            a = 0
            while a < idx.size:
                b = int(np.searchsorted(bounds, bounds[a] + budget, side="right")) - 1
                b = min(max(b, a + 1), idx.size)
                part = slice(bounds[a], bounds[b])
                a = b
                if part.start == part.stop:
                    continue
                point, chunk = pair_point[part], pair_chunk[part]
                candidates = np.minimum(
                    self._chunk_first[chunk, None] + offsets, self.n_segments - 1
                )
                self._try(
                    pts[idx[point]],
                    idx[point],
                    candidates,
                    limit[idx[point]],
                    extend_ends,
                    best,
                    first[idx[point]],
                )

    def _window_chunks(self, limit, first) -> tuple[np.ndarray, np.ndarray]:
        """The chunks ``[lo, hi)`` that hold segments ``first`` to ``limit - 1``."""
        return first // CHUNK, np.minimum((limit - 1) // CHUNK, self._chunk_first.size - 1) + 1

    def _chunk_pairs(self, p, limit, first, d2) -> tuple[np.ndarray, np.ndarray]:
        """``(point, chunk)`` pairs, point-major with chunks ascending, of the chunks that may
        hold each point's nearest usable segment: inside its window and its lower bound
        (centre distance less radius) not beyond its best distance so far.

        A point with a distance so far asks the chunk tree for the circles within it (then keeps
        those inside its window). A point without one (the tree's candidates lay outside its
        window) enumerates its window chunk by chunk and takes the nearest of their starts: a
        true distance to a usable segment, so the pruning keeps the same nearest point and far
        fewer chunks.
        """
        upper = np.sqrt(d2)
        lo_chunk, hi_chunk = self._window_chunks(limit, first)
        spans = np.maximum(hi_chunk - lo_chunk, 0)
        short = ~np.isfinite(upper)
        points, chunks = [], []
        windowed = np.flatnonzero(short)
        if windowed.size:
            span = spans[windowed]
            starts = np.cumsum(span) - span
            owner = np.repeat(np.arange(windowed.size), span)
            chunk = np.repeat(lo_chunk[windowed], span) + np.arange(int(span.sum()))
            chunk -= np.repeat(starts, span)
            unbounded = ~np.isfinite(upper[windowed])
            if unbounded.any():
                vertex = np.maximum(self._chunk_first[chunk], first[windowed][owner])
                gap = p[windowed][owner] - self.vertices[vertex]
                seed = np.full(windowed.size, np.inf)
                np.minimum.at(seed, owner, np.hypot(gap[:, 0], gap[:, 1]))
                upper = upper.copy()
                upper[windowed[unbounded]] = seed[unbounded]
            points.append(windowed[owner])
            chunks.append(chunk)
        searched = np.flatnonzero(~short)
        if searched.size:
            found = self._chunk_tree.query_ball_point(
                p[searched],
                (upper[searched] + self._chunk_radius_max) * (1.0 + 1e-9) + 1e-12,
                return_sorted=True,
            )
            counts = np.fromiter((len(f) for f in found), dtype=np.int64, count=searched.size)
            if counts.sum():
                points.append(np.repeat(searched, counts))
                chunks.append(np.concatenate([f for f in found if f]).astype(np.int64))
        if not points:
            empty = np.zeros(0, dtype=np.int64)
            return empty, empty
        point, chunk = np.concatenate(points), np.concatenate(chunks)
        if len(points) > 1:  # each group is point-major already, and a point is in one group
            order = np.argsort(point, kind="stable")
            point, chunk = point[order], chunk[order]
        lower = (
            np.hypot(
                p[point, 0] - self._chunk_centre[chunk, 0],
                p[point, 1] - self._chunk_centre[chunk, 1],
            )
            - self._chunk_radius[chunk]
        )
        keep = (lower <= upper[point]) & (chunk >= lo_chunk[point]) & (chunk < hi_chunk[point])
        return point[keep], chunk[keep]

    def _assemble(
        self,
        pts: np.ndarray,
        finite: np.ndarray,
        best: Best,
        single: bool,
    ) -> PolylineProjection:
        n = pts.shape[0]
        every = bool(finite.all())
        f = slice(None) if every else np.flatnonzero(finite)
        s, t = best.seg[f], best.t[f]
        px, py = pts[f, 0], pts[f, 1]
        foot_x = self._sx[s] + t * self._dx[s]
        foot_y = self._sy[s] + t * self._dy[s]
        # The side is judged against the segment's direction, or the vertex tangent when the
        # foot is a vertex (see _make_vertex_tangents); on an extended end ray the segment's
        # own direction is the right one.
        tx, ty = self._tx[s], self._ty[s]
        at_start = (t <= 0.0) & ~((s == 0) & (t < 0.0))
        at_end = (t >= 1.0) & ~((s == self.n_segments - 1) & (t > 1.0))
        for at, vertex in ((at_start, s), (at_end, s + 1)):
            if at.any():
                tx[at], ty[at] = self._vertex_tx[vertex[at]], self._vertex_ty[vertex[at]]
        cross = tx * (py - foot_y) - ty * (px - foot_x)
        dist_f = np.sqrt(best.d2[f])
        # A zero cross product (on the path, or on the line through an end segment beyond
        # that end) counts as left.
        signed_f = np.where(cross < 0.0, -dist_f, dist_f)
        arc_f = self.arc_length[s] + t * self._seg_lengths[s]
        if every:
            distance, signed, arc, seg = dist_f, signed_f, arc_f, best.seg
            foot = np.column_stack((foot_x, foot_y))
        else:
            distance, signed, arc = np.full(n, np.nan), np.full(n, np.nan), np.full(n, np.nan)
            foot = np.full((n, 2), np.nan)
            distance[f], signed[f], arc[f] = dist_f, signed_f, arc_f
            foot[f, 0], foot[f, 1] = foot_x, foot_y
            seg = np.where(finite, best.seg, -1)
        if single:
            return PolylineProjection(distance[0], signed[0], arc[0], foot[0], seg[0])
        return PolylineProjection(distance, signed, arc, foot, seg)

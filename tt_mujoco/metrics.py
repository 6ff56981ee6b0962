"""Tracking metrics of a finished run, and exact point-to-polyline projection.

A run is a mapping of column name -> 1-D array, one sample per control step (SI units, radians),
as logged by the simulation loop: ``t, x, y, phi, v, omega, x0, y0, x_ref, y_ref, v_d, omega_d,
T_r_cmd, T_l_cmd, slip_lateral, slip_lateral_trailer, slip_left, slip_right, eq_violation`` are
used here (other columns are ignored). :func:`compute_metrics` turns it into the numbers of
``metrics.json`` (SPEC Section 11); the RMS values are the quantities of the paper's Section 6
tables (SPEC Section 10).

Distances to a path are distances to its polyline: the nearest point on any segment, not only on
the vertices. :class:`Polyline` does this exactly and vectorised: a k-d tree over points spread
along the segments proposes candidate segments, exact projection onto those picks the nearest,
and a distance bound certifies that no segment outside the candidates can be nearer (points that
fail the bound are retried with more candidates, then by brute force). The result is therefore
exact, including for points near a vertex of a sharply curving path.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping, Sequence
from typing import NamedTuple

import numpy as np
from scipy.spatial import cKDTree

__all__ = [
    "DEFAULT_SUMMARY_KEYS",
    "REQUIRED_COLUMNS",
    "Polyline",
    "PolylineProjection",
    "compute_metrics",
    "distance_to_polyline",
    "max_abs",
    "rmse",
    "signed_lateral_error",
    "summary_table",
    "trailer_offtrack",
]

#: Columns whose first non-finite value ends the usable part of a run (a diverged run's state,
#: target and commands all turn non-finite together).
CORE_COLUMNS = (
    "t",
    "x",
    "y",
    "phi",
    "v",
    "omega",
    "x0",
    "y0",
    "x_ref",
    "y_ref",
    "v_d",
    "omega_d",
    "T_r_cmd",
    "T_l_cmd",
)

#: Plant diagnostics: a plant that cannot measure one (e.g. slip in the reduced model) may log
#: NaN, so their maxima skip NaN instead of truncating the run.
DIAGNOSTIC_COLUMNS = (
    "slip_lateral",
    "slip_lateral_trailer",
    "slip_left",
    "slip_right",
    "eq_violation",
)

#: Every column :func:`compute_metrics` reads.
REQUIRED_COLUMNS = CORE_COLUMNS + DIAGNOSTIC_COLUMNS

#: Rows of the CLI's printed summary, in order.
DEFAULT_SUMMARY_KEYS = (
    "rmse_v",
    "max_abs_v",
    "rmse_omega",
    "max_abs_omega",
    "rmse_lateral",
    "max_lateral",
    "rmse_position",
    "max_position",
    "trailer_rmse_lateral",
    "trailer_offtrack_rms",
    "trailer_offtrack_max",
    "phi_max_abs_deg",
    "eq_violation_max",
    "slip_lateral_max",
    "slip_longitudinal_max",
    "torque_saturation_fraction",
    "sim_time_s",
    "steps",
    "finite_samples",
)

# Relative margin under which a commanded torque counts as saturated: a controller that clips its
# own output to exactly the limit must count as saturated despite rounding.
SATURATION_MARGIN = 1e-9

# Initial number of candidate tree points per query; quadrupled for points the bound rejects.
_INITIAL_CANDIDATES = 16
# Brute force works on blocks of at most this many point-segment pairs (memory, not speed).
_BRUTE_FORCE_BLOCK = 1 << 20


def rmse(x) -> float:
    """Root of the mean of ``x**2`` over all samples (NaN if empty or if any sample is NaN)."""
    x = np.asarray(x, dtype=float).ravel()
    if x.size == 0:
        return math.nan
    return float(np.sqrt(np.mean(x * x)))


def max_abs(x) -> float:
    """Largest ``|x|`` over all samples (NaN if empty or if any sample is NaN)."""
    x = np.asarray(x, dtype=float).ravel()
    if x.size == 0:
        return math.nan
    return float(np.max(np.abs(x)))


def _nanmax_abs(*arrays: np.ndarray) -> float:
    """Largest ``|value|`` over the non-NaN entries of all arrays; NaN if there are none."""
    values = np.concatenate([np.abs(np.asarray(a, dtype=float).ravel()) for a in arrays])
    values = values[~np.isnan(values)]
    return float(values.max()) if values.size else math.nan


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


class Polyline:
    """A planar polyline prepared for fast, exact nearest-point queries.

    Parameters
    ----------
    vertices : array_like, shape (M, 2)
        Finite vertices in path order (metres). Exact consecutive repeats are dropped (a standing
        vehicle logs the same point many times); at least two distinct points are required.

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
        keep = np.ones(given.shape[0], dtype=bool)
        keep[1:] = np.any(given[1:] != given[:-1], axis=1)
        if keep.sum() < 2:
            raise ValueError(
                f"polyline must contain at least two distinct points, got {given.shape[0]} "
                f"copies of {given[0].tolist()}"
            )
        self.vertices = given[keep]
        self.vertex_index = np.cumsum(keep) - 1
        starts = self.vertices[:-1]
        self._starts = starts
        self._deltas = self.vertices[1:] - starts
        seg_lengths = np.hypot(self._deltas[:, 0], self._deltas[:, 1])
        self._seg_lengths = seg_lengths
        self._seg_len2 = seg_lengths * seg_lengths
        self._seg_tangents = self._deltas / seg_lengths[:, None]
        self.arc_length = np.concatenate(([0.0], np.cumsum(seg_lengths)))
        self.length = float(self.arc_length[-1])
        self._vertex_tangents = self._make_vertex_tangents()
        self._build_tree()

    @property
    def n_segments(self) -> int:
        """Number of segments (``len(vertices) - 1``)."""
        return self._starts.shape[0]

    def _make_vertex_tangents(self) -> np.ndarray:
        """Direction used for the side of points whose foot is a vertex.

        At an interior vertex it is the sum of the two adjacent unit tangents: for any point whose
        nearest path point is that vertex, the cross product with this sum is negative on the
        outside of the turn and positive on the inside for a left turn (and the reverse for a
        right turn), so the sign is right even beyond a hairpin, where the two adjacent segments
        alone disagree. A complete reversal (sum 0) falls back to the incoming tangent.
        """
        t = self._seg_tangents
        tangents = np.empty((t.shape[0] + 1, 2))
        tangents[0] = t[0]
        tangents[-1] = t[-1]
        summed = t[:-1] + t[1:]
        norm = np.hypot(summed[:, 0], summed[:, 1])
        reversal = norm < 1e-12
        tangents[1:-1] = np.where(
            reversal[:, None], t[:-1], summed / np.where(reversal, 1.0, norm)[:, None]
        )
        return tangents

    def _build_tree(self) -> None:
        """k-d tree over the midpoints of short pieces that tile every segment.

        A segment whose piece midpoint m lies at distance D from a query point is at least
        ``D - h`` away, h the piece's half-length. Cutting long segments into pieces no longer
        than ``spacing`` keeps h small everywhere, so one long straight does not weaken the bound
        for the whole path. The spacing is the median segment length, but at least
        ``length / (2 * n_segments)`` so that the tree holds at most 3 pieces per segment.
        """
        spacing = max(float(np.median(self._seg_lengths)), self.length / (2.0 * self.n_segments))
        pieces = np.maximum(1, np.ceil(self._seg_lengths / spacing).astype(np.int64))
        segment_of_piece = np.repeat(np.arange(self.n_segments), pieces)
        first_piece = np.cumsum(pieces) - pieces
        within = np.arange(segment_of_piece.size) - np.repeat(first_piece, pieces)
        fraction = (within + 0.5) / pieces[segment_of_piece]
        midpoints = (
            self._starts[segment_of_piece] + fraction[:, None] * self._deltas[segment_of_piece]
        )
        self._piece_segment = segment_of_piece
        self._piece_half_length_max = float(np.max(self._seg_lengths / pieces) / 2.0)
        self._tree = cKDTree(midpoints)

    def project(
        self, points, *, extend_ends: bool = False, segment_count=None
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
        n_seg = self.n_segments
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

        best_d2 = np.full(n, np.inf)
        best_seg = np.full(n, -1, dtype=np.int64)
        best_t = np.zeros(n)
        finite = np.all(np.isfinite(pts), axis=1)

        # Points that may only see the first vertex.
        only_start = finite & (limit == 0)
        if np.any(only_start):
            diff = pts[only_start] - self.vertices[0]
            best_d2[only_start] = np.einsum("ij,ij->i", diff, diff)
            best_seg[only_start] = 0
            best_t[only_start] = 0.0

        pending = np.flatnonzero(finite & (limit > 0))
        n_pieces = self._tree.n
        k = min(_INITIAL_CANDIDATES, n_pieces)
        while pending.size:
            if k >= n_pieces:
                self._brute_force(pts, pending, limit, extend_ends, best_d2, best_seg, best_t)
                break
            piece_dist, piece_idx = self._tree.query(pts[pending], k=k)
            candidates = self._piece_segment[piece_idx]
            if extend_ends:
                # The rays are not covered by the tree's distance bound: always try them.
                ends = np.broadcast_to(np.array([0, n_seg - 1]), (pending.size, 2))
                candidates = np.concatenate([candidates, ends], axis=1)
            d2, tt = self._segment_distance2(pts[pending], candidates, extend_ends)
            d2[candidates >= limit[pending, None]] = np.inf
            col = np.argmin(d2, axis=1)
            rows = np.arange(pending.size)
            best_d2[pending] = d2[rows, col]
            best_seg[pending] = candidates[rows, col]
            best_t[pending] = tt[rows, col]
            # Every segment without a candidate piece is at least this far away.
            bound = piece_dist[:, -1] - self._piece_half_length_max
            certified = np.sqrt(best_d2[pending]) <= bound
            pending = pending[~certified]
            k = min(4 * k, n_pieces)

        return self._assemble(pts, finite, best_d2, best_seg, best_t, single)

    def _segment_distance2(
        self, pts: np.ndarray, candidates: np.ndarray, extend_ends: bool
    ) -> tuple[np.ndarray, np.ndarray]:
        """Squared distance from ``pts[i]`` to segments ``candidates[i, j]``, and foot parameter."""
        starts = self._starts[candidates]
        deltas = self._deltas[candidates]
        rel = pts[:, None, :] - starts
        t = np.einsum("ijk,ijk->ij", rel, deltas) / self._seg_len2[candidates]
        lower = np.zeros_like(t)
        upper = np.ones_like(t)
        if extend_ends:
            lower[candidates == 0] = -np.inf
            upper[candidates == self.n_segments - 1] = np.inf
        t = np.clip(t, lower, upper)
        off = rel - t[..., None] * deltas
        return np.einsum("ijk,ijk->ij", off, off), t

    def _brute_force(
        self,
        pts: np.ndarray,
        pending: np.ndarray,
        limit: np.ndarray,
        extend_ends: bool,
        best_d2: np.ndarray,
        best_seg: np.ndarray,
        best_t: np.ndarray,
    ) -> None:
        """Exact projection of ``pts[pending]`` onto every segment (in blocks), in place."""
        n_seg = self.n_segments
        block = max(1, _BRUTE_FORCE_BLOCK // n_seg)
        all_segments = np.arange(n_seg)
        for lo in range(0, pending.size, block):
            idx = pending[lo : lo + block]
            candidates = np.broadcast_to(all_segments, (idx.size, n_seg))
            d2, tt = self._segment_distance2(pts[idx], candidates, extend_ends)
            d2[candidates >= limit[idx, None]] = np.inf
            col = np.argmin(d2, axis=1)
            rows = np.arange(idx.size)
            best_d2[idx] = d2[rows, col]
            best_seg[idx] = col
            best_t[idx] = tt[rows, col]

    def _assemble(
        self,
        pts: np.ndarray,
        finite: np.ndarray,
        best_d2: np.ndarray,
        best_seg: np.ndarray,
        best_t: np.ndarray,
        single: bool,
    ) -> PolylineProjection:
        n = pts.shape[0]
        distance = np.full(n, np.nan)
        signed = np.full(n, np.nan)
        arc = np.full(n, np.nan)
        foot = np.full((n, 2), np.nan)
        seg = np.where(finite, best_seg, -1)
        f = np.flatnonzero(finite)
        if f.size:
            s = best_seg[f]
            t = best_t[f]
            foot_f = self._starts[s] + t[:, None] * self._deltas[s]
            # The side is judged against the segment's direction, or the vertex tangent when the
            # foot is a vertex (see _make_vertex_tangents).
            tangent = self._seg_tangents[s].copy()
            at_start = t <= 0.0
            at_end = t >= 1.0
            # On an extended end ray the segment's own direction is the right one.
            at_start &= ~((s == 0) & (t < 0.0))
            at_end &= ~((s == self.n_segments - 1) & (t > 1.0))
            tangent[at_start] = self._vertex_tangents[s[at_start]]
            tangent[at_end] = self._vertex_tangents[s[at_end] + 1]
            rel = pts[f] - foot_f
            cross = tangent[:, 0] * rel[:, 1] - tangent[:, 1] * rel[:, 0]
            dist_f = np.sqrt(best_d2[f])
            distance[f] = dist_f
            # A zero cross product (on the path, or on the line through an end segment beyond
            # that end) counts as left.
            signed[f] = np.where(cross < 0.0, -dist_f, dist_f)
            arc[f] = self.arc_length[s] + t * self._seg_lengths[s]
            foot[f] = foot_f
        if single:
            return PolylineProjection(distance[0], signed[0], arc[0], foot[0], seg[0])
        return PolylineProjection(distance, signed, arc, foot, seg)


def _as_polyline(polyline) -> Polyline:
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
    ndarray, shape (N,) (0-d for a single point); NaN for non-finite points.
    """
    return _as_polyline(polyline).project(points).distance


def signed_lateral_error(
    points, polyline, *, extend_ends: bool = False
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

    Returns
    -------
    signed_distance : ndarray, shape (N,)
        Distance to the path, positive when the point is left of the direction of travel.
    arc_length : ndarray, shape (N,)
        Path length from the path's start to the nearest path point.
    """
    proj = _as_polyline(polyline).project(points, extend_ends=extend_ends)
    return proj.signed_distance, proj.arc_length


def trailer_offtrack(tractor_xy, trailer_xy) -> np.ndarray:
    """Distance from the trailer axle midpoint P0 to the path its tractor has driven so far.

    At sample i the tractor's path is the polyline of P over samples 0..i (the causal path: a
    path the tractor drives later, e.g. on its next lap or on a crossing, does not count). The
    distance is reported only once P0 has passed the tractor's starting point, i.e. when the
    nearest point of that path lies strictly beyond P's first sample (arc length > 0). Before
    that the nearest point is the start point itself and the distance is mostly along-track
    spacing, not off-tracking: those samples are NaN.

    Parameters
    ----------
    tractor_xy, trailer_xy : array_like, shape (N, 2)
        P and P0 at the same samples; finite.

    Returns
    -------
    ndarray, shape (N,)
        Off-tracking distance (metres), NaN where P0 has not passed the start.
    """
    p = np.asarray(tractor_xy, dtype=float)
    p0 = np.asarray(trailer_xy, dtype=float)
    if p.ndim != 2 or p.shape[1] != 2 or p0.shape != p.shape:
        raise ValueError(
            f"tractor_xy and trailer_xy must both have shape (N, 2), got {p.shape} and {p0.shape}"
        )
    out = np.full(p.shape[0], np.nan)
    if p.shape[0] < 2 or np.all(p == p[0]):
        return out  # the tractor never moved: P0 cannot have passed its start
    path = Polyline(p)
    # Sample i may use the de-duplicated segments that end at or before P_i.
    proj = path.project(p0, segment_count=path.vertex_index)
    passed = proj.arc_length > 0.0
    out[passed] = proj.distance[passed]
    return out


def _finite_prefix_length(columns: Mapping[str, np.ndarray], names: Sequence[str]) -> int:
    bad = np.zeros(len(columns[names[0]]), dtype=bool)
    for name in names:
        bad |= ~np.isfinite(columns[name])
    hits = np.flatnonzero(bad)
    return int(hits[0]) if hits.size else bad.size


def _check_inputs(ts, reference_polyline, torque_limit) -> tuple[dict[str, np.ndarray], int]:
    if not isinstance(ts, Mapping):
        raise ValueError(f"ts must be a mapping of column name -> array, got {type(ts).__name__}")
    missing = [name for name in REQUIRED_COLUMNS if name not in ts]
    if missing:
        raise ValueError(f"time series lacks required columns {missing}")
    columns = {}
    for name in REQUIRED_COLUMNS:
        try:
            col = np.asarray(ts[name], dtype=float)
        except (TypeError, ValueError) as err:
            raise ValueError(f"column {name!r} must be numeric: {err}") from None
        if col.ndim != 1:
            raise ValueError(f"column {name!r} must be 1-D, got shape {col.shape}")
        columns[name] = col
    n = len(columns["t"])
    wrong = {name: len(c) for name, c in columns.items() if len(c) != n}
    if wrong:
        raise ValueError(f"all columns must have the length of 't' ({n}), got {wrong}")
    if n == 0:
        raise ValueError("time series must hold at least one sample, got 0")
    if (
        isinstance(torque_limit, bool)
        or not isinstance(torque_limit, numbers.Real)
        or not math.isfinite(torque_limit)
        or torque_limit <= 0
    ):
        raise ValueError(f"torque_limit must be a finite number > 0 (N m), got {torque_limit!r}")
    return columns, n


def compute_metrics(
    ts: Mapping[str, np.ndarray], reference_polyline, torque_limit: float
) -> dict[str, float | int]:
    """Summarise a run (SPEC Section 11, ``metrics.json``).

    Parameters
    ----------
    ts : mapping of str -> ndarray, each shape (N,)
        The run's columns (see the module docstring), sampled at the control steps.
    reference_polyline : array_like, shape (M, 2), or Polyline
        The reference path, vertices in the direction of travel.
    torque_limit : float
        Actuator limit (N m; 15 for the paper, SPEC Section 1).

    Returns
    -------
    dict
        Every RMS is the root of the mean of the squared error over the samples (uniform
        sampling); every maximum is over the samples. Errors are ``e_v = v - v_d`` and
        ``e_omega = omega - omega_d`` with the true velocities (the paper's Section 6 errors).

        - ``rmse_v``, ``max_abs_v`` (m/s); ``rmse_omega``, ``max_abs_omega`` (rad/s).
        - ``rmse_lateral``, ``max_lateral``: P to the reference polyline (m). Beyond the path's
          ends this is the distance to the end vertex.
        - ``rmse_position``, ``max_position``: P to the reference point (x_ref, y_ref) (m).
        - ``trailer_rmse_lateral``, ``trailer_max_lateral``: P0 to the reference polyline (m).
        - ``trailer_offtrack_rms``, ``trailer_offtrack_max``: P0 to the tractor's own path,
          over the ``trailer_offtrack_samples`` samples after P0 passed the tractor's starting
          point (see :func:`trailer_offtrack`); NaN if there are none (e.g. reversing).
        - ``eq_violation_max`` (rad): max ``|beta - eta phi|``.
        - ``slip_lateral_max``: max of ``|slip_lateral|`` and ``|slip_lateral_trailer|``;
          ``slip_longitudinal_max``: max of ``|slip_left|`` and ``|slip_right|`` (m/s).
          These three skip NaN entries (a plant may not provide them); NaN if all are NaN.
        - ``torque_saturation_fraction``: share of samples where ``|T_r_cmd|`` or ``|T_l_cmd|``
          exceeds ``torque_limit * (1 - 1e-9)`` (a request clipped to exactly the limit counts).
        - ``phi_max_abs_deg``: max ``|phi|`` in degrees.
        - ``steps``: N, all samples given. ``finite_samples``: length of the finite prefix, the
          samples before the first non-finite value of any of :data:`CORE_COLUMNS`; every other
          metric uses only these samples (NaN if there are none).
        - ``sample_period_s``: median spacing of ``t``; ``sim_time_s``: time covered by the finite
          prefix, ``t[n-1] - t[0] + sample_period_s`` (each sample stands for one step), 0 if
          ``n = 0``.

    Raises
    ------
    ValueError
        On missing or malformed columns, a bad polyline or torque limit, or a ``t`` that does not
        strictly increase over the finite prefix.
    """
    columns, n_total = _check_inputs(ts, reference_polyline, torque_limit)
    reference = _as_polyline(reference_polyline)
    n = _finite_prefix_length(columns, CORE_COLUMNS)
    c = {name: col[:n] for name, col in columns.items()}
    t = c["t"]
    if n >= 2 and np.any(np.diff(t) <= 0.0):
        i = int(np.flatnonzero(np.diff(t) <= 0.0)[0]) + 1
        raise ValueError(
            f"column 't' must strictly increase, got t[{i}] = {t[i]!r} after t[{i - 1}] = "
            f"{t[i - 1]!r}"
        )
    all_t = columns["t"][np.isfinite(columns["t"])]
    sample_period = float(np.median(np.diff(all_t))) if all_t.size >= 2 else math.nan

    metrics: dict[str, float | int] = {}
    e_v = c["v"] - c["v_d"]
    e_omega = c["omega"] - c["omega_d"]
    metrics["rmse_v"] = rmse(e_v)
    metrics["max_abs_v"] = max_abs(e_v)
    metrics["rmse_omega"] = rmse(e_omega)
    metrics["max_abs_omega"] = max_abs(e_omega)

    tractor_xy = np.column_stack([c["x"], c["y"]])
    trailer_xy = np.column_stack([c["x0"], c["y0"]])
    lateral = reference.project(tractor_xy).distance
    metrics["rmse_lateral"] = rmse(lateral)
    metrics["max_lateral"] = max_abs(lateral)
    position = np.hypot(c["x"] - c["x_ref"], c["y"] - c["y_ref"])
    metrics["rmse_position"] = rmse(position)
    metrics["max_position"] = max_abs(position)
    trailer_lateral = reference.project(trailer_xy).distance
    metrics["trailer_rmse_lateral"] = rmse(trailer_lateral)
    metrics["trailer_max_lateral"] = max_abs(trailer_lateral)
    offtrack = trailer_offtrack(tractor_xy, trailer_xy)
    offtrack = offtrack[~np.isnan(offtrack)]
    metrics["trailer_offtrack_rms"] = rmse(offtrack)
    metrics["trailer_offtrack_max"] = max_abs(offtrack)
    metrics["trailer_offtrack_samples"] = int(offtrack.size)

    metrics["phi_max_abs_deg"] = math.degrees(max_abs(c["phi"]))
    metrics["eq_violation_max"] = _nanmax_abs(c["eq_violation"])
    metrics["slip_lateral_max"] = _nanmax_abs(c["slip_lateral"], c["slip_lateral_trailer"])
    metrics["slip_longitudinal_max"] = _nanmax_abs(c["slip_left"], c["slip_right"])
    threshold = torque_limit * (1.0 - SATURATION_MARGIN)
    saturated = (np.abs(c["T_r_cmd"]) > threshold) | (np.abs(c["T_l_cmd"]) > threshold)
    metrics["torque_saturation_fraction"] = float(saturated.mean()) if n else math.nan

    metrics["steps"] = int(n_total)
    metrics["finite_samples"] = int(n)
    metrics["sample_period_s"] = sample_period
    metrics["sim_time_s"] = float(t[-1] - t[0] + sample_period) if n else 0.0
    return metrics


def _format_value(value) -> str:
    if isinstance(value, bool | np.bool_):
        return str(bool(value))
    if isinstance(value, int | np.integer):
        return str(int(value))
    if isinstance(value, float | np.floating):
        return f"{float(value):.6g}"
    return str(value)


def summary_table(metrics: Mapping[str, object], keys: Sequence[str] = DEFAULT_SUMMARY_KEYS) -> str:
    """Plain-text two-column table of selected metrics, for the CLI's printed summary.

    Names are left-aligned, values right-aligned; floats use 6 significant digits.

    Parameters
    ----------
    metrics : mapping
        E.g. the result of :func:`compute_metrics`, possibly with more entries.
    keys : sequence of str
        Rows, in order.

    Raises
    ------
    ValueError
        If a key is not in ``metrics``.
    """
    keys = list(keys)
    missing = [k for k in keys if k not in metrics]
    if missing:
        raise ValueError(
            f"summary keys {missing} are not in the metrics; available: {sorted(metrics)}"
        )
    if not keys:
        return ""
    values = [_format_value(metrics[k]) for k in keys]
    name_width = max(len(k) for k in keys)
    value_width = max(len(v) for v in values)
    return "\n".join(
        f"{k:<{name_width}}  {v:>{value_width}}" for k, v in zip(keys, values, strict=True)
    )

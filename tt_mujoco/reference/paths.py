"""Reference paths: planar geometry by arc length (docs/model.md Section 7).

A :class:`ReferencePath` describes where the tractor's axle midpoint P should go, as a function
of the arc length ``s`` in ``[0, length]``: the pose ``(x, y, heading)``, the signed curvature
``kappa`` (positive counter-clockwise) and its rate ``dkappa/ds``. Timing (how fast ``s``
advances) is not part of a path; it lives in :mod:`tt_mujoco.reference.targets`.

Paths of the paper (Section 6) and user paths:

- :func:`cycloid`: the cycloid arch of Section 6.1, ``r(tau) = (tau - sin tau, 1 - cos tau)``
  with ``tau = t + pi/4``, ``t in [0, 3 pi/2]``; closed forms for ``s(t)`` and ``kappa(s)``.
- :func:`s_curve`: two arcs of opposite curvature ``+-1/R`` (Section 6.3).
- :func:`circle`: constant curvature ``1/R`` (Section 6.3).
- :func:`from_csv` / :func:`from_waypoints`: a cubic spline through user waypoints, resampled
  by true arc length, checked against the curvature the vehicle can follow.

All geometry methods are vectorised over arrays of ``s``. Outside ``[0, length]`` a path is
clamped: the curvature keeps its end value, the curvature rate is 0, and the pose continues
along the end tangent. Headings are continuous (not wrapped to (-pi, pi]). The per-step
:meth:`ReferencePath.curvature_and_rate` and :meth:`ReferencePath.pose_at` are plain float
arithmetic (about 1 microsecond), because the targets call them at every control step.
"""

from __future__ import annotations

import bisect
import csv
import math
from pathlib import Path
from typing import NamedTuple

import numpy as np
from scipy.integrate import cumulative_simpson
from scipy.interpolate import CubicHermiteSpline, CubicSpline, make_smoothing_spline
from scipy.optimize import brentq

from tt_mujoco.registry import Registry, is_hook, load_hook
from tt_mujoco.vehicle.params import Params

__all__ = [
    "CYCLOID_LENGTH",
    "CYCLOID_T_END",
    "DEFAULT_MAX_CURVATURE",
    "PATHS",
    "PATH_NAMES",
    "ArcsPath",
    "CycloidPath",
    "Pose",
    "ReferencePath",
    "SplinePath",
    "circle",
    "cycloid",
    "cycloid_arc_length",
    "from_csv",
    "from_waypoints",
    "get_path",
    "s_curve",
    "steady_articulation",
]

#: Built-in path names accepted by :func:`get_path` (besides a ``.csv`` file).
PATH_NAMES = ("cycloid", "s_curve", "circle")

#: End of the cycloid's time parameter, ``t in [0, 3 pi/2]`` (Section 6.1).
CYCLOID_T_END = 1.5 * math.pi

#: Length of the cycloid arc, ``l = 8 cos(pi/8)`` = 7.391 m (Section 6.1).
CYCLOID_LENGTH = 8.0 * math.cos(math.pi / 8.0)

# 4 cos(pi/8): the arc length at the arch's apex (tau = pi), the centre of the kappa(s) formula.
_CYCLOID_MID = 4.0 * math.cos(math.pi / 8.0)

#: Largest |kappa| (1/m) a user path may have by default: a turn radius of 0.5 m. With the
#: default same-path steering (eta = -1/7) the steady-state articulation there is 64.4 deg
#: (the rod O-P0 would stand perpendicular to the tractor, phi = 90 deg, near kappa = 3.02 1/m);
#: with the paper's eta = 3 it is -22.8 deg, clear of that design's singular 30 deg. The paper's
#: own paths stay below 1 1/m. See :func:`steady_articulation` and docs/paper-notes.md.
DEFAULT_MAX_CURVATURE = 2.0


class Pose(NamedTuple):
    """A planar pose: position (m) and heading (rad)."""

    x: float
    y: float
    heading: float


def _out(a: np.ndarray, scalar: bool):
    return float(a) if scalar else a


class ReferencePath:
    """A planar path parameterised by arc length ``s in [0, length]``.

    Subclasses implement the geometry on ``[0, length]`` (``_pose``, ``_curvature``,
    ``_curvature_rate``, all on float arrays) and the scalar :meth:`curvature_and_rate`; this
    base class adds clamping outside the path and the array/scalar plumbing.

    Parameters
    ----------
    name : str
        Short label used in reports ("cycloid", "s_curve", "circle" or the CSV file name).
    length : float
        Arc length (m), > 0.
    initial_pose : (x, y, heading), optional
        Where the vehicle starts. Defaults to :attr:`start_pose`; differs from it only when a
        run deliberately starts off the path (the cycloid's ``start="paper"``).
    station_speeds : (s, v) arrays, optional
        Desired speeds (m/s) at arc-length stations (m), from a CSV ``v`` column.
    """

    def __init__(self, name: str, length: float, initial_pose=None, station_speeds=None):
        if not (math.isfinite(length) and length > 0):
            raise ValueError(f"path length={length!r} is not allowed: it must be finite and > 0")
        self.name = name
        self.length = float(length)
        self.station_speeds = station_speeds
        self._initial_pose = None if initial_pose is None else Pose(*map(float, initial_pose))

    # --- subclass hooks (s is a float array already clipped to [0, length]) ----------------
    def _pose(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        raise NotImplementedError

    def _curvature(self, s: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def _curvature_rate(self, s: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def _pose_at(self, s: float) -> tuple[float, float, float]:
        raise NotImplementedError

    def pose_at(self, s: float) -> tuple[float, float, float]:
        """``(x, y, heading)`` at one float ``s`` in plain float arithmetic, for per-step logging.

        Clamped like :meth:`pose`, which it agrees with to rounding for the closed-form paths
        and to ~1e-11 m for splines.
        """
        clipped = min(max(s, 0.0), self.length)
        x, y, heading = self._pose_at(clipped)
        if s != clipped:
            x += (s - clipped) * math.cos(heading)
            y += (s - clipped) * math.sin(heading)
        return x, y, heading

    def curvature_and_rate(self, s: float) -> tuple[float, float]:
        """``(kappa(s), dkappa/ds(s))`` for one float ``s``, in plain float arithmetic.

        The fast path for the per-step tracking targets; agrees with :meth:`curvature` and
        :meth:`curvature_rate` to rounding for the closed-form paths, and to ~1e-9 (kappa) and
        ~1e-6 (rate) for splines.
        """
        raise NotImplementedError

    # --- public, vectorised ----------------------------------------------------------------
    def pose(self, s):
        """Pose at arc length ``s`` (float or array): ``(x, y, heading)``.

        Beyond either end the pose continues along the end tangent (heading held).
        """
        s_arr = np.asarray(s, dtype=float)
        clipped = np.clip(s_arr, 0.0, self.length)
        x, y, heading = self._pose(clipped)
        beyond = s_arr - clipped
        x = x + beyond * np.cos(heading)
        y = y + beyond * np.sin(heading)
        scalar = s_arr.ndim == 0
        return _out(x, scalar), _out(y, scalar), _out(heading, scalar)

    def curvature(self, s):
        """Signed curvature kappa(s) (1/m, + counter-clockwise), held at its end values outside."""
        s_arr = np.asarray(s, dtype=float)
        kappa = self._curvature(np.clip(s_arr, 0.0, self.length))
        return _out(np.asarray(kappa, dtype=float), s_arr.ndim == 0)

    def curvature_rate(self, s):
        """dkappa/ds (1/m^2): 0 outside the path and at curvature jumps."""
        s_arr = np.asarray(s, dtype=float)
        rate = self._curvature_rate(np.clip(s_arr, 0.0, self.length))
        rate = np.where((s_arr < 0.0) | (s_arr > self.length), 0.0, rate)
        return _out(np.asarray(rate, dtype=float), s_arr.ndim == 0)

    def dense(self, ds: float = 0.005) -> np.ndarray:
        """The path as an ``(N, 2)`` polyline with spacing at most ``ds`` (both ends included)."""
        if not (math.isfinite(ds) and ds > 0):
            raise ValueError(f"ds={ds!r} is not allowed: it must be finite and > 0")
        n = max(2, math.ceil(self.length / ds) + 1)
        x, y, _ = self.pose(np.linspace(0.0, self.length, n))
        return np.column_stack([x, y])

    @property
    def start_pose(self) -> Pose:
        """Pose at s = 0."""
        return Pose(*self.pose(0.0))

    @property
    def end_pose(self) -> Pose:
        """Pose at s = length."""
        return Pose(*self.pose(self.length))

    @property
    def initial_pose(self) -> Pose:
        """Where the vehicle starts (the path start unless a run starts off the path)."""
        return self._initial_pose if self._initial_pose is not None else self.start_pose

    @property
    def max_abs_curvature(self) -> float:
        """max |kappa| over the path (sampled every 1 mm, plus the closed-form cases' ends)."""
        s = np.linspace(0.0, self.length, max(2, math.ceil(self.length / 1e-3) + 1))
        return float(np.max(np.abs(self.curvature(s))))

    def __repr__(self) -> str:
        return f"{type(self).__name__}(name={self.name!r}, length={self.length:.4f})"


# --- cycloid (Section 6.1) ----------------------------------------------------------------------
def cycloid_arc_length(t):
    """Arc length of the cycloid at time parameter ``t``: ``4cos(pi/8) - 4cos((t + pi/4)/2)``.

    Section 6.1: ``s(t) = int_0^t 2 sin(y/2 + pi/8) dy``. Vectorised.
    """
    return _CYCLOID_MID - 4.0 * np.cos((np.asarray(t, dtype=float) + math.pi / 4.0) / 2.0)


class CycloidPath(ReferencePath):
    """The paper's cycloid arc (Section 6.1) in closed form.

    ``r(tau) = (tau - sin tau, 1 - cos tau)``, ``tau = t + pi/4``, ``t in [0, 3 pi/2]``. With
    ``u = 4cos(pi/8) - s = 4 cos(tau/2)``: ``tau = 2 arccos(u/4)``, heading ``pi/2 - tau/2``
    (the arch is traced clockwise, so kappa < 0) and ``kappa(s) = -1/sqrt(16 - u^2)`` (the
    paper's unsigned |kappa(s)| with the sign restored, docs/model.md Section 7). ``dkappa/ds =
    u (16 - u^2)^(-3/2)``.
    """

    def __init__(self, initial_pose=None):
        super().__init__("cycloid", CYCLOID_LENGTH, initial_pose=initial_pose)

    def _pose(self, s):
        cos_half = np.clip((_CYCLOID_MID - s) / 4.0, -1.0, 1.0)
        tau = 2.0 * np.arccos(cos_half)
        return tau - np.sin(tau), 1.0 - np.cos(tau), math.pi / 2.0 - tau / 2.0

    def _curvature(self, s):
        u = _CYCLOID_MID - s
        return -1.0 / np.sqrt(16.0 - u * u)

    def _curvature_rate(self, s):
        u = _CYCLOID_MID - s
        return u * (16.0 - u * u) ** -1.5

    def _pose_at(self, s):
        tau = 2.0 * math.acos(min(max((_CYCLOID_MID - s) / 4.0, -1.0), 1.0))
        return tau - math.sin(tau), 1.0 - math.cos(tau), math.pi / 2.0 - tau / 2.0

    def curvature_and_rate(self, s: float) -> tuple[float, float]:
        u = _CYCLOID_MID - min(max(s, 0.0), CYCLOID_LENGTH)
        if s < 0.0 or s > CYCLOID_LENGTH:
            return -1.0 / math.sqrt(16.0 - u * u), 0.0
        q = 16.0 - u * u
        root = math.sqrt(q)
        return -1.0 / root, u / (q * root)


def cycloid(start: str = "on_path") -> CycloidPath:
    """The paper's cycloid path (Section 6.1), length 8 cos(pi/8) = 7.391 m.

    Parameters
    ----------
    start : {"on_path", "paper"}
        ``"on_path"``: the vehicle starts at the path's start, (0.0783, 0.2929) heading 3pi/8.
        ``"paper"``: at the paper's initial condition q(0) = (0, 0, pi/4) (Section 6.1), which
        is 0.303 m off the path and 22.5 deg off its heading (docs/model.md Section 7). The
        geometry is
        the same either way; only :attr:`~ReferencePath.initial_pose` differs.
    """
    if start == "on_path":
        return CycloidPath()
    if start == "paper":
        return CycloidPath(initial_pose=(0.0, 0.0, math.pi / 4.0))
    raise ValueError(f"start={start!r} is not allowed: use 'on_path' or 'paper'")


# --- piecewise-constant curvature (s_curve, circle) ----------------------------------------------
class ArcsPath(ReferencePath):
    """Consecutive arcs (or straight segments) of constant curvature, in closed form.

    Parameters
    ----------
    name : str
    start : (x, y, heading)
        Pose at s = 0.
    segments : sequence of (length, kappa)
        Segment i covers ``s in [s_i, s_i + length_i)``; at a boundary the next segment's
        curvature applies. The curvature rate is 0 everywhere (jumps carry no rate).
    """

    def __init__(self, name: str, start, segments, initial_pose=None):
        lengths = np.array([float(seg[0]) for seg in segments])
        kappas = np.array([float(seg[1]) for seg in segments])
        if lengths.size == 0 or np.any(~np.isfinite(lengths)) or np.any(lengths <= 0):
            raise ValueError(f"segments={segments!r}: every segment length must be finite and > 0")
        if np.any(~np.isfinite(kappas)):
            raise ValueError(f"segments={segments!r}: every curvature must be finite")
        super().__init__(name, float(lengths.sum()), initial_pose=initial_pose)
        self._bounds = np.concatenate([[0.0], np.cumsum(lengths)])
        self._kappas = kappas
        x0, y0, h0 = (float(v) for v in start)
        starts = [(x0, y0, h0)]
        for length, kappa in zip(lengths[:-1], kappas[:-1], strict=True):
            x, y, h = starts[-1]
            dx, dy, dh = _arc_step(length, kappa, h)
            starts.append((x + dx, y + dy, h + dh))
        self._starts = np.array(starts)
        # Python lists for the scalar fast path.
        self._inner_bounds = [float(b) for b in self._bounds[1:-1]]
        self._kappa_list = [float(k) for k in kappas]
        self._bound_list = [float(b) for b in self._bounds]
        self._start_list = [tuple(map(float, row)) for row in self._starts]

    def _segment(self, s):
        idx = np.searchsorted(self._bounds[1:-1], s, side="right")
        return idx, s - self._bounds[idx]

    def _pose(self, s):
        idx, local = self._segment(s)
        kappa = self._kappas[idx]
        x0, y0, h0 = np.moveaxis(self._starts[idx], -1, 0)
        dx, dy, dh = _arc_step(local, kappa, h0)
        return x0 + dx, y0 + dy, h0 + dh

    def _curvature(self, s):
        return self._kappas[self._segment(s)[0]]

    def _curvature_rate(self, s):
        return np.zeros_like(s)

    def _pose_at(self, s):
        i = bisect.bisect_right(self._inner_bounds, s)
        x0, y0, h0 = self._start_list[i]
        kappa = self._kappa_list[i]
        local = s - self._bound_list[i]
        turn = kappa * local
        chord = local if abs(turn) < 1e-12 else 2.0 * math.sin(turn / 2.0) / kappa
        mid = h0 + turn / 2.0
        return x0 + chord * math.cos(mid), y0 + chord * math.sin(mid), h0 + turn

    def curvature_and_rate(self, s: float) -> tuple[float, float]:
        return self._kappa_list[bisect.bisect_right(self._inner_bounds, s)], 0.0


def _arc_step(length, kappa, heading):
    """Displacement and heading change along an arc of given length and curvature (any kappa).

    The chord is ``length * sinc(kappa length / 2)`` along the mid heading, which is exact and
    stays finite for kappa = 0 (np.sinc(z) = sin(pi z)/(pi z)).
    """
    turn = kappa * length
    chord = length * np.sinc(turn / (2.0 * math.pi))
    mid = heading + turn / 2.0
    return chord * np.cos(mid), chord * np.sin(mid), turn


def s_curve(R: float = 1.5) -> ArcsPath:
    """The S-curve of Section 6.3: kappa = +1/R on [0, pi R), -1/R on [pi R, 2 pi R].

    Starts at the origin heading 0 (+x); the first arc turns left, the second right, ending at
    (0, 4R) heading 0. Length 2 pi R = 9.42 m for R = 1.5 m.
    """
    R = positive_number("R", R)
    return ArcsPath("s_curve", (0.0, 0.0, 0.0), [(math.pi * R, 1.0 / R), (math.pi * R, -1.0 / R)])


def circle(R: float = 1.0, length: float | None = None) -> ArcsPath:
    """The circle of Section 6.3: centre at the origin, counter-clockwise, kappa = 1/R.

    Starts at (R, 0) heading pi/2, as the paper's ``x_d = R cos(omega_d t), y_d = R sin(omega_d
    t)``. ``length`` defaults to one lap, 2 pi R; pass more when the run lasts longer (the
    path then overlaps itself).
    """
    R = positive_number("R", R)
    length = 2.0 * math.pi * R if length is None else positive_number("length", length)
    return ArcsPath("circle", (R, 0.0, math.pi / 2.0), [(length, 1.0 / R)])


# --- user paths (CSV) ----------------------------------------------------------------------------
class SplinePath(ReferencePath):
    """A C2 cubic spline through waypoints, parameterised by true arc length.

    Built by :func:`from_waypoints`. The spline ``r(u)`` is fitted in the chord-length
    parameter ``u``; ``s(u) = int |r'(u)| du`` is integrated with Simpson's rule on a fine grid
    (32 sub-steps per waypoint interval) and inverted with a cubic Hermite interpolant that uses
    the exact slope ``du/ds = 1/|r'(u)|``, so ``pose(s)`` lies on the spline and ``|d(x, y)/ds|
    = 1`` to ~1e-8. Curvature ``(x'y'' - y'x'')/|r'|^3`` is continuous (C2 spline); its rate
    jumps at the waypoints (a cubic spline's third derivative is piecewise constant).

    The scalar :meth:`curvature_and_rate` interpolates kappa on each fine cell with the cubic
    Hermite polynomial through the exact end values and one-sided slopes, so its rate is the
    exact derivative of its kappa and both agree with the vectorised methods to ~1e-6.
    """

    def __init__(self, name, spline, u_fine, s_fine, heading_fine, station_speeds=None):
        super().__init__(name, float(s_fine[-1]), station_speeds=station_speeds)
        self._spline = spline
        self._s_fine = s_fine
        self._heading_fine = heading_fine
        d1 = spline(u_fine, 1)
        self._u_of_s = CubicHermiteSpline(s_fine, u_fine, 1.0 / np.hypot(d1[:, 0], d1[:, 1]))
        # Per fine cell: kappa at both ends and the rate from each end's own side (the third
        # derivative, constant inside a waypoint interval, is taken at the cell's middle).
        d2 = spline(u_fine, 2)
        d3_mid = spline(0.5 * (u_fine[:-1] + u_fine[1:]), 3)
        kappa = _spline_curvature(d1, d2)
        rate_left = _spline_curvature_rate(d1[:-1], d2[:-1], d3_mid)
        rate_right = _spline_curvature_rate(d1[1:], d2[1:], d3_mid)
        h = np.diff(s_fine)
        secant = np.diff(kappa) / h
        c2 = (3.0 * secant - 2.0 * rate_left - rate_right) / h
        c3 = (rate_left + rate_right - 2.0 * secant) / h**2
        self._cell_starts = [float(q) for q in s_fine[1:-1]]
        self._cells = [
            tuple(map(float, row))
            for row in zip(s_fine[:-1], kappa[:-1], rate_left, c2, c3, strict=True)
        ]
        self._kappa_ends = (float(kappa[0]), float(kappa[-1]))
        # Per fine cell for pose_at: cubic Hermite in s of x, y (slopes cos, sin of the heading)
        # and of the heading (slopes kappa); exact at the cell ends, error ~ h^4 inside.
        xy = spline(u_fine)
        self._pose_cells = [
            tuple(map(float, row))
            for row in zip(
                s_fine[:-1],
                h,
                xy[:-1, 0],
                xy[:-1, 1],
                heading_fine[:-1],
                kappa[:-1],
                xy[1:, 0],
                xy[1:, 1],
                heading_fine[1:],
                kappa[1:],
                strict=True,
            )
        ]

    def _derivatives(self, s):
        u = self._u_of_s(s)
        return u, self._spline(u, 1), self._spline(u, 2), self._spline(u, 3)

    def _pose(self, s):
        u = self._u_of_s(s)
        xy = self._spline(u)
        d1 = self._spline(u, 1)
        exact = np.arctan2(d1[..., 1], d1[..., 0])
        # atan2 wraps; pick the branch closest to the unwrapped heading on the fine grid.
        near = np.interp(s, self._s_fine, self._heading_fine)
        heading = exact + 2.0 * math.pi * np.round((near - exact) / (2.0 * math.pi))
        return xy[..., 0], xy[..., 1], heading

    def _curvature(self, s):
        _, d1, d2, _ = self._derivatives(s)
        return _spline_curvature(d1, d2)

    def _curvature_rate(self, s):
        _, d1, d2, d3 = self._derivatives(s)
        return _spline_curvature_rate(d1, d2, d3)

    def _pose_at(self, s):
        cell = self._pose_cells[
            min(bisect.bisect_right(self._cell_starts, s), len(self._cells) - 1)
        ]
        s0, h, x0, y0, a0, k0, x1, y1, a1, k1 = cell
        w = (s - s0) / h
        w2, w3 = w * w, w * w * w
        b00, b10, b01, b11 = (
            2 * w3 - 3 * w2 + 1.0,
            (w3 - 2 * w2 + w) * h,
            3 * w2 - 2 * w3,
            (w3 - w2) * h,
        )
        return (
            b00 * x0 + b10 * math.cos(a0) + b01 * x1 + b11 * math.cos(a1),
            b00 * y0 + b10 * math.sin(a0) + b01 * y1 + b11 * math.sin(a1),
            b00 * a0 + b10 * k0 + b01 * a1 + b11 * k1,
        )

    def curvature_and_rate(self, s: float) -> tuple[float, float]:
        if s < 0.0:
            return self._kappa_ends[0], 0.0
        if s > self.length:
            return self._kappa_ends[1], 0.0
        s0, c0, c1, c2, c3 = self._cells[bisect.bisect_right(self._cell_starts, s)]
        w = s - s0
        return c0 + w * (c1 + w * (c2 + w * c3)), c1 + w * (2.0 * c2 + 3.0 * w * c3)


def _spline_curvature(d1, d2):
    cross = d1[..., 0] * d2[..., 1] - d1[..., 1] * d2[..., 0]
    return cross / (d1[..., 0] ** 2 + d1[..., 1] ** 2) ** 1.5


def _spline_curvature_rate(d1, d2, d3):
    """dkappa/ds from the first three derivatives of r(u): (dkappa/du) / |r'|."""
    speed = np.hypot(d1[..., 0], d1[..., 1])
    cross = d1[..., 0] * d2[..., 1] - d1[..., 1] * d2[..., 0]
    cross_rate = d1[..., 0] * d3[..., 1] - d1[..., 1] * d3[..., 0]
    dot = d1[..., 0] * d2[..., 0] + d1[..., 1] * d2[..., 1]
    # kappa = cross / speed^3, d(speed)/du = dot / speed.
    return (cross_rate / speed**3 - 3.0 * cross * dot / speed**5) / speed


def _fmt(value: float) -> str:
    return f"{value:.6g}"


def from_waypoints(
    x,
    y,
    v=None,
    *,
    name: str = "waypoints",
    max_curvature: float = DEFAULT_MAX_CURVATURE,
    smoothing: float | None = None,
    labels=None,
) -> SplinePath:
    """Fit a curvature-continuous path through waypoints (docs/model.md Section 7, user paths).

    Parameters
    ----------
    x, y : array_like
        Waypoints (m), at least 4, finite, no two consecutive ones equal. If the last equals
        the first, the path is closed and the spline is periodic (curvature continuous across
        the seam).
    v : array_like, optional
        Desired speed (m/s) at each waypoint, finite and >= 0, never 0 at two consecutive
        waypoints; stored as :attr:`~ReferencePath.station_speeds` at the waypoints' arc
        lengths.
    name : str
    max_curvature : float
        Largest |kappa| (1/m) the vehicle is asked to follow; a path exceeding it is refused
        with the offending curvature and its place (default :data:`DEFAULT_MAX_CURVATURE`).
    smoothing : float, optional
        None (default): the interpolating cubic spline (through every waypoint, not-a-knot
        ends, or periodic if closed). A number ``lam >= 0``: scipy's
        ``make_smoothing_spline`` with that penalty on each coordinate (needs >= 5 waypoints;
        natural ends, so kappa = 0 at both ends). For noisy waypoints such as GPS logs.
    labels : list of str, optional
        How error messages name each waypoint (default "waypoint i", 0-based).

    Returns
    -------
    SplinePath
    """
    x = np.asarray(x, dtype=float).ravel()
    y = np.asarray(y, dtype=float).ravel()
    if x.shape != y.shape:
        raise ValueError(f"x and y have different lengths ({x.size} and {y.size})")
    if labels is None:
        labels = [f"waypoint {i}" for i in range(x.size)]
    max_curvature = positive_number("max_curvature", max_curvature)
    if x.size < 4:
        raise ValueError(f"{name}: {x.size} waypoints is not allowed: a path needs at least 4")
    for col, values in (("x", x), ("y", y)):
        bad = np.flatnonzero(~np.isfinite(values))
        if bad.size:
            i = int(bad[0])
            raise ValueError(
                f"{name}: {col}={float(values[i])!r} at {labels[i]} is not allowed: "
                "waypoints must be finite numbers"
            )
    step = np.hypot(np.diff(x), np.diff(y))
    repeated = np.flatnonzero(step <= 1e-9)
    if repeated.size:
        i = int(repeated[0])
        raise ValueError(
            f"{name}: {labels[i]} and {labels[i + 1]} repeat the point "
            f"(x={_fmt(x[i])}, y={_fmt(y[i])}): consecutive waypoints must differ"
        )
    if v is not None:
        v = np.asarray(v, dtype=float).ravel()
        if v.shape != x.shape:
            raise ValueError(f"{name}: v has {v.size} values for {x.size} waypoints")
        for i, value in enumerate(v):
            if not (math.isfinite(value) and value >= 0.0):
                raise ValueError(
                    f"{name}: v={float(value)!r} at {labels[i]} is not allowed: "
                    "speeds must be finite and >= 0 m/s (forward driving only)"
                )
        both_zero = np.flatnonzero((v[:-1] == 0.0) & (v[1:] == 0.0))
        if both_zero.size:
            i = int(both_zero[0])
            raise ValueError(
                f"{name}: v=0 at both {labels[i]} and {labels[i + 1]} is not allowed: "
                "the vehicle would never get from one to the other"
            )

    u = np.concatenate([[0.0], np.cumsum(step)])  # chord-length parameter
    xy = np.column_stack([x, y])
    closed = math.hypot(x[-1] - x[0], y[-1] - y[0]) <= 1e-9
    if smoothing is None:
        if closed:
            xy[-1] = xy[0]  # periodic splines need bit-equal ends
        spline = CubicSpline(u, xy, axis=0, bc_type="periodic" if closed else "not-a-knot")
    else:
        if not (math.isfinite(smoothing) and smoothing >= 0):
            raise ValueError(f"smoothing={smoothing!r} is not allowed: use None or a number >= 0")
        if x.size < 5:
            raise ValueError(
                f"{name}: smoothing needs at least 5 waypoints, got {x.size}; use smoothing=None"
            )
        spline = make_smoothing_spline(u, xy, lam=float(smoothing), axis=0)

    # Fine grid: 32 sub-intervals per waypoint interval, for the arc length and the checks.
    sub = 32
    frac = np.arange(sub) / sub
    u_fine = np.concatenate([(u[:-1, None] + frac[None, :] * np.diff(u)[:, None]).ravel(), u[-1:]])
    d1 = spline(u_fine, 1)
    speed = np.hypot(d1[:, 0], d1[:, 1])
    if np.min(speed) <= 1e-9 * max(1.0, float(np.max(speed))):
        i = int(np.argmin(speed))
        raise ValueError(
            f"{name}: the fitted path stops (zero tangent) near u={_fmt(u_fine[i])} m of chord "
            "length; remove the waypoints that double back"
        )
    s_fine = cumulative_simpson(speed, x=u_fine, initial=0.0)
    heading_fine = np.unwrap(np.arctan2(d1[:, 1], d1[:, 0]))
    kappa_fine = _spline_curvature(d1, spline(u_fine, 2))
    worst = int(np.argmax(np.abs(kappa_fine)))
    if abs(kappa_fine[worst]) > max_curvature:
        k = float(kappa_fine[worst])
        seg = min(int(np.searchsorted(u, u_fine[worst], side="right")) - 1, x.size - 2)
        raise ValueError(
            f"{name}: curvature kappa={k:.4g} 1/m (turn radius {1 / abs(k):.3g} m) at "
            f"s={s_fine[worst]:.4g} m, between {labels[seg]} (x={_fmt(x[seg])}, "
            f"y={_fmt(y[seg])}) and {labels[seg + 1]} (x={_fmt(x[seg + 1])}, "
            f"y={_fmt(y[seg + 1])}), is more than the vehicle can follow: "
            f"|kappa| <= {max_curvature:g} 1/m (turn radius >= {1 / max_curvature:.3g} m) is "
            "allowed; space or smooth the waypoints, or raise max_curvature"
        )
    station_speeds = None
    if v is not None:
        station_speeds = (s_fine[::sub].copy(), v.copy())
    return SplinePath(name, spline, u_fine, s_fine, heading_fine, station_speeds=station_speeds)


def from_csv(
    path,
    *,
    max_curvature: float = DEFAULT_MAX_CURVATURE,
    smoothing: float | None = None,
) -> SplinePath:
    """Read a user path from CSV and fit it (docs/model.md Section 7, user paths).

    The file has a header row naming the columns ``x`` and ``y`` (metres) and optionally ``v``
    (desired speed, m/s), in any order, then one waypoint per row; blank lines are skipped.
    Timing (cruise speed, start and stop) is chosen by :mod:`tt_mujoco.reference.targets`.

    Parameters
    ----------
    path : str or Path
    max_curvature, smoothing :
        See :func:`from_waypoints`.

    Raises
    ------
    ValueError
        Missing or empty file, a header without ``x`` and ``y`` (or with unknown columns), a
        row with the wrong number of fields or a non-number, fewer than 4 waypoints, NaN or
        infinite values, repeated consecutive points, bad speeds, or curvature beyond
        ``max_curvature``. The message names the bad value and its line.
    """
    file = Path(path)
    if not file.is_file():
        raise ValueError(f"path file {str(path)!r} does not exist (or is not a file)")
    with file.open(newline="", encoding="utf-8-sig") as handle:
        rows = [
            (number, row)
            for number, row in enumerate(csv.reader(handle), start=1)
            if any(cell.strip() for cell in row)
        ]
    if not rows:
        raise ValueError(f"path file {str(path)!r} is empty: it needs a header row 'x,y'")
    header_line, header = rows[0]
    columns = [cell.strip().lower() for cell in header]
    unknown = [c for c in columns if c not in ("x", "y", "v")]
    if "x" not in columns or "y" not in columns or unknown or len(set(columns)) != len(columns):
        raise ValueError(
            f"{file.name}: header {','.join(header)!r} (line {header_line}) is not allowed: the "
            "first row must name the columns x and y, optionally v (e.g. 'x,y' or 'x,y,v'), "
            "each once"
        )
    index = {c: columns.index(c) for c in columns}
    values = {c: [] for c in columns}
    labels = []
    for number, row in rows[1:]:
        if len(row) != len(columns):
            raise ValueError(
                f"{file.name}: line {number} has {len(row)} fields ({','.join(row)!r}); "
                f"the header has {len(columns)}"
            )
        for c in columns:
            cell = row[index[c]].strip()
            try:
                values[c].append(float(cell))
            except ValueError:
                raise ValueError(
                    f"{file.name}: {c}={cell!r} on line {number} is not a number"
                ) from None
        labels.append(f"line {number}")
    return from_waypoints(
        values["x"],
        values["y"],
        values.get("v"),
        name=file.name,
        max_curvature=max_curvature,
        smoothing=smoothing,
        labels=labels,
    )


# --- dispatch --------------------------------------------------------------------------------
_FACTORY_OPTIONS = {
    "cycloid": ("start",),
    "s_curve": ("R",),
    "circle": ("R", "length"),
    "csv": ("max_curvature", "smoothing"),
}


#: Path name -> factory returning a :class:`ReferencePath`. ``PATHS.register`` adds one; a
#: hook ``module:NAME`` or ``file.py:NAME`` (a ReferencePath, or a factory taking the path
#: options as keywords) needs no registration.
PATHS = Registry("path", also="a path to a .csv file")
PATHS.register("cycloid", cycloid)
PATHS.register("s_curve", s_curve)
PATHS.register("circle", circle)


def path_kind(name_or_csv) -> str:
    """``"csv"`` for a CSV file, ``"hook"`` for ``module:NAME``/``file.py:NAME``, else the
    registered name (ValueError, with the allowed names, for an unknown one)."""
    text = str(name_or_csv).strip()
    if text.lower().endswith(".csv"):
        return "csv"
    if is_hook(text):
        return "hook"
    key = text.lower().replace("-", "_")
    if key in PATHS:
        return key
    raise PATHS.unknown(text)


def check_options(path: str, options, allowed) -> None:
    """ValueError naming the options of ``path`` outside ``allowed`` (None: any is allowed,
    a hooked path's factory checks its own)."""
    unknown = sorted(set(options) - set(allowed)) if allowed is not None else []
    if unknown:
        raise ValueError(
            f"option(s) {', '.join(unknown)} not allowed for path {path!r}: allowed are "
            f"{', '.join(allowed)}"
        )


def _from_hook(spec: str, **kw) -> ReferencePath:
    obj = load_hook(spec, "path")
    if not isinstance(obj, ReferencePath):
        if not callable(obj):
            raise ValueError(f"path {spec!r} is not allowed: {obj!r} is not a ReferencePath")
        try:
            obj = obj(**kw)
        except TypeError as err:
            raise ValueError(f"path {spec!r} does not take the options {kw}: {err}") from None
    elif kw:
        raise ValueError(f"path {spec!r} is a fixed path: it takes no options ({sorted(kw)})")
    if not isinstance(obj, ReferencePath):
        raise ValueError(
            f"path {spec!r} is not allowed: it gave {type(obj).__name__}, not a "
            "tt_mujoco.reference.paths.ReferencePath"
        )
    return obj


def get_path(name_or_csv, **kw) -> ReferencePath:
    """A path by name (``"cycloid"``, ``"s_curve"``, ``"circle"``, or one registered in
    :data:`PATHS`), from a ``.csv`` file, or from a hook ``module:NAME`` / ``file.py:NAME``.

    Keyword options go to the factory: cycloid ``start``; s_curve ``R``; circle ``R``,
    ``length``; CSV ``max_curvature``, ``smoothing``; a hook or registered path, its own.
    """
    key = path_kind(name_or_csv)
    text = str(name_or_csv).strip()
    if key == "hook":
        return _from_hook(text, **kw)
    check_options(text, kw, _FACTORY_OPTIONS.get(key))
    if key == "csv":
        return from_csv(text, **kw)
    return PATHS[key](**kw)


def positive_number(name: str, value) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ValueError(f"{name}={value!r} is not allowed: it must be a number > 0")
    if not (math.isfinite(value) and value > 0):
        raise ValueError(f"{name}={value!r} is not allowed: it must be finite and > 0")
    return float(value)


# --- what the vehicle can follow ---------------------------------------------------------------
def steady_articulation(kappa: float, params: Params | None = None) -> float:
    """Steady-state articulation phi (rad) while the tractor turns with constant curvature.

    Solves ``phi_dot = 0`` in docs/model.md Section 2 with ``omega = kappa v``:
    ``sin((eta - 1) phi) + kappa (L0 cos(eta phi) + L cos((eta - 1) phi)) = 0``, taking the
    root that grows continuously from phi = 0 at kappa = 0 and staying where cos(beta) > 0.
    Returns nan if there is none (eta = 1, or the articulation would reach the singularity).
    Used to justify :data:`DEFAULT_MAX_CURVATURE`.
    """
    p = Params() if params is None else params
    eta, L, L0 = p.eta, p.L, p.L0
    kappa = float(kappa)
    if kappa == 0.0:
        return 0.0
    if eta == 1.0:
        return math.nan

    def residual(phi: float) -> float:
        return math.sin((eta - 1.0) * phi) + kappa * (
            L0 * math.cos(eta * phi) + L * math.cos((eta - 1.0) * phi)
        )

    # Near phi = 0 the residual is (eta - 1) phi + kappa (L0 + L): the root's sign follows.
    sign = math.copysign(1.0, -kappa * (eta - 1.0))
    reach = min(math.pi, p.phi_singular * (1.0 - 1e-9))
    grid = np.linspace(0.0, sign * reach, 4001)
    values = [residual(float(g)) for g in grid]
    for i in range(len(grid) - 1):
        if values[i] == 0.0 or values[i] * values[i + 1] < 0.0:
            return float(brentq(residual, grid[i], grid[i + 1], xtol=1e-13))
    return math.nan

"""User paths: waypoints or a CSV file fitted with a curvature-continuous spline, resampled by
true arc length and checked against the curvature the vehicle can follow (docs/model.md Section 7).
"""

from __future__ import annotations

import copy
import csv
import math

import numpy as np

from tt_mujoco.defaults import MAX_CSV_ROWS, MAX_SPEED
from tt_mujoco.reference.path_base import (
    DEFAULT_MAX_CURVATURE,
    SPLINE_PATH,
    ReferencePath,
    arc_segment,
    positive_number,
)
from tt_mujoco.registry import existing_file

__all__ = [
    "SplinePath",
    "from_csv",
    "from_waypoints",
]


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

    STEP_KIND = SPLINE_PATH

    def __init__(self, name, spline, u_fine, s_fine, heading_fine, station_speeds=None):
        super().__init__(name, float(s_fine[-1]), station_speeds=station_speeds)
        self._spline = spline
        self._s_fine = s_fine
        self._heading_fine = heading_fine
        from scipy.interpolate import CubicHermiteSpline  # scipy: only for a CSV path

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
        # Tuples, which nothing can change: a copy of the path shares them (__deepcopy__).
        self._bounds = tuple(float(q) for q in s_fine)
        self._cells = tuple(
            tuple(map(float, row))
            for row in zip(s_fine[:-1], kappa[:-1], rate_left, c2, c3, strict=True)
        )
        self._kappa_ends = (float(kappa[0]), float(kappa[-1]))
        # Per fine cell for pose_at: cubic Hermite in s of x, y (slopes cos, sin of the heading)
        # and of the heading (slopes kappa); exact at the cell ends, error ~ h^4 inside.
        xy = spline(u_fine)
        self._pose_cells = tuple(
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
        )

    def __deepcopy__(self, memo):
        """A copy sharing the fine tables (tuples of floats: immutable): a user's code is
        given copies of the path (:func:`tt_mujoco.sim.usercode.users_copy`), each of which
        walked every one of their tuples otherwise."""
        for table in (self._bounds, self._cells, self._pose_cells):
            memo[id(table)] = table
        clone = object.__new__(type(self))
        memo[id(self)] = clone
        clone.__dict__.update(copy.deepcopy(self.__dict__, memo))
        return clone

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
        return spline_pose_of(s, self._bounds, self._pose_cells)

    def curvature_and_rate(self, s: float) -> tuple[float, float]:
        return spline_curvature_of(s, self.length, self._kappa_ends, self._bounds, self._cells)

    @property
    def closed_form(self) -> tuple:
        """The tables the compiled episode takes: the fine cells' bounds, their curvature
        cubics (s0, c0..c3), their pose cells (:func:`spline_pose_of`) and the end curvatures."""
        return (
            np.array(self._bounds),
            np.array(self._cells),
            np.array(self._pose_cells),
            np.array(self._kappa_ends),
        )


def spline_curvature_of(s: float, length: float, kappa_ends, bounds, cells):
    """``(kappa(s), dkappa/ds)`` of a spline path from its fine cells' cubics (plain floats;
    the compiled episode shares it): held at the end values beyond the path."""
    if s < 0.0:
        return kappa_ends[0], 0.0
    if s > length:
        return kappa_ends[1], 0.0
    cell = cells[arc_segment(s, bounds)]
    s0, c0, c1, c2, c3 = cell[0], cell[1], cell[2], cell[3], cell[4]
    w = s - s0
    return c0 + w * (c1 + w * (c2 + w * c3)), c1 + w * (2.0 * c2 + 3.0 * w * c3)


def spline_pose_of(s: float, bounds, pose_cells) -> tuple[float, float, float]:
    """``(x, y, heading)`` at ``s`` in ``[0, length]``: cubic Hermite in s of x, y and the
    heading on the fine cell that holds s (plain floats; the compiled episode shares it)."""
    cell = pose_cells[arc_segment(s, bounds)]
    s0, h, x0, y0, a0 = cell[0], cell[1], cell[2], cell[3], cell[4]
    k0, x1, y1, a1, k1 = cell[5], cell[6], cell[7], cell[8], cell[9]
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


def _checked_waypoints(name: str, x: np.ndarray, y: np.ndarray, labels) -> np.ndarray:
    """The steps between consecutive waypoints (m), every waypoint finite and none repeating
    the one before (a ValueError naming it otherwise)."""
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
    return step


def _checked_speeds(name: str, v: np.ndarray, n: int, labels) -> np.ndarray:
    """The waypoints' speeds: one per waypoint, finite, in [0, MAX_SPEED], never 0 at two
    consecutive ones."""
    if v.size != n:
        raise ValueError(f"{name}: v has {v.size} values for {n} waypoints")
    for i, value in enumerate(v):
        if not (math.isfinite(value) and 0.0 <= value <= MAX_SPEED):
            raise ValueError(
                f"{name}: v={float(value)!r} at {labels[i]} is not allowed: speeds must be "
                f"finite, >= 0 and at most {MAX_SPEED:g} m/s (forward driving only)"
            )
    both_zero = np.flatnonzero((v[:-1] == 0.0) & (v[1:] == 0.0))
    if both_zero.size:
        i = int(both_zero[0])
        raise ValueError(
            f"{name}: v=0 at both {labels[i]} and {labels[i + 1]} is not allowed: "
            "the vehicle would never get from one to the other"
        )
    return v


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
    step = _checked_waypoints(name, x, y, labels)
    if v is not None:
        v = _checked_speeds(name, np.asarray(v, dtype=float).ravel(), x.size, labels)

    from scipy.integrate import cumulative_simpson  # scipy: only for a CSV path
    from scipy.interpolate import CubicSpline, make_smoothing_spline

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
    file = existing_file(path, "path file")
    rows = []
    try:
        with file.open(newline="", encoding="utf-8-sig") as handle:
            for number, row in enumerate(csv.reader(handle), start=1):
                if any(cell.strip() for cell in row):
                    rows.append((number, row))
                if len(rows) > MAX_CSV_ROWS + 1:
                    raise ValueError(
                        f"path file {str(path)!r} has more than {MAX_CSV_ROWS} waypoints: "
                        "thin it out (a few points per metre are plenty for the spline fit)"
                    )
    except UnicodeDecodeError as err:
        raise ValueError(
            f"path file {str(path)!r} is not UTF-8 text (byte {err.start}): save it as UTF-8"
        ) from None
    except csv.Error as err:
        raise ValueError(f"path file {str(path)!r} is not CSV: {err}") from None
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

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
along the end tangent. Headings are continuous (not wrapped to (-pi, pi]).
The protocol is in :mod:`tt_mujoco.reference.path_base`, the spline fit of user paths in
:mod:`tt_mujoco.reference.spline`. The per-step
:meth:`ReferencePath.curvature_and_rate` and :meth:`ReferencePath.pose_at` are plain float
arithmetic (about 1 microsecond), because the targets call them at every control step.
"""

from __future__ import annotations

import inspect
import math

import numpy as np

from tt_mujoco.defaults import MAX_PATH_LENGTH
from tt_mujoco.guard import users_failure
from tt_mujoco.reference.path_base import (
    ARCS_PATH,
    CYCLOID_PATH,
    DEFAULT_MAX_CURVATURE,
    SPLINE_PATH,
    Pose,
    ReferencePath,
    arc_segment,
    missing_hooks,
    positive_number,
)
from tt_mujoco.reference.spline import (
    SplinePath,
    from_csv,
    from_waypoints,
    spline_curvature_of,
    spline_pose_of,
)
from tt_mujoco.registry import HookError, Registry, describe_failure, is_hook, load_hook

__all__ = [
    "CYCLOID_LENGTH",
    "CYCLOID_T_END",
    "DEFAULT_MAX_CURVATURE",
    "PATHS",
    "PATH_NAMES",
    "ArcsPath",
    "ClothoidPath",
    "CycloidPath",
    "Pose",
    "ReferencePath",
    "SplinePath",
    "check_options",
    "circle",
    "clothoid",
    "cycloid",
    "cycloid_arc_length",
    "factory_options",
    "from_csv",
    "from_waypoints",
    "get_path",
    "path_kind",
    "positive_number",
    "s_curve",
]


#: Built-in path names accepted by :func:`get_path` (besides a ``.csv`` file).
PATH_NAMES = ("cycloid", "s_curve", "circle")


#: End of the cycloid's time parameter, ``t in [0, 3 pi/2]`` (Section 6.1).
CYCLOID_T_END = 1.5 * math.pi


#: Length of the cycloid arc, ``l = 8 cos(pi/8)`` = 7.391 m (Section 6.1).
CYCLOID_LENGTH = 8.0 * math.cos(math.pi / 8.0)


# 4 cos(pi/8): the arc length at the arch's apex (tau = pi), the centre of the kappa(s) formula.
_CYCLOID_MID = 4.0 * math.cos(math.pi / 8.0)


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

    STEP_KIND = CYCLOID_PATH

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
        return cycloid_pose_of(s)

    def curvature_and_rate(self, s: float) -> tuple[float, float]:
        return cycloid_curvature_and_rate(s)


def cycloid_pose_of(s: float) -> tuple[float, float, float]:
    """The cycloid's ``(x, y, heading)`` at ``s`` in ``[0, CYCLOID_LENGTH]`` as plain floats
    (the compiled episode shares it)."""
    tau = 2.0 * math.acos(min(max((_CYCLOID_MID - s) / 4.0, -1.0), 1.0))
    return tau - math.sin(tau), 1.0 - math.cos(tau), math.pi / 2.0 - tau / 2.0


def cycloid_curvature_and_rate(s: float) -> tuple[float, float]:
    """The cycloid's ``(kappa(s), dkappa/ds(s))`` as plain floats, held at the ends (the
    compiled episode, :mod:`tt_mujoco.sim.loop.compiled`, shares it)."""
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

    STEP_KIND = ARCS_PATH

    def __init__(self, name: str, start, segments, initial_pose=None, period=None):
        lengths = np.array([float(seg[0]) for seg in segments])
        kappas = np.array([float(seg[1]) for seg in segments])
        if lengths.size == 0 or np.any(~np.isfinite(lengths)) or np.any(lengths <= 0):
            raise ValueError(f"segments={segments!r}: every segment length must be finite and > 0")
        if np.any(~np.isfinite(kappas)):
            raise ValueError(f"segments={segments!r}: every curvature must be finite")
        super().__init__(name, float(lengths.sum()), initial_pose=initial_pose, period=period)
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
        self._kappa_list = [float(k) for k in kappas]
        self._bound_list = [float(b) for b in self._bounds]
        self._start_list = [tuple(map(float, row)) for row in self._starts]

    def _segment(self, s):
        idx = np.searchsorted(self._bounds[1:-1], s, side="right")
        return idx, s - self._bounds[idx]

    def _pose(self, s):
        idx, local = self._segment(s)
        kappa = self._kappas[idx]
        starts = self._starts[idx]
        x0, y0, h0 = starts[..., 0], starts[..., 1], starts[..., 2]
        dx, dy, dh = _arc_step(local, kappa, h0)
        return x0 + dx, y0 + dy, h0 + dh

    def _curvature(self, s):
        return self._kappas[self._segment(s)[0]]

    def _curvature_rate(self, s):
        return np.zeros_like(s)

    def _pose_at(self, s):
        return arcs_pose_of(s, self._bound_list, self._kappa_list, self._start_list)

    def curvature_and_rate(self, s: float) -> tuple[float, float]:
        return arcs_curvature_of(s, self._bound_list, self._kappa_list)

    @property
    def closed_form(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The arcs as the compiled episode takes them: the segments' bounds (s_0 = 0 ..
        length), their curvatures and their start poses (x, y, heading) per row."""
        return np.array(self._bound_list), np.array(self._kappa_list), np.array(self._starts)


def arcs_curvature_of(s: float, bounds, kappas) -> tuple[float, float]:
    """``(kappa(s), 0)`` of arcs with ``bounds`` and curvatures ``kappas`` (plain floats; the
    compiled episode shares it): piecewise constant, so its rate is zero."""
    return kappas[arc_segment(s, bounds)], 0.0


def arcs_pose_of(s: float, bounds, kappas, starts) -> tuple[float, float, float]:
    """``(x, y, heading)`` at ``s`` of arcs whose segment i starts at the pose ``starts[i]``
    (plain floats; the compiled episode shares it)."""
    i = arc_segment(s, bounds)
    start = starts[i]
    x0, y0, h0 = start[0], start[1], start[2]
    kappa = kappas[i]
    local = s - bounds[i]
    turn = kappa * local
    chord = local if abs(turn) < 1e-12 else 2.0 * math.sin(turn / 2.0) / kappa
    mid = h0 + turn / 2.0
    return x0 + chord * math.cos(mid), y0 + chord * math.sin(mid), h0 + turn


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
    lap = 2.0 * math.pi * R
    period = lap if length > lap else None  # more than a lap: laps past the first repeat it
    return ArcsPath("circle", (R, 0.0, math.pi / 2.0), [(length, 1.0 / R)], period=period)


# --- linear curvature (clothoid) ----------------------------------------------------------------
# Gauss-Legendre nodes and weights on [0, 1], 8 points: exact for polynomials of degree 15, so
# cos and sin of a quadratic heading over a centimetre come out to rounding.
_GAUSS_NODES, _GAUSS_WEIGHTS = (
    0.5 * (a + b) for a, b in zip(np.polynomial.legendre.leggauss(8), (1.0, 0.0), strict=True)
)
#: Longest fine cell of a clothoid's tables (m).
CLOTHOID_CELL = 0.01
_TOO_LONG = f"it may be at most {MAX_PATH_LENGTH:g} m (check R, straight, transition)"


class ClothoidPath(ReferencePath):
    """Segments whose curvature runs linearly in arc length: clothoids (Euler spirals), and
    arcs and straights as their special cases.

    The heading is a quadratic in s on each segment, ``h(s) = h_i + kappa_i u + c_i u^2 / 2``
    (``u`` from the segment's start, ``c_i`` its curvature rate); the position is its
    integral, the Fresnel integrals, taken by 8-point Gauss-Legendre quadrature cell by cell.
    The step reads it as it reads a spline (``SPLINE_PATH``): fine cells of at most
    :data:`CLOTHOID_CELL` with the curvature's line (exact) and cubic Hermite poses (within
    about 1e-11 m of the quadrature).

    Parameters
    ----------
    name : str
    start : (x, y, heading)
        Pose at s = 0.
    segments : sequence of (length, kappa_start, kappa_end)
        Segment i covers ``s in [s_i, s_i + length_i)``; its curvature runs linearly from
        ``kappa_start`` to ``kappa_end``. Consecutive segments should meet in curvature (a
        jump is allowed, as between arcs).
    """

    STEP_KIND = SPLINE_PATH

    def __init__(self, name: str, start, segments, initial_pose=None):
        rows = np.array([[float(v) for v in seg] for seg in segments], dtype=float)
        if rows.ndim != 2 or rows.shape[1] != 3 or rows.shape[0] == 0:
            raise ValueError(f"segments={segments!r}: give (length, kappa_start, kappa_end) rows")
        if not np.all(np.isfinite(rows)) or np.any(rows[:, 0] <= 0.0):
            raise ValueError(
                f"segments={segments!r}: every length must be finite and > 0, every "
                "curvature finite"
            )
        length = float(rows[:, 0].sum())
        if length > MAX_PATH_LENGTH:  # its grid of 1 cm cells is made whole, here
            raise ValueError(f"path {name!r} of length {length:g} m is not allowed: {_TOO_LONG}")
        super().__init__(name, length, initial_pose=initial_pose)
        self._lengths, self._k0 = rows[:, 0], rows[:, 1]
        self._rates = (rows[:, 2] - rows[:, 1]) / rows[:, 0]
        self._bounds = np.concatenate([[0.0], np.cumsum(self._lengths)])
        # the fine grid: each segment in equal cells, its ends among the grid's points
        grid = [np.zeros(1)]
        for i, length in enumerate(self._lengths):
            n = max(1, math.ceil(length / CLOTHOID_CELL))
            grid.append(self._bounds[i] + length * np.arange(1, n + 1) / n)
        self._grid = np.concatenate(grid)
        self._grid[-1] = self.length
        # the segments' start headings, then the grid's poses by quadrature, cell by cell
        x0, y0, h0 = (float(v) for v in start)
        turns = self._k0 * self._lengths + 0.5 * self._rates * self._lengths**2
        self._h0 = h0 + np.concatenate([[0.0], np.cumsum(turns)[:-1]])
        heading = self._heading(self._grid)
        dx, dy = self._advance(self._grid[:-1], self._grid[1:])
        self._grid_x = x0 + np.concatenate([[0.0], np.cumsum(dx)])
        self._grid_y = y0 + np.concatenate([[0.0], np.cumsum(dy)])
        kappa, rate = self._curvature(self._grid), self._curvature_rate(self._grid[:-1])
        h = np.diff(self._grid)
        self._tables = (
            self._grid.copy(),
            np.column_stack([self._grid[:-1], kappa[:-1], rate, np.zeros((h.size, 2))]),
            np.column_stack(
                [
                    *(self._grid[:-1], h, self._grid_x[:-1], self._grid_y[:-1], heading[:-1]),
                    *(kappa[:-1], self._grid_x[1:], self._grid_y[1:], heading[1:], kappa[1:]),
                ]
            ),
            np.array([kappa[0], kappa[-1]]),
        )
        self._bound_list = [float(b) for b in self._grid]
        self._cell_list = [tuple(map(float, row)) for row in self._tables[1]]
        self._pose_cell_list = [tuple(map(float, row)) for row in self._tables[2]]
        self._kappa_ends = (float(kappa[0]), float(kappa[-1]))

    def _segment(self, s):
        idx = np.searchsorted(self._bounds[1:-1], s, side="right")
        return idx, s - self._bounds[idx]

    def _heading(self, s):
        return self._heading_in(s, self._segment(s)[0])

    def _advance(self, a, b):
        """The displacement from ``s = a`` to ``s = b`` within one segment (arrays)."""
        u = a[..., None] + (b - a)[..., None] * _GAUSS_NODES
        h = self._heading_in(u, self._segment(a)[0][..., None])
        width = b - a
        return width * (np.cos(h) @ _GAUSS_WEIGHTS), width * (np.sin(h) @ _GAUSS_WEIGHTS)

    def _heading_in(self, s, idx):
        """The heading at ``s`` on segment ``idx`` (arrays): its quadratic in arc length."""
        u = s - self._bounds[idx]
        return self._h0[idx] + self._k0[idx] * u + 0.5 * self._rates[idx] * u * u

    def _pose(self, s):
        s = np.asarray(s, dtype=float)
        cell = np.clip(np.searchsorted(self._grid, s, side="right") - 1, 0, self._grid.size - 2)
        dx, dy = self._advance(self._grid[cell], s)
        return self._grid_x[cell] + dx, self._grid_y[cell] + dy, self._heading(s)

    def _curvature(self, s):
        idx, u = self._segment(s)
        return self._k0[idx] + self._rates[idx] * u

    def _curvature_rate(self, s):
        return self._rates[self._segment(s)[0]]

    def _pose_at(self, s):
        return spline_pose_of(s, self._bound_list, self._pose_cell_list)

    def curvature_and_rate(self, s: float) -> tuple[float, float]:
        return spline_curvature_of(
            s, self.length, self._kappa_ends, self._bound_list, self._cell_list
        )

    @property
    def closed_form(self) -> tuple:
        """The tables the step takes, as a spline's (:attr:`SplinePath.closed_form`)."""
        return tuple(table.copy() for table in self._tables)


def clothoid(
    R: float = 1.5, angle_deg: float = 90.0, transition: float = 1.0, straight: float = 1.0
) -> ClothoidPath:
    """A turn with clothoid transitions: a straight, a clothoid from 0 to the curvature 1/R,
    an arc of radius R, a clothoid back to 0 and a straight, from the origin heading 0 (+x).

    Each clothoid turns ``transition / (2 R)``, the arc the rest of ``angle_deg`` (positive
    left, negative right). Unlike the S-curve's and the circle's steps, the curvature is
    continuous, so the yaw rate the target asks has no jump.

    Parameters
    ----------
    R : float
        The arc's radius (m), > 0.
    angle_deg : float
        The whole turn (deg), nonzero and within +-360.
    transition : float
        Each clothoid's length (m), >= 0 (0: a plain arc between the straights); the two
        together may not turn more than ``angle_deg``.
    straight : float
        Each straight's length (m), >= 0.
    """
    R = positive_number("R", R)
    for key, value in (
        ("angle_deg", angle_deg),
        ("transition", transition),
        ("straight", straight),
    ):
        if (
            isinstance(value, bool)
            or not isinstance(value, int | float)
            or not math.isfinite(value)
        ):
            raise ValueError(f"{key}={value!r} is not allowed: it must be a finite number")
    if angle_deg == 0.0 or abs(angle_deg) > 360.0:
        raise ValueError(
            f"angle_deg={angle_deg!r} is not allowed: use a nonzero angle within +-360"
        )
    if transition < 0.0 or straight < 0.0:
        raise ValueError(
            f"transition={transition!r}, straight={straight!r} are not allowed: use lengths >= 0"
        )
    turn, side = math.radians(abs(angle_deg)), math.copysign(1.0, angle_deg)
    arc = R * turn - transition  # each clothoid turns transition / (2 R)
    if arc < 0.0:
        raise ValueError(
            f"transition={transition!r} is not allowed for R={R!r}, angle_deg={angle_deg!r}: the "
            f"two clothoids would turn more than the angle; use transition <= {R * turn:.6g}"
        )
    k = side / R
    segments = [
        (straight, 0.0, 0.0),
        (transition, 0.0, k),
        (arc, k, k),
        (transition, k, 0.0),
        (straight, 0.0, 0.0),
    ]
    return ClothoidPath("clothoid", (0.0, 0.0, 0.0), [seg for seg in segments if seg[0] > 0.0])


# --- dispatch --------------------------------------------------------------------------------
def factory_options(key: str) -> tuple[str, ...] | None:
    """The options the path ``key`` (a :func:`path_kind`) takes: a CSV file's, or the keyword
    parameters of a registered factory, read from its signature (None for a hook, whose
    factory checks its own)."""
    if key == "csv":
        return ("max_curvature", "smoothing")
    if key == "hook":
        return None
    factory = PATHS[key]
    if not callable(factory):
        return ()
    return tuple(inspect.signature(factory).parameters)


#: Path name -> factory returning a :class:`ReferencePath`. ``PATHS.register`` adds one; a
#: hook ``module:NAME`` or ``file.py:NAME`` (a ReferencePath, or a factory taking the path
#: options as keywords) needs no registration.
PATHS = Registry("path", also="a path to a .csv file")


PATHS.register("cycloid", cycloid)


PATHS.register("s_curve", s_curve)


PATHS.register("circle", circle)


PATHS.register("clothoid", clothoid)


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
            inspect.signature(obj).bind(**kw)
        except TypeError as err:
            raise ValueError(f"path {spec!r} does not take the options {kw}: {err}") from None
        except ValueError:  # a callable without a signature: it is called as it is
            pass
        try:
            obj = obj(**kw)
        except BaseException as err:  # the user's factory: its failure is bad input
            if not users_failure(err):
                raise
            raise HookError(f"path {spec!r} failed: {describe_failure(err)}") from None
    elif kw:
        raise ValueError(f"path {spec!r} is a fixed path: it takes no options ({sorted(kw)})")
    if not isinstance(obj, ReferencePath):
        raise ValueError(
            f"path {spec!r} is not allowed: it gave {type(obj).__name__}, not a "
            "tt_mujoco.reference.paths.ReferencePath"
        )
    missing = missing_hooks(type(obj))
    if missing:
        raise ValueError(
            f"path {spec!r} is not allowed: its class {type(obj).__name__} does not implement "
            f"{', '.join(missing)} (see tt_mujoco.reference.path_base.ReferencePath)"
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
    check_options(text, kw, factory_options(key))
    if key == "csv":
        return from_csv(text, **kw)
    return PATHS[key](**kw)

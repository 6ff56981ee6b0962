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

import math

import numpy as np

from tt_mujoco.guard import users_failure
from tt_mujoco.reference.path_base import (
    DEFAULT_MAX_CURVATURE,
    Pose,
    ReferencePath,
    arc_segment,
    positive_number,
)
from tt_mujoco.reference.spline import SplinePath, from_csv, from_waypoints
from tt_mujoco.registry import HookError, Registry, describe_failure, is_hook, load_hook

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
    "check_options",
    "circle",
    "cycloid",
    "cycloid_arc_length",
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
    compiled episode, :mod:`tt_mujoco.sim.compiled`, shares it)."""
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
        x0, y0, h0 = np.moveaxis(self._starts[idx], -1, 0)
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

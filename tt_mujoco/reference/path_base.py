"""The path protocol: :class:`ReferencePath` (pose, curvature and its rate by arc length,
clamped outside the path), :class:`Pose`, and the checks shared by the path modules.
"""

from __future__ import annotations

import math
from typing import ClassVar, NamedTuple

import numpy as np

__all__ = [
    "ARCS_PATH",
    "CYCLOID_PATH",
    "DEFAULT_MAX_CURVATURE",
    "HOOKED_PATH",
    "SPLINE_PATH",
    "Pose",
    "ReferencePath",
    "missing_hooks",
    "positive_number",
    "read_from_tables",
]


#: How the step reads a path (a path class's :attr:`ReferencePath.STEP_KIND`): arcs of
#: constant curvature, the cycloid, fine cells of cubic curvature and Hermite poses (a spline,
#: a clothoid; ``closed_form`` gives their tables), or a path it calls back (a user's).
ARCS_PATH, CYCLOID_PATH, SPLINE_PATH, HOOKED_PATH = 0, 1, 2, 3


#: Largest |kappa| (1/m) a user path may have by default: a turn radius of 0.5 m. With the
#: default same-path steering (eta = -1/7) the steady-state articulation there is 64.4 deg
#: (the rod O-P0 would stand perpendicular to the tractor, phi = 90 deg, near kappa = 3.02 1/m);
#: with the paper's eta = 3 it is -22.8 deg, clear of that design's singular 30 deg. The paper's
#: own paths stay below 1 1/m. See :func:`tt_mujoco.vehicle.steering.steady_articulation` and
#: docs/paper-notes.md.
DEFAULT_MAX_CURVATURE = 2.0


class Pose(NamedTuple):
    """A planar pose: position (m) and heading (rad)."""

    x: float
    y: float
    heading: float


def _out(a: np.ndarray, scalar: bool):
    return float(a) if scalar else a


#: What a path class must give: each public method the run calls, and the subclass hook
#: through which the base computes it (either overridden is enough).
PATH_HOOKS = (
    ("pose", "_pose"),
    ("pose_at", "_pose_at"),
    ("curvature", "_curvature"),
    ("curvature_rate", "_curvature_rate"),
    ("curvature_and_rate", "curvature_and_rate"),
)


def missing_hooks(cls: type) -> list[str]:
    """The hooks of :data:`PATH_HOOKS` a :class:`ReferencePath` subclass leaves to the base
    (whose own only raise ``NotImplementedError``), by the subclass hook's name."""
    return [
        hook
        for public, hook in PATH_HOOKS
        if getattr(cls, public) is getattr(ReferencePath, public)
        and getattr(cls, hook) is getattr(ReferencePath, hook)
    ]


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

    def __init__(
        self, name: str, length: float, initial_pose=None, station_speeds=None, period=None
    ):
        if not (math.isfinite(length) and length > 0):
            raise ValueError(f"path length={length!r} is not allowed: it must be finite and > 0")
        self.name = name
        self.length = float(length)
        #: The arc length after which the path repeats itself exactly (a circle's lap), or
        #: None: distances to the path are then distances to one period of it.
        self.period = None if period is None else float(period)
        self.station_speeds = station_speeds
        self._initial_pose = None if initial_pose is None else Pose(*map(float, initial_pose))

    # --- subclass hooks (s is a float array already clipped to [0, length]) ----------------
    def _pose(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        raise NotImplementedError

    def _curvature(self, s: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def _curvature_rate(self, s: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    #: How the step reads this class's paths from tables, without calling them back (one of
    #: :data:`ARCS_PATH`, :data:`CYCLOID_PATH`, :data:`SPLINE_PATH`, with ``closed_form``
    #: giving the tables). Only a class that declares it itself is read so: a subclass that
    #: does not may compute something else, and is called back (:data:`HOOKED_PATH`).
    STEP_KIND: ClassVar[int] = HOOKED_PATH

    def _pose_at(self, s: float) -> tuple[float, float, float]:
        raise NotImplementedError

    def pose_at(self, s: float) -> tuple[float, float, float]:
        """``(x, y, heading)`` at one float ``s`` in plain float arithmetic, for per-step logging.

        Clamped like :meth:`pose`, which it agrees with to rounding for the closed-form paths
        and to ~1e-11 m for splines.
        """
        clipped = min(max(s, 0.0), self.length)
        x, y, heading = self._pose_at(clipped)
        return continued_pose(s, clipped, x, y, heading)

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

    def dense(self, ds: float = 0.005, length: float | None = None) -> np.ndarray:
        """The path as an ``(N, 2)`` polyline with spacing at most ``ds`` (both ends included),
        from s = 0 to ``length`` (default, and at most, the whole path)."""
        if not (math.isfinite(ds) and ds > 0):
            raise ValueError(f"ds={ds!r} is not allowed: it must be finite and > 0")
        end = self.length if length is None else min(float(length), self.length)
        n = max(2, math.ceil(end / ds) + 1)
        x, y, _ = self.pose(np.linspace(0.0, end, n))
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


def read_from_tables(path) -> bool:
    """Whether the step reads ``path`` from its tables: its class declares its own
    :attr:`~ReferencePath.STEP_KIND`."""
    return type(path).__dict__.get("STEP_KIND", HOOKED_PATH) != HOOKED_PATH


def arc_segment(s: float, bounds) -> int:
    """The segment of arcs with ``bounds`` (s_0 = 0, ..., s_n = length) that holds ``s``: the
    last whose start is <= s (``bisect.bisect_right`` over the inner bounds), 0 before the
    path and n - 1 beyond it."""
    lo, hi = 0, len(bounds) - 2
    while lo < hi:
        mid = (lo + hi) // 2
        if s < bounds[mid + 1]:
            hi = mid
        else:
            lo = mid + 1
    return lo


def continued_pose(s: float, clipped: float, x: float, y: float, heading: float):
    """The pose at ``s`` from the pose ``(x, y, heading)`` at ``clipped``, s held within the
    path: beyond its ends the path continues along its end tangent (plain floats; the
    compiled episode shares it)."""
    if s != clipped:
        x += (s - clipped) * math.cos(heading)
        y += (s - clipped) * math.sin(heading)
    return x, y, heading


def positive_number(name: str, value) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ValueError(f"{name}={value!r} is not allowed: it must be a number > 0")
    if not (math.isfinite(value) and value > 0):
        raise ValueError(f"{name}={value!r} is not allowed: it must be finite and > 0")
    return float(value)

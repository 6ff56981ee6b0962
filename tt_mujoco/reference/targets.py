"""Speed profiles and tracking targets z_d = (v_d, omega_d) (docs/model.md §7, paper Section 6).

The controllers track ``z = (v, omega)``. A target turns a
:class:`~tt_mujoco.reference.paths.ReferencePath`
and a :class:`SpeedProfile` into ``z_d`` and ``z_d_dot`` at every control step:

- :class:`StaticTarget`: a fixed function of time (paper eq. 32 for the cycloid):
  ``v_d = v_ref(t)``, ``omega_d = kappa(s_ref(t)) v_ref(t)`` with ``s_ref = int v_ref dt``.
- :class:`DynamicTarget`: curvature-consistent (paper eqs. 33-34): ``v_d = v_ref(t)``,
  ``omega_d = kappa(s) v`` with ``v`` the *measured* speed and ``s = int v dt`` integrated by
  the target itself, so the curvature error is ``e_omega / v`` (paper eq. 37).

:func:`make_target` builds path, target and initial pose for ``cycloid``, ``s_curve``,
``circle`` or a CSV file. The equation numbers are inferred from the paper's cross references
("static ... defined in (32)", "dynamic ... defined in (34)", "Equations (37)-(39)"); the text
extraction lost the labels themselves (see docs/paper-notes.md).

A target object is the run's configuration (its path, speed profile, kind and duration) and
its noise-free reference; the step computes ``z_d`` from the target's record
(:func:`tt_mujoco.sim.loop.target_step.target_step_of`, with :func:`yaw_rate_targets` and
:func:`travelled` here), so the speed profiles and paths each have a scalar fast path
(``state``, ``curvature_and_rate``) next to their vectorised methods, and tests keep the two
equal.
"""

from __future__ import annotations

import bisect
import math
from typing import NamedTuple

import numpy as np

from tt_mujoco.reference.paths import (
    CYCLOID_LENGTH,
    CYCLOID_T_END,
    Pose,
    ReferencePath,
    check_options,
    circle,
    cycloid,
    cycloid_arc_length,
    factory_options,
    get_path,
    path_kind,
    positive_number,  # one check for both modules
)

__all__ = [
    "CIRCLE_DURATION",
    "CRUISE_SPEED",
    "RAMP_TIME",
    "TARGET_KINDS",
    "CycloidDynamicSpeed",
    "CycloidStaticSpeed",
    "DynamicTarget",
    "RampSpeed",
    "SpeedProfile",
    "StaticTarget",
    "StationSpeed",
    "Target",
    "TargetSetup",
    "make_target",
    "target_on",
]

#: Target kinds accepted by :func:`make_target`.
TARGET_KINDS = ("dynamic", "static")

#: Cruise speed of the S-curve and circle (Section 6.3) and of CSV paths without ``v`` (m/s).
CRUISE_SPEED = 0.8

#: Duration of each smooth speed ramp (s). Not in the paper; 2 s gives a peak acceleration of
#: 1.5 * 0.8 / 2 = 0.6 m/s^2 at 0.8 m/s cruise, a third of the cycloid's dynamic profile's
#: 1.85 m/s^2 at t = 0, and each ramp covers cruise * ramp / 2 = 0.8 m.
RAMP_TIME = 2.0

#: The circle's run length (s), Section 6.3.
CIRCLE_DURATION = 10.0

# v_tilde(t) = l xi^2 t e^(-xi t) with xi = 1/2 (Section 6.1): l xi^2 = 2 cos(pi/8).
_DYNAMIC_GAIN = CYCLOID_LENGTH / 4.0
# 4 cos(pi/8): s(t) = 4cos(pi/8) - 4cos((t + pi/4)/2) (Section 6.1).
_CYCLOID_MID = CYCLOID_LENGTH / 2.0


# --- speed profiles ---------------------------------------------------------------------------
class SpeedProfile:
    """A reference speed v_ref(t) >= 0 with its derivative and integral.

    ``speed(t)``, ``accel(t)``, ``distance(t)`` (= int_0^t v_ref) are vectorised;
    :meth:`state` is the scalar fast path returning all three. Each profile is defined on
    ``[0, t_end]``; before 0 and after ``t_end`` it holds its end speed (acceleration 0,
    distance growing linearly), which for the ramps means standing still at the end.

    Attributes
    ----------
    name : str
    duration : float
        Time (s) the profile is meant to run: when its ramps end, or the paper's 3 pi/2 for the
        cycloid.
    t_end : float
        End of the profile's own formula (inf for the cycloid's dynamic profile, whose closed
        form holds for all t >= 0).
    """

    name = "profile"

    def __init__(self, duration: float, t_end: float | None = None):
        self.duration = float(duration)
        self.t_end = self.duration if t_end is None else float(t_end)

    # subclass hooks: t within [0, t_end]
    def _scalar(self, t: float) -> tuple[float, float, float]:
        raise NotImplementedError

    def _arrays(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        raise NotImplementedError

    def state(self, t: float) -> tuple[float, float, float]:
        """``(distance, speed, accel)`` at one time t (plain floats)."""
        if t < 0.0:
            _, v0, _ = self._scalar(0.0)
            return v0 * t, v0, 0.0
        if t > self.t_end:
            s_end, v_end, _ = self._scalar(self.t_end)
            return s_end + v_end * (t - self.t_end), v_end, 0.0
        return self._scalar(t)

    def states(self, t):
        """``(distance, speed, accel)`` arrays at times t (vectorised :meth:`state`)."""
        t_arr = np.asarray(t, dtype=float)
        t_in = np.clip(t_arr, 0.0, min(self.t_end, np.finfo(float).max))
        s, v, a = (np.asarray(q, dtype=float) for q in self._arrays(t_in))
        outside = (t_arr < 0.0) | (t_arr > self.t_end)
        s = s + v * (t_arr - t_in)
        a = np.where(outside, 0.0, a)
        if t_arr.ndim == 0:
            return float(s), float(v), float(a)
        return s, np.broadcast_to(v, t_arr.shape).copy(), a

    def speed(self, t):
        """v_ref(t) (m/s), vectorised."""
        return self.states(t)[1]

    def accel(self, t):
        """dv_ref/dt (m/s^2), vectorised."""
        return self.states(t)[2]

    def distance(self, t):
        """int_0^t v_ref (m), vectorised."""
        return self.states(t)[0]

    __call__ = speed

    @property
    def total_distance(self) -> float:
        """Distance covered by ``duration``."""
        return self.state(self.duration)[0]

    def __repr__(self) -> str:
        return (
            f"{type(self).__name__}(duration={self.duration:.4f}, "
            f"distance={self.total_distance:.4f})"
        )


class CycloidStaticSpeed(SpeedProfile):
    """The cycloid's static speed, paper eq. (32): ``v = 2 sin((t + pi/4)/2)``, t in [0, 3pi/2].

    Its integral is the cycloid's arc length ``s(t)`` (Section 6.1), so it covers the path
    exactly in 3 pi/2 s; it starts at 2 sin(pi/8) = 0.765 m/s, a step from rest.
    """

    name = "cycloid_static"

    def __init__(self):
        super().__init__(CYCLOID_T_END)

    def _scalar(self, t):
        half = (t + math.pi / 4.0) / 2.0
        return _CYCLOID_MID - 4.0 * math.cos(half), 2.0 * math.sin(half), math.cos(half)

    def _arrays(self, t):
        half = (t + math.pi / 4.0) / 2.0
        return cycloid_arc_length(t), 2.0 * np.sin(half), np.cos(half)


class CycloidDynamicSpeed(SpeedProfile):
    """The cycloid's dynamic speed, paper eq. (34): ``v = 2cos(pi/8) t e^(-t/2)``.

    It is ``l xi^2 t e^(-xi t)`` with xi = 1/2, whose integral
    ``l (1 - (1 + t/2) e^(-t/2))`` reaches the path length l only as t -> inf: by the
    paper's end time 3 pi/2 it has covered 68.2 % of the path (5.04 m of 7.39 m), ending at
    0.825 m/s. The closed form is used for all t >= 0 (``t_end = inf``).
    """

    name = "cycloid_dynamic"

    def __init__(self):
        super().__init__(CYCLOID_T_END, t_end=math.inf)

    def _scalar(self, t):
        decay = math.exp(-t / 2.0)
        return (
            CYCLOID_LENGTH * (1.0 - (1.0 + t / 2.0) * decay),
            _DYNAMIC_GAIN * t * decay,
            _DYNAMIC_GAIN * decay * (1.0 - t / 2.0),
        )

    def _arrays(self, t):
        decay = np.exp(-t / 2.0)
        return (
            CYCLOID_LENGTH * (1.0 - (1.0 + t / 2.0) * decay),
            _DYNAMIC_GAIN * t * decay,
            _DYNAMIC_GAIN * decay * (1.0 - t / 2.0),
        )


class RampSpeed(SpeedProfile):
    """Smooth accelerate-cruise-decelerate from rest to rest (Section 6.3), covering a distance.

    Each ramp is a smoothstep, ``v = v_c (3x^2 - 2x^3)`` with ``x = t / ramp_time``, so the
    acceleration is continuous (zero at both ends of each ramp, peak 1.5 v_c / ramp_time) and
    each ramp covers ``v_c ramp_time / 2``. Cruise lasts ``(distance - v_c ramp_time) / v_c``;
    a path shorter than ``v_c ramp_time`` is covered with a lower peak speed
    ``distance / ramp_time`` and no cruise.

    Parameters
    ----------
    distance : float
        Distance to cover (m), > 0.
    cruise : float
        Cruise speed v_c (m/s), > 0.
    ramp_time : float
        Duration of each ramp (s), > 0.
    """

    name = "ramp"

    def __init__(self, distance: float, cruise: float = CRUISE_SPEED, ramp_time: float = RAMP_TIME):
        distance = positive_number("distance", distance)
        cruise = positive_number("cruise", cruise)
        ramp_time = positive_number("ramp_time", ramp_time)
        self.ramp_time = ramp_time
        self.peak = min(cruise, distance / ramp_time)
        self.cruise_time = distance / self.peak - ramp_time
        self._distance = distance
        self._ramp_distance = self.peak * ramp_time / 2.0
        super().__init__(2.0 * ramp_time + self.cruise_time)

    @classmethod
    def for_duration(
        cls, duration: float, cruise: float = CRUISE_SPEED, ramp_time: float = RAMP_TIME
    ) -> RampSpeed:
        """The ramp profile that ends exactly at ``duration`` (ramps shortened to fit if needed)."""
        duration = positive_number("duration", duration)
        cruise = positive_number("cruise", cruise)
        ramp_time = min(positive_number("ramp_time", ramp_time), duration / 2.0)
        return cls(cruise * (duration - ramp_time), cruise, ramp_time)

    def _scalar(self, t):
        T, vc = self.ramp_time, self.peak
        if t < T:
            x = t / T
            return (
                vc * T * x**3 * (1.0 - x / 2.0),
                vc * x * x * (3.0 - 2.0 * x),
                6.0 * vc / T * x * (1.0 - x),
            )
        if t <= T + self.cruise_time:
            return self._ramp_distance + vc * (t - T), vc, 0.0
        y = (self.duration - t) / T
        return (
            self._distance - vc * T * y**3 * (1.0 - y / 2.0),
            vc * y * y * (3.0 - 2.0 * y),
            -6.0 * vc / T * y * (1.0 - y),
        )

    def _arrays(self, t):
        T, vc = self.ramp_time, self.peak
        x = np.clip(t / T, 0.0, 1.0)
        y = np.clip((self.duration - t) / T, 0.0, 1.0)
        up = t < T
        down = t > T + self.cruise_time
        s = np.where(
            up,
            vc * T * x**3 * (1.0 - x / 2.0),
            np.where(
                down,
                self._distance - vc * T * y**3 * (1.0 - y / 2.0),
                self._ramp_distance + vc * (t - T),
            ),
        )
        v = np.where(up, vc * x * x * (3.0 - 2.0 * x), np.where(down, vc * y * y * (3 - 2 * y), vc))
        a = np.where(
            up, 6.0 * vc / T * x * (1.0 - x), np.where(down, -6.0 * vc / T * y * (1.0 - y), 0.0)
        )
        return s, v, a


class StationSpeed(SpeedProfile):
    """Speeds given at arc-length stations (a CSV ``v`` column), constant acceleration between.

    Between stations ``s_i`` and ``s_{i+1}``, ``v^2`` is linear in ``s`` (constant
    acceleration ``(v_{i+1}^2 - v_i^2) / (2 (s_{i+1} - s_i))``), which takes the finite time
    ``2 (s_{i+1} - s_i) / (v_i + v_{i+1})`` even from or to a standstill; v is continuous and
    the acceleration steps at the stations.

    Parameters
    ----------
    stations : array_like
        Increasing arc lengths (m), starting at 0.
    speeds : array_like
        Speeds (m/s) at the stations, >= 0, never 0 at two consecutive stations.
    """

    name = "stations"

    def __init__(self, stations, speeds):
        s = np.asarray(stations, dtype=float)
        v = np.asarray(speeds, dtype=float)
        if s.ndim != 1 or s.shape != v.shape or s.size < 2:
            raise ValueError("stations and speeds must be 1-D arrays of equal length >= 2")
        ds = np.diff(s)
        if not (np.all(np.isfinite(s)) and np.all(ds > 0)):
            raise ValueError(f"stations={s!r} are not allowed: they must increase strictly")
        if not np.all(np.isfinite(v) & (v >= 0)) or np.any((v[:-1] + v[1:]) == 0):
            raise ValueError(
                f"speeds={v!r} are not allowed: finite, >= 0, never 0 at two consecutive stations"
            )
        with np.errstate(over="ignore"):  # a crawl of 1e-320 m/s takes inf s: refused later
            dt = 2.0 * ds / (v[:-1] + v[1:])
        self._t = np.concatenate([[0.0], np.cumsum(dt)])
        self._s = s - s[0]
        self._v = v
        self._a = (v[1:] ** 2 - v[:-1] ** 2) / (2.0 * ds)
        self._t_list = [float(q) for q in self._t[1:-1]]
        self._rows = [
            (float(t0), float(s0), float(v0), float(a0))
            for t0, s0, v0, a0 in zip(self._t[:-1], self._s[:-1], v[:-1], self._a, strict=True)
        ]
        super().__init__(float(self._t[-1]))

    def _scalar(self, t):
        t0, s0, v0, a0 = self._rows[bisect.bisect_right(self._t_list, t)]
        tau = t - t0
        return s0 + tau * (v0 + 0.5 * a0 * tau), v0 + a0 * tau, a0

    def _arrays(self, t):
        i = np.searchsorted(self._t[1:-1], t, side="right")
        tau = t - self._t[i]
        v0, a0 = self._v[i], self._a[i]
        return self._s[i] + tau * (v0 + 0.5 * a0 * tau), v0 + a0 * tau, a0


# --- targets --------------------------------------------------------------------------------
class Target:
    """Common interface of the tracking targets: the path, the speed profile, the kind
    (``"static"`` or ``"dynamic"``) and the duration of a run, and the noise-free reference.
    The step reads it as a record (:func:`tt_mujoco.sim.loop.target_step.target_step_of`).

    Parameters
    ----------
    path : ReferencePath
    profile : SpeedProfile
        Gives v_ref(t), its derivative and s_ref(t) = int v_ref.
    duration : float, optional
        How long a run lasts (s); defaults to ``profile.duration``. A shorter run stops on the
        way; a longer one holds the profile's end speed (0 for the ramps).
    """

    kind = "target"

    def __init__(self, path: ReferencePath, profile: SpeedProfile, duration: float | None = None):
        self.path = path
        self.profile = profile
        self.duration = (
            profile.duration if duration is None else positive_number("duration", duration)
        )
        # Bound methods looked up once: the reference is asked at every logged step.
        self._profile_state = profile.state
        self._curvature_and_rate = path.curvature_and_rate

    @property
    def start_s(self) -> float:
        """The path's arc length (m) where a run starts: 0, the path's start."""
        return 0.0

    def reference_speed(self, t):
        """The noise-free reference speed v_ref(t) (m/s; float or array t)."""
        if isinstance(t, float | int):
            return self._profile_state(float(t))[1]
        return self.profile.speed(t)

    def reference_yaw_rate(self, t):
        """The noise-free reference yaw rate ``kappa(s_ref(t)) v_ref(t)`` (rad/s).

        This is the static target's omega_d, and the dynamic target's when the speed tracks
        v_ref exactly (float or array t).
        """
        if isinstance(t, float | int):
            s_ref, v_ref, _ = self._profile_state(float(t))
            return self._curvature_and_rate(s_ref)[0] * v_ref
        s_ref, v_ref, _ = self.profile.states(t)
        return self.path.curvature(s_ref) * v_ref

    def reference_pose(self, t):
        """Pose of the path at ``s_ref(t)`` of the speed profile (float or array t)."""
        if isinstance(t, float | int):  # per-step logging: the plain-float path
            return self.path.pose_at(self._profile_state(float(t))[0])
        return self.path.pose(self.profile.distance(t))

    def reference_point(self, t):
        """``(x, y)`` of :meth:`reference_pose`: where the tractor's P should be at time t.

        For either kind of target this is the speed profile's ``s_ref(t)``, not the dynamic
        target's integrated s: it is where a vehicle following the reference timing would be.
        """
        x, y, _ = self.reference_pose(t)
        return x, y

    def __repr__(self) -> str:
        return (
            f"{type(self).__name__}(path={self.path.name!r}, profile={self.profile.name!r}, "
            f"duration={self.duration:.4f})"
        )


class StaticTarget(Target):
    """A fixed function of time (paper eq. 32, generalised to any path).

    ``v_d = v_ref(t)``, ``omega_d = kappa(s_ref(t)) v_ref(t)``, ``s_ref = int_0^t v_ref``;
    ``z_d_dot = (v_ref_dot, kappa'(s_ref) v_ref^2 + kappa(s_ref) v_ref_dot)``. For the cycloid
    with its eq. (32) speed this is omega_d = -1/2 exactly (to rounding): the paper prints
    +1/2, but the arch turns clockwise (docs/model.md Section 7). The measured speed is ignored.
    """

    kind = "static"


class DynamicTarget(Target):
    """The curvature-consistent target of paper eqs. (33)-(34).

    ``v_d = v_ref(t)``, ``omega_d = kappa(s) v`` with ``v`` the measured speed and
    ``s = int_0^t v`` integrated here with the trapezoidal rule, so that the curvature error is
    ``Delta kappa = e_omega / v`` (paper eq. 37). The derivative is
    ``omega_d_dot = kappa'(s) v^2 + kappa(s) v_dot``; the acceleration v_dot is not measured,
    so ``v_ref_dot`` stands in for it (the velocity loop drives v to v_ref; differentiating the
    noisy measured v at 1 kHz would amplify noise instead). At a curvature jump (the S-curve's
    inflection) omega_d jumps and the jump's impulse in omega_d_dot is left out.
    """

    kind = "dynamic"


def yaw_rate_targets(kappa: float, rate: float, speed: float, accel: float):
    """``(omega_d, omega_d_dot) = (kappa u, kappa' u^2 + kappa a)`` for the path's curvature
    ``kappa`` and its rate ``kappa'`` at the reference point, met at speed ``u`` with
    acceleration ``a`` (paper eqs. 32-34; plain floats, the compiled episode shares it)."""
    return kappa * speed, rate * speed * speed + kappa * accel


def travelled(s: float, v_prev: float, v: float, dt: float) -> float:
    """The dynamic target's arc length after one step: the trapezoidal rule on the measured
    speed (paper eq. 34; the compiled episode shares it)."""
    return s + 0.5 * (v_prev + v) * dt


# --- factory --------------------------------------------------------------------------------
class TargetSetup(NamedTuple):
    """What :func:`make_target` returns: the path, the target and where the vehicle starts."""

    path: ReferencePath
    target: Target
    initial_pose: Pose


#: The options of the paths whose targets are made apart (the cycloid's speed profiles, the
#: circle's length made from the run's); any other takes these and its factory's own.
_TARGET_OPTIONS = {
    "cycloid": ("start", "speed_profile"),
    "circle": ("start", "R", "cruise", "ramp_time"),
}
_RAMP_OPTIONS = ("start", "cruise", "ramp_time")


def _target_options(key: str) -> tuple[str, ...] | None:
    if key in _TARGET_OPTIONS:
        return _TARGET_OPTIONS[key]
    own = factory_options(key)
    return None if own is None else (*_RAMP_OPTIONS, *own)


_CYCLOID_SPEEDS = ("paper", "static", "dynamic")
_STARTS = ("on_path", "paper")


def _setup(path, profile, kind: str, duration: float | None) -> TargetSetup:
    """The ``kind`` of target of ``profile`` on ``path``, and the path's initial pose."""
    target_cls = DynamicTarget if kind == "dynamic" else StaticTarget
    return TargetSetup(path, target_cls(path, profile, duration), path.initial_pose)


def target_on(
    path,
    kind: str = "dynamic",
    duration: float | None = None,
    distance: float | None = None,
    **ramp,
) -> TargetSetup:
    """The target on ``path`` (its stations' speeds, else the ramp profile over ``distance``,
    by default its length, with ``ramp``'s ``cruise`` and ``ramp_time``) and its initial
    pose."""
    if path.station_speeds is not None:
        profile = StationSpeed(*path.station_speeds)
    else:
        profile = RampSpeed(path.length if distance is None else distance, **ramp)
    return _setup(path, profile, kind, duration)


def make_target(
    path_name_or_csv: str, kind: str = "dynamic", duration: float | None = None, **kw
) -> TargetSetup:
    """Build path, target and initial pose for a run (docs/model.md Section 7).

    Parameters
    ----------
    path_name_or_csv : str
        ``"cycloid"``, ``"s_curve"``, ``"circle"`` or a path to a ``.csv`` file.
    kind : {"dynamic", "static"}
    duration : float, optional
        Run length (s). Defaults: cycloid 3 pi/2 (Section 6.1); s_curve the time its ramp
        profile needs to cover 2 pi R (13.78 s for R = 1.5 m; the paper's 10 s stops 7.2 m
        along); circle 10 s (Section 6.3; here ``duration`` shapes the profile, and the circle
        is made long enough for it, 6.4 m = 1.02 laps by default); CSV the profile's time.
    **kw
        Any path: ``start``, "on_path" (default) or "paper". They differ only for the cycloid,
        whose paper pose (0, 0, pi/4) is off the path; the paper starts the S-curve and circle
        on their paths (Section 6.3), so there both mean the path start.
        cycloid: ``speed_profile``: "paper" (default: eq. 32
        speed for the static target, eq. 34 for the dynamic one, as in the paper), "static"
        or "dynamic" (that profile for either kind, for a like-for-like comparison).
        s_curve, circle: ``R``, ``cruise`` (0.8 m/s), ``ramp_time`` (2 s).
        CSV: ``max_curvature``, ``smoothing`` (see
        :func:`tt_mujoco.reference.paths.from_waypoints`),
        ``cruise``, ``ramp_time`` (used when the file has no ``v`` column).

    Returns
    -------
    TargetSetup
        ``(path, target, initial_pose)``.
    """
    if kind not in TARGET_KINDS:
        raise ValueError(f"kind={kind!r} is not allowed: use 'dynamic' or 'static'")
    if duration is not None:
        duration = positive_number("duration", duration)
    text = str(path_name_or_csv).strip()
    key = path_kind(text)
    check_options(text, kw, _target_options(key))
    ramp = {k: kw.pop(k) for k in ("cruise", "ramp_time") if k in kw}
    start = kw.pop("start", "on_path")
    if start not in _STARTS:
        raise ValueError(f"start={start!r} is not allowed: use 'on_path' or 'paper'")

    if key == "cycloid":
        path = cycloid(start)
        choice = kw.get("speed_profile", "paper")
        if choice not in _CYCLOID_SPEEDS:
            raise ValueError(
                f"speed_profile={choice!r} is not allowed: use 'paper', 'static' or 'dynamic'"
            )
        if choice == "paper":
            choice = kind
        profile = CycloidStaticSpeed() if choice == "static" else CycloidDynamicSpeed()
    elif key == "circle":
        profile = RampSpeed.for_duration(CIRCLE_DURATION if duration is None else duration, **ramp)
        R = positive_number("R", kw.get("R", 1.0))
        path = circle(R, length=max(2.0 * math.pi * R, profile.total_distance))
    else:  # s_curve, CSV files, registered and hooked paths: ramp profile unless given speeds
        return target_on(get_path(text, **kw), kind, duration, **ramp)
    return _setup(path, profile, kind, duration)

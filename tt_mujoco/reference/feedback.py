"""Outer path-feedback loop on top of a tracking target: position errors stop accumulating.

The paper's dynamic target ``omega_d = kappa(s) v`` (eqs. 33-34) makes the curvature error
``e_omega / v`` (eq. 37), but it never looks at where the vehicle is: whatever the yaw loop lets
through is integrated twice into a lateral offset that nothing removes. :class:`PathFeedback`
wraps a target and adds the classical kinematic path-following correction (Micaelli and Samson,
"Trajectory tracking for unicycle-type and two-steering-wheels mobile robots", INRIA RR-2097,
1993; Samson, "Control of chained systems: application to path following and time-varying
point-stabilization of mobile robots", IEEE Trans. Autom. Control 40(1), 1995; linearised as in
De Luca, Oriolo and Samson, "Feedback control of a nonholonomic car-like robot", in *Robot Motion
Planning and Control*, LNCIS 229, 1998)::

    omega_d = omega_d,target + v c,     c = clip(-k_y e_y - k_psi sgn(v) e_psi, +-c_max)

with ``e_y`` the signed distance of P from the path (positive left of the direction of travel,
as ``metrics.signed_lateral_error``), ``e_psi = theta - psi_path(s*)`` the heading error at the
nearest path point s*, and v the measured speed. Near the path, ``d e_y / dt = v sin(e_psi)`` and
``d e_psi / dt = v c``, so in arc length ``e_y'' + k_psi e_y' + k_y e_y = 0``: the offset decays
over a *distance* set by the gains (independent of speed), for either direction of travel.
``c_max`` caps the added curvature so that a large initial offset cannot ask for a turn the
trailer cannot follow (``paths.DEFAULT_MAX_CURVATURE``, 2 1/m).

The speed target v_d is left alone: along-track position is not fed back (so rmse_v measures the
same speed tracking with and without the loop). The pose (x, y, theta) is taken as measured
without noise: the paper's noise model covers v and omega only (docs/model.md Section 8).
"""

from __future__ import annotations

import math
from types import SimpleNamespace

from tt_mujoco.compiled_form import compiled_form
from tt_mujoco.vehicle.path_schedule import path_pose

__all__ = [
    "DEFAULT_GAINS",
    "PathFeedback",
    "TargetWrapper",
    "check_config",
    "check_gain_table",
    "curvature_and_rate_at",
    "feedback_of",
    "path_errors",
    "path_errors_of",
]

#: Default gains. k_y = 4 1/m^2 and k_psi = 4 1/m: critically damped in arc length
#: (k_psi = 2 sqrt(k_y)), offset halved every ~0.4 m. At the cycloid's 1.36 m/s peak that is a
#: 2.7 rad/s outer loop, under half the ISMC-STA yaw loop's lambda = 6 1/s (gain set 6.1), so the
#: two loops do not fight. c_max = 2 1/m: the curvature bound of the project's paths.
DEFAULT_GAINS = {"k_y": 4.0, "k_psi": 4.0, "c_max": 2.0}

# Newton steps per control step for the nearest path point (warm-started from the last one: one
# step converges to ~1e-9 m on the project's paths at 1 kHz; the second is insurance after a jump).
_NEWTON_STEPS = 2
# Lower bound of 1 - kappa e_y in the error kinematics (inside a tight turn, far from the path).
_MIN_METRIC = 0.2


def curvature_and_rate_at(path, s: float) -> tuple[float, float]:
    """``(kappa, dkappa/ds)`` of ``path`` at arc length ``s``, zero beyond its ends: there the
    path continues straight along its end tangents (as its pose does; the compiled episode
    shares it)."""
    return feedback_curvature(path, s) if 0.0 <= s <= path.length else (0.0, 0.0)


@compiled_form("the target record's path (target_step.path_at), not a path object")
def feedback_curvature(path, s: float) -> tuple[float, float]:
    """The path's ``(kappa, dkappa/ds)`` at ``s`` as the feedback reads it (the compiled
    episode gives its path record's)."""
    return path.curvature_and_rate(s)


def path_errors(pose_at, curvature_and_rate, s: float, x: float, y: float, theta: float):
    """``(s*, e_y, e_psi)``: the nearest path point to (x, y) by Newton steps warm-started at
    arc length ``s``, the signed distance from it (positive left of the path's direction) and
    the heading error ``theta - psi_path(s*)`` in (-pi, pi] (:func:`path_errors_of`).

    ``pose_at`` and ``curvature_and_rate`` are the path's (:class:`~tt_mujoco.reference.
    path_base.ReferencePath`); called every control step from near the last answer.
    """
    path = SimpleNamespace(pose_at=pose_at, curvature_and_rate=curvature_and_rate)
    return path_errors_of(path, s, x, y, theta)


def path_errors_of(path, s: float, x: float, y: float, theta: float):
    """:func:`path_errors` through :func:`~tt_mujoco.vehicle.path_schedule.path_pose` and
    :func:`feedback_curvature` (the compiled episode shares it)."""
    for _ in range(_NEWTON_STEPS):
        xr, yr, h = path_pose(path, s)
        c, sn = math.cos(h), math.sin(h)
        dx, dy = x - xr, y - yr
        along, e_y = dx * c + dy * sn, dy * c - dx * sn
        # Newton on |P - r(s)|^2 / 2, whose second derivative is 1 - kappa e_y. On the inside
        # of a turn it is below 1 and vanishes at the centre of curvature: there a plain step
        # (metric 1) converges linearly instead of overshooting.
        s += along / max(1.0 - feedback_curvature(path, s)[0] * e_y, 1.0)
    xr, yr, h = path_pose(path, s)
    e_y = (y - yr) * math.cos(h) - (x - xr) * math.sin(h)
    return s, e_y, math.remainder(theta - h, 2.0 * math.pi)


def feedback_of(gains, target, v: float, errors, kappa: float) -> tuple[float, float]:
    """``(omega_d, omega_d_dot)``: the target's ``(omega_d, v_d_dot, omega_d_dot)`` with the
    correction of :class:`PathFeedback` (``gains = (k_y, k_psi, c_max)``) for the measured
    speed ``v``, the ``errors = (e_y, e_psi)`` and the curvature ``kappa`` at the nearest path
    point (the compiled episode shares it).

    ``omega_d_dot`` adds the correction's derivative ``v_d_dot c + v c_dot`` along the
    path-error kinematics, ``d e_y/dt = v sin(e_psi)`` and ``d e_psi/dt = omega -
    kappa(s*) v cos(e_psi) / (1 - kappa(s*) e_y)``, evaluated with omega = omega_d (what the
    inner loop is asked to track) rather than the noisy measured yaw rate; c_dot = 0 while c
    is clipped.
    """
    k_y, k_psi, c_max = gains
    w_d, v_d_dot, w_d_dot = target
    e_y, e_psi = errors
    sign = 1.0 if v >= 0.0 else -1.0
    c = -k_y * e_y - k_psi * sign * e_psi
    clipped = abs(c) >= c_max
    if clipped:
        c = math.copysign(c_max, c)
    omega_d = w_d + v * c
    c_dot = 0.0
    if not clipped:
        metric = max(1.0 - kappa * e_y, _MIN_METRIC)
        e_psi_dot = omega_d - kappa * v * math.cos(e_psi) / metric
        c_dot = -k_y * v * math.sin(e_psi) - k_psi * sign * e_psi_dot
    return omega_d, w_d_dot + v_d_dot * c + v * c_dot


def check_gain_table(option: str, config: dict | None, defaults: dict) -> dict[str, float]:
    """A dict of gains merged over ``defaults``, each checked finite and > 0.

    Raises
    ------
    ValueError
        Naming ``option`` (a Scenario field) and the first bad key or value.
    """
    config = {} if config is None else config
    label = option.replace("_", " ")
    if not isinstance(config, dict):
        raise ValueError(
            f"{option}={config!r} is not allowed: use None or a dict with keys "
            f"{', '.join(defaults)}"
        )
    unknown = sorted(set(config) - set(defaults))
    if unknown:
        raise ValueError(
            f"{option} key(s) {', '.join(map(repr, unknown))} not allowed: use "
            f"{', '.join(defaults)}"
        )
    gains = {**defaults, **config}
    for name, value in gains.items():
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise ValueError(f"{label} {name}={value!r} is not allowed: use a number > 0")
        if not (math.isfinite(value) and value > 0):
            raise ValueError(f"{label} {name}={value!r} is not allowed: it must be finite and > 0")
    return {k: float(v) for k, v in gains.items()}


def check_config(config: dict | None) -> dict[str, float]:
    """The gains of a ``Scenario.path_feedback`` dict merged over :data:`DEFAULT_GAINS`
    (keys k_y, k_psi, c_max; values finite and > 0), or ValueError."""
    return check_gain_table("path_feedback", config, DEFAULT_GAINS)


class TargetWrapper:
    """A target around another (``self.target``): the Target interface the simulation loop and
    the metrics use, passed through; a subclass adds what the step does to its yaw-rate
    target."""

    kind = property(lambda self: self.target.kind)
    duration = property(lambda self: self.target.duration)
    start_s = property(lambda self: self.target.start_s)

    def reference_point(self, t):
        return self.target.reference_point(t)

    def reference_pose(self, t):
        return self.target.reference_pose(t)

    def reference_speed(self, t):
        return self.target.reference_speed(t)

    def reference_yaw_rate(self, t):
        return self.target.reference_yaw_rate(t)


class PathFeedback(TargetWrapper):
    """A tracking target with lateral and heading error feedback on omega_d.

    Parameters
    ----------
    target : tt_mujoco.reference.targets.Target or tt_mujoco.reference.reverse.ReverseTarget
        The target to wrap (dynamic, eq. 34, or static, eq. 32); its v_d, v_d_dot and its
        omega_d are the feed-forward.
    k_y : float
        Lateral error gain (1/m^2), > 0.
    k_psi : float
        Heading error gain (1/m), > 0.
    c_max : float
        Bound on the added curvature |c| (1/m), > 0.

    The step computes the correction from the target's record (the nearest path point s*,
    which may run past either end, where the path continues along its end tangent, and e_y,
    e_psi there: :func:`path_errors_of`, then :func:`feedback_of`).
    """

    def __init__(self, target, k_y: float = 4.0, k_psi: float = 4.0, c_max: float = 2.0):
        gains = check_config({"k_y": k_y, "k_psi": k_psi, "c_max": c_max})
        self.target = target
        self.path = target.path
        self.k_y, self.k_psi, self.c_max = gains["k_y"], gains["k_psi"], gains["c_max"]

    @classmethod
    def from_config(cls, target, config: dict | None) -> PathFeedback:
        """Build from a ``Scenario.path_feedback`` dict (keys k_y, k_psi, c_max; {} = defaults)."""
        return cls(target, **check_config(config))

    @property
    def gains(self) -> tuple[float, float, float]:
        """``(k_y, k_psi, c_max)``."""
        return self.k_y, self.k_psi, self.c_max

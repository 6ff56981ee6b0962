"""Backing up: the unit that leads the motion tracks the path; the hitches are stabilised by the
tractor's yaw rate (docs/model.md Section 14).

Reversing, every passive hitch with ``eta_k < 1`` is unstable (Section 3: ``phi_dot ~ (eta - 1)
v phi / L0`` with v < 0), and the tractor's own path says nothing about where the trailers go.
:class:`HitchCascade` wraps the reverse target and replaces its yaw-rate target by a cascade,
outer loop first, every loop's rate proportional to the speed (gains per metre of travel):

1. **Path.** The leading axle P_N (the last trailer's) is taken as a unicycle rolling along
   ``alpha_N = theta_N + beta_N``; the path-following law of :mod:`tt_mujoco.reference.feedback`
   on its errors (e_y, e_psi) gives the curvature it should run at,
   ``kappa_N = kappa(s_N) + clip(-k_y e_y - k_psi sgn(v_N) e_psi, +-c_max)``; for a train
   the feed-forward is the path's curvature averaged over ``preview (N - 1)`` metres ahead of
   the axle, so that the hitches behind it start to re-form before a curvature step.
2. **Hitch N, ..., 2.** The steady relation between a trailer's own axle curvature and its
   hitch angle behind a unit steering by ``beta_(k-1)`` (:func:`steady_axle_curvature`) turns
   ``kappa_k`` into ``phi_k,d`` (bounded by ``phi_max``); the
   hitch rate ``phi_k_dot = theta_(k-1)_dot - theta_k_dot`` then asks the unit ahead to turn at
   ``theta_(k-1)_dot = theta_k_dot - k_phi |v_k| (phi_k - phi_k,d)``, i.e. at curvature
   ``kappa_(k-1) = theta_(k-1)_dot / v_(k-1)``.
3. **Hitch 1.** ``phi_1_dot`` is affine in the tractor's yaw rate omega
   (:func:`tt_mujoco.vehicle.rolling.hitch_rates`), so omega is chosen to make
   ``phi_1_dot = -k_phi |v| (phi_1 - phi_1,d)``.

The torque-level law (ISMC-STA, PID, FBL) then tracks (v_d, omega_d) as it tracks any target.
The inner loops are made faster than the outer ones by ``k_phi`` growing towards the tractor
(``k_phi * 2**(N - k)`` for hitch k).
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np

from tt_mujoco.reference.feedback import (
    TargetWrapper,
    check_gain_table,
    curvature_and_rate_at,
    path_errors_of,
)
from tt_mujoco.vehicle.params import Params, jackknife_phi_deg
from tt_mujoco.vehicle.rolling import hitch_rates_of

__all__ = [
    "DEFAULT_GAINS",
    "HitchCascade",
    "SteadyInverse",
    "check_config",
    "steady_hitch_angle",
]

#: k_y (1/m^2), k_psi (1/m): the leading axle's path loop, critically damped in arc length
#: (k_psi = 2 sqrt(k_y)), its offset halved over ~1.2 m; k_phi (1/m): the last hitch's loop,
#: doubling per hitch towards the tractor; c_max (1/m): bound on the added curvature;
#: phi_max_deg: bound on a wanted hitch angle, well short of the jackknife limits; preview (m):
#: per trailer behind the first, how far ahead of the leading axle the path's curvature is
#: averaged for the feed-forward (a train's hitches need that much travel to re-form).
DEFAULT_GAINS = {
    "k_y": 2.0,
    "k_psi": 2.8,
    "k_phi": 3.0,
    "c_max": 1.0,
    "phi_max_deg": 45.0,
    "preview": 0.2,
}
#: Points of the preview window's curvature average.
PREVIEW_POINTS = 5


#: Most steps of :meth:`SteadyInverse.solve` (it converges to rounding in about ten).
_ROOT_STEPS = 60


def check_config(config: dict | None) -> dict[str, float]:
    """The cascade's gains merged over :data:`DEFAULT_GAINS` (each finite and > 0), or
    ValueError naming the bad one."""
    return check_gain_table("hitch_feedback", config, DEFAULT_GAINS)


def steady_curvature(phi, L: float, L0: float, eta: float):
    """The curvature (1/m) the unit ahead turns at when hitch angle ``phi`` is steady.

    ``phi_dot = 0`` in Section 2's kinematics with ``omega = kappa v`` is linear in kappa:
    ``kappa = -sin((eta - 1) phi) / (L0 cos(eta phi) + L cos((eta - 1) phi))``; in either
    direction of travel. With the same-path gains the trailer's own axle runs on that curvature
    too (Section 3), which the cascade assumes for every gain.
    """
    phi = np.asarray(phi, dtype=float)
    return -np.sin((eta - 1.0) * phi) / (L0 * np.cos(eta * phi) + L * np.cos((eta - 1.0) * phi))


def steady_axle_curvature(phi, L: float, L0: float, eta: float, beta_ahead=0.0):
    """The curvature (1/m) of a trailer's own axle path when hitch angle ``phi`` is steady
    behind a unit whose axle steers by ``beta_ahead`` (0 for the tractor).

    In a steady turn every unit rotates about one centre C. In the frame of the unit ahead
    (its axle at the origin, rolling along ``beta_ahead``), C lies on the normal to that
    direction; the trailer's axle ``P = (-L - L0 cos phi, L0 sin phi)`` rolls along
    ``(eta - 1) phi``, so C also lies on the normal there. Intersecting the two normals,
    ``kappa = -sin((eta - 1) phi - beta_ahead) / (L cos beta_ahead + L0 cos(phi + beta_ahead))``
    (checked against :func:`tt_mujoco.vehicle.rolling.hitch_rates` in tests/test_backing.py).
    It is the curvature the cascade asks of each axle; :func:`steady_curvature` is the unit
    ahead's.
    """
    phi = np.asarray(phi, dtype=float)
    b = beta_ahead
    return -np.sin((eta - 1.0) * phi - b) / (L * np.cos(b) + L0 * np.cos(phi + b))


class SteadyInverse:
    """``phi(kappa)``: the inverse of a steady relation (:func:`steady_curvature`, or
    ``curvature``) on its monotone branch through 0."""

    def __init__(self, L: float, L0: float, eta: float, phi_max: float, curvature=steady_curvature):
        self._relation = (L, L0, eta, curvature)
        phi = np.linspace(-phi_max, phi_max, 2001)
        kappa = curvature(phi, L, L0, eta)
        mid = phi.size // 2
        slope = np.sign(kappa[mid + 1] - kappa[mid - 1])
        if slope == 0:
            raise ValueError(f"eta={eta!r} is not allowed for backing up: no hitch angle steers")
        lo, hi = mid, mid
        while lo > 0 and slope * (kappa[lo] - kappa[lo - 1]) > 0:
            lo -= 1
        while hi < phi.size - 1 and slope * (kappa[hi + 1] - kappa[hi]) > 0:
            hi += 1
        kappa, phi = kappa[lo : hi + 1], phi[lo : hi + 1]
        if slope < 0:
            kappa, phi = kappa[::-1], phi[::-1]
        self._kappa, self._phi = kappa, phi

    def __call__(self, kappa: float) -> float:
        """The hitch angle (rad) for curvature ``kappa``, held at the branch's ends beyond."""
        return float(np.interp(kappa, self._kappa, self._phi))

    def solve(self, kappa: float, beta_ahead: float) -> float:
        """The hitch angle (rad) for ``kappa`` behind a unit steering by ``beta_ahead`` on the
        branch of :func:`steady_axle_curvature` (:func:`steady_solve_of`)."""
        L, L0, eta, curvature = self._relation
        if curvature is not steady_axle_curvature:
            raise ValueError("solve() is not allowed here: it inverts steady_axle_curvature")
        return steady_solve_of(self.ends, (L, L0), eta, kappa, beta_ahead)

    @property
    def ends(self) -> tuple[float, float]:
        """The branch's hitch angles (rad) at its lowest and highest curvature."""
        return float(self._phi[0]), float(self._phi[-1])


def steady_axle_curvature_of(phi: float, L: float, L0: float, eta: float, b: float) -> float:
    """:func:`steady_axle_curvature` of one hitch angle, behind a unit steering by ``b`` (the
    compiled episode shares it)."""
    return -math.sin((eta - 1.0) * phi - b) / (L * math.cos(b) + L0 * math.cos(phi + b))


def steady_solve_of(ends, lengths, eta: float, kappa: float, beta_ahead: float) -> float:
    """The hitch angle (rad) at which :func:`steady_axle_curvature_of` is ``kappa`` on the
    branch from ``ends[0]`` to ``ends[1]`` (where it rises), by regula falsi (Illinois), to
    rounding; held at the branch's ends beyond (the compiled episode shares it)."""
    L, L0 = lengths[0], lengths[1]
    lo, hi = ends[0], ends[1]
    f_lo = steady_axle_curvature_of(lo, L, L0, eta, beta_ahead) - kappa
    f_hi = steady_axle_curvature_of(hi, L, L0, eta, beta_ahead) - kappa
    if f_lo >= 0.0:
        return lo
    if f_hi <= 0.0:
        return hi
    side = 0
    for _ in range(_ROOT_STEPS):
        mid = hi - f_hi * (hi - lo) / (f_hi - f_lo)
        if not lo < mid < hi:  # the bracket is down to rounding
            break
        f_mid = steady_axle_curvature_of(mid, L, L0, eta, beta_ahead) - kappa
        if f_mid == 0.0:
            return mid
        if f_mid < 0.0:
            lo, f_lo = mid, f_mid
            if side == -1:
                f_hi *= 0.5
            side = -1
        else:
            hi, f_hi = mid, f_mid
            if side == 1:
                f_lo *= 0.5
            side = 1
        if hi - lo < 1e-15:
            break
    return lo if -f_lo < f_hi else hi


class CascadeConstants(NamedTuple):
    """What :func:`cascade_of` reads of a :class:`HitchCascade`, as plain numbers."""

    #: (k_y, k_psi, k_phi, c_max)
    gains: tuple
    #: the preview window behind the first trailer (m; 0 for one trailer)
    preview: float
    #: per trailer: (L_k, L0_k), eta_k, and its steady branch's ends (rad)
    lengths: Any
    etas: Any
    ends: Any


def cascade_of(c, path, phis, lead, speeds, leading_s: float, wanted, rates):
    """The cascade's yaw-rate target (module docstring): ``(s, e_y, e_psi, omega_d)``, the
    leading axle's arc length and errors, with each hitch's wanted angle into ``wanted`` and
    ``rates`` as scratch (N x 3).

    ``lead = (x, y, theta)``: the leading unit's axle and heading; ``speeds = (v, omega)``:
    the tractor's measured speed and yaw rate (the compiled episode shares it).
    """
    k_y, k_psi, k_phi, c_max = c.gains
    v, omega = speeds
    n = len(phis)
    hitch_rates_of(phis, (v, omega), c.lengths, c.etas, rates)
    alpha = lead[2] + c.etas[n - 1] * phis[n - 1]
    s, e_y, e_psi = path_errors_of(path, leading_s, lead[0], lead[1], alpha)
    v_lead = rates[n - 1][1]
    correction = -k_y * e_y - k_psi * math.copysign(1.0, v_lead) * e_psi
    points = PREVIEW_POINTS if c.preview else 1  # one trailer: the axle's own point
    step = math.copysign(c.preview, v_lead) / (PREVIEW_POINTS - 1)
    feed = 0.0
    for j in range(points):
        feed += curvature_and_rate_at(path, s + j * step)[0]
    kappa = feed / points + max(-c_max, min(c_max, correction))
    for k in range(n - 1, 0, -1):  # hitches N..2 (index k is trailer k + 1)
        # the unit ahead is a steered trailer: its steering moves the turn's centre
        goal = steady_solve_of(
            c.ends[k], c.lengths[k], c.etas[k], kappa, c.etas[k - 1] * phis[k - 1]
        )
        wanted[k] = goal
        gain = k_phi * 2.0 ** (n - 1 - k)
        turn = rates[k][2] - gain * abs(rates[k][1]) * (phis[k] - goal)
        speed = rates[k - 1][1]
        kappa = turn / speed if abs(speed) > 1e-3 else 0.0
    goal = steady_solve_of(c.ends[0], c.lengths[0], c.etas[0], kappa, 0.0)
    wanted[0] = goal
    gain = k_phi * 2.0 ** (n - 1)
    phi_dot_wanted = -gain * abs(v) * (phis[0] - goal)
    hitch_rates_of(phis, (v, 0.0), c.lengths, c.etas, rates)
    free = rates[0][0]
    hitch_rates_of(phis, (v, 1.0), c.lengths, c.etas, rates)
    per_omega = rates[0][0] - free
    return s, e_y, e_psi, (phi_dot_wanted - free) / per_omega


def steady_hitch_angle(kappa: float, L: float, L0: float, eta: float, phi_max: float) -> float:
    """The hitch angle (rad, within +-phi_max) held steady at curvature ``kappa``."""
    return SteadyInverse(L, L0, eta, phi_max)(kappa)


class HitchCascade(TargetWrapper):
    """A reverse target whose yaw-rate target backs the train along the path (module docstring).

    Parameters
    ----------
    target : tt_mujoco.reference.reverse.ReverseTarget
        Its speed target and path are kept; its yaw-rate target becomes the feed-forward only
        through the path's curvature at the leading axle.
    params : Params
        The nominal vehicle (lengths and gains eta_k of every trailer).
    gains : dict
        See :data:`DEFAULT_GAINS`.

    The step computes the yaw-rate target from the target's record (:func:`cascade_of`: the
    leading axle's arc length, its e_y and e_psi, the hitches' wanted angles phi_k,d).
    """

    def __init__(self, target, params: Params, **gains):
        g = check_config(gains)
        self.target = target
        self.path = target.path
        self.lengths = [(t.L, t.L0) for t in params.trailers]
        etas = tuple(params.etas)
        phi_max = math.radians(g["phi_max_deg"])
        # A wanted hitch angle stays within 80 % of where a run stops as a jackknife (|beta| =
        # |eta phi| = 85 deg: 22.7 deg for the paper's eta = 3).
        inverses = [
            SteadyInverse(
                L,
                L0,
                eta,
                min(phi_max, 0.8 * math.radians(jackknife_phi_deg(eta))),
                curvature=steady_axle_curvature,
            )
            for (L, L0), eta in zip(self.lengths, etas, strict=True)
        ]
        #: What the step reads (:func:`tt_mujoco.sim.loop.target_step.cascade_step_of`)
        self.constants = CascadeConstants(
            gains=(g["k_y"], g["k_psi"], g["k_phi"], g["c_max"]),
            preview=g["preview"] * (len(self.lengths) - 1),
            lengths=tuple(self.lengths),
            etas=etas,
            ends=tuple(inverse.ends for inverse in inverses),
        )

    @property
    def leading_start_s(self) -> float:
        """The leading axle's arc length where a run starts: the train stands on the path
        behind the tractor's start."""
        return float(self.target.start_s) - sum(L + L0 for L, L0 in self.lengths)

    @classmethod
    def from_config(cls, target, params: Params, config: dict | None) -> HitchCascade:
        return cls(target, params, **check_config(config))

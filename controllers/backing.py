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

import numpy as np

from tt_mujoco.reference.feedback import (
    TargetWrapper,
    check_gain_table,
    curvature_and_rate_at,
    path_errors,
)
from tt_mujoco.vehicle.params import Params, jackknife_phi_deg
from tt_mujoco.vehicle.rolling import hitch_rates

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
_PREVIEW_POINTS = 5


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
        """The hitch angle (rad) for ``kappa`` behind a unit steering by ``beta_ahead``: the
        relation's extra argument, by regula falsi (Illinois) on the branch, to rounding
        (held at its ends beyond)."""
        L, L0, eta, curvature = self._relation
        lo, hi = float(self._phi[0]), float(self._phi[-1])  # kappa rises from lo to hi
        f_lo = float(curvature(lo, L, L0, eta, beta_ahead)) - kappa
        f_hi = float(curvature(hi, L, L0, eta, beta_ahead)) - kappa
        if f_lo >= 0.0:
            return lo
        if f_hi <= 0.0:
            return hi
        side = 0
        for _ in range(_ROOT_STEPS):
            mid = hi - f_hi * (hi - lo) / (f_hi - f_lo)
            if not lo < mid < hi:  # the bracket is down to rounding
                break
            f_mid = float(curvature(mid, L, L0, eta, beta_ahead)) - kappa
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

    Attributes
    ----------
    lateral_error, heading_error : float
        The leading axle's e_y (m) and e_psi (rad) at the last update.
    hitch_targets : list of float
        phi_k,d (rad), trailer 1 first, at the last update.
    """

    #: The stepper passes the whole measurement to :meth:`update`.
    uses_measurement = True

    def __init__(self, target, params: Params, **gains):
        g = check_config(gains)
        self.target = target
        self.path = target.path
        self.k_y, self.k_psi, self.k_phi, self.c_max = g["k_y"], g["k_psi"], g["k_phi"], g["c_max"]
        self.phi_max = math.radians(g["phi_max_deg"])
        self.lengths = [(t.L, t.L0) for t in params.trailers]
        self.etas = list(params.etas)
        # A wanted hitch angle stays within 80 % of where a run stops as a jackknife (|beta| =
        # |eta phi| = 85 deg: 22.7 deg for the paper's eta = 3).
        self._inverse = [
            SteadyInverse(
                L,
                L0,
                eta,
                min(self.phi_max, 0.8 * math.radians(jackknife_phi_deg(eta))),
                curvature=steady_axle_curvature,
            )
            for (L, L0), eta in zip(self.lengths, self.etas, strict=True)
        ]
        self.preview = g["preview"] * (len(self.lengths) - 1)
        self._pose_at = self.path.pose_at
        self._curvature = self.path.curvature_and_rate
        self.reset()

    @classmethod
    def from_config(cls, target, params: Params, config: dict | None) -> HitchCascade:
        return cls(target, params, **check_config(config))

    def reset(self) -> None:
        self.target.reset()
        n = len(self.lengths)
        behind = sum(L + L0 for L, L0 in self.lengths)
        self.leading_arc_length = float(self.target.arc_length) - behind
        self.lateral_error = self.heading_error = 0.0
        self.hitch_targets = [0.0] * n
        self.reference_omega_d = 0.0

    def update(self, t: float, dt: float, v_measured: float, me) -> tuple:
        """``(v_d, omega_d, v_d_dot, omega_d_dot)`` for measurement ``me`` (omega_d_dot = 0:
        the cascade's yaw-rate target moves with the state, not on a schedule)."""
        v_d, w_d, v_d_dot, _ = self.target.update(t, dt, v_measured)
        self.reference_omega_d = w_d
        rows = getattr(me, "train", ())
        phis = me.phis
        v = float(v_measured)
        rates = hitch_rates(phis, v, me.omega, self.lengths, self.etas)
        n = len(phis)
        x, y, theta = (me.x0, me.y0, me.theta0) if n == 1 else rows[-1][:3]
        alpha = theta + self.etas[-1] * phis[-1]
        s, e_y, e_psi = path_errors(
            self._pose_at, self._curvature, self.leading_arc_length, x, y, alpha
        )
        self.leading_arc_length = s
        self.lateral_error, self.heading_error = e_y, e_psi
        v_lead = rates[-1][1]
        c = -self.k_y * e_y - self.k_psi * math.copysign(1.0, v_lead) * e_psi
        points = _PREVIEW_POINTS if self.preview else 1  # one trailer: the axle's own point
        step = math.copysign(self.preview, v_lead) / (_PREVIEW_POINTS - 1)
        feed = sum(curvature_and_rate_at(self.path, s + j * step)[0] for j in range(points))
        kappa = feed / points + max(-self.c_max, min(self.c_max, c))
        for k in range(n - 1, 0, -1):  # hitches N..2 (index k is trailer k + 1)
            # the unit ahead is a steered trailer: its steering moves the turn's centre
            wanted = self._inverse[k].solve(kappa, self.etas[k - 1] * phis[k - 1])
            self.hitch_targets[k] = wanted
            gain = self.k_phi * 2.0 ** (n - 1 - k)
            turn = rates[k][2] - gain * abs(rates[k][1]) * (phis[k] - wanted)
            speed = rates[k - 1][1]
            kappa = turn / speed if abs(speed) > 1e-3 else 0.0
        wanted = self._inverse[0].solve(kappa, 0.0)
        self.hitch_targets[0] = wanted
        gain = self.k_phi * 2.0 ** (n - 1)
        phi_dot_wanted = -gain * abs(v) * (phis[0] - wanted)
        free = hitch_rates(phis, v, 0.0, self.lengths, self.etas)[0][0]
        per_omega = hitch_rates(phis, v, 1.0, self.lengths, self.etas)[0][0] - free
        omega_d = (phi_dot_wanted - free) / per_omega
        return v_d, omega_d, v_d_dot, 0.0

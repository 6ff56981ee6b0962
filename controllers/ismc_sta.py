"""Integral sliding mode with the super-twisting algorithm (ISMC-STA), paper Section 5.

With ``e = z - z_d``, ``z = (v, omega)`` and the nominal model ``z_dot = f + g tau``:

    S = e + lambda * int(e)                                         (paper eq. 23)
    u = g^-1 (z_d_dot - f - lambda e + u_st)                        (eqs. 26, 29)
    u_st,i = -k1_i |S_i|^(1/2) sig(S_i) - int(k2_i sig(S_i)),  sig(S) = S / (eps + |S|)

(eqs. 27-28, the smooth ``sig`` replacing ``sgn``). The extracted paper text lost its minus
signs, so the sign of the super-twisting term is derived here. On the plant
``z_dot = f + g tau + Delta`` the law gives

    S_dot = e_dot + lambda e = (f + g u + Delta - z_d_dot) + lambda e = u_st + Delta   (eq. 30),

so each channel is ``S_dot = -k1 |S|^(1/2) sig(S) + w + Delta``, ``w_dot = -k2 sig(S)``: the
classical super-twisting algorithm, which drives S to 0 only with both terms *negative*
(with a plus sign ``S S_dot > 0`` and S diverges). Writing ``xi = w + Delta``, ``xi_dot = -k2
sig(S) + Delta_dot``: the integral term absorbs the disturbance itself, and the convergence
condition concerns the disturbance's *rate*, ``k2 > |Delta_dot|``, rather than the paper's
``k2 > Delta_max``. For the paper's Delta (Section 6.1, docs/model.md Section 8) ``|Delta1_dot| <=
1.3``
and ``|Delta2_dot| <= 2.95`` against k2 = (8, 6). With ``sig`` instead of ``sgn`` S converges
to a boundary layer of width about ``eps`` rather than exactly to 0. On the sliding surface
``e_dot = -lambda e``: the error decays exponentially.

Gain presets: ``"paper_6_1"`` (default; Section 6.1: lambda = diag(5, 6), k1 = (10, 3.5),
k2 = (8, 6), eps = 0.005) and ``"paper_6_2"`` (Section 6.2, the comparison with PID and FBL:
lambda = diag(5, 0.3), same k1 and k2, eps = 0.02).

Anti-windup (see :mod:`controllers.base`): both integrators of a channel, ``int(e)`` inside S
and ``int(k2 sig(S))``, are frozen over an interval when their increment would push a
saturated torque further out. Each is tested with its own increment (``e_i`` and
``sig(S_i)``); both enter ``r_i`` with a negative sign (the first through ``-k1 |S|^(1/2)
sig(S)``, which increases with S).
"""

from __future__ import annotations

import math
from typing import ClassVar, NamedTuple

from tt_mujoco.controllers.base import (
    LAW_OK,
    LawStep,
    VelocityController,
    deepens,
    torques_of,
)

__all__ = ["IsmcStaController", "IsmcStaGains", "IsmcStaState", "ismc_sta_law"]

_sqrt = math.sqrt


class IsmcStaGains(NamedTuple):
    """The law's gains: the sliding surfaces' ``lambda`` (eq. 24), the super-twisting gains
    ``k1`` and ``k2`` (eq. 27) per channel, and the width ``eps`` of ``sig``."""

    lambda_v: float
    lambda_omega: float
    k1_v: float
    k1_omega: float
    k2_v: float
    k2_omega: float
    eps: float


class IsmcStaState(NamedTuple):
    """The law's memory: the integrators of e (inside S) and of the super-twisting term, then
    the integrands held over the coming interval (zero-order hold; 0 = frozen or first call)."""

    int_e_v: float = 0.0
    int_e_omega: float = 0.0
    sta_v: float = 0.0
    sta_omega: float = 0.0
    rate_e_v: float = 0.0
    rate_e_omega: float = 0.0
    rate_w_v: float = 0.0
    rate_w_omega: float = 0.0


def ismc_sta_law(dt, tracking, model, state, gains, saturation):
    """One step of the law (module docstring) from plain numbers: the one implementation,
    which :meth:`IsmcStaController.step` and the compiled episode
    (:mod:`tt_mujoco.sim.loop.compiled`)
    both run.

    Parameters
    ----------
    dt : float
        Time since the previous step, s.
    tracking : Tracking
        Measured ``(v, omega)``, their targets and the targets' rates.
    model : Nominal
        The nominal model's ``f`` and ``g`` at the measurement.
    state : IsmcStaState
        The integrators and the integrands held from the last step.
    gains : IsmcStaGains
    saturation : Saturation
        The torque limit, whether the previous step saturated, and the anti-windup switch.

    Returns
    -------
    LawStep
        ``aux1, aux2`` are the sliding variables ``(S_v, S_omega)``; ``status`` is
        :data:`~tt_mujoco.controllers.base.LAW_OK`, ``LAW_SINGULAR`` (g cannot be inverted) or
        ``LAW_NOT_FINITE`` (the torques are not finite).
    """
    lam1, lam2, eps = gains.lambda_v, gains.lambda_omega, gains.eps
    k11, k12, k21, k22 = gains.k1_v, gains.k1_omega, gains.k2_v, gains.k2_omega
    z, f = tracking, model
    # Explicit Euler over the elapsed interval with the integrands of the previous call.
    I1 = state.int_e_v + dt * state.rate_e_v
    I2 = state.int_e_omega + dt * state.rate_e_omega
    W1 = state.sta_v + dt * state.rate_w_v
    W2 = state.sta_omega + dt * state.rate_w_omega

    e1 = z.v - z.v_d
    e2 = z.omega - z.omega_d
    S1 = e1 + lam1 * I1
    S2 = e2 + lam2 * I2
    sig1 = S1 / (eps + abs(S1))
    sig2 = S2 / (eps + abs(S2))
    r1 = z.v_d_dot - f.f1 - lam1 * e1 - k11 * _sqrt(abs(S1)) * sig1 - W1
    r2 = z.omega_d_dot - f.f2 - lam2 * e2 - k12 * _sqrt(abs(S2)) * sig2 - W2

    w1 = k21 * sig1
    w2 = k22 * sig2
    status, T_r, T_l, u1, u2, s1, s2, a11, a12, a21, a22 = torques_of(
        f.g11, f.g12, f.g21, f.g22, r1, r2, saturation.limit
    )
    if status != LAW_OK:
        held = IsmcStaState(I1, I2, W1, W2, e1, e2, w1, w2)
        return LawStep(status, T_r, T_l, u1, u2, saturation.saturated, S1, S2, held)
    saturated = s1 != 0.0 or s2 != 0.0
    if saturated and saturation.anti_windup:
        if deepens(e1, a11, a21, s1, s2):
            e1 = 0.0
        if deepens(e2, a12, a22, s1, s2):
            e2 = 0.0
        if deepens(w1, a11, a21, s1, s2):
            w1 = 0.0
        if deepens(w2, a12, a22, s1, s2):
            w2 = 0.0
    held = IsmcStaState(I1, I2, W1, W2, e1, e2, w1, w2)
    return LawStep(LAW_OK, T_r, T_l, u1, u2, saturated, S1, S2, held)


class IsmcStaController(VelocityController):
    """ISMC-STA velocity controller (paper Section 5, eqs. 23-30). See the module docstring.

    Gain keys: ``lambda_v``, ``lambda_omega``, ``k1_v``, ``k1_omega``, ``k2_v``, ``k2_omega``,
    ``eps``. Other parameters as :class:`tt_mujoco.controllers.base.VelocityController`.
    """

    name = "ismc_sta"
    LAW = staticmethod(ismc_sta_law)
    PRESETS: ClassVar[dict[str, dict[str, float]]] = {
        "paper_6_1": {
            "lambda_v": 5.0,
            "lambda_omega": 6.0,
            "k1_v": 10.0,
            "k1_omega": 3.5,
            "k2_v": 8.0,
            "k2_omega": 6.0,
            "eps": 0.005,
        },
        "paper_6_2": {
            "lambda_v": 5.0,
            "lambda_omega": 0.3,
            "k1_v": 10.0,
            "k1_omega": 3.5,
            "k2_v": 8.0,
            "k2_omega": 6.0,
            "eps": 0.02,
        },
    }
    DEFAULT_PRESET = "paper_6_1"
    GAINS = IsmcStaGains
    STATE = IsmcStaState

    def state(self):
        s = self.law_state
        return {
            "int_e_v": s.int_e_v,
            "int_e_omega": s.int_e_omega,
            "sta_int_v": s.sta_v,
            "sta_int_omega": s.sta_omega,
            "S_v": self.aux[0],
            "S_omega": self.aux[1],
        }

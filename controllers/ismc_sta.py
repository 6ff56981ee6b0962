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
from typing import ClassVar

from tt_mujoco.controllers.base import (
    LAW_OK,
    LawStep,
    VelocityController,
    deepens,
    torques_of,
)

__all__ = ["IsmcStaController", "ismc_sta_law"]

_sqrt = math.sqrt


#: Where each of the law's state values is in its ``state`` (the integrators of e and of the
#: super-twisting term, then the integrands held from the last step).
INT_E_V, INT_E_OMEGA, STA_V, STA_OMEGA, RATE_E_V, RATE_E_OMEGA, RATE_W_V, RATE_W_OMEGA = range(8)


def ismc_sta_law(dt, tracking, model, state, gains, saturation):
    """One step of the law (module docstring) from plain numbers: the one implementation,
    which :meth:`IsmcStaController.step` and the compiled episode (:mod:`tt_mujoco.sim.compiled`)
    both run.

    Parameters
    ----------
    dt : float
        Time since the previous step, s.
    tracking : Tracking
        Measured ``(v, omega)``, their targets and the targets' rates.
    model : Nominal
        The nominal model's ``f`` and ``g`` at the measurement.
    state : tuple of 8 floats
        ``(int_e_v, int_e_omega, sta_v, sta_omega, rate_e1, rate_e2, rate_w1, rate_w2)``.
    gains : sequence of 7 floats
        ``(lambda_v, lambda_omega, k1_v, k1_omega, k2_v, k2_omega, eps)``.
    saturation : Saturation
        The torque limit, whether the previous step saturated, and the anti-windup switch.

    Returns
    -------
    LawStep
        ``aux1, aux2`` are the sliding variables ``(S_v, S_omega)``; ``status`` is
        :data:`~tt_mujoco.controllers.base.LAW_OK`, ``LAW_SINGULAR`` (g cannot be inverted) or
        ``LAW_NOT_FINITE`` (the torques are not finite).
    """
    lam1, lam2, k11, k12, k21, k22, eps = gains
    z, f = tracking, model
    # Explicit Euler over the elapsed interval with the integrands of the previous call.
    I1 = state[INT_E_V] + dt * state[RATE_E_V]
    I2 = state[INT_E_OMEGA] + dt * state[RATE_E_OMEGA]
    W1 = state[STA_V] + dt * state[RATE_W_V]
    W2 = state[STA_OMEGA] + dt * state[RATE_W_OMEGA]

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
        held = (I1, I2, W1, W2, e1, e2, w1, w2)
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
    return LawStep(LAW_OK, T_r, T_l, u1, u2, saturated, S1, S2, (I1, I2, W1, W2, e1, e2, w1, w2))


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

    def reset(self):
        self.int_e_v = self.int_e_omega = 0.0  # int(e), inside S
        self.sta_v = self.sta_omega = 0.0  # int(k2 sig(S)), the super-twisting integral
        self.S_v = self.S_omega = 0.0
        # Integrands held over the coming interval (zero-order hold; 0 = frozen or first call).
        self._rate_e1 = self._rate_e2 = self._rate_w1 = self._rate_w2 = 0.0
        self.saturated = False

    def state(self):
        return {
            "int_e_v": self.int_e_v,
            "int_e_omega": self.int_e_omega,
            "sta_int_v": self.sta_v,
            "sta_int_omega": self.sta_omega,
            "S_v": self.S_v,
            "S_omega": self.S_omega,
        }

    def _set_gains(self, gains):
        self._lam1, self._lam2 = gains["lambda_v"], gains["lambda_omega"]
        self._k11, self._k12 = gains["k1_v"], gains["k1_omega"]
        self._k21, self._k22 = gains["k2_v"], gains["k2_omega"]
        self._eps = gains["eps"]
        self.law_gains = (self._lam1, self._lam2, self._k11, self._k12, self._k21, self._k22)
        self.law_gains += (self._eps,)

    def law_state(self) -> tuple:
        """The integrators and held integrands, in :func:`ismc_sta_law`'s order."""
        return (
            self.int_e_v,
            self.int_e_omega,
            self.sta_v,
            self.sta_omega,
            self._rate_e1,
            self._rate_e2,
            self._rate_w1,
            self._rate_w2,
        )

    def set_law_state(self, state, S_v: float = 0.0, S_omega: float = 0.0) -> None:
        self.int_e_v, self.int_e_omega, self.sta_v, self.sta_omega = state[INT_E_V : STA_OMEGA + 1]
        self._rate_e1, self._rate_e2, self._rate_w1, self._rate_w2 = state[RATE_E_V:]
        self.S_v, self.S_omega = S_v, S_omega

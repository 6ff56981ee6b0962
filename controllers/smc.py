"""Sliding-mode control with a boundary layer (SMC): the classical first-order baseline.

With ``e = z - z_d``, ``z = (v, omega)`` and the nominal model ``z_dot = f + g tau``, each
channel's sliding variable is its error and the law is

    u = g^-1 (z_d_dot - f - K sat(e / Phi)),   sat(x) = max(-1, min(1, x)),

``K = diag(k_v, k_omega)`` the switching gains and ``Phi = (phi_v, phi_omega)`` the boundary
layer's half-widths (Slotine and Li, *Applied Nonlinear Control*, 1991, Sections 7.1-7.2). On
the plant ``z_dot = f + g tau + Delta`` each channel obeys ``e_dot = -k sat(e / phi) +
Delta``: outside the layer ``|e|`` falls at least at ``k - |Delta|`` (the reaching condition
needs ``k > |Delta|``), inside it ``e_dot = -(k / phi) e + Delta``, so a constant Delta leaves
the error ``phi Delta / k`` rather than FBL's ``Delta / K`` (:mod:`controllers.fbl`). The
saturation function in place of ISMC-STA's sign-like ``sig`` trades exact convergence for a
control without chattering; there is no integrator, so nothing winds up.

The preset ``"default"`` takes ``k_v = 10 m/s^2`` and ``k_omega = 10 rad/s^2``, above the
paper's disturbance bounds (5 and 2, paper Section 6.1) with a margin for what the nominal model
misses; the yaw channel needs it backing up, where the hitch cascade's yaw-rate target moves
fast (with ``k_omega = 3`` the S-curve backing up jackknifed at 8.7 s). With ``phi_v = 0.05
m/s`` and ``phi_omega = 0.05 rad/s`` the layer's linear gains are 200 1/s, inside the stability
bound ``2 / dt`` of the 1 ms control period by a factor of 10.
"""

from __future__ import annotations

from typing import ClassVar, NamedTuple

from tt_mujoco.controllers.base import LAW_OK, LawStep, VelocityController, torques_of

__all__ = ["SmcController", "SmcGains", "SmcState", "smc_law"]


class SmcGains(NamedTuple):
    """The switching gains ``K`` and the boundary layer's half-widths ``Phi``."""

    k_v: float
    k_omega: float
    phi_v: float
    phi_omega: float


class SmcState(NamedTuple):
    """SMC has no memory."""


def smc_law(dt, tracking, model, state, gains, saturation):
    """One step of the law (module docstring) from plain numbers, in the form of
    :func:`tt_mujoco.controllers.ismc_sta.ismc_sta_law` (the compiled episode runs it);
    ``gains`` is an :class:`SmcGains` and ``state`` (empty) is passed through."""
    z, f = tracking, model
    k_v, k_omega, phi_v, phi_omega = gains.k_v, gains.k_omega, gains.phi_v, gains.phi_omega
    # sat() written out, so that NaN stays NaN (min and max would drop it) and the loop stops
    x_v, x_omega = (z.v - z.v_d) / phi_v, (z.omega - z.omega_d) / phi_omega
    sat_v = 1.0 if x_v > 1.0 else (-1.0 if x_v < -1.0 else x_v)
    sat_omega = 1.0 if x_omega > 1.0 else (-1.0 if x_omega < -1.0 else x_omega)
    r1 = z.v_d_dot - f.f1 - k_v * sat_v
    r2 = z.omega_d_dot - f.f2 - k_omega * sat_omega
    status, T_r, T_l, u1, u2, s1, s2, _, _, _, _ = torques_of(
        f.g11, f.g12, f.g21, f.g22, r1, r2, saturation.limit
    )
    if status != LAW_OK:
        return LawStep(status, T_r, T_l, u1, u2, saturation.saturated, 0.0, 0.0, state)
    return LawStep(LAW_OK, T_r, T_l, u1, u2, s1 != 0.0 or s2 != 0.0, sat_v, sat_omega, state)


class SmcController(VelocityController):
    """Sliding-mode velocity controller with a boundary layer. See the module docstring.

    Gain keys: ``k_v`` (m/s^2), ``k_omega`` (rad/s^2), ``phi_v`` (m/s), ``phi_omega`` (rad/s).
    Other parameters as :class:`tt_mujoco.controllers.base.VelocityController`
    (``anti_windup`` has no effect: there is no integrator).
    """

    name = "smc"
    LAW = staticmethod(smc_law)
    PRESETS: ClassVar[dict[str, dict[str, float]]] = {
        "default": {"k_v": 10.0, "k_omega": 10.0, "phi_v": 0.05, "phi_omega": 0.05},
    }
    DEFAULT_PRESET = "default"
    GAINS = SmcGains
    STATE = SmcState

    def state(self):
        """Where each channel is in its boundary layer: ``sat(e / phi)``, +-1 outside it."""
        return {"sat_v": self.aux[0], "sat_omega": self.aux[1]}

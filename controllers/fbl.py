"""Feedback linearization (FBL), paper Section 6.2.

With ``e = z - z_d``, ``z = (v, omega)`` and the nominal model ``z_dot = f + g tau``:

    u = g^-1 (z_d_dot - f - K e),    K = diag(8, 5)  (preset ``"paper_6_2"``)

On the exact model the error obeys ``e_dot = -K e``. With a disturbance Delta it obeys
``e_dot = -K e + Delta``: a constant Delta leaves the steady error ``Delta / K`` (0.44 m/s for
the paper's Delta1 mean of 3.5 m/s^2 and K_v = 8). FBL has no integrator, so nothing winds up.
"""

from __future__ import annotations

from typing import ClassVar, NamedTuple

from tt_mujoco.controllers.base import LAW_OK, LawStep, VelocityController, torques_of

__all__ = ["FblController", "FblGains", "FblState", "fbl_law"]


class FblGains(NamedTuple):
    """The error feedback's gains ``K = diag(k_v, k_omega)``."""

    k_v: float
    k_omega: float


class FblState(NamedTuple):
    """FBL has no memory."""


def fbl_law(dt, tracking, model, state, gains, saturation):
    """One step of the law (module docstring) from plain numbers, in the form of
    :func:`tt_mujoco.controllers.ismc_sta.ismc_sta_law` (the compiled episode shares it);
    ``gains`` is a :class:`FblGains` and ``state`` (empty) is passed through."""
    z, f = tracking, model
    k_v, k_omega = gains.k_v, gains.k_omega
    r1 = z.v_d_dot - f.f1 - k_v * (z.v - z.v_d)
    r2 = z.omega_d_dot - f.f2 - k_omega * (z.omega - z.omega_d)
    status, T_r, T_l, u1, u2, s1, s2, _, _, _, _ = torques_of(
        f.g11, f.g12, f.g21, f.g22, r1, r2, saturation.limit
    )
    if status != LAW_OK:
        return LawStep(status, T_r, T_l, u1, u2, saturation.saturated, 0.0, 0.0, state)
    return LawStep(LAW_OK, T_r, T_l, u1, u2, s1 != 0.0 or s2 != 0.0, 0.0, 0.0, state)


class FblController(VelocityController):
    """Feedback-linearizing velocity controller (paper Section 6.2). See the module docstring.

    Gain keys: ``k_v``, ``k_omega``. Other parameters as
    :class:`tt_mujoco.controllers.base.VelocityController`
    (``anti_windup`` has no effect: there is no integrator).
    """

    name = "fbl"
    LAW = staticmethod(fbl_law)
    PRESETS: ClassVar[dict[str, dict[str, float]]] = {"paper_6_2": {"k_v": 8.0, "k_omega": 5.0}}
    DEFAULT_PRESET = "paper_6_2"
    GAINS = FblGains
    STATE = FblState

    def state(self):
        return {}

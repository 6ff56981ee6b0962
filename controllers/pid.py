"""PID with nominal-model feedforward, paper Section 6.2.

With ``e = z - z_d``, ``z = (v, omega)`` and the nominal model ``z_dot = f + g tau``:

    u = g^-1 (z_d_dot - f - KP e - KI int(e) - KD e_dot)

(the paper's PID law in Section 6.2, signs restored). Gains (``"paper_6_2"``, the only preset):
KP = diag(5, 3), KI = diag(2, 1.5), KD = diag(0.1, 0.05).

``e_dot`` is the backward difference ``(e(t_k) - e(t_(k-1))) / dt`` of the measured error, 0 on
the first call after :meth:`~PidController.reset` (no previous error). On the exact nominal
model the closed loop per channel is ``(1 + KD) e_dot = -KP e - KI int(e)``: both channels are
overdamped (poles -0.44 and -4.1 for v, -0.65 and -2.2 for omega with the paper's gains). A
constant disturbance d leaves no steady error (the integral absorbs it), a time-varying one
does: PID has no explicit disturbance compensation.

Anti-windup (see :mod:`controllers.base`): ``int(e_i)`` is frozen over an interval when its
increment would push a saturated torque further out.
"""

from __future__ import annotations

from typing import ClassVar, NamedTuple

from tt_mujoco.controllers.base import (
    LAW_OK,
    LawStep,
    VelocityController,
    deepens,
    torques_of,
)

__all__ = ["PidController", "PidGains", "PidState", "pid_law"]


class PidGains(NamedTuple):
    """The law's proportional, integral and derivative gains per channel."""

    kp_v: float
    kp_omega: float
    ki_v: float
    ki_omega: float
    kd_v: float
    kd_omega: float


class PidState(NamedTuple):
    """The law's memory: the integrators, the previous errors and whether there is one (1.0
    or 0.0), and the integrands held over the coming interval."""

    int_e_v: float = 0.0
    int_e_omega: float = 0.0
    prev_e_v: float = 0.0
    prev_e_omega: float = 0.0
    has_prev: float = 0.0
    rate_v: float = 0.0
    rate_omega: float = 0.0


def pid_law(dt, tracking, model, state, gains, saturation):
    """One step of the PID law (module docstring) from plain numbers, in the form of
    :func:`tt_mujoco.controllers.ismc_sta.ismc_sta_law` (the compiled episode shares it).

    ``state`` is a :class:`PidState`, ``gains`` a :class:`PidGains`.
    """
    kp1, kp2, ki1, ki2 = gains.kp_v, gains.kp_omega, gains.ki_v, gains.ki_omega
    kd1, kd2 = gains.kd_v, gains.kd_omega
    z, f = tracking, model
    I1 = state.int_e_v + dt * state.rate_v
    I2 = state.int_e_omega + dt * state.rate_omega
    e1 = z.v - z.v_d
    e2 = z.omega - z.omega_d
    if state.has_prev == 0.0:
        de1 = de2 = 0.0
    else:
        de1 = (e1 - state.prev_e_v) / dt
        de2 = (e2 - state.prev_e_omega) / dt
    r1 = z.v_d_dot - f.f1 - kp1 * e1 - ki1 * I1 - kd1 * de1
    r2 = z.omega_d_dot - f.f2 - kp2 * e2 - ki2 * I2 - kd2 * de2
    status, T_r, T_l, u1, u2, s1, s2, a11, a12, a21, a22 = torques_of(
        f.g11, f.g12, f.g21, f.g22, r1, r2, saturation.limit
    )
    if status != LAW_OK:
        held = PidState(I1, I2, e1, e2, 1.0, state.rate_v, state.rate_omega)
        return LawStep(status, T_r, T_l, u1, u2, saturation.saturated, 0.0, 0.0, held)
    saturated = s1 != 0.0 or s2 != 0.0
    rate1, rate2 = e1, e2
    if saturated and saturation.anti_windup:
        if deepens(e1, a11, a21, s1, s2):
            rate1 = 0.0
        if deepens(e2, a12, a22, s1, s2):
            rate2 = 0.0
    held = PidState(I1, I2, e1, e2, 1.0, rate1, rate2)
    return LawStep(LAW_OK, T_r, T_l, u1, u2, saturated, 0.0, 0.0, held)


class PidController(VelocityController):
    """PID velocity controller with feedforward (paper Section 6.2). See the module docstring.

    Gain keys: ``kp_v``, ``kp_omega``, ``ki_v``, ``ki_omega``, ``kd_v``, ``kd_omega``. Other
    parameters as :class:`tt_mujoco.controllers.base.VelocityController`.
    """

    name = "pid"
    LAW = staticmethod(pid_law)
    PRESETS: ClassVar[dict[str, dict[str, float]]] = {
        "paper_6_2": {
            "kp_v": 5.0,
            "kp_omega": 3.0,
            "ki_v": 2.0,
            "ki_omega": 1.5,
            "kd_v": 0.1,
            "kd_omega": 0.05,
        },
    }
    DEFAULT_PRESET = "paper_6_2"
    GAINS = PidGains
    STATE = PidState

    def state(self):
        return {"int_e_v": self.law_state.int_e_v, "int_e_omega": self.law_state.int_e_omega}

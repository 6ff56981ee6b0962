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

from typing import ClassVar

from tt_mujoco.controllers.base import (
    LAW_OK,
    LawStep,
    VelocityController,
    deepens,
    torques_of,
)

__all__ = ["PidController", "pid_law"]


#: Where each of the law's state values is in its ``state`` (the integrators, the previous
#: errors and whether there is one, the integrands held from the last step; one unused).
INT_E_V, INT_E_OMEGA, PREV_E_V, PREV_E_OMEGA, HAS_PREV, RATE_V, RATE_OMEGA = range(7)


def pid_law(dt, tracking, model, state, gains, saturation):
    """One step of the PID law (module docstring) from plain numbers, in the form of
    :func:`tt_mujoco.controllers.ismc_sta.ismc_sta_law` (the compiled episode shares it).

    ``state`` is ``(int_e_v, int_e_omega, prev_e_v, prev_e_omega, has_prev, rate_v,
    rate_omega, 0)``, ``gains`` ``(kp_v, kp_omega, ki_v, ki_omega, kd_v, kd_omega, 0)``.
    """
    kp1, kp2, ki1, ki2, kd1, kd2, _ = gains
    z, f = tracking, model
    I1 = state[INT_E_V] + dt * state[RATE_V]
    I2 = state[INT_E_OMEGA] + dt * state[RATE_OMEGA]
    e1 = z.v - z.v_d
    e2 = z.omega - z.omega_d
    if state[HAS_PREV] == 0.0:
        de1 = de2 = 0.0
    else:
        de1 = (e1 - state[PREV_E_V]) / dt
        de2 = (e2 - state[PREV_E_OMEGA]) / dt
    r1 = z.v_d_dot - f.f1 - kp1 * e1 - ki1 * I1 - kd1 * de1
    r2 = z.omega_d_dot - f.f2 - kp2 * e2 - ki2 * I2 - kd2 * de2
    status, T_r, T_l, u1, u2, s1, s2, a11, a12, a21, a22 = torques_of(
        f.g11, f.g12, f.g21, f.g22, r1, r2, saturation.limit
    )
    if status != LAW_OK:
        held = (I1, I2, e1, e2, 1.0, state[RATE_V], state[RATE_OMEGA], 0.0)
        return LawStep(status, T_r, T_l, u1, u2, saturation.saturated, 0.0, 0.0, held)
    saturated = s1 != 0.0 or s2 != 0.0
    rate1, rate2 = e1, e2
    if saturated and saturation.anti_windup:
        if deepens(e1, a11, a21, s1, s2):
            rate1 = 0.0
        if deepens(e2, a12, a22, s1, s2):
            rate2 = 0.0
    held = (I1, I2, e1, e2, 1.0, rate1, rate2, 0.0)
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

    def _set_gains(self, gains):
        self._kp1, self._kp2 = gains["kp_v"], gains["kp_omega"]
        self._ki1, self._ki2 = gains["ki_v"], gains["ki_omega"]
        self._kd1, self._kd2 = gains["kd_v"], gains["kd_omega"]
        self.law_gains = (self._kp1, self._kp2, self._ki1, self._ki2, self._kd1, self._kd2, 0.0)

    def law_state(self) -> tuple:
        """The integrators, the previous errors and the held integrands, in
        :func:`pid_law`'s order."""
        first = self._prev_e1 is None
        return (
            self.int_e_v,
            self.int_e_omega,
            0.0 if first else self._prev_e1,
            0.0 if first else self._prev_e2,
            0.0 if first else 1.0,
            self._rate1,
            self._rate2,
            0.0,
        )

    def set_law_state(self, state, aux1: float = 0.0, aux2: float = 0.0) -> None:
        self.int_e_v, self.int_e_omega = state[INT_E_V], state[INT_E_OMEGA]
        has_prev = state[HAS_PREV] != 0.0
        self._prev_e1 = state[PREV_E_V] if has_prev else None
        self._prev_e2 = state[PREV_E_OMEGA] if has_prev else None
        self._rate1, self._rate2 = state[RATE_V], state[RATE_OMEGA]

    def reset(self):
        self.int_e_v = self.int_e_omega = 0.0
        self._prev_e1 = self._prev_e2 = None  # previous error, for the backward difference
        self._rate1 = self._rate2 = 0.0  # integrand held over the coming interval
        self.saturated = False

    def state(self):
        return {"int_e_v": self.int_e_v, "int_e_omega": self.int_e_omega}

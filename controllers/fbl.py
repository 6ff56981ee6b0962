"""Feedback linearization (FBL), paper Section 6.2.

With ``e = z - z_d``, ``z = (v, omega)`` and the nominal model ``z_dot = f + g tau``:

    u = g^-1 (z_d_dot - f - K e),    K = diag(8, 5)  (preset ``"paper_6_2"``)

On the exact model the error obeys ``e_dot = -K e``. With a disturbance Delta it obeys
``e_dot = -K e + Delta``: a constant Delta leaves the steady error ``Delta / K`` (0.44 m/s for
the paper's Delta1 mean of 3.5 m/s^2 and K_v = 8). FBL has no integrator, so nothing winds up.
"""

from __future__ import annotations

import math
from typing import ClassVar

from tt_mujoco.controllers.base import VelocityController

__all__ = ["FblController"]


class FblController(VelocityController):
    """Feedback-linearizing velocity controller (paper Section 6.2). See the module docstring.

    Gain keys: ``k_v``, ``k_omega``. Other parameters as
    :class:`tt_mujoco.controllers.base.VelocityController`
    (``anti_windup`` has no effect: there is no integrator).
    """

    name = "fbl"
    PRESETS: ClassVar[dict[str, dict[str, float]]] = {"paper_6_2": {"k_v": 8.0, "k_omega": 5.0}}
    DEFAULT_PRESET = "paper_6_2"

    def _set_gains(self, gains):
        self._k1, self._k2 = gains["k_v"], gains["k_omega"]

    def reset(self):
        self.saturated = False

    def state(self):
        return {}

    def step(self, dt, phi, v, omega, v_d, omega_d, v_d_dot, omega_d_dot):
        if not 0.0 < dt < math.inf:
            self._check_dt(dt)
        f1, f2, g11, g12, g21, g22 = self.model(phi, v, omega)
        r1 = v_d_dot - f1 - self._k1 * (v - v_d)
        r2 = omega_d_dot - f2 - self._k2 * (omega - omega_d)
        a11, a12, a21, a22 = self._inverse(g11, g12, g21, g22)
        T_r, T_l, _, _ = self._saturate(a11 * r1 + a12 * r2, a21 * r1 + a22 * r2)
        return T_r, T_l

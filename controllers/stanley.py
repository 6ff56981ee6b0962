"""A Stanley-type path tracker for the differential-drive tractor, over a velocity loop.

Stanley's law (Hoffmann, Tomlin, Montemerlo and Thrun, "Autonomous automobile trajectory
tracking for off-road driving", ACC 2007) steers by the heading error and the arctangent of
the cross-track error over the speed. A differential drive has no steering angle, so here the
law sets the yaw-rate command: with ``e_y`` the signed distance of the tractor's P from the
nearest path point (positive left), ``e_psi`` the heading error there, ``kappa`` the path's
curvature and ``v`` the measured speed,

    omega_c = kappa v - k_heading v_s (e_psi + atan(k_cross e_y / v_s)),   v_s = max(|v|, v_min)

(the curvature feedforward keeps P on a circle of the path's radius; the bracket is Stanley's
steering angle, turned into a yaw rate over the travelled distance). The speed target is the
reference's ``v_d``. An inner loop tracks ``(v_d, omega_c)`` through the nominal model
``V_dot = f + g tau`` (docs/model.md Section 4): ``tau = g^-1 (a - f)`` with
``a = (v_d_dot + k_v e_v, k_omega e_omega)``. Driving forward only: reversing, the trailer
leads, which this law does not stabilise.

The nearest path point comes from :func:`tt_mujoco.reference.feedback.path_errors`, warm-started
at the previous step's.
"""

from __future__ import annotations

import math
from typing import ClassVar

from tt_mujoco.controllers.base import Controller
from tt_mujoco.controllers.nominal import track_velocities

from tt_mujoco.reference.feedback import path_errors

__all__ = ["StanleyController"]


class StanleyController(Controller):
    """Stanley-type path tracking over a velocity loop (see the module docstring).

    Gain keys: ``k_heading`` (1/m), ``k_cross`` (1/s), ``v_min`` (m/s), ``k_v`` and ``k_omega``
    (1/s, the inner loop).
    """

    name = "stanley"
    REVERSE = False
    PRESETS: ClassVar[dict[str, dict[str, float]]] = {
        "default": {"k_heading": 4.0, "k_cross": 2.0, "v_min": 0.1, "k_v": 20.0, "k_omega": 20.0},
    }
    DEFAULT_PRESET = "default"

    def reset(self) -> None:
        self._s = None  # the nearest path point's arc length, warm start of the next step

    def compute(self, t, measurement, reference):
        m, r, k = measurement, reference, self._gains
        path = self.setup.path
        s = r.s if self._s is None else self._s
        s, e_y, e_psi = path_errors(path.pose_at, path.curvature_and_rate, s, m.x, m.y, m.theta)
        self._s = s
        kappa = path.curvature_and_rate(s)[0]
        v_s = max(abs(m.v), k["v_min"])
        omega_c = kappa * m.v - k["k_heading"] * v_s * (e_psi + math.atan(k["k_cross"] * e_y / v_s))
        self.log("cross_track", e_y)
        self.log("heading_error", e_psi)
        self.log("omega_c", omega_c)
        return track_velocities(
            self.setup.model, m, r.v_d, r.v_d_dot, omega_c, k["k_v"], k["k_omega"]
        )

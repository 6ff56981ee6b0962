"""LQR path tracking on the linearised error kinematics, scheduled along the path.

At each control step the law linearises the path-frame error kinematics of the train
(:func:`tt_mujoco.vehicle.linearize.jacobians`, docs/model.md Section 15) about the steady arc
of the path's curvature at the tractor's nearest point: ``e_y = e_psi = 0``, each hitch at its
steady angle for the curvature under its own trailer's axle, ``v = v_d`` and ``omega = kappa
v_d``. The speed is the target's; the yaw rate is the input the LQR designs for: with ``A`` and
the ``omega`` column ``b`` of ``B``, ``K`` solves the continuous-time algebraic Riccati equation
for ``Q = diag(q_y, q_psi, q_phi, ...)`` and ``R = r_omega``, and

    omega_c = kappa v_d - K (z - z_ref),   z = (e_y, e_psi, phi_1, ..., phi_N).

Gains are kept per (curvature, speed) rounded to a grid (``kappa_step``, ``v_step``), so a run
solves one Riccati equation per distinct arc and speed, not one per step. An inner loop tracks
``(v_d, omega_c)`` through the nominal model (:func:`controllers.nominal.track_velocities`).

Driving forward only. Backing up, the same design holds the hitch on steady arcs, but a
curvature step asks the leading trailer to swing its hitch through tens of degrees, outside the
linearisation, and the runs of the S-curve and the circle jackknife (6.4 s and 8.5 s); the NMPC
(``nmpc``) and the hitch cascade back up.
"""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np
from tt_mujoco.controllers.backing import SteadyInverse
from tt_mujoco.controllers.base import Controller
from tt_mujoco.controllers.nominal import track_velocities

from tt_mujoco.reference.feedback import curvature_and_rate_at, path_errors
from tt_mujoco.vehicle.linearize import jacobians
from tt_mujoco.vehicle.params import jackknife_phi_deg

__all__ = ["LqrController"]


class LqrController(Controller):
    """Gain-scheduled LQR on the path-frame error kinematics (see the module docstring).

    Gain keys: ``q_y`` (1/m^2), ``q_psi``, ``q_phi`` (1/rad^2), ``r_omega`` (s^2/rad^2), the
    schedule's grid ``kappa_step`` (1/m) and ``v_step`` (m/s), ``v_min`` (m/s, the speed the
    design assumes below it), and the inner loop's ``k_v``, ``k_omega`` (1/s).
    """

    name = "lqr"
    REVERSE = False
    PRESETS: ClassVar[dict[str, dict[str, float]]] = {
        "default": {
            "q_y": 400.0, "q_psi": 10.0, "q_phi": 1.0, "r_omega": 0.1, "kappa_step": 0.01,
            "v_step": 0.02, "v_min": 0.1, "k_v": 20.0, "k_omega": 20.0,
        },
    }  # fmt: skip
    DEFAULT_PRESET = "default"

    def __init__(self, setup, gains=None):
        super().__init__(setup, gains)
        params = setup.params
        self.lengths = [(t.L, t.L0) for t in params.trailers]
        self.etas = list(params.etas)
        self._behind = np.cumsum([L + L0 for L, L0 in self.lengths])
        self._steady = [
            SteadyInverse(L, L0, eta, 0.8 * math.radians(min(80.0, jackknife_phi_deg(eta))))
            for (L, L0), eta in zip(self.lengths, self.etas, strict=True)
        ]
        k = self._gains
        n = len(self.lengths)
        self._Q = np.diag([k["q_y"], k["q_psi"], *[k["q_phi"]] * n])
        self._R = np.array([[k["r_omega"]]])

    def reset(self) -> None:
        self._s = None
        self._gain_table: dict[tuple[int, int], np.ndarray] = {}

    def gain(self, kappa: float, v: float) -> np.ndarray:
        """``K`` (shape (N + 2,)) for the steady arc of curvature ``kappa`` at speed ``v``."""
        k = self._gains
        key = (round(kappa / k["kappa_step"]), round(v / k["v_step"]))
        K = self._gain_table.get(key)
        if K is None:
            kappa_g, v_g = key[0] * k["kappa_step"], key[1] * k["v_step"]
            if abs(v_g) < k["v_min"]:
                v_g = math.copysign(k["v_min"], v if v != 0.0 else 1.0)
            z = (0.0, 0.0, *(steady(kappa_g) for steady in self._steady))
            A, B = jacobians(z, (v_g, kappa_g * v_g), kappa_g, self.lengths, self.etas)
            b = B[:, 1:2]
            from scipy.linalg import solve_continuous_are  # scipy: only where LQR runs

            P = solve_continuous_are(A, b, self._Q, self._R)
            K = (b.T @ P / self._R[0, 0]).ravel()
            self._gain_table[key] = K
        return K

    def compute(self, t, measurement, reference):
        m, r, k = measurement, reference, self._gains
        path = self.setup.path
        s = r.s if self._s is None else self._s
        s, e_y, e_psi = path_errors(path.pose_at, path.curvature_and_rate, s, m.x, m.y, m.theta)
        self._s = s
        kappa = curvature_and_rate_at(path, s)[0]
        phis = m.phis
        phis_ref = [
            steady(curvature_and_rate_at(path, s - behind)[0])
            for steady, behind in zip(self._steady, self._behind, strict=True)
        ]
        K = self.gain(kappa, r.v_d)
        error = np.array([e_y, e_psi, *(p - q for p, q in zip(phis, phis_ref, strict=True))])
        omega_c = kappa * r.v_d - float(K @ error)
        self.log("cross_track", e_y)
        self.log("heading_error", e_psi)
        self.log("omega_c", omega_c)
        return track_velocities(
            self.setup.model, m, r.v_d, r.v_d_dot, omega_c, k["k_v"], k["k_omega"]
        )

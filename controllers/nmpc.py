"""Nonlinear model predictive control on the reduced dynamics, wheel torques as inputs.

The prediction model is the project's own reduced model, for any N (docs/model.md Sections 4,
12 and 15): the state is ``x = (s, e_y, e_psi, phi_1..phi_N, v, omega)``, the nearest path
point's arc length, the tractor's path-frame errors, the hitch angles and the tractor's
velocities; the input is ``u = (T_r, T_l)``;

    s_dot = v cos(e_psi) / (1 - kappa(s) e_y),  (e_y, e_psi, phi)_dot: Section 15,
    (v, omega)_dot = f(phi, v, omega) + g(phi) u + d

with ``d`` an estimate of the unmodelled acceleration (below). Each sample period the
controller performs one real-time iteration (Diehl, Bock and Schloeder, "A real-time iteration
scheme for nonlinear optimization in optimal feedback control", SIAM J. Control Optim. 2005):
it linearises the model along the previous plan shifted by one sample (the kinematic rows by
:func:`tt_mujoco.vehicle.linearize.jacobians`, the velocity rows by central differences of the
nominal model), discretises each stage to second order, and solves one sparse QP
(:class:`controllers.mpc_qp.TrackingQP`) with the torque limit as a hard bound and the hitch
angles bounded softly (``phi_max_deg``, at most 80 % of the jackknife angle). The first torque
is held for the sample period.

The reference over the horizon is the target's arc length advanced at its speed target, with
``e_y = e_psi = 0``, each hitch at the steady angle of the path's curvature there, ``v = v_d``
and ``omega = kappa v_d``. Offset-free tracking: ``d`` is updated every sample by ``k_dist``
times the gap between the measured velocities and the ones the last plan predicted, per second.

Gains: ``horizon`` and ``horizon_reverse`` (samples, driving forward and backing up),
``sample_dt`` (s), the state weights ``q_s, q_y, q_psi, q_phi,
q_v, q_omega``, the input weights ``r_du, r_u``, ``phi_max_deg`` and ``k_dist``. It needs the
optional package OSQP (``pip install 'tt-mujoco[mpc]'``). :meth:`NmpcController.report` gives
the solve times and failures that ``metrics.json`` carries under ``controller``.
"""

from __future__ import annotations

import math
import time
from typing import ClassVar

import numpy as np
from tt_mujoco.controllers.backing import SteadyInverse
from tt_mujoco.controllers.base import Controller
from tt_mujoco.controllers.mpc_qp import QpWeights, TrackingQP

from tt_mujoco.reference.feedback import curvature_and_rate_at, path_errors
from tt_mujoco.vehicle.linearize import error_rates, jacobians
from tt_mujoco.vehicle.params import jackknife_phi_deg
from tt_mujoco.vehicle.reduced import SingularityError

__all__ = ["NmpcController"]

_FD_STEP = 1e-6


class NmpcController(Controller):
    """Real-time-iteration NMPC with torque inputs (see the module docstring)."""

    name = "nmpc"
    REVERSE = True
    PRESETS: ClassVar[dict[str, dict[str, float]]] = {
        "default": {
            "horizon": 25.0, "horizon_reverse": 50.0, "sample_dt": 0.04,
            "q_s": 5000.0, "q_y": 2.0e4, "q_psi": 2.0e3, "q_phi": 50.0, "q_v": 200.0,
            "q_omega": 20.0, "r_du": 0.02, "r_u": 1.0e-4,
            "phi_max_deg": 45.0, "k_dist": 0.3,
        },
    }  # fmt: skip
    DEFAULT_PRESET = "default"

    def __init__(self, setup, gains=None):
        super().__init__(setup, gains)
        k = self._gains
        params = setup.params
        self.lengths = [(t.L, t.L0) for t in params.trailers]
        self.etas = list(params.etas)
        self.n = n = len(self.lengths)
        # Backing up, the leading trailer must start its turns before the tractor's own
        # point reaches them: the plan looks further ahead.
        steps = k["horizon_reverse"] if setup.reverse else k["horizon"]
        self.horizon = max(2, int(round(steps)))
        self.dt = k["sample_dt"]
        self.phi_bound = [
            min(math.radians(k["phi_max_deg"]), 0.8 * math.radians(jackknife_phi_deg(eta)))
            for eta in self.etas
        ]
        self._steady = [
            SteadyInverse(L, L0, eta, bound)
            for (L, L0), eta, bound in zip(self.lengths, self.etas, self.phi_bound, strict=True)
        ]
        weights = [k["q_s"], k["q_y"], k["q_psi"], *[k["q_phi"]] * n, k["q_v"], k["q_omega"]]
        self.nx = len(weights)
        qp_weights = QpWeights(tuple(weights), k["r_du"], k["r_u"], rho=1.0e5, rho1=1.0e3)
        self._qp = TrackingQP(
            self.nx, 2, self.horizon, qp_weights, setup.torque_limit, bounded=range(3, 3 + n)
        )
        self._behind = np.cumsum([L + L0 for L, L0 in self.lengths])
        self._phi_guard = [0.95 * math.radians(jackknife_phi_deg(eta)) for eta in self.etas]

    def reset(self) -> None:
        self._next = -math.inf
        self._u = (0.0, 0.0)
        self._plan = None  # (states, inputs) of the last solve
        self._planned = False  # whether the last sample's QP was solved
        self._s = None
        self._disturbance = np.zeros(2)
        self._solve_ms: list[float] = []
        self._failures = 0

    def report(self) -> dict:
        """Solve statistics of the run: count, median and max time (ms), failures."""
        times = self._solve_ms
        return {
            "solves": len(times),
            "solve_ms_median": float(np.median(times)) if times else None,
            "solve_ms_max": float(max(times)) if times else None,
            "solve_failures": self._failures,
            "sample_dt_s": self.dt,
        }

    # -- the model ---------------------------------------------------------------------------
    def _rates(self, x, u):
        """``(x_dot, J = dx_dot/dx, G = dx_dot/du)`` at state ``x`` and torques ``u``."""
        n, path = self.n, self.setup.path
        s, e_y, e_psi = x[0], x[1], x[2]
        phis = [max(-g, min(g, p)) for p, g in zip(x[3 : 3 + n], self._phi_guard, strict=True)]
        v, omega = x[3 + n], x[4 + n]
        kappa, dkappa = curvature_and_rate_at(path, s)
        z = (e_y, e_psi, *phis)
        kin = error_rates(z, (v, omega), kappa, self.lengths, self.etas)
        A_kin, B_kin = jacobians(z, (v, omega), kappa, self.lengths, self.etas)
        J = np.zeros((self.nx, self.nx))
        xdot = np.empty(self.nx)
        metric = 1.0 - kappa * e_y
        c, sn = math.cos(e_psi), math.sin(e_psi)
        xdot[0] = v * c / metric
        J[0, 0] = v * c * e_y / metric**2 * dkappa
        J[0, 1] = v * c * kappa / metric**2
        J[0, 2] = -v * sn / metric
        J[0, 3 + n] = c / metric
        xdot[1 : 3 + n] = kin
        J[1 : 3 + n, 1 : 3 + n] = A_kin
        J[1 : 3 + n, 3 + n :] = B_kin
        J[2, 0] = -v * c / metric**2 * dkappa
        accel, G = self._velocity_rates(phis, v, omega, u)
        xdot[3 + n :] = accel + self._disturbance
        args = [*phis, v, omega]
        for j in range(n + 2):  # central differences of the nominal model
            up, down = list(args), list(args)
            up[j] += _FD_STEP
            down[j] -= _FD_STEP
            a_up = self._velocity_rates(up[:n], up[n], up[n + 1], u)[0]
            a_down = self._velocity_rates(down[:n], down[n], down[n + 1], u)[0]
            J[3 + n :, 3 + j] = (a_up - a_down) / (2.0 * _FD_STEP)
        Gfull = np.zeros((self.nx, 2))
        Gfull[3 + n :] = G
        return xdot, J, Gfull

    def _velocity_rates(self, phis, v, omega, u):
        phi = phis[0] if self.n == 1 else tuple(phis)
        f1, f2, g11, g12, g21, g22 = self.setup.model(phi, v, omega)
        g = np.array([[g11, g12], [g21, g22]])
        return np.array([f1, f2]) + g @ u, g

    def _stage(self, x, u):
        """``(A, B, c)`` of the second-order discretisation about ``(x, u)``."""
        h = self.dt
        xdot, J, G = self._rates(x, u)
        Jh = J * h
        A = np.eye(self.nx) + Jh + 0.5 * Jh @ Jh
        B = h * G + 0.5 * h * Jh @ G
        nxt = x + h * xdot + 0.5 * h * (Jh @ xdot)
        return A, B, nxt - A @ x - B @ u

    # -- one sample --------------------------------------------------------------------------
    def _measured_state(self, m, r) -> np.ndarray:
        path = self.setup.path
        s0 = r.s if self._s is None else self._s
        s, e_y, e_psi = path_errors(path.pose_at, path.curvature_and_rate, s0, m.x, m.y, m.theta)
        self._s = s
        return np.array([s, e_y, e_psi, *m.phis, m.v, m.omega])

    def _references(self, r) -> np.ndarray:
        n, path = self.n, self.setup.path
        refs = np.zeros((self.horizon, self.nx))
        for k in range(1, self.horizon + 1):
            tau = k * self.dt
            s = r.s + r.v_d * tau + 0.5 * r.v_d_dot * tau * tau
            v = r.v_d + r.v_d_dot * tau
            kappa = curvature_and_rate_at(path, s)[0]
            refs[k - 1, 0] = s
            # each hitch at the steady angle of the curvature under its own trailer's axle
            refs[k - 1, 3 : 3 + n] = [
                steady(curvature_and_rate_at(path, s - behind)[0])
                for steady, behind in zip(self._steady, self._behind, strict=True)
            ]
            refs[k - 1, 3 + n] = v
            refs[k - 1, 4 + n] = kappa * v
        return refs

    def _solve(self, m, r) -> None:
        x0 = self._measured_state(m, r)
        n = self.n
        if self._plan is None:
            refs = self._references(r)
            states = np.vstack([x0, refs])
            states[1:, 1:3] = x0[1:3]
            inputs = np.zeros((self.horizon, 2))
        else:
            prev_states, prev_inputs = self._plan
            # offset-free: the velocity gap the last plan did not predict, per second
            if self._planned:
                gap = x0[3 + n :] - prev_states[1, 3 + n :]
                self._disturbance += self._gains["k_dist"] * gap / self.dt
            states = np.vstack([prev_states[1:], prev_states[-1:]])
            inputs = np.vstack([prev_inputs[1:], prev_inputs[-1:]])
            refs = self._references(r)
        states[0] = x0
        A_list, B_list, c_list = [], [], []
        for k in range(self.horizon):
            A, B, c = self._stage(states[k], inputs[k])
            A_list.append(A)
            B_list.append(B)
            c_list.append(c)
        solution = self._qp.solve(x0, A_list, B_list, c_list, refs, self._u, self.phi_bound)
        if solution.ok:
            self._plan = (solution.states, solution.inputs)
            self._planned = True
            self._u = tuple(float(t) for t in solution.inputs[0])
        else:  # keep to the last plan, shifted
            self._failures += 1
            self._plan = (states, inputs)
            self._planned = False
            self._u = tuple(float(t) for t in inputs[0])

    def compute(self, t, measurement, reference):
        if t >= self._next - 1e-9:
            start = time.perf_counter()
            try:
                self._solve(measurement, reference)
            except SingularityError:
                self._failures += 1
            self._solve_ms.append(1e3 * (time.perf_counter() - start))
            self._next = t + self.dt
            self.log("disturbance_v", float(self._disturbance[0]))
            self.log("disturbance_omega", float(self._disturbance[1]))
        return self._u

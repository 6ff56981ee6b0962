"""The reduced plant: the analytic ODE (docs/model.md Section 4) behind the plant protocol."""

from __future__ import annotations

from tt_mujoco.sim.measure import Measurement
from tt_mujoco.sim.plant import Plant
from tt_mujoco.vehicle import reduced
from tt_mujoco.vehicle.params import Params

__all__ = ["ReducedPlant"]


class ReducedPlant(Plant):
    """The reduced model integrated with RK4; measurements are exact (no slip).

    Parameters
    ----------
    params : Params
        The plant's parameters.
    pose : (x, y, theta)
        Initial tractor pose.
    v_init : float
        Initial forward speed (m/s).
    timestep : float
        Integration step (s).
    phi0 : float
        Initial articulation (rad).
    """

    name = "reduced"

    def __init__(self, params: Params, pose, v_init: float, timestep: float, phi0: float = 0.0):
        self.params = params
        state = [pose[0], pose[1], pose[2], phi0, 0.0, 0.0, v_init, 0.0]
        self.ode = reduced.ReducedPlant(params, state=state)
        self.timestep = timestep
        self._tau = (0.0, 0.0)

    def measure(self):
        p = self.params
        x, y, theta, phi, th_l, th_r, v, omega = (float(c) for c in self.ode.state)
        _, P0, theta0 = reduced.trailer_pose(x, y, theta, phi, p)
        v0, _ = reduced.trailer_velocity(phi, (v, omega), p)
        return Measurement(
            x=x,
            y=y,
            theta=theta,
            phi=phi,
            beta=p.eta * phi,
            v=v,
            omega=omega,
            x0=float(P0[0]),
            y0=float(P0[1]),
            theta0=theta0,
            v0=v0,
            theta_l=th_l,
            theta_r=th_r,
            theta_l_dot=(v - 0.5 * p.d * omega) / p.r,
            theta_r_dot=(v + 0.5 * p.d * omega) / p.r,
            slip_lateral=0.0,
            slip_lateral_trailer=0.0,
            slip_left=0.0,
            slip_right=0.0,
        )

    def apply(self, T_r, T_l, dist_r, dist_l, wrench_force, wrench_torque, theta) -> None:
        self._tau = (T_r + dist_r, T_l + dist_l)

    def scale_trailer_mass(self, factor: float) -> None:
        p = self.params
        self._set_params(p.replace(Mr=p.Mr * factor, Ird=p.Ird * factor))

    def set_eta(self, eta: float) -> None:
        self._set_params(self.params.replace(eta=eta))

    def _set_params(self, params: Params) -> None:
        self.params = params
        self.ode.params = params

    def advance(self, substeps: int) -> None:
        """Raises :class:`tt_mujoco.vehicle.reduced.SingularityError` at |beta| = 90 deg."""
        for _ in range(substeps):
            self.ode.step(self._tau, self.timestep)

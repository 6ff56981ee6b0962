"""Demo data: an open-loop run's time series without a simulation loop, for figures and tests."""

from __future__ import annotations

import numpy as np

from tt_mujoco.vehicle import reduced
from tt_mujoco.vehicle.params import Params
from tt_mujoco.viz.scene import cumulative_trapezoid

__all__ = ["TIMESERIES_COLUMNS", "open_loop_timeseries"]


#: Every column of a run's ``timeseries.csv`` (the simulation loop's contract).
TIMESERIES_COLUMNS = (
    "t x y theta phi beta v omega x0 y0 theta0 v0 theta_l theta_r s x_ref y_ref v_d omega_d "
    "v_d_dot omega_d_dot v_meas omega_meas T_r T_l T_r_cmd T_l_cmd slip_lateral "
    "slip_lateral_trailer slip_left slip_right eq_violation kappa_d"
).split()


def open_loop_timeseries(
    params: Params | None = None,
    torques=(0.6, 0.4),
    duration: float = 3.0,
    dt: float = 0.01,
) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """A run-shaped time series of the reduced model under constant wheel torques.

    For tests and benchmarks until (and besides) the simulation loop: the reduced plant
    (:class:`~tt_mujoco.vehicle.reduced.ReducedPlant`) from rest, ``beta = eta phi``, the reference
    point and targets equal to the motion itself, columns without a model value zero.

    Returns
    -------
    ts : dict of str to ndarray
        All :data:`TIMESERIES_COLUMNS`.
    reference_polyline : ndarray, shape (n, 2)
        The path P drove.
    """
    p = Params() if params is None else params
    n = round(duration / dt) + 1
    plant = reduced.ReducedPlant(p)
    states = np.empty((n, 8))
    states[0] = plant.state
    for k in range(1, n):
        states[k] = plant.step(torques, dt)
    x, y, theta, phi, theta_l, theta_r, v, omega = states.T
    ts = {name: np.zeros(n) for name in TIMESERIES_COLUMNS}
    ts.update(t=np.arange(n) * dt, x=x, y=y, theta=theta, phi=phi, beta=p.eta * phi, v=v)
    ts.update(omega=omega, theta_l=theta_l, theta_r=theta_r, x_ref=x, y_ref=y, v_d=v)
    ts.update(omega_d=omega, v_meas=v, omega_meas=omega)
    ts["T_r"][:], ts["T_l"][:] = torques
    ts["T_r_cmd"][:], ts["T_l_cmd"][:] = torques
    for k in range(n):
        _, P0, theta0 = reduced.trailer_pose(x[k], y[k], theta[k], phi[k], p)
        ts["x0"][k], ts["y0"][k], ts["theta0"][k] = P0[0], P0[1], theta0
        ts["v0"][k] = reduced.trailer_velocity(phi[k], (v[k], omega[k]), p)[0]
    ts["s"] = cumulative_trapezoid(v, ts["t"])
    return ts, np.column_stack([x, y])

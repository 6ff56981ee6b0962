"""The reduced plant: the analytic ODE (docs/model.md Section 4) behind the plant protocol."""

from __future__ import annotations

import dataclasses

from tt_mujoco.sim.parts.measure import (
    ROW_BETA,
    ROW_PHI,
    ROW_THETA0,
    ROW_V0,
    ROW_X0,
    ROW_Y0,
    Measurement,
    TrainMeasurement,
)
from tt_mujoco.sim.parts.plant import Plant
from tt_mujoco.vehicle import reduced, train
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
    phi0 : float or tuple of float
        Initial articulation (rad): phi_1, or phi_1..phi_N of a train.
    """

    name = "reduced"

    def __init__(self, params: Params, pose, v_init: float, timestep: float, phi0: float = 0.0):
        self.params = params
        n = params.n_trailers
        hitches = list(phi0) if isinstance(phi0, tuple | list) else [phi0]
        hitches += [0.0] * (n - len(hitches))
        state = [pose[0], pose[1], pose[2], *hitches, 0.0, 0.0, v_init, 0.0]
        ode = reduced.ReducedPlant if n == 1 else train.TrainODE
        self.ode = ode(params, state=state)
        self.timestep = timestep

    def measure(self):
        p = self.params
        if p.n_trailers > 1:
            return self._measure_train()
        state = [float(c) for c in self.ode.state]
        return Measurement._make(reduced_measure_values(state, reduced.model_constants(p)))

    def _measure_train(self) -> TrainMeasurement:
        """The train's state from the chain (docs/model.md Section 12), exact like the rest."""
        p = self.params
        n = p.n_trailers
        state = [float(c) for c in self.ode.state]
        # Trailer 1 as for one trailer; trailers 2..N from the chain.
        first = [*state[:4], *state[3 + n :]]
        out = TrainMeasurement._make(reduced_measure_values(first, reduced.model_constants(p)))
        places, speeds = [[0.0] * 5 for _ in range(n)], [[0.0] * 3 for _ in range(n)]
        rows = [[0.0] * 6 for _ in range(n - 1)]
        reduced_train_rows_of(state, train.train_constants(p), places, speeds, rows)
        out.train = tuple(tuple(row) for row in rows)
        return out

    def scale_trailer_mass(self, factor: float, trailer: int = 1) -> None:
        p = self.params
        if trailer == 1:
            self._set_params(p.replace(Mr=p.Mr * factor, Ird=p.Ird * factor))
            return
        train = list(p.train)
        t = train[trailer - 2]
        train[trailer - 2] = dataclasses.replace(t, Mr=t.Mr * factor, Ird=t.Ird * factor)
        self._set_params(p.replace(train=tuple(train)))

    def set_eta(self, eta: float) -> None:
        self._set_params(self.params.replace(eta=eta))

    def set_etas(self, etas) -> None:
        self._set_params(self.params.with_etas(etas))

    def _set_params(self, params: Params) -> None:
        self.params = params
        self.ode.params = params


def reduced_train_rows_of(state, c, places, speeds, out) -> None:
    """Trailers 2..N of the reduced train's state ``(x, y, theta, phi_1..phi_N, theta_l,
    theta_r, v, omega)`` into ``out[k - 2]`` (:data:`~tt_mujoco.sim.parts.measure.TRAIN_FIELDS`),
    with the train's constants ``c`` and scratch rows ``places`` (N x 5) and ``speeds``
    (N x 3): exact, without slip (the compiled episode shares it)."""
    n = len(c.trailers)
    phis = state[3 : 3 + n]
    train.poses_of(state[0], state[1], state[2], phis, c, places)
    train.trailer_rates_of(phis, state[5 + n], state[6 + n], c, speeds)
    for k in range(1, n):
        row, place = out[k - 1], places[k]
        row[ROW_X0], row[ROW_Y0], row[ROW_THETA0] = place[2], place[3], place[4]
        row[ROW_PHI], row[ROW_BETA] = phis[k], c.trailers[k][2] * phis[k]
        row[ROW_V0] = speeds[k][1]


def reduced_measure_values(state, c: reduced.ModelConstants) -> tuple:
    """The :class:`~tt_mujoco.sim.parts.measure.Measurement` fields of the reduced plant's state
    ``(x, y, theta, phi, theta_l, theta_r, v, omega)`` with the plant's constants ``c``: exact,
    without slip (the compiled episode, :mod:`tt_mujoco.sim.loop.compiled`, shares it)."""
    eta, L, L0, r, d = c.eta, c.L, c.L0, c.r, c.d
    x, y, theta, phi = state[0], state[1], state[2], state[3]
    th_l, th_r, v, omega = state[4], state[5], state[6], state[7]
    theta0 = theta - phi
    _, _, x0, y0 = reduced.hitch_and_axle(x, y, theta, theta0, L, L0)
    return (
        x,
        y,
        theta,
        phi,
        eta * phi,
        v,
        omega,
        x0,
        y0,
        theta0,
        reduced.trailer_speed_of(phi, v, omega, eta, L),
        th_l,
        th_r,
        (v - 0.5 * d * omega) / r,
        (v + 0.5 * d * omega) / r,
        0.0,
        0.0,
        0.0,
        0.0,
    )

"""The nominal model as the controllers see it: ``model(phi, v, omega) -> (f1, f2, g11, g12,
g21, g22)`` of plain floats, with ``V_dot = f + g tau`` (docs/model.md Section 4; the paper's eq.
22), and the velocity tracking every built-in law shares."""

from __future__ import annotations

import math
from collections.abc import Callable

__all__ = ["ModelFn", "reduced_model", "track_velocities"]

#: The nominal model as the controllers see it: ``(phi, v, omega) -> (f1, f2, g11, g12, g21, g22)``.
ModelFn = Callable[[float, float, float], tuple[float, float, float, float, float, float]]

_INF = math.inf


def reduced_model(params, axle_slew_rate: float = _INF) -> ModelFn:
    """Wrap :func:`~tt_mujoco.vehicle.reduced.dynamics` as the controllers' plain-float model.

    Parameters
    ----------
    params : tt_mujoco.vehicle.params.Params
        The controller's *nominal* parameters (they may differ from the plant's).
    axle_slew_rate : float
        How fast the trailers' axles turn at most (rad/s), when actuators steer them (the path
        schedule): the model then takes, at each call, the gains the axles can follow at the
        hitch rates of ``(phi, v, omega)``
        (:func:`~tt_mujoco.vehicle.steering.followed_gain_of`), not ``params.etas`` whole.
        Infinite (default): a linkage, ``params.etas`` as they are.

    Returns
    -------
    callable
        ``model(phi, v, omega) -> (f1, f2, g11, g12, g21, g22)`` with ``V_dot = f + g tau`` and
        ``tau = (T_r, T_l)`` (docs/model.md Section 4). Raises
        :class:`tt_mujoco.vehicle.reduced.SingularityError` at a jackknife, like ``dynamics``.
        It carries ``params`` and ``axle_slew_rate``, from which
        :meth:`VelocityController.steering_changed` rebuilds it with a scheduler's gains.
    """
    # Imported here so that importing ``controllers`` stays free of tt_mujoco and numpy.
    from tt_mujoco.vehicle import train
    from tt_mujoco.vehicle.reduced import dynamics_scalar
    from tt_mujoco.vehicle.steering import followed_gains_of, trailer_followed_gain_of

    bounded = axle_slew_rate < _INF
    if getattr(params, "n_trailers", 1) > 1:
        # A train's model takes every hitch angle: ``phi`` is then the tuple phi_1..phi_N
        # (``Measurement.phis``), and the built-in laws pass it whole.
        def train_model(phi, v: float, omega: float):
            p = params
            if bounded:
                rates = train.trailer_rates(phi, v, omega, params)
                followed = list(params.etas)
                followed_gains_of(params.etas, rates, axle_slew_rate, followed)
                etas = tuple(followed)
                p = params if etas == params.etas else params.with_etas(etas)
            return train.dynamics_scalar(phi, v, omega, p)

        model = train_model
    else:

        def model(phi: float, v: float, omega: float):
            p = params
            if bounded:
                eta = trailer_followed_gain_of(
                    phi, v, omega, params.eta, params.L, params.L0, axle_slew_rate
                )
                p = params if eta == params.eta else params.with_etas((eta,))
            return dynamics_scalar(phi, v, omega, p)

    model.builtin = True  # the compiled episode may run its closed form instead
    model.params = params
    model.axle_slew_rate = axle_slew_rate
    return model


def track_velocities(model: ModelFn, m, v_c, v_c_dot, omega_c, k_v, k_omega):
    """Wheel torques that make ``(v, omega)`` track ``(v_c, omega_c)`` through the nominal model
    ``V_dot = f + g tau``: ``tau = g^-1 (a - f)`` with ``a = (v_c_dot + k_v e_v, k_omega e_omega)``
    (the inner loop of the path trackers; ``m`` the measurement)."""
    phi = m.phis if getattr(m, "train", ()) else m.phi  # a train's model takes every hitch
    f1, f2, g11, g12, g21, g22 = model(phi, m.v, m.omega)
    a_v = v_c_dot + k_v * (v_c - m.v) - f1
    a_w = k_omega * (omega_c - m.omega) - f2
    det = g11 * g22 - g12 * g21
    return (g22 * a_v - g12 * a_w) / det, (g11 * a_w - g21 * a_v) / det

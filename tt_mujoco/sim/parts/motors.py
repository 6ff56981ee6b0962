"""Actuators between the controller's torque command and the wheels (docs/model.md Section 17).

``"ideal"`` (the default, the paper's): the wheel gets the commanded torque at once.
``"dc_motor"``: each drive wheel has a DC motor behind a gearbox and a current-controlled
driver. The driver asks for the current ``i = T_cmd / (gear K_t)``, which it can give only
within the current limit and what the supply voltage leaves beside the back-EMF,

    i_max(omega_m) = min(i_limit, (V_max -+ K_t omega_m) / R),   omega_m = gear omega_wheel

(minus when the torque drives the wheel the way it turns, plus when it brakes it; K_e = K_t in
SI units), and the current, with it the torque, follows with the driver's first-order lag
``motor_lag``:

    T_dot = (clip(T_cmd, -T_max_back, T_max_forward) - T) / motor_lag.

Each control step advances that lag exactly over the step. The constants are fields of
:class:`~tt_mujoco.vehicle.params.Params` (``motor_kt``, ``motor_resistance``,
``motor_voltage``, ``motor_current_limit``, ``motor_gear``, ``motor_lag``).
"""

from __future__ import annotations

import math
from typing import NamedTuple

__all__ = ["ACTUATORS", "DcMotors", "MotorConstants", "available_torque", "deliver_of"]

#: The actuator models of ``Scenario.actuator`` / ``--actuator``.
ACTUATORS = ("ideal", "dc_motor")


def available_torque(omega_wheel: float, p) -> tuple[float, float]:
    """``(forward, backward)``: the largest wheel torque (N m, >= 0) the motor gives along and
    against the positive spin direction at wheel speed ``omega_wheel`` (rad/s)."""
    omega_m = p.motor_gear * omega_wheel
    per_amp = p.motor_gear * p.motor_kt  # wheel torque per ampere
    emf = p.motor_kt * omega_m
    forward = min(p.motor_current_limit, (p.motor_voltage - emf) / p.motor_resistance)
    backward = min(p.motor_current_limit, (p.motor_voltage + emf) / p.motor_resistance)
    return per_amp * max(0.0, forward), per_amp * max(0.0, backward)


class MotorConstants(NamedTuple):
    """The motors' constants as plain numbers, named as the fields of
    :class:`~tt_mujoco.vehicle.params.Params` (so :func:`available_torque` reads either), and
    ``keep``, the lag's factor over one control step."""

    motor_gear: float
    motor_kt: float
    motor_voltage: float
    motor_resistance: float
    motor_current_limit: float
    keep: float


def deliver_of(motor, torques, commands, omegas) -> tuple[float, float]:
    """One control step of both motors (right, left): the ``commands`` (N m) at wheel speeds
    ``omegas`` (rad/s); ``torques`` (the torques delivered now) advanced in place and returned
    (the compiled episode shares it)."""
    for i in range(2):
        forward, backward = available_torque(omegas[i], motor)
        wanted = max(-backward, min(forward, commands[i]))
        torques[i] = wanted + motor.keep * (torques[i] - wanted)
    return torques[0], torques[1]


class DcMotors:
    """The two drive motors' state: the torques they deliver now (module docstring).

    Parameters
    ----------
    params : Params
        The plant's parameters (its ``motor_*`` fields).
    dt : float
        The control period (s): the torque command is held over it.
    """

    def __init__(self, params, dt: float):
        self.params = params
        self.constants = MotorConstants(
            *(float(getattr(params, name)) for name in MotorConstants._fields[:-1]),
            keep=math.exp(-dt / params.motor_lag),  # the lag's exact step over dt
        )
        self.torques = [0.0, 0.0]

    def deliver(self, T_r: float, T_l: float, omega_r: float, omega_l: float) -> tuple:
        """Advance one control step with the commands ``T_r, T_l`` (N m) at wheel speeds
        ``omega_r, omega_l`` (rad/s); returns the torques the wheels get over the step."""
        return deliver_of(self.constants, self.torques, (T_r, T_l), (omega_r, omega_l))

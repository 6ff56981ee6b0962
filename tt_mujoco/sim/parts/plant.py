"""The plant protocol: what the stepper needs of a simulated vehicle.

Two plants implement it: :class:`tt_mujoco.sim.parts.plant_mujoco.MujocoPlant` (contact physics) and
:class:`tt_mujoco.sim.parts.plant_reduced.ReducedPlant` (the reduced ODE of docs/model.md Section
4).
Nothing outside a plant reaches into its members: options a plant cannot honour are refused by
:meth:`Plant.check_supported` before any work.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import ClassVar

from tt_mujoco.guard import control_signal

__all__ = ["Plant", "StopRun"]


@control_signal  # the project's own stop: it passes through the guard of user code as it is
class StopRun(Exception):  # noqa: N818 - a control-flow signal, not an error
    """The run must stop: ``status`` is "jackknife", "diverged" or "failed" (the user's code
    failed), ``message`` says when and why, ``details`` (optional) is the user code's
    traceback."""

    def __init__(self, status: str, message: str, details: str | None = None):
        super().__init__(message)
        self.status = status
        self.message = message
        self.details = details


class Plant(ABC):
    """A vehicle the stepper drives: measure, apply inputs, advance.

    Class attributes say which scenario options it supports; :meth:`check_supported` refuses the
    others with a message naming the option.
    """

    #: Disturbance injection modes the plant can carry out.
    DISTURBANCE_MODES: ClassVar[tuple[str, ...]] = ("matched", "none")

    @classmethod
    def check_supported(cls, disturbance_mode: str) -> None:
        """Raise ValueError if this plant cannot carry out ``disturbance_mode``."""
        if disturbance_mode not in cls.DISTURBANCE_MODES:
            raise ValueError(
                f"disturbance mode {disturbance_mode!r} is not supported by plant {cls.name!r}: "
                f"use one of {cls.DISTURBANCE_MODES} (a wrench on the chassis needs tyres to "
                "pass it, which only the MuJoCo plant has)"
            )

    name: ClassVar[str] = "plant"

    @abstractmethod
    def measure(self):
        """The vehicle's state now, a :class:`tt_mujoco.sim.parts.measure.Measurement`."""

    @abstractmethod
    def scale_trailer_mass(self, factor: float, trailer: int = 1) -> None:
        """Payload step: trailer ``trailer``'s body mass and yaw inertia times ``factor``."""

    @abstractmethod
    def set_eta(self, eta: float) -> None:
        """Change the passive steering gain beta = eta phi from the next step on."""

    def steer_by_actuator(self) -> None:
        """From now on each trailer's axle is steered by an actuator that holds
        beta_k = eta_k phi_k, its reaction on the trailer's own body, instead of by a linkage
        whose reaction acts on the hitch (a gain that changes along the path is not a fixed
        linkage ratio: docs/model.md Section 13). A kinematic plant steers the same either way,
        so by default this does nothing."""
        return None

    def set_etas(self, etas) -> None:
        """Change every trailer's gain, eta_1..eta_N (a plant of one trailer needs only
        :meth:`set_eta`)."""
        if len(etas) != 1:
            raise NotImplementedError(f"{type(self).__name__} steers one trailer")
        self.set_eta(etas[0])

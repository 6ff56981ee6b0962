"""Disturbances Delta(t) on the reduced dynamics, and how they enter a plant.

A disturbance is an acceleration in the (v, omega) channels, ``z_dot = f + g tau + Delta(t)``
(docs/model.md Section 8). It is chosen by name from :data:`DISTURBANCES` or by hook
(``module:Name`` / ``file.py:Name``; a :class:`Disturbance` subclass, or any callable
``t -> (a_v, a_omega)``). How it enters is the scenario's ``disturbance`` mode: "matched" wheel
torques ``g_nominal(phi)^-1 Delta`` outside the actuators' saturation (both plants), or a
"wrench" on the chassis (MuJoCo only) that the tyres must transmit.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod

from tt_mujoco.registry import Registry, call_hook

__all__ = [
    "DISTURBANCES",
    "Disturbance",
    "PaperDisturbance",
    "disturbance",
    "make_disturbance",
]


class Disturbance(ABC):
    """An acceleration disturbance Delta(t) = (a_v, a_omega) in m/s^2 and rad/s^2."""

    @abstractmethod
    def __call__(self, t: float) -> tuple[float, float]:
        """Delta at time ``t`` (s)."""


class PaperDisturbance(Disturbance):
    """The paper's multi-frequency disturbance (Section 6.1):
    ``Delta1 = 3.5 + sin(0.3 t) + 0.5 cos(2 t)`` m/s^2, ``Delta2 = 1.5 sin(0.3 t) + 0.5 cos(5 t)``
    rad/s^2 (bounds 5 and 2)."""

    def __call__(self, t: float) -> tuple[float, float]:
        return paper_disturbance_of(t)


def paper_disturbance_of(t: float) -> tuple[float, float]:
    """The paper's Delta(t) (:class:`PaperDisturbance`) as plain floats (the compiled episode,
    :mod:`tt_mujoco.sim.compiled`, shares it)."""
    return (
        3.5 + math.sin(0.3 * t) + 0.5 * math.cos(2.0 * t),
        1.5 * math.sin(0.3 * t) + 0.5 * math.cos(5.0 * t),
    )


#: Disturbance name -> class (or callable). ``DISTURBANCES.register`` adds one.
DISTURBANCES = Registry("disturbance")
DISTURBANCES.register("paper", PaperDisturbance)

#: The paper's Delta(t) as a function.
disturbance = PaperDisturbance()


def make_disturbance(spec: str):
    """The disturbance callable ``t -> (a_v, a_omega)`` a name or hook stands for."""
    obj = DISTURBANCES.resolve(spec)
    if isinstance(obj, type):
        obj = call_hook(f"disturbance {spec!r}", obj)
    if not callable(obj):
        raise ValueError(f"disturbance {spec!r} is not allowed: {obj!r} is not callable")
    return obj


def wrench_of(mass, a_v: float, a_w: float) -> tuple[float, float]:
    """The generalised force ``Mbar Delta`` for ``Mbar = (M11, M12, M22)``: the force along the
    heading and the yaw moment with the effect of Delta on (v, omega) (the compiled episode
    shares it)."""
    M11, M12, M22 = mass
    return M11 * a_v + M12 * a_w, M12 * a_v + M22 * a_w

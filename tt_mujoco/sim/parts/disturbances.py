"""Disturbances Delta(t) on the reduced dynamics, and how they enter a plant.

A disturbance is an acceleration in the (v, omega) channels, ``z_dot = f + g tau + Delta(t)``
(docs/model.md Section 8). It is chosen by name from :data:`DISTURBANCES` or by hook
(``module:Name`` / ``file.py:Name``; a :class:`Disturbance` subclass, or any callable
``t -> (a_v, a_omega)``). How it enters is the scenario's ``disturbance`` mode: "matched" wheel
torques ``g_nominal(phi)^-1 Delta`` outside the actuators' saturation (both plants), or a
"wrench" on the chassis (MuJoCo only) that the tyres must transmit.

A built-in disturbance (a class of this module, registered in :data:`DISTURBANCES`) declares
its plain-number :attr:`~Disturbance.FORM`, ``form(t, v, omega, params) -> (a_v, a_omega)``
at the tractor's true speed and yaw rate, and its :meth:`~Disturbance.form_params`: the step
computes it itself, on both loops (:func:`builtin_forms`). Adding one is its class, its form
and its registry line, here. A user's disturbance is called back with ``t``.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Callable
from typing import ClassVar

from tt_mujoco.compiled_form import compiled_form
from tt_mujoco.registry import Registry, call_hook
from tt_mujoco.sim.parts.terrain import GRAVITY

__all__ = [
    "DISTURBANCES",
    "DISTURBANCE_FORMS",
    "Disturbance",
    "PaperDisturbance",
    "RollingResistance",
    "builtin_forms",
    "disturbance",
    "disturbance_at",
    "form_of",
    "make_disturbance",
]


class Disturbance(ABC):
    """An acceleration disturbance Delta(t) = (a_v, a_omega) in m/s^2 and rad/s^2."""

    #: A built-in's plain-number form ``form(t, v, omega, params) -> (a_v, a_omega)`` (module
    #: docstring); None: the step calls the object back with ``t``.
    FORM: ClassVar[Callable | None] = None

    @abstractmethod
    def __call__(self, t: float) -> tuple[float, float]:
        """Delta at time ``t`` (s)."""

    def form_params(self) -> tuple[float, ...]:
        """The numbers :attr:`FORM` reads as ``params``."""
        return ()


def paper_form(t, v, omega, params):
    """:class:`PaperDisturbance`'s form: the paper's Delta(t), whatever the motion."""
    return paper_disturbance_of(t)


def rolling_resistance_of(t, v, omega, params):
    """:class:`RollingResistance`'s ``(a_v, a_omega)`` for ``params = (c_rr, v_smooth)``."""
    return -params[0] * GRAVITY * math.tanh(v / params[1]), 0.0


class PaperDisturbance(Disturbance):
    """The paper's multi-frequency disturbance (Section 6.1):
    ``Delta1 = 3.5 + sin(0.3 t) + 0.5 cos(2 t)`` m/s^2, ``Delta2 = 1.5 sin(0.3 t) + 0.5 cos(5 t)``
    rad/s^2 (bounds 5 and 2)."""

    FORM = staticmethod(paper_form)

    def __call__(self, t: float) -> tuple[float, float]:
        return paper_disturbance_of(t)


def paper_disturbance_of(t: float) -> tuple[float, float]:
    """The paper's Delta(t) (:class:`PaperDisturbance`) as plain floats (the compiled episode,
    :mod:`tt_mujoco.sim.loop.compiled`, shares it)."""
    return (
        3.5 + math.sin(0.3 * t) + 0.5 * math.cos(2.0 * t),
        1.5 * math.sin(0.3 * t) + 0.5 * math.cos(5.0 * t),
    )


class RollingResistance(Disturbance):
    """The wheels' rolling resistance: ``a_v = -c_rr g tanh(v / v_smooth)``, ``a_omega = 0``.

    Every wheel of the train (the tractor's and each trailer's) rolls against ``c_rr`` times
    its load, so the train decelerates by ``c_rr g`` whatever its masses; ``tanh`` turns the
    sign of v into a smooth step ``v_smooth`` wide, so that the resistance vanishes at rest
    instead of chattering. Matched (the default mode) it enters at the wheels, where it acts.

    Parameters
    ----------
    c_rr : float
        Rolling-resistance coefficient, in [0, 1) (0.01-0.015: pneumatic tyres on concrete,
        0.05-0.3: on soft ground).
    v_smooth : float
        Width of the sign's smooth step (m/s), > 0.
    """

    def __init__(self, c_rr: float = 0.015, v_smooth: float = 0.05):
        for name, value in (("c_rr", c_rr), ("v_smooth", v_smooth)):
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise ValueError(f"{name}={value!r} is not allowed: it must be a number")
        if not (0.0 <= c_rr < 1.0):
            raise ValueError(f"c_rr={c_rr!r} is not allowed: use a coefficient in [0, 1)")
        if not (math.isfinite(v_smooth) and v_smooth > 0.0):
            raise ValueError(f"v_smooth={v_smooth!r} is not allowed: use a speed > 0")
        self.c_rr, self.v_smooth = float(c_rr), float(v_smooth)

    FORM = staticmethod(rolling_resistance_of)

    def __call__(self, t: float, v: float = 0.0, omega: float = 0.0) -> tuple[float, float]:
        return rolling_resistance_of(t, v, omega, self.form_params())

    def form_params(self) -> tuple[float, ...]:
        return self.c_rr, self.v_smooth


#: Disturbance name -> class (or callable). ``DISTURBANCES.register`` adds one.
DISTURBANCES = Registry("disturbance", called_as=("t",))
DISTURBANCES.register("paper", PaperDisturbance)
DISTURBANCES.register("rolling", RollingResistance)


def _builtin_classes() -> tuple[type[Disturbance], ...]:
    return tuple(
        cls
        for cls in (DISTURBANCES[name] for name in DISTURBANCES)
        if isinstance(cls, type)
        and issubclass(cls, Disturbance)
        and cls.__module__ == __name__
        and cls.__dict__.get("FORM") is not None
    )


def builtin_forms() -> tuple[Callable, ...]:
    """The built-in disturbances' forms in registration order; a form's index is its
    ``kind`` in the step's record."""
    return tuple(cls.__dict__["FORM"].__func__ for cls in _builtin_classes())


def form_of(obj) -> tuple[int, tuple[float, ...]] | None:
    """``(kind, params)`` of a built-in disturbance, which the step computes itself; None for
    any other (a user's, or a subclass, which may compute something else: called back)."""
    classes = _builtin_classes()
    if type(obj) not in classes:
        return None
    return classes.index(type(obj)), tuple(float(p) for p in obj.form_params())


#: The paper's Delta(t) as a function.
disturbance = PaperDisturbance()


def make_disturbance(spec: str):
    """The disturbance callable ``t -> (a_v, a_omega)`` a name or hook stands for."""
    obj = DISTURBANCES.resolve(spec)
    if isinstance(obj, type):
        obj = call_hook(f"disturbance {spec!r}", obj)
    DISTURBANCES.check_call(obj, spec)
    return obj


def wrench_of(mass, a_v: float, a_w: float) -> tuple[float, float]:
    """The generalised force ``Mbar Delta`` for ``Mbar = (M11, M12, M22)``: the force along the
    heading and the yaw moment with the effect of Delta on (v, omega) (the compiled episode
    shares it)."""
    M11, M12, M22 = mass
    return M11 * a_v + M12 * a_w, M12 * a_v + M22 * a_w


#: The built-in disturbances' forms, ``form(t, v, omega, params) -> (a_v, a_w)``, in their
#: registration order (:func:`builtin_forms`); a form's index here is its
#: ``disturbance_kind`` in the loop record.
DISTURBANCE_FORMS = builtin_forms()
#: What the kernel asks of a user's disturbance it calls back (``tt_mujoco.sim.loop._kernel``)
HOOK_DISTURBANCE = 3.0


# --- the disturbance's part of the step (plain numbers and the loop record; the closed loop,
# tt_mujoco.sim.loop.closed_loop, calls it and numba compiles it) ---------------------------------
@compiled_form("the disturbance's Python code called back through a C function (HookCallback)")
def hooked_disturbance_at(loop, t):
    """``(a_v, a_w)`` of a user's disturbance at ``t``, with its checks (the kernel calls it
    back: ``stop.raised`` says when it raised)."""
    return loop.disturbance_hook(t)


@compiled_form(
    "a test of kind for each built-in disturbance, written out (numba cannot index a tuple of "
    "functions)"
)
def run_disturbance(kind: int, t, v, omega, params):
    """The built-in disturbance ``DISTURBANCE_FORMS[kind]`` at ``t`` and the tractor's true
    ``v`` and ``omega``."""
    return DISTURBANCE_FORMS[kind](t, v, omega, params)


def disturbance_at(loop, t, v, omega):
    """``(a_v, a_w)`` of the disturbance at ``t`` and the tractor's true ``v``, ``omega``: a
    built-in's, or a user's (called back with ``t``)."""
    if not loop.hooked_disturbance:
        return run_disturbance(loop.disturbance_kind, t, v, omega, loop.disturbance_params)
    return hooked_disturbance_at(loop, t)

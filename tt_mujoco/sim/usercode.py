"""User code is a boundary: a user's controller or disturbance is called through here.

Before the run, :func:`check_user_code` builds a hooked controller, resets it and asks it once
for torques on the initial state, and calls a hooked disturbance at ``t = 0``: what fails there
is bad input (:class:`tt_mujoco.registry.HookError`, exit code 2), before any output exists.
During the run, :func:`failure` turns what the user's code raised (``SystemExit`` included) into
a :class:`~tt_mujoco.sim.plant.StopRun` with status ``"failed"``, and :func:`checked_torques` /
:func:`checked_disturbance` refuse what it returned if it is not two finite numbers: the run
then stops there, its rows so far kept (exit code 3), the traceback in its ``details``.
"""

from __future__ import annotations

import math
import traceback
from numbers import Real

import numpy as np

from tt_mujoco.registry import HookError, describe_failure, is_hook, shown
from tt_mujoco.sim.plant import StopRun

__all__ = [
    "check_user_code",
    "checked_disturbance",
    "checked_signals",
    "checked_torques",
    "failure",
]


def failure(who: str, t: float, err: BaseException) -> StopRun:
    """The stop for user code that raised ``err`` at time ``t`` (``who``: "controller 'x'")."""
    details = "".join(traceback.format_exception(err))
    return StopRun("failed", f"{who} failed at t={t:.3f} s: {describe_failure(err)}", details)


def _two_numbers(out, who: str, what: str, t: float, names: tuple[str, str]):
    try:
        a, b = out
    except (TypeError, ValueError):
        a = b = None
    if not (isinstance(a, Real) and isinstance(b, Real)):
        raise StopRun(
            "failed",
            f"{who} returned {shown(out)} at t={t:.3f} s: {what} must return two numbers "
            f"({names[0]}, {names[1]})",
        )
    if not (math.isfinite(a) and math.isfinite(b)):
        raise StopRun(
            "failed",
            f"{who} returned {names[0]}={float(a)!r}, {names[1]}={float(b)!r} at t={t:.3f} s: "
            "both must be finite numbers",
        )
    return float(a), float(b)


def checked_torques(out, who: str, t: float) -> tuple[float, float]:
    """``(T_r, T_l)`` from what a controller's ``compute`` returned, or a "failed" stop."""
    return _two_numbers(out, who, "compute", t, ("T_r", "T_l"))


def checked_disturbance(out, who: str, t: float) -> tuple[float, float]:
    """``(a_v, a_omega)`` from what a disturbance returned, or a "failed" stop."""
    return _two_numbers(out, who, "a disturbance", t, ("a_v", "a_omega"))


def checked_signals(signals: dict, who: str, t: float) -> dict[str, float]:
    """What a controller logged this step (:meth:`~tt_mujoco.controllers.Controller.log`), as
    floats, or a "failed" stop naming the bad name or value."""
    out = {}
    for name, value in signals.items():
        if not (isinstance(name, str) and name.isidentifier() and name[:1].isalpha()):
            raise StopRun(
                "failed",
                f"{who} logged a signal named {shown(name)} at t={t:.3f} s: a name is letters, "
                "digits and _, starting with a letter",
            )
        if not isinstance(value, Real):
            raise StopRun(
                "failed",
                f"{who} logged {name}={shown(value)} at t={t:.3f} s: a logged signal is a number",
            )
        out[name] = float(value)
    return out


def controller_label(built) -> str:
    return f"controller {built.scenario.controller!r}"


def disturbance_label(built) -> str:
    return f"disturbance {built.scenario.disturbance_model!r}"


def check_user_code(built) -> None:
    """Build, reset and call once the scenario's hooked controller, and call its hooked
    disturbance at t = 0, on throwaway copies of the run's state.

    Raises
    ------
    HookError
        What failed, with the hook, the file and line, and what was wrong.
    """
    from tt_mujoco.sim.stepper import Stepper

    s = built.scenario
    if is_hook(s.controller):
        who = controller_label(built)
        try:
            controller = built.new_controller()
            controller.reset()
            _ = controller.gains, controller.name  # what the run's record reads at its end
        except (Exception, SystemExit) as err:
            hint = ""
            if isinstance(err, AttributeError):
                hint = " (does its __init__ call super().__init__(setup, gains)?)"
            raise HookError(f"{who} cannot be built: {describe_failure(err)}{hint}") from None
        probe = Stepper(built)
        probe.reset(np.random.default_rng(0))
        try:
            me, ref = probe.sense()
            out = controller.compute(ref.t, me, ref)
        except StopRun:
            pass  # the initial state itself stops the run: the run will say so
        except (Exception, SystemExit) as err:
            raise HookError(f"{who} fails on the initial state: {describe_failure(err)}") from None
        else:
            try:
                checked_torques(out, who, 0.0)
                checked_signals(controller.take_signals(), who, 0.0)
            except StopRun as stop:
                raise HookError(stop.message) from None
    if built.disturbance is not None and is_hook(s.disturbance_model):
        who = disturbance_label(built)
        try:
            checked_disturbance(built.disturbance(0.0), who, 0.0)
        except StopRun as stop:
            raise HookError(stop.message) from None
        except (Exception, SystemExit) as err:
            raise HookError(f"{who} fails at t=0: {describe_failure(err)}") from None

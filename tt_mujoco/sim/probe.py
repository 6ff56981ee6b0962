"""Before the run: a user's controller and disturbance are tried once on throwaway copies
(a controller of its own, a copy of the disturbance: a stateful one is called by the run as if
the check had not been).

What fails here is bad input (:class:`tt_mujoco.registry.HookError`, exit code 2), before any
output exists; the same checks during the run are :mod:`tt_mujoco.sim.usercode`'s.
"""

from __future__ import annotations

import numpy as np

from tt_mujoco.guard import users_failure
from tt_mujoco.registry import HookError, describe_failure, is_hook
from tt_mujoco.sim.loop.stepper import Stepper
from tt_mujoco.sim.parts.plant import StopRun
from tt_mujoco.sim.usercode import (
    checked_disturbance,
    checked_signals,
    checked_torques,
    controller_label,
    disturbance_label,
    users_copy,
)

__all__ = ["check_user_code"]


def check_user_code(built) -> None:
    """Build, reset and call once the scenario's hooked controller, and call its hooked
    disturbance at t = 0, on throwaway copies of the run's state.

    Raises
    ------
    HookError
        What failed, with the hook, the file and line, and what was wrong.
    """
    s = built.scenario
    if is_hook(s.controller):
        who = controller_label(built)
        controller = built.new_controller()  # its construction guarded there (HookError)
        try:
            controller.reset()
            _ = controller.gains, controller.name  # what the run's record reads at its end
        except BaseException as err:
            if not users_failure(err):
                raise
            hint = ""
            if isinstance(err, AttributeError):
                hint = " (does its __init__ call super().__init__(setup, gains)?)"
            raise HookError(f"{who} cannot be built: {describe_failure(err)}{hint}") from None
        probe = Stepper(built, steps=1)  # the first step's state: not the episode's tables
        probe.reset(np.random.default_rng(0))
        try:
            me, ref = probe.sense()
            out = controller.compute(ref.t, me, ref)
        except StopRun:
            pass  # the initial state itself stops the run: the run will say so
        except BaseException as err:
            if not users_failure(err):
                raise
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
            checked_disturbance(users_copy(built.disturbance)(0.0), who, 0.0)
        except StopRun as stop:
            raise HookError(stop.message) from None
        except BaseException as err:
            if not users_failure(err):
                raise
            raise HookError(f"{who} fails at t=0: {describe_failure(err)}") from None

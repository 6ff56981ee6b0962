"""User code is a boundary: what a user's controller or disturbance does is checked here.

During the run, :func:`failure` turns what the user's code raised (``SystemExit`` included) into
a :class:`~tt_mujoco.sim.parts.plant.StopRun` with status ``"failed"``, and :func:`checked_torques`,
:func:`checked_disturbance` and :func:`checked_signals` refuse what it returned or logged if it
is not numbers (two finite ones for torques): the run then stops there, its rows so far kept
(exit code 3), the traceback in its ``details``. Before the run,
:func:`tt_mujoco.sim.probe.check_user_code` makes the same checks on the initial state, where a
failure is bad input (exit code 2).
"""

from __future__ import annotations

import copy
import dataclasses
import math
import traceback

from tt_mujoco.guard import users_failure
from tt_mujoco.registry import describe_failure, finite_number, real_number, shown
from tt_mujoco.sim.parts.plant import StopRun

__all__ = [
    "MAX_SIGNALS",
    "CheckedPath",
    "checked_disturbance",
    "checked_signals",
    "checked_torques",
    "failure",
    "users_copy",
    "users_setup",
]


def users_copy(obj):
    """A deep copy of what the run keeps using (its path) for a user's code to be given: what
    that code changes in it changes nothing of the run. An object that cannot be copied (a
    user's path holding a lock, say) is given as it is."""
    try:
        return copy.deepcopy(obj)
    except BaseException as err:
        if not users_failure(err):
            raise
        return obj


def users_setup(setup):
    """A user's controller's :class:`~tt_mujoco.controllers.ControllerSetup`: its own copies of
    the nominal parameters (and the model made from them) and of the path, so that a
    controller that writes into them (``object.__setattr__`` on frozen parameters included)
    changes nothing the run checks or steps with."""
    from tt_mujoco.controllers import reduced_model

    params = users_copy(setup.params)
    slew = getattr(setup.model, "axle_slew_rate", math.inf)
    return dataclasses.replace(
        setup,
        params=params,
        model=reduced_model(params, slew) if params is not setup.params else setup.model,
        path=users_copy(setup.path),
    )


def failure(who: str, t: float, err: BaseException) -> StopRun:
    """The stop for user code that raised ``err`` at time ``t`` (``who``: "controller 'x'")."""
    details = "".join(traceback.format_exception(err))
    return StopRun("failed", f"{who} failed at t={t:.3f} s: {describe_failure(err)}", details)


def _finite_floats(out, n: int):
    """``out`` itself when it is a tuple of ``n`` finite Python floats: what a hook returns
    at nearly every step, checked without the general path's calls; else None."""
    if type(out) is not tuple or len(out) != n:
        return None
    for v in out:
        if type(v) is not float or v - v != 0.0:  # NaN and the infinities give NaN
            return None
    return out


def _two_numbers(out, who: str, what: str, t: float, names: tuple[str, str]):
    fast = _finite_floats(out, 2)
    if fast is not None:
        return fast
    pair = _sequence_of(out, 2)
    if pair is None or not all(real_number(v) for v in pair):
        raise StopRun(
            "failed",
            f"{who} returned {shown(out)} at t={t:.3f} s: {what} must return two numbers "
            f"({names[0]}, {names[1]})",
        )
    numbers = [finite_number(v) for v in pair]
    if None in numbers:
        said = ", ".join(f"{name}={_said(v)}" for name, v in zip(names, pair, strict=True))
        raise StopRun(
            "failed", f"{who} returned {said} at t={t:.3f} s: both must be finite numbers"
        )
    return numbers[0], numbers[1]


def _said(value) -> str:
    """A real number for a message: as a float where it is one, else cut short."""
    try:
        return repr(float(value))
    except OverflowError:
        return shown(value, 40)


def _sequence_of(out, n: int):
    """``out`` as a tuple if it is a sequence (a tuple, list or array) of ``n`` items, else
    None: a generator or a string is not what a hook returns."""
    if (
        isinstance(out, str | bytes)
        or not hasattr(out, "__len__")
        or not hasattr(out, "__getitem__")
    ):
        return None
    try:
        return tuple(out) if len(out) == n else None
    except BaseException as err:
        if not users_failure(err):
            raise
        return None


def checked_torques(out, who: str, t: float) -> tuple[float, float]:
    """``(T_r, T_l)`` from what a controller's ``compute`` returned, or a "failed" stop."""
    return _two_numbers(out, who, "compute", t, ("T_r", "T_l"))


def checked_disturbance(out, who: str, t: float) -> tuple[float, float]:
    """``(a_v, a_omega)`` from what a disturbance returned, or a "failed" stop."""
    return _two_numbers(out, who, "a disturbance", t, ("a_v", "a_omega"))


#: The most signals a controller logs in a run: each is a column of the time series as long
#: as the run, so a name made afresh at every step would fill the memory.
MAX_SIGNALS = 100


def checked_signals(signals: dict, who: str, t: float, logged=()) -> dict[str, float]:
    """What a controller logged this step (:meth:`~tt_mujoco.controllers.Controller.log`), as
    floats, or a "failed" stop naming the bad name or value, or the name beyond
    :data:`MAX_SIGNALS` (``logged``: the names logged before this step)."""
    fresh = [name for name in signals if name not in logged]
    if fresh and len(logged) + len(fresh) > MAX_SIGNALS:
        raise StopRun(
            "failed",
            f"{who} logged a signal named {shown(fresh[-1])} at t={t:.3f} s, beyond the "
            f"{MAX_SIGNALS} names a run may log (each is a column of the time series)",
        )
    out = {}
    for name, value in signals.items():
        if not (isinstance(name, str) and name.isidentifier() and name[:1].isalpha()):
            raise StopRun(
                "failed",
                f"{who} logged a signal named {shown(name)} at t={t:.3f} s: a name is letters, "
                "digits and _, starting with a letter",
            )
        try:
            number = float(value) if real_number(value) else None
        except OverflowError:
            number = None
        if number is None:
            raise StopRun(
                "failed",
                f"{who} logged {name}={shown(value)} at t={t:.3f} s: a logged signal is a number",
            )
        out[name] = number
    return out


class CheckedPath:
    """A user's path as the step asks it (``curvature_and_rate``, ``pose_at``), on both loops:
    what it raises that is its failure (:func:`tt_mujoco.guard.users_failure`), or an answer
    that is not finite numbers, stops the run as "failed" at that arc length, its rows kept."""

    def __init__(self, path, who: str):
        self.path, self.who = path, who

    def _asked(self, method: str, s: float, names: tuple[str, ...]):
        try:
            out = getattr(self.path, method)(s)
        except BaseException as err:
            if not users_failure(err):
                raise
            details = "".join(traceback.format_exception(err))
            message = f"{self.who} failed at s={s:.3f} m: {describe_failure(err)}"
            raise StopRun("failed", message, details) from None
        fast = _finite_floats(out, len(names))
        if fast is not None:
            return fast
        items = _sequence_of(out, len(names))
        values = None if items is None else tuple(finite_number(v) for v in items)
        if values is None or None in values:
            raise StopRun(
                "failed",
                f"{self.who} returned {shown(out)} from {method}({s:.6g}): it must return "
                f"{len(names)} finite numbers ({', '.join(names)})",
            )
        return values

    def curvature_and_rate(self, s: float) -> tuple[float, float]:
        return self._asked("curvature_and_rate", s, ("kappa", "dkappa/ds"))

    def pose_at(self, s: float) -> tuple[float, float, float]:
        return self._asked("pose_at", s, ("x", "y", "heading"))


class CheckedProgress:
    """A caller's ``progress(steps_done, steps_total)`` as the run calls it: what it raises
    that is its failure (:func:`tt_mujoco.guard.users_failure`) stops the run as "failed" at
    that step, its rows kept, as any user code's does.

    Raises
    ------
    TypeError
        ``progress`` is not callable (before anything is simulated).
    """

    def __init__(self, progress, dt: float):
        if not callable(progress):
            raise TypeError(
                f"progress={shown(progress)} is not allowed: give None or a function "
                "progress(steps_done, steps_total)"
            )
        self.progress, self.dt = progress, dt

    def __call__(self, done: int, total: int) -> None:
        try:
            self.progress(done, total)
        except BaseException as err:
            if not users_failure(err):
                raise
            raise failure("progress", done * self.dt, err) from None


def path_label(built) -> str:
    return f"path {built.scenario.traj!r}"


def controller_label(built) -> str:
    return f"controller {built.scenario.controller!r}"


def disturbance_label(built) -> str:
    return f"disturbance {built.scenario.disturbance_model!r}"

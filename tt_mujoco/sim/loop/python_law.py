"""A controller's Python ``compute`` as the step's law, and what it is given.

CPython's step calls a :class:`PythonLaw` between its halves, the kernel's calls it back
(:class:`tt_mujoco.sim.loop._kernel.PythonLawCallback`); either way it reads the measurement
and the reference as the law record holds them (:func:`seen_measurement`,
:func:`reference_of`), calls the controller with the checks of user code, and answers
``(status, T_r, T_l, u1, u2)`` or raises :class:`~tt_mujoco.sim.parts.plant.StopRun`
(:func:`law_failure`).
"""

from __future__ import annotations

import numpy as np

from tt_mujoco.controllers import Reference
from tt_mujoco.guard import users_failure
from tt_mujoco.sim import usercode
from tt_mujoco.sim.loop import closed_loop
from tt_mujoco.sim.parts.measure import Measurement, TrainMeasurement
from tt_mujoco.sim.parts.plant import StopRun

__all__ = [
    "GIVEN_REFERENCE_FIELDS",
    "PythonLaw",
    "law_failure",
    "reference_of",
    "seen_measurement",
]


def seen_measurement(law) -> Measurement:
    """The measurement as a Python law sees it at this step (``law.measurement_values``,
    ``law.measurement_rows``: noise, faults and the delay included), in floats from either
    kind of record (CPython's lists, or the kernel's arrays)."""
    values, rows = law.measurement_values, law.measurement_rows
    if isinstance(values, np.ndarray):
        values, rows = values.tolist(), rows.tolist()
    if not len(rows):
        return Measurement._make(values)
    out = TrainMeasurement._make(values)
    out.train = tuple(tuple(row) for row in rows)
    return out


def reference_of(law, path) -> Reference:
    """The target at this step as a Python law sees it (``law.reference``) on ``path``, in
    floats from either kind of record."""
    r = law.reference[0]
    if isinstance(r, np.void):  # the kernel's record, as floats: its leading fields
        return Reference(*r.tolist()[: len(GIVEN_REFERENCE_FIELDS)], path)
    return Reference(r.t, r.s, r.kappa, r.v_d, r.omega_d, r.v_d_dot, r.omega_d_dot, path)


#: What a Python law is given of the reference record: its leading fields, in
#: :class:`Reference`'s order (``tests/test_compiled.py`` checks both orders).
GIVEN_REFERENCE_FIELDS = ("t", "s", "kappa", "v_d", "omega_d", "v_d_dot", "omega_d_dot")


def law_failure(who: str, t: float, err: BaseException) -> StopRun:
    """What a law's failure at ``t`` stops the run with."""
    if isinstance(err, FloatingPointError):  # a built-in law's own failure
        return StopRun("diverged", f"controller failed at t={t:.3f} s: {err}")
    return usercode.failure(who, t, err)


class PythonLaw:
    """A controller's Python ``compute`` as the step's law (:data:`~tt_mujoco.sim.loop.closed_loop.
    PYTHON`), with the checks of user code: called with the law record by CPython's step, or
    back from the kernel's (:class:`tt_mujoco.sim.loop._kernel.PythonLawCallback`), it returns
    ``(status, T_r, T_l, u1, u2)`` or raises :class:`~tt_mujoco.sim.parts.plant.StopRun`.
    """

    def __init__(self, stepper, controller):
        self.stepper, self.controller = stepper, controller
        self.who = usercode.controller_label(stepper.built)
        # the episode's copy of the path (Stepper.given_path): what it changes stays with it
        self.path, self.dt = stepper.given_path, stepper.dt
        self.steering = None  # the plant record's (Stepper.begin)
        self.told = -1  # the schedule's updates the controller has been told of
        self.steering_changed = getattr(controller, "steering_changed", None)

    def __call__(self, law):
        controller, who, steering = self.controller, self.who, self.steering
        seen, ref = seen_measurement(law), reference_of(law, self.path)
        t = ref.t
        try:
            if self.steering_changed is not None and steering.kind:
                if steering.updates[0] != self.told:
                    self.told = int(steering.updates[0])
                    self.steering_changed(tuple(map(float, steering.etas)))
            out = controller.compute(t, seen, ref)
        except BaseException as err:
            if not users_failure(err):
                raise
            raise law_failure(who, t, err) from None
        T_r, T_l = usercode.checked_torques(out, who, t)
        signals = controller.take_signals()
        if signals:
            k = round(t / self.dt)
            logged = self.stepper.signal_names
            self.stepper.record_signals(usercode.checked_signals(signals, who, t, logged), k)
        command = controller.command
        u1, u2 = (T_r, T_l) if command is None else command
        return closed_loop.LAW_OK, T_r, T_l, u1, u2

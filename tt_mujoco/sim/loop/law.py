"""The law's part of the step: its record, its step, and what it gives back to the controller.

Three kinds of law run between the step's halves (the record's ``kind``):

- a **built-in law** (:data:`LAW_CLASSES`: ISMC-STA, PID, FBL, SMC) is a plain-number function
  of its module, ``LAW(dt, tracking, model, state, gains, saturation) -> LawStep``, whose gains
  and memory its class declares by name (``GAINS`` and ``STATE``, each a ``NamedTuple`` of
  floats). The record keeps their values in that order; :func:`run_law` names them again for
  the law, so the law reads ``gains.lambda_v``, never a position;
- a **user's plain-number law** (:data:`USER`), compiled apart (:mod:`tt_mujoco.sim.loop.compiled`)
  and called through its C entry with the record's arrays, which it reads as named records;
- a **law Python computes** (:data:`PYTHON`): a controller's ``compute``, or an agent's
  torques, called back (:func:`python_law`).

:func:`law_record` makes the record from the controller at the start of an episode, and
:func:`hand_law_back` gives the law's memory back to it at the end. Like
:mod:`tt_mujoco.sim.loop.closed_loop`, this is one source that CPython runs and the kernel compiles;
:func:`run_law`, :func:`pointer` and :func:`python_law` are given compiled forms there.
"""

from __future__ import annotations

import ctypes
import math

import numpy as np

from tt_mujoco.compiled_form import compiled_form
from tt_mujoco.controllers import base, compiled_laws
from tt_mujoco.sim.loop import records, step
from tt_mujoco.vehicle import reduced, train
from tt_mujoco.vehicle import steering as steering_math

__all__ = [
    "ETA_COLUMN",
    "LAWS",
    "LAW_CLASSES",
    "NOMINAL_SINGULAR",
    "PYTHON",
    "USER",
    "follow_train",
    "hand_law_back",
    "law_record",
    "law_step",
    "model_steered",
    "nominal_mass",
    "nominal_model_step",
    "pointer",
    "python_law",
    "run_law",
    "run_law_written_out",
]

#: The built-in laws' classes, those of :func:`tt_mujoco.controllers.compiled_laws` in their
#: registration order; a law's index here is its ``kind`` in the law record.
LAW_CLASSES = tuple(compiled_laws().values())
#: Their plain-number laws, in the same order.
LAWS = tuple(cls.LAW for cls in LAW_CLASSES)
#: ``law.kind`` of a user's plain-number law, and of a law that Python computes between the
#: halves (a controller class, or a plain-number law when CPython runs the step)
USER = len(LAWS)
PYTHON = USER + 1

LAW_OK, LAW_RAISED, LAW_NOT_FINITE = base.LAW_OK, base.LAW_RAISED, base.LAW_NOT_FINITE
#: ``stop.law_status`` when the nominal model itself is singular at the measured hitch
NOMINAL_SINGULAR = -1.0
#: where a trailer's gain is in a train's row
ETA_COLUMN = train.TRAILER_ROW.index("eta")
#: ``law.torques`` as a plain-number law's C entry leaves it: its two torques, and whether the
#: law raised (1.0): an exception cannot leave a C function (:mod:`tt_mujoco.sim.loop.compiled`,
#: its entry)
USER_OUT = ("T_r", "T_l", "raised")
USER_T_R, USER_T_L, USER_RAISED = range(len(USER_OUT))
#: ``law.torques`` as a Python law called back leaves it (``_kernel.PythonLawCallback``)
CALLED_BACK_OUT = ("T_r", "T_l", "u1", "u2", "status")
BACK_T_R, BACK_T_L, BACK_U1, BACK_U2, BACK_STATUS = range(len(CALLED_BACK_OUT))


@compiled_form("a test of kind for each built-in law, written out (run_law_written_out)")
def run_law(kind: int, dt, tracking, model, state, gains, saturation):
    """One step of the built-in law of index ``kind`` in :data:`LAW_CLASSES`, its gains and
    memory (the record's ``gains`` and ``state`` arrays) named as its class declares them; its
    new memory written back into ``state``. ``(status, T_r, T_l, u1, u2, saturated, aux1,
    aux2)``: the law's :class:`~tt_mujoco.controllers.base.LawStep` without its state."""
    cls = LAW_CLASSES[kind]
    out = cls.LAW(dt, tracking, model, cls.STATE(*state), cls.GAINS(*gains), saturation)
    for i, value in enumerate(out.state):
        state[i] = value
    return out[:-1]


def run_law_written_out():
    """:func:`run_law` as the kernel compiles it: a test of ``kind`` for each law, written
    out, each branch naming the record's ``gains`` and ``state`` by its class's ``GAINS`` and
    ``STATE`` element by element (numba can index neither a tuple of functions nor an array
    into a tuple's arguments). CPython runs the same; the kernel takes it as :func:`run_law`'s
    compiled form."""
    lines = ["def run_law(kind, dt, tracking, model, state, gains, saturation):"]
    scope = {}
    for i, cls in enumerate(LAW_CLASSES):
        scope.update({f"LAW_{i}": cls.LAW, f"GAINS_{i}": cls.GAINS, f"STATE_{i}": cls.STATE})
        gains = ", ".join(f"gains[{j}]" for j in range(len(cls.GAINS._fields)))
        state = ", ".join(f"state[{j}]" for j in range(len(cls.STATE._fields)))
        branch = [
            f"out = LAW_{i}(dt, tracking, model, STATE_{i}({state}), GAINS_{i}({gains}), "
            "saturation)",
            *(f"state[{j}] = out.state[{j}]" for j in range(len(cls.STATE._fields))),
            "return out[0], out[1], out[2], out[3], out[4], out[5], out[6], out[7]",
        ]
        last = i == len(LAW_CLASSES) - 1
        if not last:
            lines.append(f"    if kind == {i}:")
        lines += [("    " if last else "        ") + line for line in branch]
    exec("\n".join(lines), scope)
    return scope["run_law"]


@compiled_form("the array's data address as a C double pointer (an intrinsic)")
def pointer(array):
    """The address of a contiguous float array's data, as a C double pointer. A record as
    CPython reads it (:func:`tt_mujoco.sim.loop.records.interpreted`) is passed as a copy of its
    fields: the law it goes to only reads it."""
    if isinstance(array, list):
        element = array[0]
        array = np.array([getattr(element, name) for name in element.__slots__], dtype=float)
    return array.ctypes.data_as(ctypes.POINTER(ctypes.c_double))


@compiled_form(
    "the controller's Python compute called back through a C function (PythonLawCallback)"
)
def python_law(law):
    """The law Python computes between the halves (:data:`PYTHON`): ``law.user``, called with
    the law record; ``(status, T_r, T_l, u1, u2)``. The kernel calls it back through a C
    function instead, which leaves them in ``law.torques``."""
    return law.user(law)


def law_step(law, v_m, w_m, dt, limit):
    """The law's ``(status, T_r, T_l, u1, u2)`` at the reference and the nominal model in
    ``law``; its state updated in place."""
    if law.kind == PYTHON:
        return python_law(law)
    r, nominal, flags = law.reference[0], law.model[0], law.flags[0]
    if law.kind == USER:
        out = law.torques
        law.user(
            pointer(law.measurement_values), pointer(law.reference), pointer(law.model),
            pointer(law.user_gains), pointer(law.user_state), pointer(out), dt, limit,
        )  # fmt: skip
        if out[USER_RAISED] != 0.0:
            return LAW_RAISED, math.nan, math.nan, math.nan, math.nan
        T_r, T_l = out[USER_T_R], out[USER_T_L]
        if not (math.isfinite(T_r) and math.isfinite(T_l)):
            return LAW_NOT_FINITE, T_r, T_l, T_r, T_l
        return LAW_OK, T_r, T_l, T_r, T_l
    tracking = base.Tracking(v_m, w_m, r.v_d, r.omega_d, r.v_d_dot, r.omega_d_dot)
    model = base.Nominal(nominal.f1, nominal.f2, nominal.g11, nominal.g12, nominal.g21, nominal.g22)
    saturation = base.Saturation(limit, flags.saturated != 0.0, law.anti_windup)
    out = run_law(law.kind, dt, tracking, model, law.state, law.gains, saturation)
    status, T_r, T_l, u1, u2, saturated, aux1, aux2 = out
    flags.aux1, flags.aux2 = aux1, aux2
    if status == LAW_OK:
        flags.saturated = 1.0 if saturated else 0.0
    return status, T_r, T_l, u1, u2


def model_steered(steering_kind: int, follows_steering: bool) -> bool:
    """Whether the law's nominal model takes the scheduled gains: the plant's steering is
    scheduled (``plant.steering.kind``) and the law follows it (a built-in law's model does)."""
    return steering_kind != 0 and follows_steering


def nominal_model_step(law, steering, phis, phi_m, v_m, w_m, n, stop):
    """The law's nominal model at what it sees (``phi_m``, ``v_m``, ``w_m``; ``phis`` the
    hitches of a train) into ``law.model`` and its mass matrix into ``law.reading``: for the
    law and the matched disturbance (a built-in law's model takes the plant's scheduled gains,
    ``steering.etas``, and those its actuated axles can follow; the disturbance keeps the
    nominal's). RUNNING, or LAW_FAILED where the model is singular (``stop`` says where)."""
    nominal, seen_by_law, etas = law.model[0], law.reading[0], steering.etas
    c, model_train = law.nominal, law.nominal_train
    if model_steered(steering.kind, law.follows_steering):
        c, model_train = reduced.with_eta_of(c, etas[0]), law.steered_train
        if law.axle_slew_rate < math.inf:  # reduced_model: the gains the axles can follow
            if n == 1:
                eta = steering_math.trailer_followed_gain_of(
                    phi_m, v_m, w_m, c.eta, c.L, c.L0, law.axle_slew_rate
                )
                c = reduced.with_eta_of(c, eta)
            elif not follow_train(law, etas, phis, phi_m, v_m, w_m):
                stop.law_status = NOMINAL_SINGULAR
                step.first_singular_of(phis, model_train, stop)
                return step.LAW_FAILED
    if n == 1:
        if math.cos(c.eta * phi_m) < reduced.COS_BETA_MIN:
            stop.law_status, stop.phi, stop.eta = NOMINAL_SINGULAR, phi_m, c.eta
            return step.LAW_FAILED
        terms = reduced.inertia_terms_of(phi_m, c)
        mass, bias = reduced.coriolis_of(terms, c.gamma, v_m, w_m)
    else:
        phis[0] = phi_m  # what the law sees
        ok, mass, bias = train.mass_and_bias_of(phis, v_m, w_m, model_train, law.rates)
        if not ok:
            stop.law_status = NOMINAL_SINGULAR
            step.first_singular_of(phis, model_train, stop)
            return step.LAW_FAILED
    nominal.f1, nominal.f2, nominal.g11, nominal.g12, nominal.g21, nominal.g22 = (
        reduced.solve_dynamics_of(mass, bias, c.r, c.d)
    )
    seen_by_law.M11, seen_by_law.M12, seen_by_law.M22 = mass[0], mass[1], mass[2]
    return step.RUNNING


def follow_train(law, etas, phis, phi_m, v_m, w_m) -> bool:
    """The train model's gains set to those its actuated axles can follow at the hitch rates
    the scheduled ``etas`` give (reduced_model's train model); False where those are singular."""
    rows = law.steered_train.trailers
    for k in range(len(etas)):
        rows[k, ETA_COLUMN] = etas[k]
    phis[0] = phi_m  # what the law sees
    if not train.trailer_rates_of(phis, v_m, w_m, law.steered_train, law.rates):
        return False
    steering_math.followed_gains_of(etas, law.rates, law.axle_slew_rate, rows[:, ETA_COLUMN])
    return True


def nominal_mass(law, n, phi, phis, v_m, w_m):
    """The nominal model's mass matrix at the measured hitches (the disturbance's, when the
    law's model takes scheduled gains)."""
    if n == 1:
        c = law.nominal
        return reduced.coriolis_of(reduced.inertia_terms_of(phi, c), c.gamma, v_m, w_m)[0]
    return train.mass_and_bias_of(phis, v_m, w_m, law.nominal_train, law.rates)[1]


def law_record(controller, nominal, user, steering, python) -> records.LawRecord:
    """The law's record for an episode of ``controller``: a built-in law's gains and memory by
    its class's field order, a user's plain-number law's (``user``, its C entry) named
    records, or the law Python computes (``python``, the call back). ``nominal``: the
    controller's nominal parameters; ``steering``: the plant's steering record."""
    from tt_mujoco.controllers.plain import PlainLawController
    from tt_mujoco.sim.parts.measure import TRAIN_FIELDS

    gains, state, flags = np.zeros(0), np.zeros(0), (0.0, 0.0, 0.0)
    user_gains, user_state, anti_windup = np.zeros(1), np.zeros(1), False
    if python is not None:
        kind, user = PYTHON, python
    elif isinstance(controller, PlainLawController):
        kind = USER
        user_gains = _floats_or_one(controller.law_data())
        user_state = _floats_or_one([getattr(controller.law_state, f) for f in controller.STATE])
    else:
        kind = LAWS.index(type(controller).LAW)
        gains = np.array(controller.law_gains, dtype=float)
        state = np.array(controller.law_state, dtype=float)
        flags = (float(controller.saturated), *controller.aux)
        anti_windup = bool(controller.anti_windup)
    return records.LawRecord(
        kind=kind,
        gains=gains,
        state=state,
        flags=records.new_record(
            records.LAW_FLAGS, **dict(zip(records.LAW_FLAGS, flags, strict=True))
        ),
        nominal=reduced.model_constants(nominal),
        nominal_train=records.train_record(nominal),
        phis=np.zeros(nominal.n_trailers),
        rates=np.zeros((nominal.n_trailers, 3)),
        anti_windup=anti_windup,
        user=user,
        user_gains=user_gains,
        user_state=user_state,
        reference=records.new_record(records.REFERENCE_FIELDS),
        model=records.new_record(records.NOMINAL_FIELDS),
        measurement_values=np.zeros(len(records.MEASUREMENT_DTYPE)),
        torques=np.zeros(max(len(USER_OUT), len(CALLED_BACK_OUT))),
        follows_steering=kind < USER,
        steered_train=records.train_record(nominal.with_etas(tuple(steering.etas.tolist()))),
        axle_slew_rate=float(getattr(controller, "axle_slew_rate", math.inf)),
        reading=records.new_record(records.READING_FIELDS),
        measurement_rows=np.zeros((nominal.n_trailers - 1, len(TRAIN_FIELDS))),
    )


def _floats_or_one(values) -> np.ndarray:
    """``values`` as a float array; one unused 0.0 where there are none (an empty array has
    no data address for a C entry)."""
    array = np.array(values, dtype=float)
    return array if array.size else np.zeros(1)


def hand_law_back(controller, law) -> None:
    """Give the law's memory at the end of an episode back to ``controller``: a built-in
    law's state, report and saturation flag, or a user's plain-number law's named state."""
    if law.kind == USER:
        for name, value in zip(controller.STATE, law.user_state.tolist(), strict=False):
            setattr(controller.law_state, name, value)
    elif law.kind < USER:
        flags = records.values_of(law.flags)
        cls = type(controller)
        controller.law_state = cls.STATE(*np.asarray(law.state).tolist())
        controller.aux = (flags["aux1"], flags["aux2"])
        controller.saturated = bool(flags["saturated"])

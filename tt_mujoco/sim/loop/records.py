"""The named records the closed-loop step reads and writes: one schema for both loops.

Every bundle the compiled chunk loop (:mod:`tt_mujoco.sim.loop._kernel`) takes is a
:class:`~typing.NamedTuple` or a NumPy structured array defined here, so a field is read by
its name, never by a bare index: the limits, the plant's arrays, the law's state, the target's
state, the log row and why a run stopped. CPython runs the same step on them as plain objects
(:func:`interpreted`).
"""

from __future__ import annotations

import functools
from typing import Any, NamedTuple

import numpy as np

# What a law sees of the target and of the nominal model: the plain-number law's records.
from tt_mujoco.controllers.backing import CascadeConstants
from tt_mujoco.controllers.plain import NOMINAL_FIELDS, REFERENCE_FIELDS
from tt_mujoco.sim.loop.timeseries import LOOP_COLUMNS
from tt_mujoco.sim.parts.measure import Addresses, Lengths, Measurement
from tt_mujoco.sim.parts.motors import MotorConstants
from tt_mujoco.sim.parts.wind import DragConstants
from tt_mujoco.vehicle.reduced import ModelConstants
from tt_mujoco.vehicle.train import TrainConstants
from tt_mujoco.world.part import WorldRecord

__all__ = [
    "LAW_FLAGS",
    "LOG_DTYPE",
    "MEASUREMENT_DTYPE",
    "NOMINAL_FIELDS",
    "READING_FIELDS",
    "REFERENCE_FIELDS",
    "STOP_FIELDS",
    "TARGET_FIELDS",
    "DelayRecord",
    "FaultRecord",
    "GroundRecord",
    "LawRecord",
    "Limits",
    "LogRecord",
    "LoopRecord",
    "MujocoRecord",
    "PlantRecord",
    "SteeringRecord",
    "TargetRecord",
    "WindRecord",
    "interpreted",
    "listed",
    "new_record",
    "record_dtype",
    "set_value",
    "train_record",
    "value_of",
    "values_of",
]


def train_record(params) -> TrainConstants:
    """A train's constants (:func:`tt_mujoco.vehicle.train.train_constants`) with the
    trailers' rows as a float array, one row a trailer."""
    from tt_mujoco.vehicle.train import TRAILER_ROW, train_constants

    c = train_constants(params)
    rows = np.array(c.trailers, dtype=float)
    return c._replace(trailers=rows.reshape(-1, len(TRAILER_ROW)))


def record_dtype(fields) -> np.dtype:
    """The structured dtype of float ``fields``, in their order."""
    return np.dtype([(name, np.float64) for name in fields])


#: The measurement, field by field.
MEASUREMENT_DTYPE = record_dtype(Measurement._fields)

#: One logged row of the loop's own values (:data:`tt_mujoco.sim.loop.timeseries.LOOP_COLUMNS`).
LOG_DTYPE = record_dtype(LOOP_COLUMNS)

#: The target's state between steps: arc length, the previous measured speed (NaN before the
#: first update) and the curvature at the last update; with path feedback the nearest path
#: point's arc length and curvature, the errors (e_y, e_psi) and the path's own omega_d; backing
#: up with the hitch cascade, the leading axle's arc length (and its errors).
TARGET_FIELDS = (
    *("s", "v_prev", "kappa", "s_near", "kappa_near", "e_y", "e_psi", "omega_ref"),
    "s_lead",
)

#: A built-in law's values beside its state vector: whether the last torques saturated and the
#: two auxiliary outputs (the sliding variables of ISMC-STA).
LAW_FLAGS = ("saturated", "aux1", "aux2")

#: What the law sees of the measurement (noise, sensor faults and the delay included) and
#: what it asks, from the step's sense half to its actuate half: the hitch angle, the speeds,
#: the nominal mass matrix there (M11, M12, M22), the torques and the unsaturated request.
READING_FIELDS = ("phi", "v", "omega", "M11", "M12", "M22", "T_r", "T_l", "u1", "u2")

#: Why a stretch of steps stopped, with what the message names; at a payload step on the
#: reduced plant, how many changes it made and the step's torques and disturbance, still to
#: be applied.
STOP_FIELDS = (
    *("v", "phi", "beta", "x", "y", "eta", "hitch", "warning", "law_status"),
    *("g11", "g12", "g21", "g22", "u1", "u2"),
    *("payloads", "T_r", "T_l", "dist_r", "dist_l"),
    # a collision: the unit (0: the tractor), the obstacle and how deep they overlap (m)
    *("unit", "obstacle", "gap"),
    # 1 once Python code the kernel called back (a law, a path, a disturbance) raised: the step
    # stops there, and the kernel's caller raises it
    "raised",
)


def new_record(fields, **values) -> np.ndarray:
    """A one-element structured array of float ``fields`` (zeros, or the ``values`` given);
    its element ``[0]`` is the record a compiled function reads and writes by name."""
    record = np.zeros(1, dtype=record_dtype(fields))
    for name, value in values.items():
        record[0][name] = value
    return record


@functools.cache
def _fields_class(names: tuple[str, ...]) -> type:
    """A class of plain attributes ``names`` (slots), made from their values in order: what
    CPython reads and writes fast."""
    body = "\n".join(f"    self.{name} = {name}" for name in names)
    scope: dict = {}
    exec(f"def __init__(self, {', '.join(names)}):\n{body}", scope)
    return type("Fields", (), {"__slots__": names, "__init__": scope["__init__"]})


def interpreted(record):
    """``record`` (a named tuple of the records here, or one of them) as CPython runs the step
    on it: each structured array becomes a list of objects with the same fields as plain
    attributes (a NumPy record's field costs a microsecond or more to reach from Python, an
    attribute some tens of nanoseconds); other arrays, and numbers, are the same objects."""
    if isinstance(record, np.ndarray) and record.dtype.names:
        cls = _fields_class(record.dtype.names)
        return [cls(*values) for values in record.tolist()]
    if isinstance(record, tuple):
        items = [interpreted(item) for item in record]
        return type(record)(*items) if hasattr(record, "_fields") else tuple(items)
    return record


def values_of(record) -> dict:
    """The fields of a one-element record (:func:`new_record`, or its :func:`interpreted`
    twin) by name, as Python floats."""
    element = record[0]
    if isinstance(record, np.ndarray):
        return dict(zip(record.dtype.names, element.tolist(), strict=True))
    return {name: getattr(element, name) for name in element.__slots__}


def value_of(record, name: str) -> float:
    """Field ``name`` of a one-element record (:func:`new_record`, or its twin)."""
    if isinstance(record, np.ndarray):
        return float(record[0][name])
    return getattr(record[0], name)


def set_value(record, name: str, value: float) -> None:
    """Set field ``name`` of a one-element record (:func:`new_record`, or its twin)."""
    if isinstance(record, np.ndarray):
        record[0][name] = value
    else:
        setattr(record[0], name, value)


class Limits(NamedTuple):
    """The step's fixed bounds and noise levels."""

    #: wheel torque limit (N m)
    torque_limit: float
    #: per-wheel bound on the disturbance's torques (N m; inf: none)
    disturbance_bound: float
    #: hitch angle at which the run stops as a jackknife (rad)
    jackknife_phi: float
    #: steering angle at which the run stops as a jackknife (rad)
    jackknife_beta: float
    #: speed above which the state has blown up (m/s)
    max_speed: float
    #: standard deviations of the speed and yaw-rate noise (m/s, rad/s)
    noise_v: float
    noise_w: float


class MujocoRecord(NamedTuple):
    """The MuJoCo plant's arrays, seen from the compiled loop (dummies on the reduced plant)."""

    #: addresses of ``MjModel`` and ``MjData`` for ``mj_step``
    pointers: np.ndarray
    qpos: np.ndarray
    qvel: np.ndarray
    ctrl: np.ndarray
    qfrc_applied: np.ndarray
    #: ``MjData.warning.number``: a step that raises any of them stops the run
    warnings: np.ndarray
    #: ``MjData.xfrc_applied`` and the tractor's body, where the wrench disturbance acts
    xfrc_applied: np.ndarray
    tractor_body: int
    addresses: Addresses
    lengths: Lengths
    #: ``MjModel.body_mass``, ``body_inertia`` and the trailers' body ids (payload faults)
    body_mass: np.ndarray
    body_inertia: np.ndarray
    trailer_bodies: np.ndarray


class SteeringRecord(NamedTuple):
    """The trailers' steering gains and how the compiled loop schedules them."""

    #: 0 constant gains, or :data:`~tt_mujoco.sim.parts.schedule.PATH_SCHEDULE` or
    #: :data:`~tt_mujoco.sim.parts.schedule.CURVATURE_SCHEDULE`
    kind: int
    #: the gains eta_1..eta_N in force: the plant's, and a built-in law's model's
    etas: np.ndarray
    #: the gains a step's schedule offers (scratch)
    offered: np.ndarray
    #: a gain is re-applied when one moved by more than this
    tolerance: float
    #: the trailers' (L_k, L0_k), N x 2
    lengths: np.ndarray
    #: the path schedule: each axle's arc length, and per trailer its table (s, eta,
    #: d eta/ds, beta, d beta/ds) as an N x 5 x M array
    arcs: np.ndarray
    tables: np.ndarray
    #: (w, eta_max) of :func:`~tt_mujoco.vehicle.path_schedule.blended_gain_of`
    bounds: tuple
    #: the path the tractor drove (:class:`~tt_mujoco.vehicle.path_schedule.DrivenPath`): the
    #: path scheduler's own arrays
    driven: Any
    #: MuJoCo: the model's ``eq_data``, the steering equalities' ids, their hitches' qpos
    #: addresses, whether the axles are steered by actuator (else by linkage), and how far an
    #: actuated axle's target moves in a physics step at most (rad)
    eq_data: np.ndarray
    ids: np.ndarray
    hitches_q: np.ndarray
    actuated: bool
    max_turn: float
    #: the changes applied so far
    updates: np.ndarray


class PlantRecord(NamedTuple):
    """The plant the compiled loop advances: MuJoCo (``mj_step``) or the reduced ODE (RK4)."""

    mujoco: bool
    #: plant steps per control step
    substeps: int
    mj: MujocoRecord
    #: the reduced plant's state (x, y, theta, phi, theta_l, theta_r, v, omega), advanced in place
    ode_state: np.ndarray
    #: the reduced plant's (true) constants
    ode: ModelConstants
    #: the reduced plant's RK4 step (s)
    timestep: float
    #: a train's (true) constants, trailers as an N x 9 float array
    train: TrainConstants
    #: MuJoCo: trailers 2..N as rows (hitch_q, hitch_v, steer_q, L_k, L0_k)
    train_joints: np.ndarray
    #: the reduced train's scratch rows: poses (N x 5), rates (N x 3), RK4 slopes (5 x len(y))
    places: np.ndarray
    speeds: np.ndarray
    slopes: np.ndarray
    steering: SteeringRecord


class LawRecord(NamedTuple):
    """The law the step runs on the controller's nominal model."""

    #: a built-in law's index in :data:`tt_mujoco.sim.loop.law.LAW_CLASSES`, then
    #: :data:`~tt_mujoco.sim.loop.law.USER` (a user's plain-number law, compiled:
    #: :mod:`tt_mujoco.controllers.plain`) or :data:`~tt_mujoco.sim.loop.law.PYTHON` (a law
    #: that Python computes between the halves, ``user``)
    kind: int
    #: a built-in law's gains and memory, in the order of its class's ``GAINS`` and ``STATE``
    gains: np.ndarray
    state: np.ndarray
    #: :data:`LAW_FLAGS`
    flags: np.ndarray
    nominal: ModelConstants
    #: a train's nominal constants (a row per trailer), its hitch angles and the
    #: trailers' rates (scratch)
    nominal_train: TrainConstants
    phis: np.ndarray
    rates: np.ndarray
    anti_windup: bool
    #: the user's law, compiled (a placeholder for the built-in ones), or a Python law's hook
    user: Any
    #: the user law's gains and state records
    user_gains: np.ndarray
    user_state: np.ndarray
    #: what the law sees: the :data:`REFERENCE_FIELDS` record, the nominal model
    #: (:data:`NOMINAL_FIELDS`) at the measurement, and the measurement as seen (noise
    #: included), in :data:`MEASUREMENT_DTYPE`'s field order
    reference: np.ndarray
    model: np.ndarray
    measurement_values: np.ndarray
    #: where a law the kernel calls out to writes what it computed: a plain-number law its two
    #: torques; a Python law called back (law.python_law) its torques, its request
    #: and its status
    torques: np.ndarray
    #: whether the law's model takes the scheduled gains (a built-in law's does), and a
    #: train's nominal constants with those gains (scratch: with the gains the axles follow,
    #: below, once the step's model is made)
    follows_steering: bool
    steered_train: TrainConstants
    #: how fast actuated axles turn at most (rad/s; inf: a linkage): the model takes the
    #: gains they can follow (:func:`tt_mujoco.controllers.nominal.reduced_model`)
    axle_slew_rate: float
    #: :data:`READING_FIELDS`: what the law saw and asked this step (scratch)
    reading: np.ndarray
    #: trailers 2..N as a Python law sees them (the delay included), in
    #: :data:`~tt_mujoco.sim.parts.measure.TRAIN_FIELDS` order
    measurement_rows: np.ndarray


class TargetRecord(NamedTuple):
    """The tracking target: its speed profile tabulated per step and a closed-form path."""

    dynamic: bool
    #: per control step, the speed profile's (s_ref, v_ref, a_ref)
    profile: np.ndarray
    #: the path class's ``STEP_KIND`` (:mod:`tt_mujoco.reference.path_base`): ``ARCS_PATH``
    #: (``bounds``, ``kappas``, ``starts``), ``CYCLOID_PATH``, ``SPLINE_PATH`` (``bounds`` of
    #: its fine cells, their ``cells``, ``pose_cells`` and ``kappa_ends``) or ``HOOKED_PATH``
    #: (``path_hook``)
    path_kind: int
    length: float
    bounds: np.ndarray
    kappas: np.ndarray
    starts: np.ndarray
    cells: np.ndarray
    pose_cells: np.ndarray
    kappa_ends: np.ndarray
    #: :data:`TARGET_FIELDS`
    state: np.ndarray
    #: whether path feedback corrects omega_d (:class:`~tt_mujoco.reference.feedback.
    #: PathFeedback`), and its (k_y, k_psi, c_max)
    feedback: bool
    feedback_gains: tuple
    #: reversing (:class:`~tt_mujoco.reference.reverse.ReverseTarget`) from arc length s_end
    reverse: bool
    s_end: float
    #: the along-track loop's gain k_s (1/s; 0: none): v_d gains k_s (s_nominal - s_near)
    along_gain: float
    #: whether the hitch cascade sets omega_d (:class:`~tt_mujoco.controllers.backing.
    #: HitchCascade`), its constants (arrays), the hitches' wanted angles and scratch rates
    cascade: bool
    cascade_constants: CascadeConstants
    wanted: np.ndarray
    rates: np.ndarray
    #: the path object of a path without closed form (``path_kind`` 3), else None; the kernel's
    #: record holds a C function that calls it back (:mod:`tt_mujoco.sim.loop._kernel`), and it
    #: writes what it computed into ``hook_out``
    path_hook: Any
    hook_out: np.ndarray

    # What a path offers the path feedback and the path schedule, run by CPython (the kernel
    # overloads the functions that call these).
    def pose_at(self, s: float) -> tuple[float, float, float]:
        """The path's pose at ``s`` (:func:`tt_mujoco.sim.loop.target_step.pose_at`)."""
        from tt_mujoco.sim.loop.target_step import pose_at

        return pose_at(self, s)

    def curvature_and_rate(self, s: float) -> tuple[float, float]:
        """``(kappa, dkappa/ds)`` at ``s`` (:func:`tt_mujoco.sim.loop.target_step.path_at`)."""
        from tt_mujoco.sim.loop.target_step import path_at

        return path_at(self, s)


class FaultRecord(NamedTuple):
    """The sensor and actuator faults (:class:`~tt_mujoco.sim.parts.faults.FaultSchedule`)."""

    #: dropout windows (k0, k1) and actuator faults (k0, k1, scale right, scale left), per row
    dropouts: np.ndarray
    actuators: np.ndarray
    #: :data:`~tt_mujoco.sim.parts.faults.HELD`: what a dropout holds
    held: np.ndarray
    #: :data:`~tt_mujoco.sim.parts.faults.PAYLOAD_ROW` per payload, their state (last s, dt), and
    #: scratch for the changes of a step
    payloads: np.ndarray
    payload_state: np.ndarray
    payload_changes: np.ndarray


class WindRecord(NamedTuple):
    """The wind (:mod:`tt_mujoco.sim.parts.wind`) on the MuJoCo plant's tractor and trailer."""

    #: the wind's speed along its direction at each control step (m/s; empty: calm)
    speeds: np.ndarray
    #: its direction's (cos, sin)
    direction: tuple
    drag: DragConstants
    #: the wind's (F_x, F_y, M_z) on the tractor, then on the trailer, over this step (scratch)
    wrenches: np.ndarray


class DelayRecord(NamedTuple):
    """The sensor delay's line: the readings of the
    last ``depth = delay steps + 1`` steps, step ``j`` in slot ``j % depth`` (one unused slot
    without a delay)."""

    #: the measurement, field by field (depth x Measurement fields)
    measurements: np.ndarray
    #: trailers 2..N (depth x (N - 1) x :data:`~tt_mujoco.sim.parts.measure.TRAIN_FIELDS`)
    rows: np.ndarray
    #: (phi, v, omega) as the law sees them: noise and sensor faults included (depth x 3)
    seen: np.ndarray


class GroundRecord(NamedTuple):
    """Friction patches (:mod:`tt_mujoco.sim.parts.ground`) under the MuJoCo plant's wheels."""

    #: the wheels' contact geoms (empty: no patches), ``MjData.geom_xpos`` and
    #: ``MjModel.geom_friction``
    geoms: np.ndarray
    geom_xpos: np.ndarray
    geom_friction: np.ndarray
    #: the patches as :func:`~tt_mujoco.sim.parts.ground.wheel_frictions_of` takes them: kinds,
    #: bounds (P x 4), friction coefficients; the coefficient off them
    kinds: np.ndarray
    bounds: np.ndarray
    mus: np.ndarray
    base_mu: float
    #: each wheel's arc length (empty without bands), and scratch: the wheels' points (W x 2)
    #: and coefficients
    arcs: np.ndarray
    points: np.ndarray
    frictions: np.ndarray
    #: per control step, the bit mask of the patches some wheel stood on during its advance
    masks: np.ndarray


class LoopRecord(NamedTuple):
    """The episode's constants and its noise."""

    limits: Limits
    dt: float
    #: the last control step
    steps: int
    #: the episode's standard normal draws (empty without noise)
    noise: np.ndarray
    #: whether the disturbance enters as matched torques, or as a chassis wrench
    disturbed: bool
    wrench: bool
    #: the trailers N (:attr:`tt_mujoco.vehicle.params.Params.n_trailers`); every train
    #: record has as many rows
    n_trailers: int
    #: the hitch limits of trailers 2..N (rad)
    hitch_limits: np.ndarray
    faults: FaultRecord
    #: the DC motors (:mod:`tt_mujoco.sim.parts.motors`; ``dc_motor`` False: ideal actuators), and
    #: the torques they deliver now (right, left)
    dc_motor: bool
    motor: MotorConstants
    motor_torques: np.ndarray
    wind: WindRecord
    delay: DelayRecord
    ground: GroundRecord
    world: WorldRecord
    #: a built-in disturbance's index in :data:`~tt_mujoco.sim.parts.disturbances.DISTURBANCE_FORMS`
    #: and the numbers its form reads (:func:`tt_mujoco.sim.parts.disturbances.form_of`)
    disturbance_kind: int
    disturbance_params: np.ndarray
    #: whether the disturbance is a user's, ``disturbance_hook``: ``t -> (a_v, a_w)`` with its
    #: checks (else None: a built-in's); the kernel's record holds a C function that calls it
    #: back and writes what it computed into ``hook_out``
    hooked_disturbance: bool
    disturbance_hook: Any
    hook_out: np.ndarray


class EpisodeRecords(NamedTuple):
    """An episode's records, as the step takes them (with the log of the chunk it runs)."""

    loop: LoopRecord
    plant: PlantRecord
    law: LawRecord
    target: TargetRecord
    #: :data:`STOP_FIELDS`
    stop: np.ndarray


class LogRecord(NamedTuple):
    """Where a chunk logs its rows: the Measurement fields and the loop's own values."""

    measurement: np.ndarray
    #: :data:`LOG_DTYPE`
    loop: np.ndarray
    #: trailers 2..N per row: (N - 1) x :data:`~tt_mujoco.sim.parts.measure.TRAIN_FIELDS`
    train: np.ndarray
    #: the gains eta_1..eta_N in force at each row (a schedule's)
    etas: np.ndarray


def listed(made):
    """The interpreted records with the arrays the step reads element by element every step as
    lists of floats (a NumPy element is a NumPy scalar, whose arithmetic is slower)."""
    loop, plant, law, target, stop = made
    delay, faults = loop.delay, loop.faults
    loop = loop._replace(
        noise=loop.noise.tolist(),
        wind=loop.wind._replace(speeds=loop.wind.speeds.tolist()),
        delay=delay._replace(**{name: getattr(delay, name).tolist() for name in delay._fields}),
        faults=faults._replace(**{name: getattr(faults, name).tolist() for name in faults._fields}),
        motor_torques=loop.motor_torques.tolist(),
    )
    law = law._replace(
        measurement_values=law.measurement_values.tolist(),
        measurement_rows=law.measurement_rows.tolist(),
        state=law.state.tolist(),
        gains=law.gains.tolist(),
        phis=law.phis.tolist(),
        rates=law.rates.tolist(),
        nominal_train=_listed_train(law.nominal_train),
    )
    steering = plant.steering
    scheduled = ("etas", "offered", "lengths", "arcs", "tables")
    plant = plant._replace(
        train=_listed_train(plant.train),
        train_joints=plant.train_joints.tolist(),
        steering=steering._replace(
            **{name: getattr(steering, name).tolist() for name in scheduled}
        ),
    )
    if not plant.mujoco:  # the reduced ODE's state and its scratch rows
        lists = {name: getattr(plant, name).tolist() for name in ("places", "speeds", "slopes")}
        plant = plant._replace(ode_state=plant.ode_state.tolist(), **lists)
    tables = ("profile", "bounds", "kappas", "starts", "cells", "pose_cells", "kappa_ends")
    target = target._replace(
        **{name: getattr(target, name).tolist() for name in (*tables, "wanted", "rates")},
        cascade_constants=target.cascade_constants._replace(
            **{
                name: getattr(target.cascade_constants, name).tolist()
                for name in ("lengths", "etas", "ends")
            }
        ),
    )
    return EpisodeRecords(loop, plant, law, target, stop)


def _listed_train(constants):
    """A train's constants with its trailers' rows as lists of floats."""
    return constants._replace(trailers=constants.trailers.tolist())

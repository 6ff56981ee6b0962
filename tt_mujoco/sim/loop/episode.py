"""An episode's records, made from the run's Python objects.

The closed loop's step (:mod:`tt_mujoco.sim.loop.closed_loop`) reads and writes the named records of
:mod:`tt_mujoco.sim.loop.records`; :func:`episode_records` makes them from a reset
:class:`~tt_mujoco.sim.loop.stepper.Stepper` (the plant, the target, the faults, the schedule) and
the controller. The objects are configuration and factories: what the run did stays in the
records, which the reports read when the episode ends (the faults, the friction patches, the
schedule's gains, a collision: :attr:`~tt_mujoco.sim.loop.stepper.Stepper.records`), whichever
loop ran it (the kernel's, or CPython's over the same source). :func:`hand_back` gives the
controller its law's memory, which it keeps between its own steps when driven by hand.
:func:`outcome` words why it ended, as :func:`tt_mujoco.sim.simulate.run_episode` reports it."""

from __future__ import annotations

import math
import pickle

import numpy as np

from tt_mujoco.guard import users_failure
from tt_mujoco.sim import usercode
from tt_mujoco.sim.loop import records, step
from tt_mujoco.sim.loop.law import LAWS, hand_law_back, law_record
from tt_mujoco.sim.loop.records import (
    DelayRecord,
    FaultRecord,
    GroundRecord,
    LoopRecord,
    WindRecord,
)
from tt_mujoco.sim.parts import disturbances, schedule
from tt_mujoco.sim.parts.faults import (
    ACTUATOR_ROW,
    HELD,
    PAYLOAD_CHANGE,
    PAYLOAD_ROW,
    PAYLOAD_STATE,
)
from tt_mujoco.sim.parts.measure import TRAIN_FIELDS, Measurement
from tt_mujoco.sim.parts.motors import MotorConstants

__all__ = [
    "carry_payloads",
    "changes_of",
    "episode_records",
    "hand_back",
    "inner_target",
    "is_law_class",
    "loop_record",
    "model_of",
    "runs_built_in",
    "target_record",
]


def inner_target(target):
    """The tracking target itself (inside path feedback or the hitch cascade, if any)."""
    from tt_mujoco.controllers.backing import HitchCascade
    from tt_mujoco.reference.feedback import PathFeedback

    return target.target if type(target) in (PathFeedback, HitchCascade) else target


def model_of(controller):
    """The nominal model a controller runs (a built-in law's own, or its setup's)."""
    model = getattr(controller, "model", None)
    if model is None:
        model = getattr(getattr(controller, "setup", None), "model", None)
    return model


def has_closed_form(path) -> bool:
    """Whether the step reads ``path`` from its own tables (its class declares its
    :attr:`~tt_mujoco.reference.path_base.ReferencePath.STEP_KIND`), not by calling it."""
    from tt_mujoco.reference.path_base import read_from_tables

    return read_from_tables(path)


def users_disturbance(built) -> bool:
    """Whether the run's disturbance is a user's, which the step calls, rather than none or a
    built-in, which it computes itself (:func:`tt_mujoco.sim.parts.disturbances.form_of`)."""
    from tt_mujoco.sim.parts.disturbances import form_of

    return built.disturbance is not None and form_of(built.disturbance) is None


def is_law_class(controller) -> bool:
    """Whether ``controller`` is of a built-in law's own class (:data:`tt_mujoco.sim.
    loop.law.LAWS`; a subclass may change what it runs)."""
    law = getattr(type(controller), "LAW", None)
    return law in LAWS and type(controller).__module__ == law.__module__


def runs_built_in(controller) -> bool:
    """Whether the step runs ``controller``'s law itself, not its Python ``compute``: a built-in
    law's own class on the built-in nominal model."""
    return is_law_class(controller) and bool(getattr(model_of(controller), "builtin", False))


def carry_payloads(stepper, plant, faults, stop_record):
    """The payload changes of a step on the reduced plant: made to the plant (its parameters,
    in the order made), and the plant record rebuilt on its new constants (the gains in force
    kept); ``stop.payloads`` cleared."""
    from tt_mujoco.vehicle import reduced
    from tt_mujoco.vehicle.train import TRAILER_ROW

    count = int(records.value_of(stop_record, "payloads"))
    for trailer, factor in np.asarray(faults.payload_changes[:count]).tolist():
        stepper.plant.scale_trailer_mass(factor, int(trailer))
    records.set_value(stop_record, "payloads", 0.0)
    params = stepper.plant.params
    train = records.train_record(params)
    eta = TRAILER_ROW.index("eta")
    for k in range(len(train.trailers)):  # a schedule's gains in force, not the parameters'
        train.trailers[k, eta] = plant.train.trailers[k][eta]
    if isinstance(plant.train.trailers, list):  # as CPython's step reads them
        train = train._replace(trailers=train.trailers.tolist())
    return plant._replace(ode=reduced.model_constants(params), train=train)


def episode_records(stepper, controller, user, python=None) -> tuple:
    """The records of the (reset) ``stepper``'s episode as the step reads them
    (:mod:`tt_mujoco.sim.loop.closed_loop`): ``(loop, plant, law, target, stop)``, with ``user`` the
    compiled form of a plain-number law (any placeholder for a built-in one), or ``python``,
    the law that Python computes between the halves (:data:`~tt_mujoco.sim.loop.closed_loop.
    PYTHON`: a controller's :meth:`compute`, or an agent's torques)."""

    plant = _plant_record(stepper, stepper.built.nominal)
    law = law_record(controller, stepper.built.nominal, user, plant.steering, python)
    return records.EpisodeRecords(
        loop_record(stepper),
        plant,
        law,
        target_record(stepper.built, stepper.steps),
        records.new_record(records.STOP_FIELDS),
    )


def changes_of(etas: np.ndarray, changes: list, first_row: int) -> list:
    """``(row, gains)`` of each logged row whose gains differ from the row before it."""
    out, last = [], changes[-1][1]
    for i, row in enumerate(map(tuple, etas.tolist())):
        if row != last:
            out.append((first_row + i, row))
            last = row
    return out


def _steering_record(stepper, mujoco_plant: bool):
    """The scheduler's gains and tables, and where the plant's couplings are."""
    from tt_mujoco.sim.parts.schedule import EtaScheduler, PathEtaScheduler
    from tt_mujoco.vehicle.path_schedule import BLEND_PHI, driven_path

    scheduler, n = stepper.scheduler, stepper.built.plant_params.n_trailers
    if mujoco_plant:
        eq_data, ids, hitches_q, actuated, max_turn = stepper.plant.steering
    else:
        eq_data, ids, hitches_q, actuated, max_turn = np.zeros((1, 1)), [0] * n, [0] * n, False, 0.0
    kind, tables, arcs, bounds = 0, np.zeros((n, 5, 1)), np.zeros(n), (0.0, 0.0)
    etas, tolerance, driven = stepper.plant_etas, 0.0, driven_path(0, 0.0, 0.0)
    if isinstance(scheduler, PathEtaScheduler):
        kind, tolerance = schedule.PATH_SCHEDULE, scheduler.tolerance
        tables = np.array(scheduler.schedule.tables, dtype=float)
        arcs = np.array(scheduler.arc_lengths, dtype=float)
        bounds = (BLEND_PHI, scheduler.schedule.eta_max)
        driven = scheduler.driven  # its arrays: the compiled steps log into them
    elif isinstance(scheduler, EtaScheduler):
        kind, tolerance = schedule.CURVATURE_SCHEDULE, scheduler.tolerance
    return records.SteeringRecord(
        kind=kind,
        etas=np.array(etas, dtype=float),
        offered=np.zeros(n),
        tolerance=tolerance,
        lengths=np.array([(t.L, t.L0) for t in stepper.built.plant_params.trailers]),
        arcs=arcs,
        tables=tables,
        bounds=bounds,
        driven=driven,
        eq_data=eq_data,
        ids=np.array(ids, dtype=np.int64),
        hitches_q=np.array(hitches_q, dtype=np.int64),
        actuated=actuated,
        max_turn=max_turn,
        updates=np.zeros(1, dtype=np.int64),
    )


def _plant_record(stepper, nominal):
    from tt_mujoco.sim.parts.measure import Addresses, Lengths
    from tt_mujoco.sim.parts.plant_mujoco import MujocoPlant
    from tt_mujoco.vehicle import reduced

    plant, substeps = stepper.plant, stepper.built.substeps

    if isinstance(plant, MujocoPlant):
        d, lay = plant.data, plant.layout
        mj = records.MujocoRecord(
            pointers=np.array([plant.model._address, d._address], dtype=np.int64),
            qpos=d.qpos,
            qvel=d.qvel,
            ctrl=d.ctrl,
            qfrc_applied=d.qfrc_applied,
            warnings=d.warning.number,
            xfrc_applied=d.xfrc_applied,
            tractor_body=plant.tractor_body,
            addresses=lay.addresses,
            lengths=lay.lengths,
            body_mass=plant.model.body_mass,
            body_inertia=plant.model.body_inertia,
            trailer_bodies=np.array(plant.trailer_bodies, dtype=np.int64),
        )
        ode_state, ode, timestep = np.zeros(8), reduced.model_constants(nominal), 0.0
        params, joints = nominal, np.array(lay.train, dtype=float).reshape(-1, 5)
    else:
        one, none = np.zeros(1), np.zeros(0, dtype=np.int64)
        mj = records.MujocoRecord(
            none, one, one, one, one, np.zeros(1, dtype=np.int32), np.zeros((1, 6)), 0,
            Addresses(*[0] * len(Addresses._fields)), Lengths(0.0, 0.0, 0.0, 0.0),
            np.zeros(1), np.zeros((1, 3)), np.zeros(1, dtype=np.int64),
        )  # fmt: skip
        ode_state = np.array(plant.ode.state, dtype=float)
        ode, timestep = reduced.model_constants(plant.params), plant.timestep
        params, joints = plant.params, np.zeros((0, 5))
    n = params.n_trailers
    return records.PlantRecord(
        mujoco=isinstance(plant, MujocoPlant),
        substeps=substeps,
        mj=mj,
        ode_state=ode_state,
        ode=ode,
        timestep=timestep,
        train=records.train_record(params),
        train_joints=joints,
        places=np.zeros((n, 5)),
        speeds=np.zeros((n, 3)),
        slopes=np.zeros((5, len(ode_state))),
        steering=_steering_record(stepper, isinstance(plant, MujocoPlant)),
    )


def target_record(built, steps: int):
    """The step's record of the run's target (its path's tables, its speed profile per
    step, its state at the start)."""
    from tt_mujoco.controllers.backing import CascadeConstants, HitchCascade
    from tt_mujoco.reference.feedback import PathFeedback
    from tt_mujoco.reference.path_base import ARCS_PATH, HOOKED_PATH, SPLINE_PATH
    from tt_mujoco.reference.reverse import ReverseTarget
    from tt_mujoco.reference.targets import DynamicTarget, StaticTarget

    target, path, outer = inner_target(built.target), built.path, built.target
    if type(target) not in (StaticTarget, DynamicTarget, ReverseTarget):
        raise TypeError(f"the step has no record of the target {type(target).__name__}")
    fed, cascade = type(outer) is PathFeedback, type(outer) is HitchCascade
    n = built.plant_params.n_trailers
    constants = CascadeConstants(
        (0.0, 0.0, 0.0, 0.0), 0.0, np.zeros((n, 2)), np.zeros(n), np.zeros((n, 2))
    )
    if cascade:
        c = outer.constants
        constants = CascadeConstants(
            c.gains, c.preview, *(np.array(x, dtype=float) for x in (c.lengths, c.etas, c.ends))
        )
    kappas, starts = np.zeros(0), np.zeros((0, 3))
    cells, pose_cells, kappa_ends = np.zeros((0, 5)), np.zeros((0, 10)), np.zeros(2)
    bounds, hook = np.zeros(0), None
    kind = path.STEP_KIND if has_closed_form(path) else HOOKED_PATH
    if kind == HOOKED_PATH:  # a user's path: the step calls it, guarded and checked
        from tt_mujoco.sim.usercode import CheckedPath, path_label

        hook = CheckedPath(path, path_label(built))
    elif kind == ARCS_PATH:
        bounds, kappas, starts = path.closed_form
    elif kind == SPLINE_PATH:
        bounds, cells, pose_cells, kappa_ends = path.closed_form
    return records.TargetRecord(
        dynamic=target.kind == "dynamic",
        profile=_profile_table(target, built.control_dt, steps),
        path_kind=kind,
        length=float(path.length),
        bounds=bounds,
        kappas=kappas,
        starts=starts,
        cells=cells,
        pose_cells=pose_cells,
        kappa_ends=kappa_ends,
        state=records.new_record(
            records.TARGET_FIELDS,
            v_prev=math.nan,
            kappa=0.0,  # set by the first step before any reads it: no call of a user's path
            s=target.start_s,
            s_near=target.start_s if fed else built.start_s,
            s_lead=outer.leading_start_s if cascade else 0.0,
        ),
        feedback=fed,
        feedback_gains=outer.gains if fed else (0.0, 0.0, 0.0),
        reverse=isinstance(target, ReverseTarget),
        s_end=float(getattr(target, "s_end", 0.0)),
        along_gain=built.along_track_gain,
        cascade=cascade,
        cascade_constants=constants,
        wanted=np.zeros(n),
        rates=np.zeros((n, 3)),
        path_hook=hook,
        hook_out=np.zeros(3),
    )


def hand_back(stepper, controller, status, k, law) -> None:
    """The episode's end at step ``k`` (``status``) to the stepper, and the law's memory (the
    ``law`` record's) to ``controller``, which keeps it between its own steps. Everything else
    stays in the episode's records, which the reports read
    (:attr:`~tt_mujoco.sim.loop.stepper.Stepper.records`): the faults, the friction patches,
    the schedule's gains and arc lengths; the motors' torques are the record's own
    (:meth:`~tt_mujoco.sim.loop.stepper.Stepper.begin`); the stepper syncs the reduced ODE."""
    stepper.k = k
    stepper.finished = status == step.FINISHED
    hand_law_back(controller, law)


#: Speed-profile tables by (pickled profile, dt, steps): a sweep's episodes share their profile.
_PROFILES: dict = {}


def prepare_profile(built, steps: int) -> None:
    """Make the table of the run's speed profile over ``steps`` steps ahead of the episode's
    records (their :func:`target_record` then finds it made): a constant of the episode, as
    its noise is, which a stepper's reset makes with the noise."""
    target = inner_target(built.target)
    if hasattr(target, "profile"):
        _profile_table(target, built.control_dt, steps)


def _profile_table(target, dt: float, steps: int) -> np.ndarray:
    """``(s_ref, v_ref, a_ref)`` of the target's speed profile at every control step, from
    the profile's own scalar ``state`` at the stepper's times ``k dt``."""
    key = (pickle.dumps(target.profile), dt, steps)
    table = _PROFILES.get(key)
    if table is None:
        times = [k * dt for k in range(steps + 1)]
        table = np.array([target.profile.state(t) for t in times], dtype=float)
        if len(_PROFILES) >= 8:
            _PROFILES.pop(next(iter(_PROFILES)))
        _PROFILES[key] = table
    return table


def loop_record(stepper) -> LoopRecord:
    """The episode's constants and noise as the step reads them (after the stepper's
    :meth:`~tt_mujoco.sim.loop.stepper.Stepper.reset`)."""
    dist = stepper.built.disturbance is not None
    form = disturbances.form_of(stepper.built.disturbance)  # None: none, or a user's
    mode = stepper.built.scenario.disturbance
    noise, faults = stepper.noise, stepper.faults
    rows = faults.payload_rows if faults else []
    motors = stepper.motors
    depth = stepper.built.delay_steps + 1
    return LoopRecord(
        limits=stepper.limits,
        dt=stepper.dt,
        steps=stepper.steps,
        noise=np.zeros(0) if noise is None else noise,
        disturbed=dist and mode == "matched",
        wrench=dist and mode == "wrench",
        n_trailers=stepper.built.plant_params.n_trailers,
        hitch_limits=np.array(stepper.train_limits, dtype=float),
        faults=FaultRecord(
            dropouts=np.array(faults.dropouts if faults else [], dtype=float).reshape(-1, 2),
            actuators=np.array(faults.actuators if faults else [], dtype=float).reshape(
                -1, len(ACTUATOR_ROW)
            ),
            held=np.array(faults.held if faults else [0.0] * len(HELD), dtype=float),
            payloads=np.array(rows, dtype=float).reshape(-1, len(PAYLOAD_ROW)),
            payload_state=np.array(faults.payload_state if faults else [0.0] * len(PAYLOAD_STATE)),
            payload_changes=np.zeros((len(rows), len(PAYLOAD_CHANGE))),
        ),
        dc_motor=motors is not None,
        motor=motors.constants if motors else MotorConstants(*[0.0] * 6),
        motor_torques=np.array(motors.torques if motors else [0.0, 0.0]),
        wind=WindRecord(
            np.zeros(0) if stepper.wind_speeds is None else stepper.wind_speeds,
            stepper.wind_direction,
            stepper.drag,
            np.zeros(6),
        ),
        delay=DelayRecord(
            measurements=np.zeros((depth, len(Measurement._fields))),
            rows=np.zeros((depth, len(stepper.train_limits), len(TRAIN_FIELDS))),
            seen=np.zeros((depth, 3)),
        ),
        ground=_ground_record(stepper),
        world=stepper.world,
        disturbance_kind=form[0] if form else 0,
        disturbance_params=np.array(form[1] if form else (), dtype=float),
        hooked_disturbance=users_disturbance(stepper.built),
        disturbance_hook=_disturbance_hook(stepper.built),
        hook_out=np.zeros(2),
    )


def _disturbance_hook(built):
    """A user's disturbance with its checks, as CPython's step calls it (None: none, or
    the paper's, which the step computes itself)."""
    if not users_disturbance(built):
        return None
    dist = built.disturbance
    who = usercode.disturbance_label(built)

    def disturbance(t: float) -> tuple[float, float]:
        try:
            out = dist(t)
        except BaseException as err:
            if not users_failure(err):
                raise
            raise usercode.failure(who, t, err) from None
        return usercode.checked_disturbance(out, who, t)

    return disturbance


def _ground_record(stepper) -> GroundRecord:
    """The friction patches under the wheels, as the step reads them."""
    ground = getattr(stepper.plant, "ground", None)
    if ground is None:
        none, no_ints = np.zeros(0), np.zeros(0, dtype=np.int64)
        return GroundRecord(
            no_ints, np.zeros((1, 3)), np.zeros((1, 3)), no_ints, np.zeros((0, 4)), none,
            0.0, none, np.zeros((0, 2)), none, no_ints,
        )  # fmt: skip
    patches, geoms, xpos, friction = ground
    points = np.array(xpos[geoms, :2], dtype=float)
    return GroundRecord(
        geoms=np.array(geoms, dtype=np.int64),
        geom_xpos=xpos,
        geom_friction=friction,
        kinds=patches.kinds,
        bounds=patches.bounds,
        mus=patches.mus,
        base_mu=patches.base_mu,
        arcs=patches.start(points),
        points=points,
        frictions=np.zeros(len(geoms)),
        masks=np.zeros(stepper.steps + 1, dtype=np.int64),
    )

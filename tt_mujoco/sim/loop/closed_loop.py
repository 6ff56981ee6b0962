"""The closed loop's step over the named records: one source, compiled and interpreted.

A control step is :func:`sense_step` (measure, check, noise, faults, delay, target, the law's
reference and nominal model), the law (:func:`law_step` runs a compiled one) and
:func:`actuate_step` (saturation, faults, motors, disturbance, log, schedule, advance), over the
records of :mod:`tt_mujoco.sim.loop.records`, each taking the step, its row and the records; what
the law saw and asked passes between them in ``law.reading``. The kernel's chunk loop
(:func:`tt_mujoco.sim.loop._kernel.run_chunk`) sequences them over a stretch of steps.

These are plain functions: the compiled kernel (:mod:`tt_mujoco.sim.loop._kernel`) compiles them
from this source (:data:`BORROWING` and :data:`HALVES` say how), and CPython runs the same
source. One call reaches what only one of them has: :func:`mj_step` (MuJoCo's C step, by the
addresses of the model and data); the kernel gives it its compiled form, as it does the law's
own (:mod:`tt_mujoco.sim.loop.law`). Importing this module imports no numba.
"""

from __future__ import annotations

import ctypes
import functools
import math
import os
from typing import NamedTuple

import numpy as np

from tt_mujoco.compiled_form import compiled_form
from tt_mujoco.controllers import base
from tt_mujoco.sim.loop import step, target_step
from tt_mujoco.sim.loop.law import (
    ETA_COLUMN,
    PYTHON,
    USER,
    follow_train,
    law_step,
    model_steered,
    nominal_mass,
    nominal_model_step,
)
from tt_mujoco.sim.parts import (
    disturbances,
    faults,
    ground,
    measure,
    motors,
    plant_mujoco,
    plant_reduced,
    schedule,
    wind,
)
from tt_mujoco.sim.parts.measure import (
    BETA,
    OMEGA,
    PHI,
    ROW_BETA,
    ROW_PHI,
    ROW_THETA0,
    ROW_X0,
    ROW_Y0,
    THETA,
    THETA0,
    X0,
    Y0,
    V,
    X,
    Y,
)
from tt_mujoco.vehicle import path_schedule, reduced, train
from tt_mujoco.world import contact

__all__ = [
    "BORROWING",
    "HALVES",
    "actuate_step",
    "advance_after_payload",
    "floats",
    "mj_step",
    "run_steps",
    "sense_step",
]

RUNNING, FINISHED, BLEW_UP, JACKKNIFE = step.RUNNING, step.FINISHED, step.BLEW_UP, step.JACKKNIFE
WARNING, LAW_FAILED, SINGULAR = step.WARNING, step.LAW_FAILED, step.SINGULAR
PAYLOAD, RAISED, COLLISION = step.PAYLOAD, step.RAISED, step.COLLISION
LAW_OK = base.LAW_OK
#: What the kernel asks of a hook it calls back (:mod:`tt_mujoco.sim.loop._kernel`, ``HOOK``): a
#: path's (:mod:`tt_mujoco.sim.loop.target_step`), or a disturbance's answer
HOOK_CURVATURE, HOOK_POSE = target_step.HOOK_CURVATURE, target_step.HOOK_POSE
HOOK_LAW_POSE, HOOK_DISTURBANCE = target_step.HOOK_LAW_POSE, disturbances.HOOK_DISTURBANCE
PATH_SCHEDULE, CURVATURE_SCHEDULE = schedule.PATH_SCHEDULE, schedule.CURVATURE_SCHEDULE
#: where the hitch angle, speed and yaw rate the law saw are in a row of the delay's line
SEEN_PHI, SEEN_V, SEEN_OMEGA = 0, 1, 2


class Push(NamedTuple):
    """What a control period applies besides the wheel torques: the matched disturbance's
    wheel torques, or (``wrench``) the disturbance's force and moment on the chassis."""

    dist_r: float
    dist_l: float
    wrench: bool
    fx: float
    fy: float
    mz: float


#: where the wheels' rates are in the measurement
WHEEL_RATES = tuple(measure.Measurement._fields.index(f"theta_{w}_dot") for w in ("r", "l"))


def mujoco_library() -> str:
    """The path of MuJoCo's shared library, which its Python bindings load."""
    import mujoco

    folder = os.path.dirname(mujoco.__file__)
    return os.path.join(folder, next(f for f in os.listdir(folder) if f.startswith("libmujoco.so")))


@functools.cache
def _c_mj_step():
    function = ctypes.CDLL(mujoco_library()).mj_step
    function.argtypes, function.restype = (ctypes.c_void_p, ctypes.c_void_p), None
    return function


@compiled_form("MuJoCo's C step, called by its symbol in MuJoCo's library")
def mj_step(model_address, data_address) -> None:
    """MuJoCo's ``mj_step`` on the model and data at these addresses (the plant record's
    ``pointers``); the kernel calls the library's symbol."""
    _c_mj_step()(int(model_address), int(data_address))


@compiled_form("the array itself: numba reads an array's floats as they are")
def floats(array):
    """A float array to read from: CPython reads a list of its values (a NumPy element is a
    NumPy scalar, whose arithmetic is slower than a float's); the kernel, the array itself."""
    return array.tolist() if isinstance(array, np.ndarray) else array


def _sense(plant, n, rows):
    """The Measurement fields of the plant's state; trailers 2..N of ``n`` into ``rows``."""
    if plant.mujoco:
        mj = plant.mj
        qpos, qvel = floats(mj.qpos), floats(mj.qvel)
        measurement = measure.measure_values(qpos, qvel, mj.addresses, mj.lengths)
        if n > 1:
            measure.train_rows_of(
                qpos, qvel, mj.addresses, mj.lengths, measurement, plant.train_joints, rows
            )
        return measurement
    y, ode = floats(plant.ode_state), _ode(plant)
    if n == 1:
        return plant_reduced.reduced_measure_values(y, ode)
    first = (y[0], y[1], y[2], y[3], y[3 + n], y[4 + n], y[5 + n], y[6 + n])
    plant_reduced.reduced_train_rows_of(y, plant.train, plant.places, plant.speeds, rows)
    return plant_reduced.reduced_measure_values(first, ode)


def _place_payloads(k, s, fault, plant) -> int:
    """The payloads placed at step ``k`` (arc length ``s``): into MuJoCo's bodies at once; for
    the reduced plant, how many changes its caller makes to the constants."""
    changes = fault.payload_changes
    count = faults.payloads_of(k, s, fault.payloads, fault.payload_state, changes)
    if not plant.mujoco:
        return count
    mj = plant.mj
    for i in range(count):
        body = mj.trailer_bodies[int(changes[i][faults.CHANGE_TRAILER]) - 1]
        scale = changes[i][faults.CHANGE_FACTOR]
        plant_mujoco.scale_body_of(mj.body_mass, mj.body_inertia, body, scale)
    return 0


def _ode(plant):
    """The reduced plant's constants with trailer 1's gain in force."""
    if plant.steering.kind == 0:
        return plant.ode
    return reduced.with_eta_of(plant.ode, plant.steering.etas[0])


def _advance(plant, T_r, T_l, push, weather, stop):
    """Apply the torques, the disturbance ``push`` (:class:`Push`) and the wind
    (``weather.wrenches`` of this step, when there is a wind) and advance the plant one control
    period; the stop code."""
    dist_r, dist_l = push.dist_r, push.dist_l
    if plant.mujoco:
        mj = plant.mj
        a = mj.addresses
        mj.ctrl[a.act_right] = T_r
        mj.ctrl[a.act_left] = T_l
        if push.wrench:
            xfrc = mj.xfrc_applied[mj.tractor_body]
            xfrc[0], xfrc[1], xfrc[5] = push.fx, push.fy, push.mz
        else:
            mj.qfrc_applied[a.wheel_right_v] = dist_r
            mj.qfrc_applied[a.wheel_left_v] = dist_l
        if len(weather.speeds):
            wind.blow_of(mj, push.wrench, weather.wrenches)
        steering = plant.steering
        for _ in range(plant.substeps):
            if steering.actuated:  # the axles' targets follow the hitches every physics step
                plant_mujoco.aim_steering_of(
                    steering.eq_data,
                    steering.ids,
                    steering.hitches_q,
                    steering.etas,
                    mj.qpos,
                    steering.max_turn,
                )
            mj_step(mj.pointers[0], mj.pointers[1])
        for i in range(mj.warnings.size):
            if mj.warnings[i] != 0:
                stop.warning = i
                return WARNING
        return RUNNING
    y = plant.ode_state
    n = len(plant.train.trailers)
    if n > 1:
        inputs = (T_r + dist_r, T_l + dist_l, 0.0, 0.0)
        for _ in range(plant.substeps):
            if not train.train_rk4_step_of(
                y, inputs, plant.train, plant.timestep, plant.speeds, plant.slopes
            ):
                step.first_singular_of(plant.slopes[4][3 : 3 + n], plant.train, stop)
                return SINGULAR
        return RUNNING
    ode = _ode(plant)
    for _ in range(plant.substeps):
        ok, phi, new = reduced.rk4_step_of(
            y, T_r + dist_r, T_l + dist_l, 0.0, 0.0, ode, plant.timestep
        )
        if not ok:
            stop.phi, stop.eta = phi, ode.eta
            return SINGULAR
        for i in range(8):
            y[i] = new[i]
    return RUNNING


def advance_after_payload(plant, weather, stop_record):
    """The step a payload on the reduced plant interrupted (:data:`PAYLOAD`), advanced on the
    plant's new constants with the torques and disturbance in ``stop_record``; the stop code."""
    stop = stop_record[0]
    push = Push(stop.dist_r, stop.dist_l, False, 0.0, 0.0, 0.0)
    return _advance(plant, stop.T_r, stop.T_l, push, weather, stop)


def _offer_path(steering, target, measurement, rows, n):
    """The path schedule (:class:`~tt_mujoco.sim.parts.schedule.PathEtaScheduler`): every axle
    projected onto the path and its gain there, into
    ``steering.offered``."""
    offered, arcs, driven = steering.offered, steering.arcs, steering.driven
    if driven.gain != 0.0:
        path_schedule.record_driven_of(target, driven, measurement[X], measurement[Y])
    for k in range(n):
        if k == 0:
            x, y, heading, phi = (
                measurement[X0],
                measurement[Y0],
                measurement[THETA0],
                measurement[PHI],
            )
        else:
            row = rows[k - 1]
            x, y, heading, phi = row[ROW_X0], row[ROW_Y0], row[ROW_THETA0], row[ROW_PHI]
        arcs[k], offered[k] = path_schedule.axle_gain_of(
            target, arcs[k], (x, y), heading, phi, steering.tables[k], steering.bounds, driven
        )


def _steer(plant, law):
    """EtaScheduler._offer: the offered gains applied when one moved by more than the
    tolerance, into the plant (a linkage's ratio, a reduced train's rows) and the law's
    train model."""
    steering, n = plant.steering, len(plant.train.trailers)
    if not schedule.gains_moved(steering.offered, steering.etas, steering.tolerance):
        return
    etas = steering.etas
    steering.updates[0] += 1
    for k in range(len(etas)):
        etas[k] = steering.offered[k]  # not etas[:] = ...: a slice copy may allocate
        if plant.mujoco and not steering.actuated:
            steering.eq_data[steering.ids[k], 1] = -etas[k]
        if n > 1:  # one trailer: the ODE's constants take the gain (_ode)
            plant.train.trailers[k][ETA_COLUMN] = etas[k]
        # a test of its own: merged into the one above, the compiled reduced loop's code came
        # out markedly slower (bench_cli's reduced case)
        if law.steered_train.trailers.shape[0] > 1:
            law.steered_train.trailers[k, ETA_COLUMN] = etas[k]


def _delayed(delay, k, measurement, rows, seen):
    """The sensor delay's line: step ``k``'s ``measurement``, its train ``rows`` and the
    ``seen = (phi, v, omega)`` stored, and those of the delay's steps ago returned (the first
    step's until there are that many): ``(measurement, rows, phi, v, omega)``."""
    depth = len(delay.seen)
    slot = k % depth
    store = delay.measurements[slot]
    for i in range(len(store)):
        store[i] = measurement[i]
    stored = delay.rows[slot]  # element by element: a slice copy may allocate
    for i in range(len(rows)):
        row, stored_row = rows[i], stored[i]
        for j in range(len(row)):
            stored_row[j] = row[j]
    slot_seen = delay.seen[slot]
    slot_seen[SEEN_PHI], slot_seen[SEEN_V], slot_seen[SEEN_OMEGA] = seen
    read = max(0, k - depth + 1) % depth
    was = delay.seen[read]
    return delay.measurements[read], delay.rows[read], was[SEEN_PHI], was[SEEN_V], was[SEEN_OMEGA]


def _touch(world, k, measurement, rows, n, stop):
    """The world's contact check at step ``k``: every unit's pose from the ``measurement``
    and the train's ``rows``, their least gap to the obstacles logged in
    ``world.clearance``; COLLISION (the unit, obstacle and gap in ``stop``) when one touches,
    else RUNNING."""
    poses = world.poses
    poses[0, 0], poses[0, 1], poses[0, 2] = measurement[X], measurement[Y], measurement[THETA]
    poses[1, 0], poses[1, 1], poses[1, 2] = measurement[X0], measurement[Y0], measurement[THETA0]
    for i in range(n - 1):
        row = rows[i]
        poses[i + 2, 0], poses[i + 2, 1], poses[i + 2, 2] = (
            row[ROW_X0],
            row[ROW_Y0],
            row[ROW_THETA0],
        )
    gap, unit, obstacle = contact.clearance_of(
        poses, world.boxes, world.polygons, world.sizes, world.circles, world.corners, math.inf
    )
    world.clearance[k] = gap
    if gap > 0.0:
        return RUNNING
    stop.unit, stop.obstacle, stop.gap = unit, obstacle, gap
    return COLLISION


def _has_delay(depth: int) -> bool:
    """Whether the sensors are delayed: the delay line (``loop.delay``, ``depth`` slots) holds
    more than this step's slot."""
    return depth > 1


def sense_step(k, row, loop, plant, law, target, log, stop):
    """The step's first half at step ``k``: measure the plant into ``log``'s ``row``, check
    it, add the noise and sensor faults, read the delay line, update the target and make the
    law's reference and nominal model; what the law sees into ``law.reading``. RUNNING, or the
    stop code (its details in ``stop``)."""
    lim, dt, noise, fault = loop.limits, loop.dt, loop.noise, loop.faults
    r, seen_by_law = law.reference[0], law.reading[0]
    n, phis = loop.n_trailers, law.phis
    steering = plant.steering
    t = k * dt
    rows = log.train[row]
    measurement = _sense(plant, n, rows)
    x, y, phi, beta, v, omega = (
        measurement[X],
        measurement[Y],
        measurement[PHI],
        measurement[BETA],
        measurement[V],
        measurement[OMEGA],
    )
    code = step.stop_code(x, v, omega, phi, beta, lim)
    if code != RUNNING:
        stop.v, stop.phi, stop.beta, stop.x, stop.y, stop.hitch = v, phi, beta, x, y, 1.0
        return code
    if n > 1:
        i = step.hitch_stop(rows, loop.hitch_limits, lim.jackknife_beta)
        if i >= 0:
            stop.v, stop.x, stop.y = v, x, y
            stop.phi, stop.beta = rows[i][ROW_PHI], rows[i][ROW_BETA]
            stop.hitch, stop.eta = i + 2.0, law.nominal_train.trailers[i + 1][2]
            return JACKKNIFE
    if len(loop.world.sizes):  # a world: no unit may touch an obstacle
        code = _touch(loop.world, k, measurement, rows, n, stop)
        if code != RUNNING:
            stop.v, stop.x, stop.y = v, x, y
            return code
    if len(noise):
        v_m = step.noisy(v, lim.noise_v, noise, 2 * k)
        w_m = step.noisy(omega, lim.noise_w, noise, 2 * k + 1)
    else:
        v_m, w_m = v, omega
    phi_m = phi
    if len(fault.dropouts):  # the sensor dropouts hold the last sample
        phi_m, v_m, w_m = faults.sensor_of(k, fault.dropouts, fault.held, phi, v_m, w_m)
    measured = log.measurement[row]
    for i in range(len(measured)):  # the Measurement tuple, in its field order
        measured[i] = measurement[i]
    # What the outer loops (sensed: no noise, no fault) and the law read: the readings of the
    # sensor delay's steps ago, or this step's
    sensed, sensed_rows = measured, rows
    if _has_delay(len(loop.delay.seen)):
        readings = (phi_m, v_m, w_m)
        sensed, sensed_rows, phi_m, v_m, w_m = _delayed(loop.delay, k, measurement, rows, readings)
    phis[0] = sensed[3]  # the hitch angles as sensed (trailers 2..N are never held)
    for i in range(n - 1):
        phis[i + 1] = sensed_rows[i][ROW_PHI]
    pose = (sensed[0], sensed[1], sensed[2])
    r.v_d, r.omega_d, r.v_d_dot, r.omega_d_dot = target_step.update_target(target, k, v_m, dt, pose)
    if target.cascade:  # backing up with the hitch cascade: the hitches set the yaw rate
        r.omega_d, r.omega_d_dot = target_step.cascade_step_of(
            target, sensed, sensed_rows, phis, v_m
        )
    state = target.state[0]
    r.t, r.s, r.kappa = t, state.s, state.kappa
    seen_by_law.phi, seen_by_law.v, seen_by_law.omega = phi_m, v_m, w_m
    if law.kind >= USER:  # a user's law sees the measurement with its noise
        seen = law.measurement_values
        for i in range(len(measured)):
            seen[i] = sensed[i]
        seen[PHI], seen[V], seen[OMEGA] = phi_m, v_m, w_m
        if law.kind == PYTHON:
            # and trailers 2..N; it makes its own model (the disturbance takes the nominal's
            # at the true hitch angles: actuate_step)
            seen_rows = law.measurement_rows
            for i in range(n - 1):
                seen_row, sensed_row = seen_rows[i], sensed_rows[i]
                for j in range(len(seen_row)):
                    seen_row[j] = sensed_row[j]
            return RUNNING
        r.x_ref, r.y_ref, r.theta_ref = target_step.law_pose_at(target, state.s)
    # The nominal model at the measurement, for the law and the matched disturbance
    return nominal_model_step(law, steering, phis, phi_m, v_m, w_m, n, stop)
    return RUNNING


def actuate_step(k, row, loop, plant, law, target, log, stop):
    """The step's second half at step ``k``, the law's request in ``law.reading``: clip it,
    apply the actuator faults, payloads and motors, add the disturbance, log ``row``, then
    (unless ``k`` is the last step) schedule the gains and advance the plant. RUNNING,
    FINISHED, PAYLOAD (the caller changes the reduced plant's constants, then advances) or the
    advance's stop code."""
    lim, dt, fault, c = loop.limits, loop.dt, loop.faults, law.nominal
    r, reading = law.reference[0], law.reading[0]
    n, phis, steering, state = loop.n_trailers, law.phis, plant.steering, target.state[0]
    t, v_m, w_m, phi_m = k * dt, reading.v, reading.omega, reading.phi
    measurement, rows = log.measurement[row], log.train[row]
    T_r = step.clip(reading.T_r, lim.torque_limit)
    T_l = step.clip(reading.T_l, lim.torque_limit)
    dist_r = dist_l = clipped = fx = fy = mz = 0.0
    if len(fault.actuators):  # the actuator faults scale the torques
        T_r, T_l = faults.fault_torque_of(k, fault.actuators, T_r, T_l)
    # the payloads placed at a time or an arc length; what the caller changes in the reduced
    # plant's constants
    pending = _place_payloads(k, state.s, fault, plant) if len(fault.payloads) else 0
    if loop.dc_motor:  # what the motors deliver of the command, over this step
        omegas = (measurement[WHEEL_RATES[0]], measurement[WHEEL_RATES[1]])
        T_r, T_l = motors.deliver_of(loop.motor, loop.motor_torques, (T_r, T_l), omegas)
    mass = (reading.M11, reading.M12, reading.M22)
    phi = measurement[PHI]
    depth = len(loop.delay.seen)
    moved = law.kind == PYTHON or model_steered(steering.kind, law.follows_steering)
    moved = moved or _has_delay(depth) or phi_m != phi
    if moved and (loop.disturbed or loop.wrench):
        phis[0] = phi  # the disturbance acts at the true hitch angles
        for i in range(n - 1):
            phis[i + 1] = rows[i][ROW_PHI]
        mass = nominal_mass(law, n, phi, phis, v_m, w_m)
    if loop.disturbed:
        a_v, a_w = disturbances.disturbance_at(loop, t, measurement[V], measurement[OMEGA])
        dist_r, dist_l = reduced.torque_for_force_of(mass, a_v, a_w, c.r, c.d)
        # What a disturbance of motor size can apply, per wheel: beyond it the paper's
        # g^-1 Delta (unbounded as g nears singular) would itself drive a jackknife.
        dist_r, dist_l, clipped = step.clip_pair(dist_r, dist_l, lim.disturbance_bound)
    elif loop.wrench:
        a_v, a_w = disturbances.disturbance_at(loop, t, measurement[V], measurement[OMEGA])
        force, torque = disturbances.wrench_of(mass, a_v, a_w)
        fx, fy, mz = plant_mujoco.chassis_wrench_of(force, torque, measurement[THETA])
    if stop.raised:  # the disturbance, called back, raised: this row is not logged
        return RAISED
    out = log.loop[row]
    out.s, out.v_d, out.omega_d = state.s, r.v_d, state.omega_ref
    out.v_d_dot, out.omega_d_dot, out.v_meas, out.omega_meas = (
        r.v_d_dot,
        r.omega_d_dot,
        v_m,
        w_m,
    )
    out.T_r, out.T_l, out.T_r_cmd, out.T_l_cmd = T_r, T_l, reading.u1, reading.u2
    out.dist_T_r, out.dist_T_l, out.kappa_d = dist_r, dist_l, state.kappa
    out.omega_d_tracked, out.dist_clipped = r.omega_d, clipped
    if steering.kind != 0:
        for i in range(n):
            log.etas[row][i] = steering.etas[i]
    out.t = t  # last: a row whose time is logged is whole (an interrupted CPython step's is not)
    stop.payloads = pending
    if k == loop.steps:
        return FINISHED
    if steering.kind == PATH_SCHEDULE:
        _offer_path(steering, target, measurement, rows, n)
        if stop.raised:  # the path, called back, raised
            return RAISED
        _steer(plant, law)
    elif steering.kind == CURVATURE_SCHEDULE and schedule.curvature_gains_of(
        state.kappa, steering.lengths, steering.offered
    ):
        _steer(plant, law)
    push = Push(dist_r, dist_l, loop.wrench, fx, fy, mz)
    if len(loop.wind.speeds):
        wind.gusts_step(loop.wind, k, measurement)
    if loop.ground.geoms.size:  # logged for step k; a failed advance is not handed back
        loop.ground.masks[k] = ground.ground_step(loop.ground, target)
    if stop.raised:  # the path, called back, raised: the plant does not advance
        return RAISED
    if pending:  # the caller changes the reduced plant's constants, then advances
        stop.T_r, stop.T_l, stop.dist_r, stop.dist_l = T_r, T_l, dist_r, dist_l
        return PAYLOAD
    return _advance(plant, T_r, T_l, push, loop.wind, stop)


def run_steps(k, k_end, loop, plant, law, target, log, stop_record):
    """Control steps ``k..k_end``: :func:`sense_step`, the law (:func:`law_step`),
    :func:`actuate_step`; ``(status, k)``: the step it stopped at, or ``k_end + 1`` to go on.
    Rows go to ``log`` from its row 0. The one loop of every episode: the kernel's chunk
    (:func:`tt_mujoco.sim.loop._kernel.run_chunk`) is this, compiled."""
    dt, limit = loop.dt, loop.limits.torque_limit
    stop, nominal, reading = stop_record[0], law.model[0], law.reading[0]
    row = 0
    while k <= k_end:
        code = sense_step(k, row, loop, plant, law, target, log, stop)
        if stop.raised:  # Python code called back by the kernel raised: its caller raises it
            return RAISED, k
        if code != RUNNING:
            return code, k
        status, T_r, T_l, u1, u2 = law_step(law, reading.v, reading.omega, dt, limit)
        if stop.raised:
            return RAISED, k
        if status != LAW_OK:
            stop.law_status = status
            stop.g11, stop.g12, stop.g21, stop.g22 = (
                nominal.g11,
                nominal.g12,
                nominal.g21,
                nominal.g22,
            )
            stop.u1, stop.u2 = u1, u2
            return LAW_FAILED, k
        reading.T_r, reading.T_l, reading.u1, reading.u2 = T_r, T_l, u1, u2
        code = actuate_step(k, row, loop, plant, law, target, log, stop)
        row += 1
        if code != RUNNING:
            return code, k
        k += 1
    return RUNNING, k


#: The step's functions that the kernel compiles without numba's reference counting (see
#: :mod:`tt_mujoco.sim.loop._kernel`), called as functions.
BORROWING = (
    advance_after_payload,
    target_step.path_at,
    target_step.pose_at,
    target_step.law_pose_at,
    disturbances.disturbance_at,
    _sense,
    _ode,
    target_step.update_target,
    target_step.target_step_of,
    target_step.cascade_step_of,
    law_step,
    nominal_model_step,
    _place_payloads,
    follow_train,
    nominal_mass,
    model_steered,
    step.first_singular_of,
    wind.blow_of,
    _advance,
    _offer_path,
    _steer,
    _delayed,
    ground.ground_step,
    wind.gusts_step,
    _touch,
    _has_delay,
)
#: The parts' step functions the kernel inlines where the step calls them (numba's inlining,
#: before typing): called, each would take the records it is given by value, at every step.
INLINED = (nominal_model_step, _place_payloads)
#: The step's halves, which the kernel inlines into its chunk loop (:func:`run_steps`):
#: called, each would take every record it is given by value, at every step.
HALVES = (sense_step, actuate_step)

"""What the compiled kernel compiles: the closed loop's step and the plain-number functions it
calls, the one list of them.

:mod:`tt_mujoco.sim._kernel` registers each of :data:`SHARED` and :data:`STEP` with numba, and
:func:`tt_mujoco.sim.compiled.source_digest` keys the compiled-code cache by the files they are
defined in: a function added here is compiled and watched with no second list to keep.
Importing this module imports no numba.
"""

from __future__ import annotations

import inspect

from tt_mujoco.analysis import nearest
from tt_mujoco.controllers import backing, base
from tt_mujoco.reference import feedback, path_base, paths, reverse, spline, targets
from tt_mujoco.sim import (
    closed_loop,
    disturbances,
    faults,
    ground,
    measure,
    motors,
    plant_mujoco,
    plant_reduced,
    records,
    schedule,
    step,
    wind,
)
from tt_mujoco.vehicle import params, path_schedule, reduced, rolling, steering, train

__all__ = ["LAWS", "RECORDS", "SHARED", "STEP", "source_files"]

#: The built-in laws (:data:`tt_mujoco.sim.closed_loop.LAWS`).
LAWS = closed_loop.LAWS

#: The closed loop's step (:mod:`tt_mujoco.sim.closed_loop`), which the kernel registers with
#: its own options.
STEP = (*closed_loop.BORROWING, *closed_loop.HALVES)

SHARED = (
    step.stop_code,
    step.noisy,
    step.clip,
    step.clip_pair,
    step.hitch_stop,
    measure.train_rows_of,
    plant_reduced.reduced_train_rows_of,
    train.tractor_pass,
    train._behind,
    train._beside,
    train.trailer_pass,
    train._masses,
    train._add,
    train.mass_and_bias_of,
    train.trailer_rates_of,
    train.poses_of,
    train.train_derivative_of,
    train.train_rk4_step_of,
    measure.yaw_from_quat,
    measure.measure_values,
    reduced.hitch_and_axle,
    reduced.phi_rate_of,
    reduced.rolling_rates_of,
    reduced.inertia_terms_of,
    reduced.coriolis_of,
    reduced.solve_dynamics_of,
    reduced.nominal_of,
    reduced.derivative_of,
    reduced.rk4_step_of,
    reduced.torque_for_force_of,
    reduced.trailer_speed_of,
    reduced.rk4_stage,
    reduced.rk4_combine,
    reduced.rk4_update,
    reduced.with_eta_of,
    plant_reduced.reduced_measure_values,
    targets.yaw_rate_targets,
    targets.travelled,
    path_base.arc_segment,
    spline.spline_curvature_of,
    spline.spline_pose_of,
    paths.arcs_curvature_of,
    paths.arcs_pose_of,
    paths.cycloid_pose_of,
    path_base.continued_pose,
    base.inverse_of,
    base.saturate_of,
    base.deepens,
    base.finite_pair,
    base.torques_of,
    *LAWS,
    paths.cycloid_curvature_and_rate,
    feedback.path_errors_of,
    feedback.feedback_of,
    feedback.curvature_and_rate_at,
    reverse.reverse_targets_of,
    rolling.hitch_rates_of,
    backing.steady_axle_curvature_of,
    backing.steady_solve_of,
    backing.cascade_of,
    disturbances.paper_disturbance_of,
    disturbances.wrench_of,
    plant_mujoco.chassis_wrench_of,
    plant_mujoco.aim_steering_of,
    schedule.gains_moved,
    faults.dropped_of,
    faults.sensor_of,
    faults.fault_torque_of,
    faults.payloads_of,
    motors.available_torque,
    motors.deliver_of,
    plant_mujoco.scale_body_of,
    ground.patch_contains_of,
    ground.wheel_frictions_of,
    wind.drag_force,
    wind.drag_moment,
    wind.wind_wrenches_of,
    schedule.curvature_gains_of,
    params.same_path_eta,
    params.train_same_path_etas_of,
    steering.wrap_angle,
    steering.same_path_geometry_of,
    steering.exact_same_path_eta_of,
    steering.exact_train_same_path_etas_of,
    steering.followed_gain_of,
    steering.followed_gains_of,
    steering.trailer_followed_gain_of,
    path_schedule.nearest_arc_length_of,
    path_schedule.bisect_right_of,
    path_schedule.hermite_of,
    path_schedule.blended_gain_of,
    path_schedule.table_eta_of,
    path_schedule.table_gain_of,
    path_schedule.signed_offset_of,
    path_schedule.record_driven_of,
    path_schedule.driven_offset_of,
    path_schedule.driven_steering_of,
    path_schedule.axle_gain_of,
    nearest.segment_distance2_of,
    nearest._better,
    nearest._beyond,
    nearest._chord_distance2,
    nearest._scan,
    nearest._rays,
    nearest.nearest_segment_of,
    nearest.nearest_segments_of,
)


#: The record types the kernel takes: their fields are part of its compiled signature.
RECORDS = (
    records.Limits,
    backing.CascadeConstants,
    records.LoopRecord,
    records.FaultRecord,
    records.WindRecord,
    records.DelayRecord,
    records.GroundRecord,
    wind.DragConstants,
    motors.MotorConstants,
    records.PlantRecord,
    records.SteeringRecord,
    records.MujocoRecord,
    records.LawRecord,
    records.TargetRecord,
    records.LogRecord,
    measure.Addresses,
    measure.Lengths,
    reduced.ModelConstants,
    train.TrainConstants,
)


def source_files() -> list[str]:
    """The files the shared functions and the record types are defined in, each once, in the
    order of their modules' names (so the same sources in another folder list alike); numba
    compiles the functions with their module's constants, so the whole file counts."""
    objects = (*SHARED, *STEP, *RECORDS)
    files = {obj.__module__: inspect.getsourcefile(obj) for obj in objects}
    return [files[module] for module in sorted(files)]

"""The target's part of the step: its path read from the target record (the arcs, the
cycloid, the fine cells, or a user's path called back), its speed and yaw-rate targets (paper
eqs. 32-34; backing up), the path feedback's correction and the hitch cascade's yaw rate.

Plain functions of numbers and the records (:mod:`tt_mujoco.sim.loop.records`'s
:class:`~tt_mujoco.sim.loop.records.TargetRecord`), which CPython runs and numba compiles
(:mod:`tt_mujoco.sim.loop.closed_loop` composes them into the step). The formulas are the parts':
:mod:`tt_mujoco.reference.targets`, :mod:`~tt_mujoco.reference.reverse`,
:mod:`~tt_mujoco.reference.feedback`, :mod:`tt_mujoco.controllers.backing`.
"""

from __future__ import annotations

import math

from tt_mujoco.compiled_form import compiled_form
from tt_mujoco.controllers import backing
from tt_mujoco.reference import feedback, path_base, paths, reverse, spline, targets
from tt_mujoco.reference.path_base import ARCS_PATH, HOOKED_PATH, SPLINE_PATH
from tt_mujoco.sim.parts.measure import OMEGA, ROW_THETA0, ROW_X0, ROW_Y0, THETA0, X0, Y0

__all__ = [
    "HOOK_CURVATURE",
    "HOOK_LAW_POSE",
    "HOOK_POSE",
    "cascade_step_of",
    "law_pose_at",
    "path_at",
    "pose_at",
    "target_step_of",
    "update_target",
]

#: What the kernel asks of a path it calls back (:mod:`tt_mujoco.sim.loop._kernel`, ``HOOK``): its
#: curvature and its rate, its pose, its pose as a plain-number law's reference
HOOK_CURVATURE, HOOK_POSE, HOOK_LAW_POSE = 0.0, 1.0, 2.0
#: where the speed profile's arc length, speed and acceleration are in a target's profile row
S_REF, V_REF, A_REF = 0, 1, 2


def path_at(target, s):
    """``(kappa, dkappa/ds)`` of the target's path at ``s``."""
    if target.path_kind == ARCS_PATH:
        return paths.arcs_curvature_of(s, target.bounds, target.kappas)
    if target.path_kind == SPLINE_PATH:
        bounds, cells = target.bounds, target.cells
        return spline.spline_curvature_of(s, target.length, target.kappa_ends, bounds, cells)
    if target.path_kind == HOOKED_PATH:
        return hooked_curvature(target, s)
    return paths.cycloid_curvature_and_rate(s)


def pose_at(target, s):
    """The path's pose at ``s`` (ReferencePath.pose_at)."""
    if target.path_kind == HOOKED_PATH:
        return hooked_pose(target, s)
    bounds = target.bounds
    clipped = min(max(s, 0.0), target.length)
    if target.path_kind == ARCS_PATH:
        x, y, heading = paths.arcs_pose_of(clipped, bounds, target.kappas, target.starts)
    elif target.path_kind == SPLINE_PATH:
        x, y, heading = spline.spline_pose_of(clipped, bounds, target.pose_cells)
    else:
        x, y, heading = paths.cycloid_pose_of(clipped)
    return path_base.continued_pose(s, clipped, x, y, heading)


def law_pose_at(target, s):
    """The path's pose at ``s`` as a plain-number law's reference (:func:`pose_at`)."""
    if target.path_kind == HOOKED_PATH:
        return hooked_law_pose(target, s)
    return pose_at(target, s)


@compiled_form("the path's Python code called back through a C function (HookCallback)")
def hooked_curvature(target, s):
    """``(kappa, dkappa/ds)`` of a path without closed form (:data:`HOOKED_PATH`), from the
    path object itself (the kernel calls it back: ``stop.raised`` says when it raised)."""
    return target.path_hook.curvature_and_rate(s)


@compiled_form("the path's Python code called back through a C function (HookCallback)")
def hooked_pose(target, s):
    """The pose of a path without closed form at ``s`` (ReferencePath.pose_at)."""
    return target.path_hook.pose_at(s)


@compiled_form("the path's Python code called back through a C function (HookCallback)")
def hooked_law_pose(target, s):
    """:func:`hooked_pose` asked for a plain-number law's reference: when the path fails there,
    the law fails, as its Python form does when it asks the path itself (only the kernel runs
    a plain-number law from the step's records)."""
    return target.path_hook.pose_at(s)


def update_target(target, k, v_m, dt, pose):
    """The target's step ``k``: :func:`target_step_of` on the speed profile's row ``k`` (its
    three numbers, not the row: a view of the table, passed on, is made at every step)."""
    row = target.profile[k]
    return target_step_of(target, (row[S_REF], row[V_REF], row[A_REF]), v_m, dt, pose)


def target_step_of(target, reference, v_m, dt, pose):
    """One step of the target (:class:`~tt_mujoco.reference.targets.StaticTarget`, eq. 32;
    :class:`~tt_mujoco.reference.targets.DynamicTarget`, eqs. 33-34; backing up,
    :class:`~tt_mujoco.reference.reverse.ReverseTarget`; with
    :class:`~tt_mujoco.reference.feedback.PathFeedback` at the measured ``pose``) for the
    speed profile's ``reference = (s_ref, v_ref, a_ref)`` and the measured speed ``v_m``, the
    control period ``dt`` after the last: ``(v_d, omega_d, v_d_dot, omega_d_dot)``, the
    target record's state updated in place."""
    state = target.state[0]
    s_ref, v_ref, a_ref = reference
    if target.reverse:
        v = -v_ref
        if target.dynamic:
            v = v_m
            if not math.isnan(state.v_prev):
                state.s = targets.travelled(state.s, state.v_prev, v, dt)
            state.v_prev = v
        else:
            state.s = target.s_end - s_ref
        kappa, rate = path_at(target, state.s)
        v_ref, omega_d, a_ref, omega_d_dot = reverse.reverse_targets_of(
            kappa, rate, v, v_ref, a_ref
        )
    elif target.dynamic:
        if not math.isnan(state.v_prev):
            state.s = targets.travelled(state.s, state.v_prev, v_m, dt)
        state.v_prev = v_m
        kappa, rate = path_at(target, state.s)
        omega_d, omega_d_dot = targets.yaw_rate_targets(kappa, rate, v_m, a_ref)
    else:
        kappa, rate = path_at(target, s_ref)
        state.s = s_ref
        omega_d, omega_d_dot = targets.yaw_rate_targets(kappa, rate, v_ref, a_ref)
    state.kappa = kappa
    state.omega_ref = omega_d
    if target.feedback or target.along_gain > 0.0:
        s_near, e_y, e_psi = feedback.path_errors_of(
            target, state.s_near, pose[0], pose[1], pose[2]
        )
        state.s_near, state.e_y, state.e_psi = s_near, e_y, e_psi
    if target.along_gain > 0.0:  # where the profile puts the tractor, less where it is
        nominal = target.s_end - s_ref if target.reverse else s_ref
        v_ref += target.along_gain * (nominal - state.s_near)
    if target.feedback:
        state.kappa_near = path_at(target, state.s_near)[0]
        e_y, e_psi = state.e_y, state.e_psi
        omega_d, omega_d_dot = feedback.feedback_of(
            target.feedback_gains,
            (omega_d, a_ref, omega_d_dot),
            v_m,
            (e_y, e_psi),
            state.kappa_near,
        )
    return v_ref, omega_d, a_ref, omega_d_dot


def cascade_step_of(target, measurement, rows, phis, v_m):
    """One step of the hitch cascade (:class:`~tt_mujoco.controllers.backing.HitchCascade`):
    ``(omega_d, omega_d_dot)`` at the ``measurement``, the train's ``rows`` and the measured
    hitch angles ``phis``; the target record's state updated in place."""
    n = len(phis)
    if n == 1:
        lead = (measurement[X0], measurement[Y0], measurement[THETA0])
    else:
        lead = (rows[n - 2][ROW_X0], rows[n - 2][ROW_Y0], rows[n - 2][ROW_THETA0])
    state = target.state[0]
    s, e_y, e_psi, omega_d = backing.cascade_of(
        target.cascade_constants, target, phis, lead, (v_m, measurement[OMEGA]), state.s_lead,
        target.wanted, target.rates,
    )  # fmt: skip
    state.s_lead, state.e_y, state.e_psi = s, e_y, e_psi
    return omega_d, 0.0

"""The numba side of :mod:`tt_mujoco.sim.compiled`: imported only when an episode runs compiled.

It is imported from a copy of this file inside the compiled-code cache
(:func:`tt_mujoco.sim.compiled.kernel`), so that numba's own cache, which checks the source
file's path and time stamp, stays valid for every checkout of the same sources.

The shared plain-number functions are registered with numba here, so the chunk loop below
compiles them from their own source; the loop itself only sequences them as
:class:`tt_mujoco.sim.stepper.Stepper` does (sense, law, actuate, log, advance).
"""

from __future__ import annotations

import math
import os

import mujoco
import numpy as np
from llvmlite import binding
from numba import njit, types
from numba.extending import register_jitable

from tt_mujoco.controllers import base, fbl, ismc_sta, pid
from tt_mujoco.reference import paths
from tt_mujoco.sim import disturbances, measure, plant_reduced
from tt_mujoco.sim.kernel_sources import SHARED
from tt_mujoco.vehicle import reduced

for _fn in SHARED:
    register_jitable(_fn)

measure_values = measure.measure_values
reduced_measure_values = plant_reduced.reduced_measure_values
inertia_terms_of = reduced.inertia_terms_of
coriolis_of = reduced.coriolis_of
solve_dynamics_of = reduced.solve_dynamics_of
torque_for_force_of = reduced.torque_for_force_of
rolling_rates_of = reduced.rolling_rates_of
rk4_stage = reduced.rk4_stage
rk4_combine = reduced.rk4_combine
ismc_sta_law = ismc_sta.ismc_sta_law
pid_law = pid.pid_law
fbl_law = fbl.fbl_law
cycloid_curvature_and_rate = paths.cycloid_curvature_and_rate
paper_disturbance_of = disturbances.paper_disturbance_of
COS_BETA_MIN = reduced.COS_BETA_MIN
LAW_OK, LAW_SINGULAR = base.LAW_OK, base.LAW_SINGULAR

# mj_step by its symbol in MuJoCo's library, which the Python bindings load: no pointer is
# baked into the compiled code, so it can be cached on disk.
_LIB = [f for f in os.listdir(os.path.dirname(mujoco.__file__)) if f.startswith("libmujoco.so")]
binding.load_library_permanently(os.path.join(os.path.dirname(mujoco.__file__), _LIB[0]))
mj_step = types.ExternalFunction("mj_step", types.void(types.voidptr, types.voidptr))

_RUNNING, _FINISHED, _BLEW_UP, _JACKKNIFE, _WARNING, _LAW_FAILED, _SINGULAR = range(7)


@njit(cache=True)
def _curvature(s, path_kind, bounds, kappas):
    if path_kind == 0:
        # bisect.bisect_right, as ArcsPath.curvature_and_rate
        return kappas[np.searchsorted(bounds, s, side="right")], 0.0
    return cycloid_curvature_and_rate(s)


@njit(cache=True)
def _derivative(y, T_r, T_l, pc, r, d, out):
    """ReducedPlant.derivative (no disturbance): False at the singularity."""
    theta, phi, v, omega = y[2], y[3], y[6], y[7]
    eta = pc[0]
    if math.cos(eta * phi) < COS_BETA_MIN:
        return False
    terms = inertia_terms_of(phi, pc[0], pc[1], pc[2], pc[3], pc[4], pc[5], pc[6], pc[7], pc[8])
    mass, bias = coriolis_of(terms, pc[9], v, omega)
    f1, f2, g11, g12, g21, g22 = solve_dynamics_of(mass, bias, r, d)
    rates = rolling_rates_of(theta, phi, v, omega, eta, pc[1], pc[2], r, d)
    for i in range(6):
        out[i] = rates[i]
    out[6] = f1 + g11 * T_r + g12 * T_l + 0.0
    out[7] = f2 + g21 * T_r + g22 * T_l + 0.0
    return True


@njit(cache=True)
def _rk4(y, T_r, T_l, pc, r, d, info):
    """ReducedPlant.step: y advanced in place by pc[10]; False (info: phi, eta) if singular."""
    dt = pc[10]
    k1, k2, k3, k4 = np.empty(8), np.empty(8), np.empty(8), np.empty(8)
    if not _derivative(y, T_r, T_l, pc, r, d, k1):
        info[0], info[1] = y[3], pc[0]
        return False
    stage = rk4_stage(y, k1, 0.5 * dt)
    if not _derivative(stage, T_r, T_l, pc, r, d, k2):
        info[0], info[1] = stage[3], pc[0]
        return False
    stage = rk4_stage(y, k2, 0.5 * dt)
    if not _derivative(stage, T_r, T_l, pc, r, d, k3):
        info[0], info[1] = stage[3], pc[0]
        return False
    stage = rk4_stage(y, k3, dt)
    if not _derivative(stage, T_r, T_l, pc, r, d, k4):
        info[0], info[1] = stage[3], pc[0]
        return False
    new = rk4_combine(y, k1, k2, k3, k4, dt / 6.0)
    for i in range(8):
        y[i] = new[i]
    return True


@njit(cache=True, nogil=True)
def run_chunk(
    k,
    k_end,
    mujoco_plant,
    pointers,
    qpos,
    qvel,
    ctrl,
    qfrc,
    warnings,
    layout,
    lengths,
    ode_state,
    plant_consts,
    consts,
    gamma,
    law_kind,
    gains,
    law,
    path_kind,
    bounds,
    kappas,
    dynamic,
    profile,
    target_state,
    noise,
    limits,
    scalars,
    meas,
    loop,
    info,
):
    """Control steps ``k..k_end`` (Stepper.sense, the law, Stepper.actuate); returns
    ``(status, k)``: the step it stopped at, or ``k_end + 1`` to go on."""
    dt, substeps, steps, max_speed, r_n, d_n = (
        scalars[0],
        int(scalars[1]),
        int(scalars[2]),
        scalars[3],
        scalars[4],
        scalars[5],
    )
    lim, bound, jk, jk_phi, noise_v, noise_w = (
        limits[0],
        limits[1],
        limits[2],
        limits[3],
        limits[4],
        limits[5],
    )
    disturbed, anti_windup = limits[6] != 0.0, limits[7] != 0.0
    L, L0, r, d = lengths[0], lengths[1], lengths[2], lengths[3]
    eta_n = consts[0]
    row = 0
    while k <= k_end:
        t = k * dt
        if mujoco_plant:
            me = measure_values(
                qpos,
                qvel,
                layout[0],
                layout[1],
                layout[2],
                layout[3],
                layout[4],
                layout[5],
                layout[6],
                layout[7],
                layout[8],
                L,
                L0,
                r,
                d,
            )
        else:
            me = reduced_measure_values(ode_state, plant_consts[0], L, L0, r, d)
        x, y, phi, beta, v, omega = me[0], me[1], me[3], me[4], me[5], me[6]
        if not (math.isfinite(x) and math.isfinite(v) and math.isfinite(omega)) or (
            abs(v) > max_speed
        ):
            info[0] = v
            return _BLEW_UP, k
        if abs(phi) >= jk_phi or abs(beta) >= jk:
            info[0], info[1], info[2], info[3], info[4] = phi, beta, x, y, v
            return _JACKKNIFE, k
        if noise.size:
            v_m = v + noise_v * noise[2 * k]
            w_m = omega + noise_w * noise[2 * k + 1]
        else:
            v_m, w_m = v, omega
        # The target (StaticTarget.update / DynamicTarget.update).
        if dynamic:
            if not math.isnan(target_state[1]):
                target_state[0] += 0.5 * (target_state[1] + v_m) * dt
            target_state[1] = v_m
            v_ref, a_ref = profile[k, 1], profile[k, 2]
            kappa, rate = _curvature(target_state[0], path_kind, bounds, kappas)
            v_d, w_d, v_d_dot, w_d_dot = v_ref, kappa * v_m, a_ref, rate * v_m * v_m + kappa * a_ref
        else:
            s_ref, v_ref, a_ref = profile[k, 0], profile[k, 1], profile[k, 2]
            kappa, rate = _curvature(s_ref, path_kind, bounds, kappas)
            target_state[0] = s_ref
            v_d, w_d = v_ref, kappa * v_ref
            v_d_dot, w_d_dot = a_ref, rate * v_ref * v_ref + kappa * a_ref
        target_state[2] = kappa
        # The law on the nominal model.
        if math.cos(eta_n * phi) < COS_BETA_MIN:
            info[0], info[1], info[2] = 0.0, phi, eta_n
            return _LAW_FAILED, k
        terms = inertia_terms_of(
            phi, consts[0], consts[1], consts[2], consts[3], consts[4], consts[5], consts[6],
            consts[7], consts[8],
        )  # fmt: skip
        mass, bias = coriolis_of(terms, gamma, v_m, w_m)
        f1, f2, g11, g12, g21, g22 = solve_dynamics_of(mass, bias, r_n, d_n)
        state = (law[0], law[1], law[2], law[3], law[4], law[5], law[6], law[7])
        args = (dt, v_m, w_m, v_d, w_d, v_d_dot, w_d_dot, f1, f2, g11, g12, g21, g22, state, gains)
        if law_kind == 0:
            out = ismc_sta_law(*args, lim, law[8] != 0.0, anti_windup)
        elif law_kind == 1:
            out = pid_law(*args, lim, law[8] != 0.0, anti_windup)
        else:
            out = fbl_law(*args, lim, law[8] != 0.0, anti_windup)
        status, T_r, T_l, u1, u2, saturated, aux1, aux2, state = out
        law[9], law[10] = aux1, aux2
        for i in range(8):
            law[i] = state[i]
        if status != LAW_OK:
            info[0] = status
            if status == LAW_SINGULAR:
                info[1], info[2], info[3], info[4] = g11, g12, g21, g22
            else:
                info[1], info[2] = u1, u2
            return _LAW_FAILED, k
        law[8] = 1.0 if saturated else 0.0
        # Stepper.actuate
        T_r = -lim if T_r < -lim else (lim if T_r > lim else T_r)
        T_l = -lim if T_l < -lim else (lim if T_l > lim else T_l)
        dist_r = dist_l = 0.0
        clipped = 0.0
        if disturbed:
            a_v, a_w = paper_disturbance_of(t)
            dist_r, dist_l = torque_for_force_of(terms[0], a_v, a_w, r_n, d_n)
            if abs(dist_r) > bound or abs(dist_l) > bound:
                dist_r = max(-bound, min(bound, dist_r))
                dist_l = max(-bound, min(bound, dist_l))
                clipped = 1.0
        for i in range(19):
            meas[row, i] = me[i]
        out = (t, target_state[0], v_d, w_d, v_d_dot, w_d_dot, v_m, w_m, T_r, T_l, u1, u2)
        for i in range(12):
            loop[row, i] = out[i]
        loop[row, 12], loop[row, 13], loop[row, 14] = dist_r, dist_l, kappa
        loop[row, 15], loop[row, 16] = w_d, clipped
        row += 1
        if k == steps:
            return _FINISHED, k
        if mujoco_plant:
            ctrl[layout[9]] = T_r
            ctrl[layout[10]] = T_l
            qfrc[layout[6]] = dist_r
            qfrc[layout[5]] = dist_l
            for _ in range(substeps):
                mj_step(pointers[0], pointers[1])
            for i in range(warnings.size):
                if warnings[i] != 0:
                    info[0] = i
                    return _WARNING, k
        else:
            for _ in range(substeps):
                if not _rk4(ode_state, T_r + dist_r, T_l + dist_l, plant_consts, r, d, info):
                    return _SINGULAR, k
        k += 1
    return _RUNNING, k

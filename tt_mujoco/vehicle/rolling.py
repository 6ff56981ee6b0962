"""The pure-rolling chain alone: a tractor driven exactly along a path, its trailers following by
kinematics only (no masses, no controller, no plant), for checking steering schedules.

Each trailer is a rod from its hitch O_k to its axle midpoint P_k (length L0_k); the hitch is a
distance L_k behind the unit ahead, along that unit's heading. The axle rolls without slip in
the direction ``theta_k + beta_k``. Writing n(a) = (-sin a, cos a), the axle's velocity is
``V_P = V_O - L0 theta_k_dot n(theta_k)``; no side slip, ``V_P . n(theta_k + beta_k) = 0``, gives

    theta_k_dot = V_O . n(theta_k + beta_k) / (L0_k cos beta_k),

and the next hitch moves with ``V_P - L_{k+1} theta_k_dot n(theta_k)``. This is derived here
from the rod geometry alone, independently of :mod:`tt_mujoco.vehicle.train`, so a schedule
checked with it is checked against the rolling constraint itself (docs/model.md Section 13).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from tt_mujoco.vehicle.path_schedule import nearest_arc_length

__all__ = [
    "constant_steering",
    "drive_along_path",
    "hitch_rates",
    "hitch_rates_of",
    "schedule_steering",
]


def _rates(path, s, thetas, lengths, steering, arcs, v):
    """Heading rates of every trailer, their axles (x, y) and the axles' arc lengths."""
    x, y, heading = path.pose_at(s)
    kappa = path.curvature_and_rate(s)[0]
    px, py = x, y
    vx, vy = v * math.cos(heading), v * math.sin(heading)
    front, front_rate = heading, kappa * v
    rates, axles, axle_arcs = [], [], []
    for k, ((L, L0), theta) in enumerate(zip(lengths, thetas, strict=True)):
        ox, oy = px - L * math.cos(front), py - L * math.sin(front)
        vox = vx + L * front_rate * math.sin(front)
        voy = vy - L * front_rate * math.cos(front)
        px, py = ox - L0 * math.cos(theta), oy - L0 * math.sin(theta)
        s_axle = nearest_arc_length(path, arcs[k], px, py)
        beta = steering(k, s_axle, front - theta)
        rate = (-vox * math.sin(theta + beta) + voy * math.cos(theta + beta)) / (
            L0 * math.cos(beta)
        )
        vx = vox + L0 * rate * math.sin(theta)
        vy = voy - L0 * rate * math.cos(theta)
        rates.append(rate)
        axles.append((px, py))
        axle_arcs.append(s_axle)
        front, front_rate = theta, rate
    return np.array(rates), axles, axle_arcs


def drive_along_path(
    path, lengths, steering: Callable, step: float = 0.002, speed: float = 1.0
) -> dict[str, np.ndarray]:
    """Drive P exactly along ``path`` from s = 0 to its end, trailers straight behind at first.

    Parameters
    ----------
    path : ReferencePath
        The tractor's path (continued along its first tangent before s = 0).
    lengths : sequence of (L_k, L0_k)
        Trailers 1..N (m).
    steering : callable
        ``steering(k, s_axle, phi) -> beta``: trailer ``k``'s (from 0) steering angle (rad)
        when its axle is at arc length ``s_axle`` (the nearest point of the path) with hitch
        angle ``phi``. :func:`schedule_steering` and :func:`constant_steering` make the two
        usual ones.
    step : float
        Largest arc-length step of the classical Runge-Kutta integration (m).
    speed : float
        The tractor's speed (m/s); the paths are geometric, so it only scales time.

    Returns
    -------
    dict
        ``s`` (the tractor's arc length at each sample) and per trailer k (from 1) arrays
        ``x_k``, ``y_k`` (its axle), ``s_k`` (the axle's arc length) and ``offset_k``: the
        axle's signed distance from the path there (m, + left), NaN while the axle is still
        behind the path's start.
    """
    heading = path.pose_at(0.0)[2]
    n = max(1, math.ceil(path.length / step))
    h = path.length / n
    thetas = np.full(len(lengths), heading)
    arcs = list(-np.cumsum([L + L0 for L, L0 in lengths]))  # straight behind, on the tangent
    out_s = np.empty(n + 1)
    out = np.empty((n + 1, len(lengths), 3))
    s = 0.0
    for i in range(n + 1):
        k1, axles, arcs = _rates(path, s, thetas, lengths, steering, arcs, speed)
        out_s[i] = s
        out[i, :, :2] = axles
        out[i, :, 2] = arcs
        if i == n:
            break
        stage = thetas + h / 2 * k1 / speed
        k2 = _rates(path, s + h / 2, stage, lengths, steering, arcs, speed)[0]
        stage = thetas + h / 2 * k2 / speed
        k3 = _rates(path, s + h / 2, stage, lengths, steering, arcs, speed)[0]
        k4 = _rates(path, s + h, thetas + h * k3 / speed, lengths, steering, arcs, speed)[0]
        thetas = thetas + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4) / speed
        s += h
    result = {"s": out_s}
    for k in range(len(lengths)):
        ax, ay, sk = out[:, k, 0], out[:, k, 1], out[:, k, 2]
        fx, fy, tangent = path.pose(sk)
        offset = -(ax - fx) * np.sin(tangent) + (ay - fy) * np.cos(tangent)
        result[f"x_{k + 1}"], result[f"y_{k + 1}"], result[f"s_{k + 1}"] = ax, ay, sk
        result[f"offset_{k + 1}"] = np.where(sk >= 0.0, offset, np.nan)
    return result


def constant_steering(etas) -> Callable:
    """The passive law beta_k = eta_k phi_k with constant gains (a sequence, trailer 1 first)."""
    gains = [float(e) for e in etas]
    return lambda k, s_axle, phi: gains[k] * phi


def schedule_steering(schedule) -> Callable:
    """The path schedule's law beta_k = eta_k phi_k with the gain of the axle's own arc length
    and hitch angle, as the running plant applies it
    (:meth:`tt_mujoco.vehicle.path_schedule.PathSchedule.gain`)."""
    return lambda k, s_axle, phi: schedule.gain(k, s_axle, phi) * phi


def hitch_rates(phis, v: float, omega: float, lengths, etas) -> list[tuple[float, float, float]]:
    """``(phi_k_dot, v_k, theta_k_dot)`` of every trailer from the tractor's ``(v, omega)``:
    velocities only, in the tractor's frame (the same values as
    :func:`tt_mujoco.vehicle.train.trailer_rates`, without its accelerations, for per-step use
    in controllers).

    Parameters
    ----------
    phis : sequence of float
        Hitch angles phi_1..phi_N (rad).
    v, omega : float
        The tractor's speed (m/s, negative reversing) and yaw rate (rad/s).
    lengths : sequence of (L_k, L0_k)
    etas : sequence of float
        The steering gains (beta_k = eta_k phi_k).
    """
    if not len(lengths) == len(phis) == len(etas):
        raise ValueError(
            f"{len(phis)} hitch angles, {len(lengths)} lengths and {len(etas)} gains are not "
            "allowed: give one of each per trailer"
        )
    out = [[0.0, 0.0, 0.0] for _ in phis]
    hitch_rates_of(phis, (v, omega), lengths, etas, out)
    return [tuple(row) for row in out]


def hitch_rates_of(phis, speeds, lengths, etas, out) -> None:
    """:func:`hitch_rates` of the tractor's ``speeds = (v, omega)`` into the rows of ``out``
    (the compiled episode shares it)."""
    heading, (vx, rate), vy = 0.0, speeds, 0.0
    for k in range(len(phis)):
        L, L0, phi, eta = lengths[k][0], lengths[k][1], phis[k], etas[k]
        c, s = math.cos(heading), math.sin(heading)
        ox, oy = vx + L * rate * s, vy - L * rate * c  # the hitch, L behind along the heading
        theta = heading - phi
        beta = eta * phi
        cos_beta = math.cos(beta)
        alpha = theta + beta
        v_k = (ox * math.cos(theta) + oy * math.sin(theta)) / cos_beta
        theta_dot = (-ox * math.sin(alpha) + oy * math.cos(alpha)) / (L0 * cos_beta)
        out[k][0], out[k][1], out[k][2] = rate - theta_dot, v_k, theta_dot
        # the axle: the hitch's velocity minus the drawbar's rotation
        vx = ox + L0 * theta_dot * math.sin(theta)
        vy = oy - L0 * theta_dot * math.cos(theta)
        heading, rate = theta, theta_dot

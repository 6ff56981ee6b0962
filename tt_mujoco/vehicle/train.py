"""The reduced model of a train of N passively steered off-axle trailers (docs/model.md Section 12).

Generalised coordinates ``q = (x, y, theta, phi_1..phi_N, theta_l, theta_r)``, velocities
``V = (v, omega)`` as for one trailer. Trailer k's hitch O_k is fixed to the body in front of it:
``O_1 = P - L_1 e(theta)``, ``O_k = P_(k-1) - L_k e(theta_(k-1))``; its axle midpoint is
``P_k = O_k - L0_k e(theta_k)`` with ``theta_k = theta_(k-1) - phi_k``, and P_k rolls along
``alpha_k = theta_k + beta_k``, ``beta_k = eta_k phi_k``, without side slip.

**Kinematics by recursion.** Writing O_k's velocity as P_k's rolling velocity plus the drawbar's
rotation, ``v_Ok = v_k e(alpha_k) + L0_k theta_k_dot e_perp(theta_k)``, and projecting on
``e(theta_k)`` and ``e_perp(alpha_k)`` gives

    v_k = v_Ok . e(theta_k) / cos(beta_k),
    theta_k_dot = v_Ok . e_perp(alpha_k) / (L0_k cos(beta_k)).

The same projection of the accelerations gives ``v_k_dot`` and ``theta_k_ddot``. One pass down
the chain (:func:`tractor_pass`, then :func:`trailer_pass` per trailer) therefore yields every
body's velocity and acceleration, both linear in ``(V, V_dot)`` plus a velocity-product part.

**Dynamics body by body.** With each body's centre velocity ``A_b V`` and rotation (yaw or wheel
spin) ``c_b V``, Kane's equations are ``sum_b A_b^T m_b a_b + c_b^T I_b c_b_dot = B tau``, so

    Mbar = sum_b m_b A_b^T A_b + I_b c_b^T c_b,    Cbar V = sum_b m_b A_b^T a_b|_(V_dot = 0) + ...

which :func:`mass_and_bias_of` evaluates from three passes made side by side (V = e_1, V = e_2,
and the state's V with V_dot = 0), body by body; :func:`kinetic_energy` sums the same bodies
from their list (:func:`_chain`). The ``*_of`` functions take plain numbers
(:class:`TrainConstants`), so that the compiled episode runs them from this source. For N = 1
this equals the closed form of :mod:`tt_mujoco.vehicle.reduced` to round-off
(``tests/test_train.py``), which the single-trailer code keeps using.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from tt_mujoco.vehicle.params import Params
from tt_mujoco.vehicle.reduced import (
    COS_BETA_MIN,
    ReducedPlant,
    SingularityError,
    solve_dynamics,
    solve_dynamics_of,
    torque_for_force,
)

__all__ = [
    "TrainODE",
    "dynamics_scalar",
    "kinetic_energy",
    "mass_and_bias",
    "matched_torque",
    "poses",
    "rates",
    "trailer_rates",
]


class TrainConstants(NamedTuple):
    """A train's constants as plain numbers: the tractor's, and one row per trailer of
    :data:`TRAILER_ROW` (a tuple of tuples here, a float array in the compiled episode)."""

    Mf: float
    Mw: float
    Ifd: float
    Iwd: float
    Iw: float
    r: float
    d: float
    trailers: tuple


#: The columns of :attr:`TrainConstants.trailers`.
TRAILER_ROW = ("L", "L0", "eta", "Mc1", "Ic1", "Mc2", "Mr", "Ird", "Ic2")


def train_constants(p: Params) -> TrainConstants:
    """The :class:`TrainConstants` of ``p`` (cached on ``p``, which is frozen)."""
    cached = p.__dict__.get("_train_constants")
    if cached is None:
        rows = tuple(tuple(float(getattr(t, name)) for name in TRAILER_ROW) for t in p.trailers)
        cached = TrainConstants(p.Mf, p.Mw, p.Ifd, p.Iwd, p.Iw, p.r, p.d, rows)
        object.__setattr__(p, "_train_constants", cached)
    return cached


def _behind(point, turn, dist):
    """Velocity and acceleration ``(vx, vy, ax, ay)`` of the point ``dist`` behind a body's
    reference point moving as ``point``, along its heading ``turn = (cos, sin, w, w_dot)``."""
    vx, vy, ax, ay = point
    c, s, w, w_dot = turn
    return (
        vx + dist * w * s,
        vy - dist * w * c,
        ax + dist * w_dot * s + dist * w * w * c,
        ay - dist * w_dot * c + dist * w * w * s,
    )


def _beside(point, turn, offset):
    """As :func:`_behind`, for the point ``offset`` to the left (along ``e_perp``)."""
    vx, vy, ax, ay = point
    c, s, w, w_dot = turn
    return (
        vx - offset * w * c,
        vy - offset * w * s,
        ax - offset * w_dot * c + offset * w * w * s,
        ay - offset * w_dot * s - offset * w * w * c,
    )


def tractor_pass(theta: float, V, h: float):
    """The tractor's point P moving with ``V = (v, omega, v_dot, omega_dot)`` at heading
    ``theta``: ``(P, turn, wheel_left, wheel_right, spin rates)``, the spin rates being the
    two wheels' ``(v -+ h omega, v_dot -+ h omega_dot)``."""
    v, omega, v_dot, omega_dot = V
    c, s = math.cos(theta), math.sin(theta)
    point = (v * c, v * s, v_dot * c - v * omega * s, v_dot * s + v * omega * c)
    turn = (c, s, omega, omega_dot)
    spins = (v - h * omega, v_dot - h * omega_dot, v + h * omega, v_dot + h * omega_dot)
    return point, turn, _beside(point, turn, h), _beside(point, turn, -h), spins


def trailer_pass(front, heading, row, phi: float, h: float):
    """One trailer behind the body in front (its reference point moving as ``front``, its
    ``heading = (theta, w, w_dot)``), trailer constants ``row`` (:data:`TRAILER_ROW`) and
    hitch angle ``phi``: ``(ok, bodies, rates, next_heading)``.

    ``bodies`` is the front rod, the drawbar, the axle midpoint and its two wheels, each
    ``(vx, vy, ax, ay)``; ``rates`` is ``(phi_dot, v_k, w_k, w_k_dot, alpha_dot, alpha_ddot,
    v_k_dot)``;
    ``ok`` is False at the singularity cos(beta_k) < COS_BETA_MIN (everything else zero).
    """
    L, L0, eta = row[0], row[1], row[2]
    fth, fw, fwd = heading
    front_turn = (math.cos(fth), math.sin(fth), fw, fwd)
    rod = _behind(front, front_turn, 0.5 * L)
    hitch = _behind(front, front_turn, L)
    ovx, ovy, oax, oay = hitch
    thk = fth - phi
    beta = eta * phi
    cb = math.cos(beta)
    zero = (0.0, 0.0, 0.0, 0.0)
    if cb < COS_BETA_MIN:
        return False, (zero, zero, zero, zero, zero), (0.0,) * 7, (0.0, 0.0, 0.0)
    ck, sk = math.cos(thk), math.sin(thk)
    ca, sa = math.cos(thk + beta), math.sin(thk + beta)
    vk = (ovx * ck + ovy * sk) / cb
    wk = (-ovx * sa + ovy * ca) / (L0 * cb)
    phi_dot = fw - wk
    alpha_dot = wk + eta * phi_dot
    # Accelerations: a_O = vk_dot e(alpha) + vk alpha_dot n(alpha) + L0 wk_dot n(thk)
    # - L0 wk^2 e(thk); project the remainder as for the velocities.
    rx = oax + vk * alpha_dot * sa + L0 * wk * wk * ck
    ry = oay - vk * alpha_dot * ca + L0 * wk * wk * sk
    vk_dot = (rx * ck + ry * sk) / cb
    wk_dot = (-rx * sa + ry * ca) / (L0 * cb)
    alpha_ddot = wk_dot + eta * (fwd - wk_dot)
    axle = (
        vk * ca,
        vk * sa,
        vk_dot * ca - vk * alpha_dot * sa,
        vk_dot * sa + vk * alpha_dot * ca,
    )
    steer = (ca, sa, alpha_dot, alpha_ddot)
    drawbar = _behind(hitch, (ck, sk, wk, wk_dot), 0.5 * L0)
    bodies = (rod, drawbar, axle, _beside(axle, steer, h), _beside(axle, steer, -h))
    rates = (phi_dot, vk, wk, wk_dot, alpha_dot, alpha_ddot, vk_dot)
    return True, bodies, rates, (thk, wk, wk_dot)


def _masses(row, Mw: float) -> tuple:
    """The masses of :func:`trailer_pass`'s bodies."""
    return (row[3], row[5], row[6], Mw, Mw)


def _chain(theta: float, phis, v: float, omega: float, v_dot: float, omega_dot: float, p: Params):
    """One pass down the chain, body by body (the form :func:`kinetic_energy` sums).

    Returns
    -------
    translations : list of (m, vx, vy, ax, ay)
        Every point mass (body centres, rods, wheels) with its velocity and acceleration.
    rotations : list of (I, rate, rate_dot)
        Every yaw or spin inertia with its rate and the rate's derivative.
    trailers : list of (phi_dot, v_k, theta_k_dot)
        Per trailer.
    """
    c = train_constants(p)
    h = 0.5 * c.d
    spin = c.Iw / (c.r * c.r)
    point, _turn, left, right, spins = tractor_pass(theta, (v, omega, v_dot, omega_dot), h)
    trans = [(c.Mf, *point), (c.Mw, *left), (c.Mw, *right)]
    rots = [
        (c.Ifd + 2.0 * c.Iwd, omega, omega_dot),
        (spin, spins[0], spins[1]),
        (spin, spins[2], spins[3]),
    ]
    trailers = []
    front, heading = point, (theta, omega, omega_dot)
    for row, phi in zip(c.trailers, phis, strict=True):
        fw, fwd = heading[1], heading[2]
        ok, bodies, rates, heading = trailer_pass(front, heading, row, phi, h)
        if not ok:
            raise SingularityError(phi, row[2])
        trans.extend((m, *body) for m, body in zip(_masses(row, c.Mw), bodies, strict=True))
        phi_dot, vk, wk, wk_dot, alpha_dot, alpha_ddot, vk_dot = rates
        rots.append((row[4], fw, fwd))  # the front rod, rigid with the body in front
        rots.append((row[7] + row[8], wk, wk_dot))
        rots.append((2.0 * c.Iwd, alpha_dot, alpha_ddot))
        rots.append((spin, vk - h * alpha_dot, vk_dot - h * alpha_ddot))
        rots.append((spin, vk + h * alpha_dot, vk_dot + h * alpha_ddot))
        trailers.append((phi_dot, vk, wk))
        front = bodies[2]
    return trans, rots, trailers


def _add(acc, m: float, u0, u1, w0, w1, b0, b1):
    """``acc = (M11, M12, M22, c1, c2)`` plus one body's share: ``m`` times the products of
    its velocity for V = e_1 ``(u0, u1)``, for V = e_2 ``(w0, w1)`` and its bias ``(b0, b1)``."""
    return (
        acc[0] + m * (u0 * u0 + u1 * u1),
        acc[1] + m * (u0 * w0 + u1 * w1),
        acc[2] + m * (w0 * w0 + w1 * w1),
        acc[3] + m * (u0 * b0 + u1 * b1),
        acc[4] + m * (w0 * b0 + w1 * b1),
    )


def mass_and_bias_of(phis, v: float, omega: float, c: TrainConstants, rates_out):
    """``(ok, (M11, M12, M22), (c1, c2))`` of the train at the hitch angles ``phis`` and
    ``V = (v, omega)``, from three passes down the chain at once (V = e_1, V = e_2, and V with
    V_dot = 0; position and heading do not matter, so they run at theta = 0); trailer k's
    ``(phi_k_dot, v_k, theta_k_dot)`` at V go to ``rates_out[k]``. Plain numbers (the compiled
    episode shares it); ``ok`` is False at a trailer's singularity."""
    h = 0.5 * c.d
    spin = c.Iw / (c.r * c.r)
    pu, _tu, lu, ru, su = tractor_pass(0.0, (1.0, 0.0, 0.0, 0.0), h)
    pw, _tw, lw, rw, sw = tractor_pass(0.0, (0.0, 1.0, 0.0, 0.0), h)
    pb, _tb, lb, rb, sb = tractor_pass(0.0, (v, omega, 0.0, 0.0), h)
    acc = (0.0, 0.0, 0.0, 0.0, 0.0)
    acc = _add(acc, c.Mf, pu[0], pu[1], pw[0], pw[1], pb[2], pb[3])
    acc = _add(acc, c.Mw, lu[0], lu[1], lw[0], lw[1], lb[2], lb[3])
    acc = _add(acc, c.Mw, ru[0], ru[1], rw[0], rw[1], rb[2], rb[3])
    acc = _add(acc, c.Ifd + 2.0 * c.Iwd, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0)  # yaw: rate omega
    acc = _add(acc, spin, su[0], 0.0, sw[0], 0.0, sb[1], 0.0)
    acc = _add(acc, spin, su[2], 0.0, sw[2], 0.0, sb[3], 0.0)
    hu, hw, hb = (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, omega, 0.0)
    zero = (0.0, 0.0, 0.0)
    for k in range(len(c.trailers)):
        row, phi = c.trailers[k], phis[k]
        fu, fw_, fb = hu[1], hw[1], hb
        oku, bu, ratu, hu = trailer_pass(pu, hu, row, phi, h)
        okw, bw, ratw, hw = trailer_pass(pw, hw, row, phi, h)
        okb, bb, ratb, hb = trailer_pass(pb, hb, row, phi, h)
        if not (oku and okw and okb):
            return False, zero, (0.0, 0.0)
        masses = _masses(row, c.Mw)
        for i in range(5):
            u, w, b = bu[i], bw[i], bb[i]
            acc = _add(acc, masses[i], u[0], u[1], w[0], w[1], b[2], b[3])
        # the front rod's yaw turns with the body in front; the trailer's body with w_k; the
        # steered axle with alpha_dot; its wheels spin at v_k -+ h alpha_dot
        acc = _add(acc, row[4], fu, 0.0, fw_, 0.0, fb[2], 0.0)
        acc = _add(acc, row[7] + row[8], ratu[2], 0.0, ratw[2], 0.0, ratb[3], 0.0)
        acc = _add(acc, 2.0 * c.Iwd, ratu[4], 0.0, ratw[4], 0.0, ratb[5], 0.0)
        vu, vw, vb = ratu[1] - h * ratu[4], ratw[1] - h * ratw[4], ratb[6] - h * ratb[5]
        acc = _add(acc, spin, vu, 0.0, vw, 0.0, vb, 0.0)
        vu, vw, vb = ratu[1] + h * ratu[4], ratw[1] + h * ratw[4], ratb[6] + h * ratb[5]
        acc = _add(acc, spin, vu, 0.0, vw, 0.0, vb, 0.0)
        out = rates_out[k]
        out[0], out[1], out[2] = ratb[0], ratb[1], ratb[2]
        pu, pw, pb = bu[2], bw[2], bb[2]
    return True, (acc[0], acc[1], acc[2]), (acc[3], acc[4])


def trailer_rates_of(phis, v: float, omega: float, c: TrainConstants, out) -> bool:
    """Trailer k's ``(phi_k_dot, v_k, theta_k_dot)`` at ``V = (v, omega)`` into ``out[k]``
    (one pass down the chain at theta = 0, the one :func:`mass_and_bias_of` makes for the
    state's V); False at a trailer's singularity. Plain numbers (the compiled episode shares
    it)."""
    h = 0.5 * c.d
    front = tractor_pass(0.0, (v, omega, 0.0, 0.0), h)[0]
    heading = (0.0, omega, 0.0)
    for k in range(len(c.trailers)):
        ok, bodies, rates, heading = trailer_pass(front, heading, c.trailers[k], phis[k], h)
        if not ok:
            return False
        row = out[k]
        row[0], row[1], row[2] = rates[0], rates[1], rates[2]
        front = bodies[2]
    return True


def _raise_singular(phis, p: Params) -> None:
    """The SingularityError of the first trailer at cos(beta_k) < COS_BETA_MIN."""
    for t, phi in zip(p.trailers, phis, strict=True):
        if math.cos(t.eta * phi) < COS_BETA_MIN:
            raise SingularityError(phi, t.eta)


def _scratch(n: int) -> list:
    return [[0.0, 0.0, 0.0] for _ in range(n)]


def rates(theta: float, phis, v: float, omega: float, p: Params) -> tuple:
    """``q_dot = S(q) V`` as floats: ``(x_dot, y_dot, theta_dot, phi_1_dot..phi_N_dot,
    theta_l_dot, theta_r_dot)``."""
    trailers = trailer_rates(phis, v, omega, p)
    spin = p.d * omega / (2.0 * p.r)
    return (
        v * math.cos(theta),
        v * math.sin(theta),
        omega,
        *(row[0] for row in trailers),
        v / p.r - spin,
        v / p.r + spin,
    )


def trailer_rates(phis, v: float, omega: float, p: Params) -> list[tuple[float, float, float]]:
    """``(phi_k_dot, v_k, theta_k_dot)`` of every trailer: hitch rate, the axle's rolling speed
    and the trailer's heading rate."""
    out = _scratch(p.n_trailers)
    if not trailer_rates_of(phis, v, omega, train_constants(p), out):
        _raise_singular(phis, p)
    return [tuple(row) for row in out]


def poses_of(x: float, y: float, theta: float, phis, c: TrainConstants, out) -> None:
    """Trailer k's ``(ox, oy, x_k, y_k, theta_k)`` (hitch O_k, axle midpoint P_k, heading)
    into ``out[k]``. Plain numbers (the compiled episode shares it)."""
    fx, fy, fth = x, y, theta
    for k in range(len(c.trailers)):
        L, L0 = c.trailers[k][0], c.trailers[k][1]
        ox, oy = fx - L * math.cos(fth), fy - L * math.sin(fth)
        thk = fth - phis[k]
        fx, fy, fth = ox - L0 * math.cos(thk), oy - L0 * math.sin(thk), thk
        row = out[k]
        row[0], row[1], row[2], row[3], row[4] = ox, oy, fx, fy, thk


def poses(x: float, y: float, theta: float, phis, p: Params) -> list[tuple]:
    """``(ox, oy, x_k, y_k, theta_k)`` of every trailer: hitch O_k, axle midpoint P_k, heading."""
    out = [[0.0] * 5 for _ in range(p.n_trailers)]
    poses_of(x, y, theta, phis, train_constants(p), out)
    return [tuple(row) for row in out]


def mass_and_bias(phis, v: float, omega: float, p: Params):
    """``Mbar(phi)`` as ``(M11, M12, M22)`` and ``Cbar(phi, V) V`` as ``(c1, c2)``
    (:func:`mass_and_bias_of`; raises :class:`SingularityError` at a trailer's singularity)."""
    ok, mass, bias = mass_and_bias_of(phis, v, omega, train_constants(p), _scratch(len(phis)))
    if not ok:
        _raise_singular(phis, p)
    return mass, bias


def train_derivative_of(y, T_r: float, T_l: float, a_v: float, a_w: float, c, work, out) -> bool:
    """``out = dy/dt`` of the train's state ``y = (x, y, theta, phi_1..phi_N, theta_l,
    theta_r, v, omega)`` for the torques and the added acceleration ``(a_v, a_w)``; False at a
    trailer's singularity. ``work`` holds N rows of 3 (the trailers' rates). Plain numbers (the
    compiled episode shares it)."""
    n = len(c.trailers)
    theta, v, omega = y[2], y[5 + n], y[6 + n]
    ok, mass, bias = mass_and_bias_of(y[3 : 3 + n], v, omega, c, work)
    if not ok:
        return False
    f1, f2, g11, g12, g21, g22 = solve_dynamics_of(mass, bias, c.r, c.d)
    out[0], out[1], out[2] = v * math.cos(theta), v * math.sin(theta), omega
    for k in range(n):
        out[3 + k] = work[k][0]
    spin = c.d * omega / (2.0 * c.r)
    out[3 + n], out[4 + n] = v / c.r - spin, v / c.r + spin
    out[5 + n] = f1 + g11 * T_r + g12 * T_l + a_v
    out[6 + n] = f2 + g21 * T_r + g22 * T_l + a_w
    return True


def train_rk4_step_of(y, inputs, c: TrainConstants, dt: float, work, slopes) -> bool:
    """One classical RK4 step of :func:`train_derivative_of`, ``y`` advanced in place, the
    ``inputs = (T_r, T_l, a_v, a_w)`` held over it; False (``y`` unchanged) where a stage
    meets a singularity. ``slopes`` holds 5 rows of len(y) (four slopes and a stage)."""
    T_r, T_l, a_v, a_w = inputs
    m = len(y)
    stage = slopes[4]
    for j in range(4):
        step = 0.0 if j == 0 else (0.5 * dt if j < 3 else dt)
        for i in range(m):
            stage[i] = y[i] if j == 0 else y[i] + step * slopes[j - 1][i]
        if not train_derivative_of(stage, T_r, T_l, a_v, a_w, c, work, slopes[j]):
            for i in range(m):  # the stage that failed, for the caller's message
                slopes[4][i] = stage[i]
            return False
    h = dt / 6.0
    k1, k2, k3, k4 = slopes[0], slopes[1], slopes[2], slopes[3]
    for i in range(m):
        y[i] = y[i] + h * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
    return True


def matched_torque(phis, a_v: float, a_omega: float, p: Params) -> tuple[float, float]:
    """The wheel torques adding the acceleration ``(a_v, a_omega)`` (as
    :func:`tt_mujoco.vehicle.reduced.matched_torque`, with the train's Mbar)."""
    return torque_for_force(mass_and_bias(phis, 0.0, 0.0, p)[0], a_v, a_omega, p)


def dynamics_scalar(phis, v: float, omega: float, p: Params):
    """``V_dot = f + g tau`` as six floats ``(f1, f2, g11, g12, g21, g22)``, like
    :func:`tt_mujoco.vehicle.reduced.dynamics_scalar` for one trailer."""
    return solve_dynamics(*mass_and_bias(phis, v, omega, p), p)


def kinetic_energy(phis, V, p: Params) -> float:
    """The whole train's kinetic energy under rolling, summed body by body."""
    trans, rots, _ = _chain(0.0, phis, float(V[0]), float(V[1]), 0.0, 0.0, p)
    return 0.5 * (
        sum(m * (vx * vx + vy * vy) for m, vx, vy, _, _ in trans)
        + sum(inertia * w * w for inertia, w, _ in rots)
    )


class TrainODE(ReducedPlant):
    """The train's reduced model as an ODE: RK4 (:func:`train_rk4_step_of`, zero-order hold
    of the torques) on the state ``(x, y, theta, phi_1..phi_N, theta_l, theta_r, v, omega)``."""

    def step(self, tau, dt: float, accel_disturbance=(0.0, 0.0)) -> np.ndarray:
        """Advance by ``dt``; raises :class:`SingularityError` at a jackknife."""
        p = self.params
        y = [float(c) for c in self.state]
        inputs = (float(tau[0]), float(tau[1]), *(float(a) for a in accel_disturbance))
        slopes = [[0.0] * len(y) for _ in range(5)]
        if not train_rk4_step_of(y, inputs, train_constants(p), dt, _scratch(p.n_trailers), slopes):
            _raise_singular(slopes[4][3 : 3 + p.n_trailers], p)
        self.state = np.array(y)
        self.time += dt
        return self.state

    def derivative(self, y, tau, accel_disturbance=(0.0, 0.0)) -> list[float]:
        p = self.params
        out = [0.0] * len(y)
        a_v, a_w = accel_disturbance
        c = train_constants(p)
        if not train_derivative_of(y, tau[0], tau[1], a_v, a_w, c, _scratch(p.n_trailers), out):
            _raise_singular(y[3 : 3 + p.n_trailers], p)
        return out

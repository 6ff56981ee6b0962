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
the chain (:func:`_chain`) therefore yields every body's velocity and acceleration, both linear
in ``(V, V_dot)`` plus a velocity-product part.

**Dynamics body by body.** With each body's centre velocity ``A_b V`` and rotation (yaw or wheel
spin) ``c_b V``, Kane's equations are ``sum_b A_b^T m_b a_b + c_b^T I_b c_b_dot = B tau``, so

    Mbar = sum_b m_b A_b^T A_b + I_b c_b^T c_b,    Cbar V = sum_b m_b A_b^T a_b|_(V_dot = 0) + ...

which :func:`mass_and_bias` evaluates from three passes (V = e_1, V = e_2, and the state's V with
V_dot = 0). For N = 1 this equals the closed form of :mod:`tt_mujoco.vehicle.reduced` to
round-off (``tests/test_train.py``), which the single-trailer code keeps using.
"""

from __future__ import annotations

import math

import numpy as np

from tt_mujoco.vehicle.params import Params
from tt_mujoco.vehicle.reduced import (
    COS_BETA_MIN,
    ReducedPlant,
    SingularityError,
    rk4_combine,
    rk4_stage,
    solve_dynamics,
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


def _behind(vx, vy, ax, ay, c, s, w, w_dot, dist):
    """Velocity and acceleration of the point ``dist`` behind a body's reference point along its
    heading ``e = (c, s)``, the body turning at ``w`` with ``w_dot``."""
    return (
        vx + dist * w * s,
        vy - dist * w * c,
        ax + dist * w_dot * s + dist * w * w * c,
        ay - dist * w_dot * c + dist * w * w * s,
    )


def _beside(vx, vy, ax, ay, c, s, w, w_dot, offset):
    """As :func:`_behind`, for the point ``offset`` to the left (along ``e_perp``)."""
    return (
        vx - offset * w * c,
        vy - offset * w * s,
        ax - offset * w_dot * c + offset * w * w * s,
        ay - offset * w_dot * s - offset * w * w * c,
    )


def _chain(theta: float, phis, v: float, omega: float, v_dot: float, omega_dot: float, p: Params):
    """One pass down the chain.

    Returns
    -------
    translations : list of (m, vx, vy, ax, ay)
        Every point mass (body centres, rods, wheels) with its velocity and acceleration.
    rotations : list of (I, rate, rate_dot)
        Every yaw or spin inertia with its rate and the rate's derivative.
    trailers : list of (phi_dot, v_k, theta_k_dot)
        Per trailer.
    """
    h = 0.5 * p.d
    spin = p.Iw / (p.r * p.r)
    c, s = math.cos(theta), math.sin(theta)
    tractor = (v * c, v * s, v_dot * c - v * omega * s, v_dot * s + v * omega * c)
    turn = (c, s, omega, omega_dot)
    trans = [
        (p.Mf, *tractor),
        (p.Mc1, *_behind(*tractor, *turn, 0.5 * p.L)),  # rod P-O
        (p.Mw, *_beside(*tractor, *turn, h)),  # wheels at P +- (d/2) e_perp(theta)
        (p.Mw, *_beside(*tractor, *turn, -h)),
    ]
    rots = [
        (p.Ifd + p.Ic1 + 2.0 * p.Iwd, omega, omega_dot),
        (spin, v - h * omega, v_dot - h * omega_dot),
        (spin, v + h * omega, v_dot + h * omega_dot),
    ]
    trailers = []
    # The body in front: its reference point (P, then P_(k-1)) moving, its heading turning.
    front, fth, fw, fwd = tractor, theta, omega, omega_dot
    for k, (t, phi) in enumerate(zip(p.trailers, phis, strict=True)):
        L, L0, eta = t.L, t.L0, t.eta
        front_turn = (math.cos(fth), math.sin(fth), fw, fwd)
        if k:  # trailer k's front rod, rigid with the body in front, centred L/2 behind it
            trans.append((t.Mc1, *_behind(*front, *front_turn, 0.5 * L)))
            rots.append((t.Ic1, fw, fwd))
        ovx, ovy, oax, oay = hitch = _behind(*front, *front_turn, L)
        thk = fth - phi
        beta = eta * phi
        cb = math.cos(beta)
        if cb < COS_BETA_MIN:
            raise SingularityError(phi, eta)
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
        trans.append((t.Mc2, *_behind(*hitch, ck, sk, wk, wk_dot, 0.5 * L0)))  # drawbar
        trans.append((t.Mr, *axle))
        trans.append((p.Mw, *_beside(*axle, *steer, h)))
        trans.append((p.Mw, *_beside(*axle, *steer, -h)))
        rots.append((t.Ird + t.Ic2, wk, wk_dot))
        rots.append((2.0 * p.Iwd, alpha_dot, alpha_ddot))
        rots.append((spin, vk - h * alpha_dot, vk_dot - h * alpha_ddot))
        rots.append((spin, vk + h * alpha_dot, vk_dot + h * alpha_ddot))
        trailers.append((phi_dot, vk, wk))
        front, fth, fw, fwd = axle, thk, wk, wk_dot
    return trans, rots, trailers


def rates(theta: float, phis, v: float, omega: float, p: Params) -> tuple:
    """``q_dot = S(q) V`` as floats: ``(x_dot, y_dot, theta_dot, phi_1_dot..phi_N_dot,
    theta_l_dot, theta_r_dot)``."""
    _, _, trailers = _chain(theta, phis, v, omega, 0.0, 0.0, p)
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
    return _chain(0.0, phis, v, omega, 0.0, 0.0, p)[2]


def poses(x: float, y: float, theta: float, phis, p: Params) -> list[tuple]:
    """``(ox, oy, x_k, y_k, theta_k)`` of every trailer: hitch O_k, axle midpoint P_k, heading."""
    out = []
    fx, fy, fth = x, y, theta
    for t, phi in zip(p.trailers, phis, strict=True):
        ox, oy = fx - t.L * math.cos(fth), fy - t.L * math.sin(fth)
        thk = fth - phi
        fx, fy, fth = ox - t.L0 * math.cos(thk), oy - t.L0 * math.sin(thk), thk
        out.append((ox, oy, fx, fy, thk))
    return out


def mass_and_bias(phis, v: float, omega: float, p: Params):
    """``Mbar(phi)`` as ``(M11, M12, M22)`` and ``Cbar(phi, V) V`` as ``(c1, c2)``.

    Neither depends on the position or heading, so the passes run at theta = 0.
    """
    t1, r1, _ = _chain(0.0, phis, 1.0, 0.0, 0.0, 0.0, p)
    t2, r2, _ = _chain(0.0, phis, 0.0, 1.0, 0.0, 0.0, p)
    tb, rb, _ = _chain(0.0, phis, v, omega, 0.0, 0.0, p)
    M11 = M12 = M22 = c1 = c2 = 0.0
    for (m, ux, uy, _, _), (_, wx, wy, _, _), (_, _, _, bx, by) in zip(t1, t2, tb, strict=True):
        M11 += m * (ux * ux + uy * uy)
        M12 += m * (ux * wx + uy * wy)
        M22 += m * (wx * wx + wy * wy)
        c1 += m * (ux * bx + uy * by)
        c2 += m * (wx * bx + wy * by)
    for (inertia, a, _), (_, b, _), (_, _, bd) in zip(r1, r2, rb, strict=True):
        M11 += inertia * a * a
        M12 += inertia * a * b
        M22 += inertia * b * b
        c1 += inertia * a * bd
        c2 += inertia * b * bd
    return (M11, M12, M22), (c1, c2)


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
    """The train's reduced model as an ODE: :class:`tt_mujoco.vehicle.reduced.ReducedPlant`'s
    RK4 step (zero-order hold of the torques) on the state
    ``(x, y, theta, phi_1..phi_N, theta_l, theta_r, v, omega)``."""

    def step(self, tau, dt: float, accel_disturbance=(0.0, 0.0)) -> np.ndarray:
        """Advance by ``dt`` with RK4 on :meth:`derivative` (any N; one trailer's plain-number
        step is :func:`tt_mujoco.vehicle.reduced.rk4_step_of`)."""
        y = [float(c) for c in self.state]
        tau = (float(tau[0]), float(tau[1]))
        acc = (float(accel_disturbance[0]), float(accel_disturbance[1]))
        k1 = self.derivative(y, tau, acc)
        k2 = self.derivative(rk4_stage(y, k1, 0.5 * dt), tau, acc)
        k3 = self.derivative(rk4_stage(y, k2, 0.5 * dt), tau, acc)
        k4 = self.derivative(rk4_stage(y, k3, dt), tau, acc)
        self.state = np.array(rk4_combine(y, k1, k2, k3, k4, dt / 6.0))
        self.time += dt
        return self.state

    def derivative(self, y, tau, accel_disturbance=(0.0, 0.0)) -> list[float]:
        p = self.params
        theta, phis, v, omega = y[2], y[3 : 3 + p.n_trailers], y[-2], y[-1]
        f1, f2, g11, g12, g21, g22 = dynamics_scalar(phis, v, omega, p)
        T_r, T_l = tau
        return [
            *rates(theta, phis, v, omega, p),
            f1 + g11 * T_r + g12 * T_l + accel_disturbance[0],
            f2 + g21 * T_r + g22 * T_l + accel_disturbance[1],
        ]

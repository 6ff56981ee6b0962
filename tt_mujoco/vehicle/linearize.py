"""The train's path-frame error kinematics and their analytic Jacobians (docs/model.md Section 15).

The reduced model's velocity layer, with the tractor's ``u = (v, omega)`` as input (the torque
layer below it is what the project's inner laws track): for a reference path of curvature
``kappa(s)``, the state ``z = (e_y, e_psi, phi_1, ..., phi_N)`` (the tractor's P signed distance
from the path, its heading error, the hitch angles) evolves as

    e_y_dot   = v sin(e_psi)
    e_psi_dot = omega - kappa v cos(e_psi) / (1 - kappa e_y)
    phi_k_dot = theta_(k-1)_dot - theta_k_dot     (Section 12's recursion)

and the nearest path point moves with ``s_dot = v cos(e_psi) / (1 - kappa e_y)``. :func:`jacobians`
gives ``A = df/dz`` and ``B = df/du`` in closed form (the hitch rows by differentiating the
recursion trailer by trailer), for any N; ``tests/test_linearize.py`` checks them against central
finite differences. About a steady arc (``e_y = e_psi = 0``, each phi_k at its steady angle,
``omega = kappa v``) they are the model an LQR or MPC designer linearises about.
"""

from __future__ import annotations

import math

import numpy as np

from tt_mujoco.vehicle.rolling import hitch_rates

__all__ = ["error_rates", "hitch_rates_with_jacobian", "jacobians"]


def hitch_rates_with_jacobian(phis, v: float, omega: float, lengths, etas):
    """Every hitch rate phi_k_dot and its gradient with respect to ``(phi_1..phi_N, v, omega)``.

    Parameters
    ----------
    phis : sequence of float
        Hitch angles (rad).
    v, omega : float
        The tractor's speed (m/s) and yaw rate (rad/s).
    lengths : sequence of (L_k, L0_k)
    etas : sequence of float
        beta_k = eta_k phi_k.

    Returns
    -------
    rates : ndarray, shape (N,)
        phi_k_dot (rad/s), as :func:`tt_mujoco.vehicle.rolling.hitch_rates`.
    jacobian : ndarray, shape (N, N + 2)
        d phi_k_dot / d (phi_1..phi_N, v, omega).
    """
    n = len(phis)
    dims = n + 2
    zero = np.zeros(dims)
    # Each quantity carries (value, gradient) in the tractor's frame (heading 0).
    h, dh = 0.0, zero.copy()
    vx, dvx = float(v), zero.copy()
    dvx[n] = 1.0
    vy, dvy = 0.0, zero.copy()
    rate, drate = float(omega), zero.copy()
    drate[n + 1] = 1.0
    rates, jac = np.empty(n), np.empty((n, dims))
    for k, ((L, L0), phi, eta) in enumerate(zip(lengths, phis, etas, strict=True)):
        unit = zero.copy()
        unit[k] = 1.0
        c, s = math.cos(h), math.sin(h)
        dc, ds = -s * dh, c * dh
        ox, dox = vx + L * rate * s, dvx + L * (drate * s + rate * ds)
        oy, doy = vy - L * rate * c, dvy - L * (drate * c + rate * dc)
        theta, dtheta = h - phi, dh - unit
        beta, dbeta = eta * phi, eta * unit
        alpha, dalpha = theta + beta, dtheta + dbeta
        ct, st = math.cos(theta), math.sin(theta)
        ca, sa = math.cos(alpha), math.sin(alpha)
        cb, dcb = math.cos(beta), -math.sin(beta) * dbeta
        # theta_k_dot = num / (L0 cos(beta))
        num = -ox * sa + oy * ca
        dnum = -dox * sa - ox * ca * dalpha + doy * ca - oy * sa * dalpha
        theta_dot = num / (L0 * cb)
        dtheta_dot = (dnum * cb - num * dcb) / (L0 * cb * cb)
        rates[k] = rate - theta_dot
        jac[k] = drate - dtheta_dot
        # the axle: the hitch's velocity minus the drawbar's rotation
        vx, dvx = ox + L0 * theta_dot * st, dox + L0 * (dtheta_dot * st + theta_dot * ct * dtheta)
        vy, dvy = oy - L0 * theta_dot * ct, doy - L0 * (dtheta_dot * ct - theta_dot * st * dtheta)
        h, dh, rate, drate = theta, dtheta, theta_dot, dtheta_dot
    return rates, jac


def error_rates(z, u, kappa: float, lengths, etas) -> np.ndarray:
    """``z_dot`` of the path-frame error kinematics (module docstring) at curvature ``kappa``."""
    e_y, e_psi, *phis = (float(x) for x in z)
    v, omega = (float(x) for x in u)
    metric = 1.0 - kappa * e_y
    rates = [row[0] for row in hitch_rates(phis, v, omega, lengths, etas)]
    return np.concatenate(
        [[v * math.sin(e_psi), omega - kappa * v * math.cos(e_psi) / metric], rates]
    )


def jacobians(z, u, kappa: float, lengths, etas) -> tuple[np.ndarray, np.ndarray]:
    """``(A, B)``: d z_dot / d z, shape (N + 2, N + 2), and d z_dot / d u, shape (N + 2, 2), in
    closed form at state ``z``, input ``u = (v, omega)`` and path curvature ``kappa`` (held
    fixed: the curvature at the nearest path point, which moves with s, not with z)."""
    e_y, e_psi, *phis = (float(x) for x in z)
    v, omega = (float(x) for x in u)
    n = len(phis)
    metric = 1.0 - kappa * e_y
    c, s = math.cos(e_psi), math.sin(e_psi)
    A = np.zeros((n + 2, n + 2))
    B = np.zeros((n + 2, 2))
    A[0, 1] = v * c
    B[0, 0] = s
    A[1, 0] = -kappa * kappa * v * c / (metric * metric)
    A[1, 1] = kappa * v * s / metric
    B[1, 0] = -kappa * c / metric
    B[1, 1] = 1.0
    _, jac = hitch_rates_with_jacobian(phis, v, omega, lengths, etas)
    A[2:, 2:] = jac[:, :n]
    B[2:, :] = jac[:, n:]
    return A, B

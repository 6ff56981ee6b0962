"""Backing a trailer along a path on its own axle: a plain-number law that sees the path.

Run it with ``python -m tt_mujoco.run --reverse --controller examples/backing_law.py:backing_law``.
It declares ``backs_up_itself=True``, so the loop gives it the path's own reverse target (no
hitch cascade: the law steers the train itself), and ``path=True``, so it reads the path and
the vehicle (:mod:`tt_mujoco.controllers.path_view`). Written for one trailer.

Backing up, the trailer's axle P0 leads. Three loops, each in the path's arc length:

1. **The axle on the path.** Backing up, the train faces along the path's tangent and runs
   back towards s = 0 (``tt_mujoco.reference.reverse``). ``path_nearest`` gives the axle's
   signed distance ``e_y`` from the path (left of increasing s) and the path's heading
   ``theta_path`` there; the axle rolls along ``alpha = theta0 + beta``, so its heading error
   is ``e_psi = alpha - theta_path``. Along its heading the axle should run at the curvature
   ``kappa = kappa_path - k_y e_y - direction k_psi sin(e_psi)``: the usual path-following
   law in the direction of travel (critically damped in arc length for ``k_psi = 2
   sqrt(k_y)``), whose heading term changes sign with the direction.
2. **The hitch angle that holds it.** Steadily, a trailer behind the tractor runs at the
   curvature ``kappa(phi) = -sin((eta - 1) phi) / (L + L0 cos phi)`` along its heading
   (docs/model.md, the steady turn). Newton's method on that relation gives the hitch angle
   ``phi_d`` (bounded well short of the jackknife).
3. **The tractor's yaw rate that makes the hitch.** The hitch rate is affine in the tractor's
   yaw rate omega (the off-axle linkage, ``beta = eta phi``):
   ``phi_dot = omega (1 + L cos a / (L0 cos b)) + v sin a / (L0 cos b)``, ``a = (eta - 1) phi``,
   ``b = eta phi``; omega is chosen so that ``phi_dot = -k_phi |v| (phi - phi_d)``.

The wheel torques then track (v_d, omega_c) through the nominal model, as
``examples/kanayama.py`` does, with an integral term and the yaw-rate target's own rate (by
difference) as feed-forward.
"""

import math

from tt_mujoco.controllers import plain_law
from tt_mujoco.controllers.path_view import path_nearest

GAINS = {
    "k_y": 4.0,
    "k_psi": 4.0,
    "k_phi": 3.0,
    "phi_max_deg": 40.0,
    "k_v": 20.0,
    "k_i": 60.0,
}


def wrap(angle):
    """The angle in (-pi, pi]."""
    return math.atan2(math.sin(angle), math.cos(angle))


def steady_hitch(kappa, L, L0, eta, phi_max):
    """The hitch angle at which a trailer behind the tractor runs steadily at curvature
    ``kappa`` along its heading, by Newton's method from the small-angle root."""
    phi = kappa * (L + L0) / (1.0 - eta)
    for _ in range(6):
        phi = min(max(phi, -phi_max), phi_max)
        a = (eta - 1.0) * phi
        den = L + L0 * math.cos(phi)
        f = -math.sin(a) / den - kappa
        slope = (-(eta - 1.0) * math.cos(a) * den - math.sin(a) * L0 * math.sin(phi)) / (den * den)
        if slope == 0.0:
            break
        phi -= f / slope
    return min(max(phi, -phi_max), phi_max)


@plain_law(
    gains=GAINS,
    state=("s0", "int_v", "int_w", "omega_c", "started"),
    path=True,
    backs_up_itself=True,
)
def backing_law(m, r, model, k, s, dt, torque_limit, path, vehicle):
    L, L0, eta = vehicle.L, vehicle.L0, vehicle.eta
    reach = 0.1 if s.s0 > 0.0 else 0.0  # the whole path once, then around the last point
    s0, _, _, theta_p, kappa_p, e_y = path_nearest(path, m.x0, m.y0, s.s0, reach)
    s.s0 = max(s0, 1e-9)
    # the path-following law in the direction of travel, written along the axle's heading
    e_psi = wrap(m.theta0 + m.beta - theta_p)
    kappa_heading = kappa_p - k.k_y * e_y - vehicle.direction * k.k_psi * math.sin(e_psi)
    phi_max = math.radians(k.phi_max_deg)
    phi_d = steady_hitch(kappa_heading, L, L0, eta, phi_max)

    a, b = (eta - 1.0) * m.phi, eta * m.phi
    gain = 1.0 + L * math.cos(a) / (L0 * math.cos(b))
    drift = m.v * math.sin(a) / (L0 * math.cos(b))
    omega_c = (-k.k_phi * abs(m.v) * (m.phi - phi_d) - drift) / gain

    # the yaw-rate target's own rate, by difference, as the feed-forward of the inner loop
    omega_c_dot = (omega_c - s.omega_c) / dt if s.started != 0.0 else 0.0
    s.omega_c, s.started = omega_c, 1.0
    e_v, e_w = r.v_d - m.v, omega_c - m.omega
    s.int_v += e_v * dt
    s.int_w += e_w * dt
    a_v = r.v_d_dot + k.k_v * e_v + k.k_i * s.int_v - model.f1
    a_w = omega_c_dot + k.k_v * e_w + k.k_i * s.int_w - model.f2
    det = model.g11 * model.g22 - model.g12 * model.g21
    T_r = (model.g22 * a_v - model.g12 * a_w) / det
    T_l = (model.g11 * a_w - model.g21 * a_v) / det
    return T_r, T_l

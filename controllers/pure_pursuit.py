"""Pure pursuit for the differential-drive tractor, over a velocity loop.

Pure pursuit (Coulter, "Implementation of the pure pursuit path tracking algorithm",
CMU-RI-TR-92-01, 1992) steers the tractor's axle midpoint P on the circle through a point of
the path ahead. The look-ahead point ``(x_l, y_l)`` is ``l_a`` of arc length past the path
point nearest to P:

    l_a = l_min + k_ahead |v|,   kappa_c = 2 sin(alpha) / l_d,   omega_c = kappa_c v

with ``l_d`` the point's distance from P and ``alpha`` its bearing from the tractor's heading
(``kappa_c`` is the curvature of the circle through P, tangent to the heading, that reaches
the point). The nearest point is searched near the last one, so the law never jumps to
another lap of a path that crosses itself; past the path's end the look-ahead goes on along
the end tangent, as every path does (docs/model.md Section 7). The inner loop tracks ``(v_d,
omega_c)`` through the nominal model ``V_dot = f + g tau`` (docs/model.md Section 4): ``tau =
g^-1 (a - f)`` with ``a = (v_d_dot + k_v e_v, k_omega e_omega)``, as
:mod:`tt_mujoco.controllers.stanley` does.

On a circle it holds P on the path in the steady state: with P on the circle, the look-ahead
point's chord subtends ``l_a / R`` and ``2 sin(alpha) / l_d`` is exactly ``1 / R``, whatever the
look-ahead. It cuts where the curvature changes, turning towards the next arc about ``l_d``
early (the S-curve's reversal), so a short look-ahead tracks closer and a long one smooths
more. Forward only: backing up, the trailer leads, which this law does not stabilise.

A plain-number law that sees the path (:mod:`tt_mujoco.controllers.plain`), so both loops run
the same text and the compiled loop runs it at the physics' speed.
"""

from __future__ import annotations

import math

from tt_mujoco.controllers.path_view import path_nearest, path_pose_at
from tt_mujoco.controllers.plain import plain_law

__all__ = ["pure_pursuit"]


@plain_law(
    gains={"l_min": 0.15, "k_ahead": 0.25, "k_v": 20.0, "k_omega": 20.0},
    state=("s_near", "started"),
    name="pure_pursuit",
    reverse=False,
    path=True,
)
def pure_pursuit(m, r, model, k, s, dt, torque_limit, path, vehicle):
    """Pure pursuit of the path (module docstring); the torques that track ``(v_d, omega_c)``."""
    reach = 0.5 if s.started != 0.0 else 0.0  # the first step searches the whole path
    s.started = 1.0
    s.s_near, x, y, theta, _, _ = path_nearest(path, m.x, m.y, s.s_near, reach)
    # Past the end the path goes on along its end tangent (docs/model.md Section 7): the
    # nearest point is then the end, and P is ``along`` beyond it (0 inside the path).
    along = max(math.cos(theta) * (m.x - x) + math.sin(theta) * (m.y - y), 0.0)
    s_ahead = s.s_near + along + k.l_min + k.k_ahead * abs(m.v)
    x_l, y_l, theta_l, _ = path_pose_at(path, s_ahead)
    beyond = s_ahead - path[0, path.shape[1] - 1]
    if beyond > 0.0:
        x_l, y_l = x_l + beyond * math.cos(theta_l), y_l + beyond * math.sin(theta_l)
    dx, dy = x_l - m.x, y_l - m.y
    l_d = max(math.hypot(dx, dy), 1e-6)
    alpha = math.atan2(dy, dx) - m.theta
    omega_c = 2.0 * math.sin(alpha) / l_d * m.v
    a_v = r.v_d_dot + k.k_v * (r.v_d - m.v) - model.f1
    a_w = k.k_omega * (omega_c - m.omega) - model.f2
    det = model.g11 * model.g22 - model.g12 * model.g21
    return (model.g22 * a_v - model.g12 * a_w) / det, (model.g11 * a_w - model.g21 * a_v) / det

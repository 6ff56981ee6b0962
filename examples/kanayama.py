"""A pose-feedback path tracker written outside the package (Kanayama et al., 1990).

Run it with ``python -m tt_mujoco.run --controller examples/kanayama.py:KanayamaTracker``, or
its plain-number form ``kanayama_law`` (below), which the loop compiles.

The outer law turns the tractor's pose error against the reference point into velocity
targets; an inner loop turns those into wheel torques through the nominal model
(``V_dot = f + g tau``):

    e_x, e_y, e_th = pose error in the tractor's frame
    v_c = v_d cos(e_th) + k_x e_x
    omega_c = omega_d + v_d (k_y e_y + k_th sin(e_th))
    tau = g^-1 (a_c - f),   a_c = (v_d_dot, omega_d_dot) + k_v e_c + k_i int(e_c) dt
    e_c = (v_c - v, omega_c - omega)

The integral term holds the speed against a constant disturbance (the paper's pushes with
3.5 m/s^2); it is frozen while the torques saturate.
"""

import math

from tt_mujoco.controllers import Controller, plain_law


def wrap(angle):
    """The angle in (-pi, pi]."""
    return math.atan2(math.sin(angle), math.cos(angle))


class KanayamaTracker(Controller):
    name = "kanayama"
    PRESETS = {"default": {"k_x": 4.0, "k_y": 16.0, "k_th": 8.0, "k_v": 20.0, "k_i": 100.0}}  # noqa: RUF012
    DEFAULT_PRESET = "default"

    def reset(self):
        self._int_v = self._int_w = 0.0
        self._saturated = False

    def compute(self, t, measurement, reference):
        m, r, k = measurement, reference, self._gains
        x_ref, y_ref, th_ref = r.pose
        dx, dy = x_ref - m.x, y_ref - m.y
        c, s = math.cos(m.theta), math.sin(m.theta)
        e_x, e_y = c * dx + s * dy, -s * dx + c * dy
        e_th = wrap(th_ref - m.theta)
        if r.v_d < 0:  # reversing: the heading error is against the backward tangent
            e_th = wrap(e_th + math.pi)
        v_c = r.v_d * math.cos(e_th) + k["k_x"] * e_x
        omega_c = r.omega_d + r.v_d * (k["k_y"] * e_y + k["k_th"] * math.sin(e_th))
        e_v, e_w = v_c - m.v, omega_c - m.omega
        if not self._saturated:
            self._int_v += e_v * self.setup.control_dt
            self._int_w += e_w * self.setup.control_dt
        f1, f2, g11, g12, g21, g22 = self.setup.model(m.phi, m.v, m.omega)
        a_v = r.v_d_dot + k["k_v"] * e_v + k["k_i"] * self._int_v - f1
        a_w = r.omega_d_dot + k["k_v"] * e_w + k["k_i"] * self._int_w - f2
        det = g11 * g22 - g12 * g21
        T_r, T_l = (g22 * a_v - g12 * a_w) / det, (g11 * a_w - g21 * a_v) / det
        self._saturated = max(abs(T_r), abs(T_l)) > self.setup.torque_limit
        return T_r, T_l


# The same tracker as a plain-number law: the loop compiles it (tt_mujoco.controllers.plain),
# so it runs at the cost of the physics. Run it with
# ``python -m tt_mujoco.run --controller examples/kanayama.py:kanayama_law``.
@plain_law(gains=KanayamaTracker.PRESETS["default"], state=("int_v", "int_w", "saturated"))
def kanayama_law(m, r, model, k, s, dt, torque_limit):
    dx, dy = r.x_ref - m.x, r.y_ref - m.y
    c, sn = math.cos(m.theta), math.sin(m.theta)
    e_x, e_y = c * dx + sn * dy, -sn * dx + c * dy
    e_th = wrap(r.theta_ref - m.theta)
    if r.v_d < 0:  # reversing: the heading error is against the backward tangent
        e_th = wrap(e_th + math.pi)
    v_c = r.v_d * math.cos(e_th) + k.k_x * e_x
    omega_c = r.omega_d + r.v_d * (k.k_y * e_y + k.k_th * math.sin(e_th))
    e_v, e_w = v_c - m.v, omega_c - m.omega
    if s.saturated == 0.0:
        s.int_v += e_v * dt
        s.int_w += e_w * dt
    a_v = r.v_d_dot + k.k_v * e_v + k.k_i * s.int_v - model.f1
    a_w = r.omega_d_dot + k.k_v * e_w + k.k_i * s.int_w - model.f2
    det = model.g11 * model.g22 - model.g12 * model.g21
    T_r = (model.g22 * a_v - model.g12 * a_w) / det
    T_l = (model.g11 * a_w - model.g21 * a_v) / det
    s.saturated = 1.0 if max(abs(T_r), abs(T_l)) > torque_limit else 0.0
    return T_r, T_l

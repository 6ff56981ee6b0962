"""The MuJoCo side of the model: compile the MJCF for a :class:`Params`, find the joints, put
the vehicle in a planar state, and map reduced velocities onto MuJoCo's ``qvel``.

Together with the simulation loop and rendering, this is one of the few modules that import
MuJoCo.
"""

from __future__ import annotations

import copy
import math

import mujoco
import numpy as np

from tt_mujoco.sim.measure import Layout, Measurement, measure, measure_train
from tt_mujoco.vehicle import reduced, train
from tt_mujoco.vehicle.mjcf import VEHICLE_FILE, scene_xml, trailer_suffix, vehicle_xml
from tt_mujoco.vehicle.params import Params

__all__ = ["Vehicle", "compile_model", "layout_of"]


#: Compiled models by their vehicle XML: compiling costs several copies, and sweeps build
#: thousands of vehicles with a handful of distinct parameter sets.
_COMPILED: dict[str, mujoco.MjModel] = {}
_COMPILED_MAX = 16


def compile_model(p: Params) -> mujoco.MjModel:
    """Compile the scene for ``p`` from the generated XML (no files are read or written).

    Returns a private copy: callers may change it (faults edit ``body_mass``, the steering
    schedule ``eq_data``) without touching the cached original.
    """
    xml = vehicle_xml(p)
    model = _COMPILED.get(xml)
    if model is None:
        try:
            model = mujoco.MjModel.from_xml_string(scene_xml(), assets={VEHICLE_FILE: xml.encode()})
        except ValueError as err:
            default = Params(eta=p.eta, timestep=p.timestep, friction=p.friction)
            changed = {
                k: v
                for k, v in p.to_dict().items()
                if k != "steering" and default.to_dict().get(k) != v
            }
            shown = ", ".join(f"{k}={v!r}" for k, v in changed.items()) or "the defaults"
            raise ValueError(
                f"MuJoCo cannot build the vehicle with {shown}: "
                f"{' '.join(line.strip() for line in str(err).splitlines() if line.strip())}"
            ) from None
        if len(_COMPILED) >= _COMPILED_MAX:
            _COMPILED.pop(next(iter(_COMPILED)))
        _COMPILED[xml] = model
    return copy.copy(model)


def layout_of(model: mujoco.MjModel, p: Params) -> Layout:
    """Joint and actuator addresses of a compiled tractor-trailer model."""

    def jq(name: str) -> int:
        return int(model.jnt_qposadr[model.joint(name).id])

    def jv(name: str) -> int:
        return int(model.jnt_dofadr[model.joint(name).id])

    return Layout(
        root_q=jq("root"),
        root_v=jv("root"),
        hitch_q=jq("hitch"),
        hitch_v=jv("hitch"),
        steer_q=jq("steer"),
        steer_v=jv("steer"),
        wheel_left_v=jv("tractor_wheel_left"),
        wheel_right_v=jv("tractor_wheel_right"),
        trailer_wheel_left_v=jv("trailer_wheel_left"),
        trailer_wheel_right_v=jv("trailer_wheel_right"),
        wheel_left_q=jq("tractor_wheel_left"),
        wheel_right_q=jq("tractor_wheel_right"),
        act_right=int(model.actuator("torque_right").id),
        act_left=int(model.actuator("torque_left").id),
        L=p.L,
        L0=p.L0,
        r=p.r,
        d=p.d,
        train=tuple(
            (jq(f"hitch_{k}"), jv(f"hitch_{k}"), jq(f"steer_{k}"), t.L, t.L0)
            for k, t in enumerate(p.train, start=2)
        ),
    )


class Vehicle:
    """A compiled model with its data, layout and parameters.

    Parameters
    ----------
    params : Params
        Parameters the MJCF is built from (the *plant's* parameters).
    """

    def __init__(self, params: Params):
        self.params = params
        self.model = compile_model(params)
        self.data = mujoco.MjData(self.model)
        self.layout = layout_of(self.model, params)
        self._settled_height = None

    # --- state ----------------------------------------------------------------------------
    def full_selection(self, phi, theta: float = 0.0) -> np.ndarray:
        """``Sfull`` (nv x 2): MuJoCo's ``qvel`` for reduced velocities V under pure rolling.

        Free joint: world linear velocity ``v e(theta)`` and body angular velocity ``omega e_z``;
        hitch ``-phi_dot``; steer ``beta_dot = eta phi_dot``; tractor wheels ``(v -+ d omega/2)/r``;
        trailer wheels ``(v0 -+ (d/2) alpha_dot)/r`` (docs/model.md Section 4).
        """
        p, lay = self.params, self.layout
        if p.n_trailers > 1:
            return self.rolling_selection(phi, theta)
        kappa, (s1, s2), a = (np.array(row) for row in reduced.trailer_rows(phi, p))
        S = np.zeros((self.model.nv, 2))
        S[lay.root_v + 0] = [math.cos(theta), 0.0]
        S[lay.root_v + 1] = [math.sin(theta), 0.0]
        S[lay.root_v + 5] = [0.0, 1.0]
        S[lay.hitch_v] = [-s1, -s2]
        S[lay.steer_v] = [p.eta * s1, p.eta * s2]
        S[lay.wheel_left_v] = [1 / p.r, -p.d / (2 * p.r)]
        S[lay.wheel_right_v] = [1 / p.r, p.d / (2 * p.r)]
        S[lay.trailer_wheel_left_v] = (kappa - 0.5 * p.d * a) / p.r
        S[lay.trailer_wheel_right_v] = (kappa + 0.5 * p.d * a) / p.r
        return S

    def rolling_selection(self, phis, theta: float = 0.0) -> np.ndarray:
        """``Sfull`` for hitch angles ``phis`` (phi_1..phi_N, any N), from the train's velocity
        pass (docs/model.md Section 12) at V = (1, 0) and (0, 1): :meth:`full_selection` for
        any train, and for one trailer the general code's check against the closed form."""
        p, lay = self.params, self.layout
        phis = tuple(phis)
        S = np.zeros((self.model.nv, 2))
        S[lay.root_v + 0] = [math.cos(theta), 0.0]
        S[lay.root_v + 1] = [math.sin(theta), 0.0]
        S[lay.root_v + 5] = [0.0, 1.0]
        S[lay.wheel_left_v] = [1 / p.r, -p.d / (2 * p.r)]
        S[lay.wheel_right_v] = [1 / p.r, p.d / (2 * p.r)]
        m = self.model
        for col, V in enumerate(((1.0, 0.0), (0.0, 1.0))):
            rows = train.trailer_rates(phis, *V, p)
            pairs = zip(rows, p.trailers, strict=True)
            for k, ((phi_dot, v_k, theta_k_dot), t) in enumerate(pairs, start=1):
                sfx = trailer_suffix(k)
                a_dot = theta_k_dot + t.eta * phi_dot  # the axle's heading rate
                S[m.jnt_dofadr[m.joint(f"hitch{sfx}").id], col] = -phi_dot
                S[m.jnt_dofadr[m.joint(f"steer{sfx}").id], col] = t.eta * phi_dot
                left = m.jnt_dofadr[m.joint(f"trailer_wheel_left{sfx}").id]
                right = m.jnt_dofadr[m.joint(f"trailer_wheel_right{sfx}").id]
                S[left, col] = (v_k - 0.5 * p.d * a_dot) / p.r
                S[right, col] = (v_k + 0.5 * p.d * a_dot) / p.r
        return S

    def set_state(self, x=0.0, y=0.0, theta=0.0, phi=0.0, v=0.0, omega=0.0, z=None) -> None:
        """Place the vehicle at pose ``(x, y, theta, phi)`` with ``beta = eta phi`` and rolling
        velocities ``(v, omega)``; wheels touch the floor (or at height ``z`` of P). For a train
        ``phi`` may be the hitch angles phi_1..phi_N (a single value: the first, the others 0).
        """
        p, lay, d = self.params, self.layout, self.data
        phis = tuple(phi) if isinstance(phi, list | tuple | np.ndarray) else (phi,)
        phis = phis + (0.0,) * (p.n_trailers - len(phis))
        for angle, eta in zip(phis, p.etas, strict=True):
            if abs(eta * angle) >= math.pi / 2 - reduced.COS_BETA_MIN:
                raise reduced.SingularityError(angle, eta)
        mujoco.mj_resetData(self.model, d)
        i = lay.root_q
        d.qpos[i : i + 3] = [x, y, p.r if z is None else z]
        d.qpos[i + 3 : i + 7] = [math.cos(theta / 2), 0.0, 0.0, math.sin(theta / 2)]
        d.qpos[lay.hitch_q] = -phis[0]
        d.qpos[lay.steer_q] = p.eta * phis[0]
        rest = zip(lay.train, phis[1:], p.etas[1:], strict=True)
        for (hitch_q, _, steer_q, _, _), angle, eta in rest:
            d.qpos[hitch_q] = -angle
            d.qpos[steer_q] = eta * angle
        selection = self.full_selection(phis if p.n_trailers > 1 else phis[0], theta)
        d.qvel[:] = selection @ np.array([v, omega])
        mujoco.mj_forward(self.model, d)

    def measure(self) -> Measurement:
        if self.params.n_trailers > 1:
            return measure_train(self.data.qpos, self.data.qvel, self.layout)
        return measure(self.data.qpos, self.data.qvel, self.layout)

    def set_torque(self, T_r: float, T_l: float) -> None:
        self.data.ctrl[self.layout.act_right] = T_r
        self.data.ctrl[self.layout.act_left] = T_l

    def full_mass_matrix(self) -> np.ndarray:
        """MuJoCo's joint-space mass matrix M(qpos) (nv x nv); needs a current mj_forward."""
        M = np.zeros((self.model.nv, self.model.nv))
        mujoco.mj_fullM(self.model, self.data, M)
        return M

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

from tt_mujoco.sim.measure import Layout, Measurement, measure
from tt_mujoco.vehicle import reduced
from tt_mujoco.vehicle.mjcf import VEHICLE_FILE, scene_xml, vehicle_xml
from tt_mujoco.vehicle.params import Params

__all__ = ["Vehicle", "compile_model", "layout_of"]


#: Compiled models by their vehicle XML: compiling takes ~27 ms, copying ~4 ms, and sweeps
#: build thousands of vehicles with a handful of distinct parameter sets.
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
    def full_selection(self, phi: float, theta: float = 0.0) -> np.ndarray:
        """``Sfull`` (nv x 2): MuJoCo's ``qvel`` for reduced velocities V under pure rolling.

        Free joint: world linear velocity ``v e(theta)`` and body angular velocity ``omega e_z``;
        hitch ``-phi_dot``; steer ``beta_dot = eta phi_dot``; tractor wheels ``(v -+ d omega/2)/r``;
        trailer wheels ``(v0 -+ (d/2) alpha_dot)/r`` (docs/model.md Section 4).
        """
        p, lay = self.params, self.layout
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

    def set_state(self, x=0.0, y=0.0, theta=0.0, phi=0.0, v=0.0, omega=0.0, z=None) -> None:
        """Place the vehicle at pose ``(x, y, theta, phi)`` with ``beta = eta phi`` and rolling
        velocities ``(v, omega)``; wheels touch the floor (or at height ``z`` of P)."""
        p, lay, d = self.params, self.layout, self.data
        if abs(p.eta * phi) >= math.pi / 2 - reduced.COS_BETA_MIN:
            raise reduced.SingularityError(phi, p.eta)
        mujoco.mj_resetData(self.model, d)
        i = lay.root_q
        d.qpos[i : i + 3] = [x, y, p.r if z is None else z]
        d.qpos[i + 3 : i + 7] = [math.cos(theta / 2), 0.0, 0.0, math.sin(theta / 2)]
        d.qpos[lay.hitch_q] = -phi
        d.qpos[lay.steer_q] = p.eta * phi
        d.qvel[:] = self.full_selection(phi, theta) @ np.array([v, omega])
        mujoco.mj_forward(self.model, d)

    def measure(self) -> Measurement:
        return measure(self.data.qpos, self.data.qvel, self.layout)

    def set_torque(self, T_r: float, T_l: float) -> None:
        self.data.ctrl[self.layout.act_right] = T_r
        self.data.ctrl[self.layout.act_left] = T_l

    def full_mass_matrix(self) -> np.ndarray:
        """MuJoCo's joint-space mass matrix M(qpos) (nv x nv); needs a current mj_forward."""
        M = np.zeros((self.model.nv, self.model.nv))
        mujoco.mj_fullM(self.model, self.data, M)
        return M

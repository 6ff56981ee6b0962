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

from tt_mujoco.sim.parts.measure import Layout, Measurement, measure, measure_train
from tt_mujoco.vehicle import reduced, train
from tt_mujoco.vehicle.mjcf import FLOOR_XML, VEHICLE_FILE, scene_xml, trailer_suffix, vehicle_xml
from tt_mujoco.vehicle.params import Params

__all__ = ["Vehicle", "compile_model", "layout_of"]


#: Compiled models by their vehicle XML: compiling costs several copies, and sweeps build
#: thousands of vehicles with a handful of distinct parameter sets.
_COMPILED: dict[tuple[str, str], mujoco.MjModel] = {}
_COMPILED_MAX = 16


def compile_model(p: Params, relief=None, world=None) -> mujoco.MjModel:
    """Compile the scene for ``p`` from the generated XML (no files are read or written), on
    the ground ``relief`` (:mod:`tt_mujoco.sim.parts.relief`; None: the flat floor), among the
    obstacles of ``world`` (:mod:`tt_mujoco.world`; None: none).

    Returns a private copy: callers may change it (faults edit ``body_mass``, the steering
    schedule ``eq_data``) without touching the cached original.
    """
    obstacles = world is not None and bool(world.all_obstacles)
    xml = vehicle_xml(p, uneven=relief is not None, footprints=obstacles)
    assets, geoms = ("", FLOOR_XML) if relief is None else relief.geoms_xml()
    if obstacles:
        from tt_mujoco.vehicle.footprint import footprints
        from tt_mujoco.world.mjcf import obstacles_xml

        polygons = world.polygons(footprints(p)[-1])
        more = obstacles_xml(polygons, [o.name for o in world.all_obstacles])
        assets, geoms = "\n    ".join(filter(None, (assets, more[0]))), f"{geoms}\n    {more[1]}"
    scene = scene_xml(ground=(assets, geoms))
    key = (xml, scene)
    model = _COMPILED.get(key)
    if model is None:
        try:
            model = mujoco.MjModel.from_xml_string(scene, assets={VEHICLE_FILE: xml.encode()})
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
        _COMPILED[key] = model
    return copy.copy(model)


#: The joints only the vehicle for uneven ground has (``vehicle_xml(uneven=True)``).
UNEVEN_JOINTS = ("hitch_roll", "hitch_pitch")
#: How long (s) a vehicle settles on a ramp or a rough ground before its run starts.
SETTLE_S = 0.5


def wheel_geoms(model: mujoco.MjModel) -> list[int]:
    """The wheels' collision spheres: the geoms that touch the ground and whose friction
    (priority 1) sets their contacts'."""
    return [g for g in range(model.ngeom) if model.geom_contype[g] and model.geom_priority[g] == 1]


def _rotation_onto(normal: np.ndarray) -> np.ndarray:
    """The smallest rotation taking the vertical onto the unit vector ``normal``."""
    axis = np.array([-normal[1], normal[0], 0.0])  # e_z x normal
    sin = float(np.linalg.norm(axis))
    if sin < 1e-15:
        return np.eye(3)
    axis /= sin
    cos = float(normal[2])
    cross = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + sin * cross + (1 - cos) * cross @ cross


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
    relief : RampRelief or RoughRelief, optional
        The ground's shape (:mod:`tt_mujoco.sim.parts.relief`): the vehicle is placed resting on it.
    world : World, optional
        Obstacles (:mod:`tt_mujoco.world`), collision geoms of the scene.
    """

    def __init__(self, params: Params, relief=None, world=None):
        self.params = params
        self.relief = relief
        self.model = compile_model(params, relief, world)
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
        rolling = selection @ np.array([v, omega])
        if self.relief is not None and z is None:
            mujoco.mj_kinematics(self.model, d)
            tilt = self.rest_on_relief()
            self._settle()
            rolling[lay.root_v : lay.root_v + 3] = tilt @ rolling[lay.root_v : lay.root_v + 3]
        d.qvel[:] = rolling
        mujoco.mj_forward(self.model, d)

    def _settle(self) -> None:
        """Let the vehicle come to rest on the relief under gravity, every planar coordinate
        held (position, heading, hitch and steering angles, wheel spins): only its height, roll
        and pitch and the hitches' roll and pitch move, for :data:`SETTLE_S` of simulated
        time. A plane fitted under the wheels (:meth:`rest_on_relief`) leaves a wheel of an
        articulated train above a rough ground; this puts every wheel on it."""
        m, d, lay = self.model, self.data, self.layout
        uneven = [j for j in range(m.njnt) if m.joint(j).name.startswith(UNEVEN_JOINTS)]
        free_v = {lay.root_v + 2, lay.root_v + 3, lay.root_v + 4}
        free_v |= {int(m.jnt_dofadr[j]) for j in uneven}
        held_v = [i for i in range(m.nv) if i not in free_v]
        root, free_q = lay.root_q, {int(m.jnt_qposadr[j]) for j in uneven}
        # the root's x and y, and every joint after it but the hitches' roll and pitch
        held_q = [root, root + 1, *(i for i in range(root + 7, m.nq) if i not in free_q)]
        kept = d.qpos[held_q].copy()
        for _ in range(round(SETTLE_S / m.opt.timestep)):
            d.qvel[held_v] = 0.0
            mujoco.mj_step(m, d)
            d.qpos[held_q] = kept
        d.qvel[:] = 0.0
        d.time = 0.0

    def rest_on_relief(self) -> np.ndarray:
        """Tilt and lift the whole vehicle, from its pose on the flat floor (kinematics
        computed), onto the ground's plane fitted under its wheels, high enough that no wheel
        is below the ground; its (x, y) and heading stay. Returns the tilt (3 x 3).

        The train is rigid in pitch and roll (its hitches are vertical hinges), so on a
        ground that is not a plane it stands on some of its wheels; a wheel above the ground
        at the start drops by at most the plane fit's misfit."""
        m, d, lay = self.model, self.data, self.layout
        wheels = wheel_geoms(m)
        centres = d.geom_xpos[wheels]
        below = np.asarray(self.relief.height(centres[:, 0], centres[:, 1]))
        fit = np.column_stack([np.ones(len(wheels)), centres[:, 0], centres[:, 1]])
        _, gx, gy = np.linalg.lstsq(fit, below, rcond=None)[0]
        normal = np.array([-gx, -gy, 1.0]) / math.sqrt(1.0 + gx * gx + gy * gy)
        tilt = _rotation_onto(normal)
        i = lay.root_q
        root = d.qpos[i : i + 3].copy()
        moved = root + (centres - root) @ tilt.T
        heights = np.asarray(self.relief.height(moved[:, 0], moved[:, 1]))
        radius = m.geom_size[wheels, 0]
        lift = np.max(heights + radius / normal[2] - moved[:, 2])
        d.qpos[i + 2] += lift
        quat = np.empty(4)
        mujoco.mju_mat2Quat(quat, tilt.ravel())
        mujoco.mju_mulQuat(d.qpos[i + 3 : i + 7], quat, d.qpos[i + 3 : i + 7].copy())
        mujoco.mj_kinematics(m, d)
        return tilt

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

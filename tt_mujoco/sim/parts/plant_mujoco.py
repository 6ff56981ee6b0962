"""The MuJoCo plant: the compiled multibody model behind the plant protocol."""

from __future__ import annotations

import math

from tt_mujoco.sim.parts.measure import measure, measure_train
from tt_mujoco.sim.parts.physics import Vehicle, wheel_geoms
from tt_mujoco.sim.parts.plant import Plant
from tt_mujoco.vehicle.params import Params

__all__ = ["MujocoPlant"]


def chassis_wrench_of(force: float, torque: float, theta: float) -> tuple[float, float, float]:
    """The chassis' ``xfrc_applied`` (fx, fy, mz) of a force along the heading ``theta`` and a
    yaw moment (the compiled episode shares it)."""
    return force * math.cos(theta), force * math.sin(theta), torque


def scale_body_of(body_mass, body_inertia, body: int, factor: float) -> None:
    """A payload step: ``body``'s mass and inertia times ``factor`` (the compiled episode
    shares it)."""
    body_mass[body] *= factor
    for axis in range(body_inertia.shape[1]):  # not the row at once: that allocates, compiled
        body_inertia[body, axis] *= factor


def aim_steering_of(eq_data, ids, hitches_q, etas, qpos, max_turn: float) -> None:
    """Actuated axles (:meth:`MujocoPlant.steer_by_actuator`): each steering equality's target
    ``eq_data[id, 0]`` moved towards ``eta_k phi_k`` from its hitch, by at most ``max_turn``
    (rad), before a physics step (the compiled episode shares it)."""
    for k in range(len(ids)):
        aim = -etas[k] * qpos[hitches_q[k]]  # the hitch joint's angle is -phi
        now = eq_data[ids[k], 0]
        if aim > now + max_turn:  # the slew rate binds (set exactly, not now + (aim - now))
            aim = now + max_turn
        elif aim < now - max_turn:
            aim = now - max_turn
        eq_data[ids[k], 0] = aim


def warning_message(name: str, t: float) -> str:
    """The stop for a MuJoCo warning in the control step that started at ``t``."""
    return f"MuJoCo warning {name} in the step from t={t:.3f} s"


class MujocoPlant(Plant):
    """Contact physics: four wheels in friction contact, the steering coupling an equality.

    Parameters
    ----------
    params : Params
        The plant's parameters (the MJCF is generated from them).
    pose : (x, y, theta)
        Initial tractor pose.
    v_init : float
        Initial forward speed (m/s), rolling.
    wrench : bool
        Disturbances arrive as a chassis wrench instead of wheel torques.
    phi0 : float or tuple of float
        Initial articulation (rad), with beta = eta phi: phi_1, or phi_1..phi_N of a train.
    gravity : (gx, gy, gz) or None
        Gravity in the ground's frame (m/s^2): a grade (:mod:`tt_mujoco.sim.parts.terrain`); None
        keeps the model's flat-ground gravity.
    relief : RampRelief or RoughRelief, optional
        The ground's shape (:mod:`tt_mujoco.sim.parts.relief`), the vehicle resting on it.
    world : World, optional
        The obstacles (:mod:`tt_mujoco.world`), collision geoms of the scene.
    """

    name = "mujoco"
    DISTURBANCE_MODES = ("matched", "wrench", "none")

    def __init__(
        self,
        params: Params,
        pose,
        v_init: float,
        wrench: bool,
        phi0: float = 0.0,
        gravity=None,
        relief=None,
        world=None,
    ):
        self.vehicle = Vehicle(params, relief, world)
        if gravity is not None:  # the model is the vehicle's own copy (physics.compile_model)
            self.vehicle.model.opt.gravity[:] = gravity
        self.vehicle.set_state(x=pose[0], y=pose[1], theta=pose[2], phi=phi0, v=v_init)
        self.model, self.data = self.vehicle.model, self.vehicle.data
        lay = self.vehicle.layout
        self._wheel_r, self._wheel_l = lay.wheel_right_v, lay.wheel_left_v
        self._act_r, self._act_l = lay.act_right, lay.act_left
        self._tractor = self.model.body("tractor").id
        self._trailer = self.model.body("trailer_body").id
        self._wrench = wrench
        self._ground = None  # friction patches, see set_ground
        self._qpos, self._qvel, self._layout = self.data.qpos, self.data.qvel, lay
        self._measure = measure if params.n_trailers == 1 else measure_train
        # eq_data rows of the joint equalities q_steer = polycoef(q_hitch): polycoef[1] = -eta.
        names = ["steering"] + [f"steering_{k}" for k in range(2, params.n_trailers + 1)]
        self._steering_ids = [self.model.equality(name).id for name in names]
        self._eq_data = self.model.eq_data
        self._steering_rows = [self._eq_data[i] for i in self._steering_ids]
        self._hitches_q = [lay.hitch_q, *(hitch_q for hitch_q, *_ in lay.train)]
        self._steers_q = [lay.steer_q, *(steer_q for _, _, steer_q, *_ in lay.train)]
        self._max_turn = params.axle_slew_rate * params.timestep  # per physics step
        self._actuated_etas: list[float] | None = None  # see steer_by_actuator

    @property
    def steering(self) -> tuple:
        """``(eq_data, equality ids, hitch qpos addresses, actuated, max_turn)``: where the
        trailers' steering couplings are (the compiled episode writes its scheduled gains
        there), and how far an actuated axle's target moves in a physics step at most."""
        actuated = self._actuated_etas is not None
        return self._eq_data, self._steering_ids, self._hitches_q, actuated, self._max_turn

    @property
    def tractor_body(self) -> int:
        """The tractor's body id (where the wrench disturbance and the wind act)."""
        return self._tractor

    @property
    def layout(self):
        """The model's addresses and lengths (:class:`tt_mujoco.sim.parts.measure.Layout`) that a
        measurement reads."""
        return self._layout

    def measure(self):
        return self._measure(self._qpos, self._qvel, self._layout)

    def scale_trailer_mass(self, factor: float, trailer: int = 1) -> None:
        """MuJoCo builds the mass matrix from ``body_mass``/``body_inertia`` every step, so this
        acts at once (only the solver's compile-time ``body_invweight0``, which scales contact
        softness, keeps its old value)."""
        scale_body_of(
            self.model.body_mass, self.model.body_inertia, self.trailer_bodies[trailer - 1], factor
        )

    @property
    def trailer_bodies(self) -> list[int]:
        """The body ids of trailers 1..N (where a payload fault acts)."""
        n = len(self._steering_ids)
        return [self._trailer, *(self.model.body(f"trailer_body_{k}").id for k in range(2, n + 1))]

    def steer_by_actuator(self) -> None:
        """Each coupling becomes an equality on the steering joint alone, ``q_steer =
        polycoef[0]``, its target set to ``eta_k phi_k`` from the hitch before every physics
        step: the constraint's force then acts between the axle and its trailer's body, and
        the hitch carries none of it (the linkage's acts on the hitch times eta). The target
        starts where the axle stands and turns at most at ``Params.axle_slew_rate``."""
        if self._actuated_etas is None:
            self._actuated_etas = [-row[1] for row in self._steering_rows]
            for i, row in zip(self._steering_ids, self._steering_rows, strict=True):
                self.model.eq_obj2id[i] = -1
                row[1] = 0.0
        for row, steer_q in zip(self._steering_rows, self._steers_q, strict=True):
            row[0] = self._qpos[steer_q]

    def set_eta(self, eta: float) -> None:
        self.set_etas((eta,))

    def set_etas(self, etas) -> None:
        if len(etas) != len(self._steering_rows):
            raise ValueError(
                f"{len(etas)} gains are not allowed: the plant has {len(self._steering_rows)} "
                "trailers"
            )
        if self._actuated_etas is not None:
            self._actuated_etas = [float(eta) for eta in etas]
            return
        for row, eta in zip(self._steering_rows, etas, strict=True):
            row[1] = -eta

    def set_ground(self, ground) -> None:
        """Friction patches (:class:`tt_mujoco.sim.parts.ground.GroundPatches`): from now on each
        step sets every wheel's contact friction from where it touches the floor."""
        m = self.model
        self._ground = ground
        self._contact_geoms = wheel_geoms(m)

    @property
    def ground(self):
        """``(GroundPatches, the wheels' contact geom ids, MjData.geom_xpos,
        MjModel.geom_friction)`` of :meth:`set_ground`, or None: what the compiled episode
        reads and writes to set each wheel's friction."""
        if self._ground is None:
            return None
        return self._ground, self._contact_geoms, self.data.geom_xpos, self.model.geom_friction

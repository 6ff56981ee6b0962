"""A Gymnasium environment on the project's plant (optional extra: ``pip install tt-mujoco[gym]``).

:class:`TractorTrailerEnv` drives the same plant as :func:`tt_mujoco.sim.simulate` (the MuJoCo
model by default, or the reduced ODE), with the same reference targets, disturbance, noise and
faults, all taken from a :class:`~tt_mujoco.sim.Scenario`. Instead of a controller, the agent
chooses the wheel torques:

- **action**: ``(T_r, T_l)`` in N m, a ``Box(-torque_limit, torque_limit, (2,))``; the
  actuators saturate, so values outside are clipped, as a real motor driver would.
- **observation**: the measurement layer (:class:`tt_mujoco.sim.measure.Measurement`, its 19
  fields in order, with the scenario's measurement noise on v and omega and any sensor dropout
  applied) followed by the tracking target ``(v_d, omega_d)``; names in
  :data:`OBSERVATION_NAMES`.
- **reward**: the negative squared tracking error ``-(e_v^2 + e_omega^2)`` after the step,
  ``e = z - z_d`` with the true velocities, so that an episode's return is ``-N`` times
  ``rmse_v^2 + rmse_omega^2`` of ``metrics.json``. A jackknife or a blow-up ends the episode
  (``terminated``) with the reward ``-(1 + steps left)``, as if every remaining step had an
  error of 1: ending early never pays.
- **truncated** when the scenario's duration is reached.
- **info**: ``t``, ``status`` ("running", "jackknife", "diverged"), the errors ``e_v``,
  ``e_omega``, the target's derivatives ``v_d_dot``, ``omega_d_dot`` (what the project's
  controllers also use) and ``slip_longitudinal`` (m/s).

The action keeps physical units (N m); wrap it in ``gymnasium.wrappers.RescaleAction`` for a
normalised ``[-1, 1]`` space. The observation is unbounded (positions, wheel angles).

One step is one control period ``scenario.control_dt`` (default here 0.01 s: 10 physics
steps of 1 ms). The default scenario has no disturbance (``Scenario(disturbance="none")``);
pass any other. Registered as ``tt_mujoco/TractorTrailer-v0``.
"""

from __future__ import annotations

import dataclasses
import math
from typing import ClassVar

import numpy as np

try:
    import gymnasium
    from gymnasium import spaces
except ImportError as err:  # pragma: no cover - depends on the optional extra
    raise ImportError("tt_mujoco.gym_env needs gymnasium: pip install 'tt-mujoco[gym]'") from err

from tt_mujoco import sim
from tt_mujoco.sim.measure import Measurement
from tt_mujoco.vehicle import reduced

__all__ = ["ENV_ID", "OBSERVATION_NAMES", "TractorTrailerEnv"]

ENV_ID = "tt_mujoco/TractorTrailer-v0"
OBSERVATION_NAMES = (*Measurement._fields, "v_d", "omega_d")
#: The environment's default control period (s): 100 Hz is plenty for an agent.
DEFAULT_CONTROL_DT = 0.01


class TractorTrailerEnv(gymnasium.Env):
    """Wheel-torque control of the tractor-trailer along a reference path.

    Parameters
    ----------
    scenario : Scenario, optional
        Path, target, plant, steering, disturbance, noise, faults, timing. Its ``controller``
        and ``gains`` are ignored (the agent is the controller). Default:
        ``Scenario(disturbance="none", control_dt=0.01)``.
    render_mode : {None, "rgb_array"}
        ``"rgb_array"`` renders the MuJoCo plant offscreen (needs an OpenGL backend, see
        :func:`tt_mujoco.viz.render.select_gl_backend`).
    **overrides
        Scenario fields to replace, e.g. ``traj="circle", plant="reduced"``.
    """

    metadata: ClassVar[dict] = {"render_modes": ["rgb_array"], "render_fps": 30}

    def __init__(self, scenario: sim.Scenario | None = None, render_mode=None, **overrides):
        if scenario is None:
            scenario = sim.Scenario(disturbance="none", control_dt=DEFAULT_CONTROL_DT)
        if overrides:
            unknown = sorted(set(overrides) - {f.name for f in dataclasses.fields(scenario)})
            if unknown:
                raise ValueError(f"unknown Scenario field(s) {unknown}")
            scenario = dataclasses.replace(scenario, **overrides)
        scenario.validate()
        # Loop features the environment does not reproduce (yet): refuse rather than ignore.
        unsupported = [
            name
            for name, off in (("reverse", False), ("eta_schedule", False), ("path_feedback", None))
            if getattr(scenario, name, off) != off
        ]
        if unsupported:
            raise ValueError(
                f"Scenario {', '.join(unsupported)} is not supported by TractorTrailerEnv"
            )
        if render_mode not in (None, *self.metadata["render_modes"]):
            raise ValueError(f"render_mode={render_mode!r} is not allowed: use None or 'rgb_array'")
        if render_mode is not None and scenario.plant != "mujoco":
            raise ValueError("render_mode='rgb_array' needs plant='mujoco'")
        self.scenario = scenario
        self.render_mode = render_mode
        self.nominal = scenario.nominal_params()
        self.plant_params = scenario.plant_params()
        limit = self.nominal.torque_limit
        self.action_space = spaces.Box(-limit, limit, shape=(2,), dtype=np.float32)
        self.observation_space = spaces.Box(
            -np.inf, np.inf, shape=(len(OBSERVATION_NAMES),), dtype=np.float64
        )
        self.dt = scenario.control_dt
        self._substeps = round(scenario.control_dt / scenario.timestep)
        self._jk = math.radians(sim.JACKKNIFE_DEG)
        self._jk_phi = math.radians(sim.jackknife_phi_deg(self.nominal.eta))
        self._plant = None
        self._renderer = None
        self._setup_target()

    def _setup_target(self) -> None:
        from tt_mujoco.reference.targets import make_target
        from tt_mujoco.sim.faults import FaultSchedule, parse_faults

        s = self.scenario
        self.path, self.target, self._pose = make_target(
            s.traj, kind=s.target, duration=s.duration, start=s.start
        )
        self.duration = float(self.target.duration)
        self.max_steps = round(self.duration / self.dt)
        self._fault_specs = parse_faults(s.faults)
        self._make_faults = lambda: (
            FaultSchedule(self._fault_specs, self.dt, self.duration) if self._fault_specs else None
        )
        if s.noise_snr_db is not None:
            self._noise = sim._noise_std(self.target, self.duration, float(s.noise_snr_db))
        else:
            self._noise = (0.0, 0.0)

    # --- gymnasium API -----------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict | None = None):
        """Start an episode at the path start (as ``simulate``). ``options`` may hold
        ``phi0_deg``, the initial articulation (default the scenario's)."""
        super().reset(seed=seed)
        s = self.scenario
        phi0_deg = s.phi0_deg if not options else options.get("phi0_deg", s.phi0_deg)
        if phi0_deg != s.phi0_deg:
            dataclasses.replace(s, phi0_deg=phi0_deg).validate()
        v_init = self.target.reference_speed(0.0) if s.start == "on_path" else 0.0
        phi0 = math.radians(phi0_deg)
        if s.plant == "mujoco":
            wrench = s.disturbance == "wrench"
            self._plant = sim._MujocoPlant(self.plant_params, self._pose, v_init, wrench, phi0)
        else:
            self._plant = sim._ReducedPlantAdapter(
                self.plant_params, self._pose, v_init, s.timestep, phi0
            )
        self._faults = self._make_faults()
        self.target.reset()
        self._k = 0
        me = self._plant.measure()
        obs = self._observe(me)
        self._last_obs = obs
        return obs, self._info(me, "running")

    def step(self, action):
        if self._plant is None:
            raise RuntimeError("call reset() before step()")
        limit = self.nominal.torque_limit
        a = np.asarray(action, dtype=float).reshape(2)
        if not np.all(np.isfinite(a)):
            raise ValueError(f"action={action!r} is not allowed: torques must be finite")
        T_r, T_l = (float(np.clip(x, -limit, limit)) for x in a)
        k, t = self._k, self._k * self.dt
        if self._faults is not None:
            T_r, T_l = self._faults.torque(k, T_r, T_l)
            factor = self._faults.payload_factor(k)
            if factor is not None:
                self._plant.scale_trailer_mass(factor)
        dist_r = dist_l = force = torque = 0.0
        me = self._me
        if self.scenario.disturbance != "none":
            a_v, a_w = sim.disturbance(t)
            if self.scenario.disturbance == "wrench":
                M = reduced.mass_matrix(me.phi, self.nominal)
                force = M[0, 0] * a_v + M[0, 1] * a_w
                torque = M[1, 0] * a_v + M[1, 1] * a_w
            else:
                dist_r, dist_l = reduced.matched_torque(me.phi, a_v, a_w, self.nominal)
        self._plant.apply(T_r, T_l, dist_r, dist_l, force, torque, me.theta)
        self._k += 1
        steps_left = self.max_steps - self._k
        try:
            self._plant.advance(self._substeps)
            self._plant.check_warnings()
            me = self._plant.measure()
            status = self._status(me)
        except reduced.SingularityError:
            status = "jackknife"
        except sim._StopRunError as stop:
            status = stop.status
        if status != "running":
            info = {"t": self._k * self.dt, "status": status}
            return self._last_obs, -(1.0 + steps_left), True, False, info
        obs = self._observe(me)
        self._last_obs = obs
        e_v, e_w = me.v - self._v_d, me.omega - self._w_d
        reward = -(e_v * e_v + e_w * e_w)
        truncated = steps_left <= 0
        return obs, float(reward), False, truncated, self._info(me, "running")

    def render(self):
        if self.render_mode != "rgb_array" or self._plant is None:
            return None
        if self._renderer is None:
            import mujoco

            from tt_mujoco.viz.render import select_gl_backend

            select_gl_backend()
            self._renderer = mujoco.Renderer(self._plant.model, 480, 640)
        self._renderer.update_scene(self._plant.data, camera="chase")
        return self._renderer.render()

    def close(self):
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    # --- helpers -----------------------------------------------------------------------------
    def _status(self, me) -> str:
        if not (math.isfinite(me.x) and math.isfinite(me.v) and math.isfinite(me.omega)):
            return "diverged"
        if abs(me.v) > sim.MAX_SPEED:
            return "diverged"
        if abs(me.phi) >= self._jk_phi or abs(me.beta) >= self._jk:
            return "jackknife"
        return "running"

    def _observe(self, me) -> np.ndarray:
        """Measurement (noisy v, omega; held during a dropout) and the target at this step."""
        self._me = me
        rng = self.np_random
        noise_v, noise_w = self._noise
        v_m = me.v + (noise_v * rng.standard_normal() if noise_v else 0.0)
        w_m = me.omega + (noise_w * rng.standard_normal() if noise_w else 0.0)
        phi_m = me.phi
        if self._faults is not None:
            phi_m, v_m, w_m = self._faults.sensor(self._k, phi_m, v_m, w_m)
        t = self._k * self.dt
        self._v_d, self._w_d, self._v_d_dot, self._w_d_dot = self.target.update(t, self.dt, v_m)
        seen = me._replace(phi=phi_m, v=v_m, omega=w_m)
        return np.array([*seen, self._v_d, self._w_d], dtype=np.float64)

    def _info(self, me, status: str) -> dict:
        return {
            "t": self._k * self.dt,
            "status": status,
            "e_v": me.v - self._v_d,
            "e_omega": me.omega - self._w_d,
            "v_d_dot": self._v_d_dot,
            "omega_d_dot": self._w_d_dot,
            "slip_longitudinal": max(abs(me.slip_left), abs(me.slip_right)),
        }


if ENV_ID not in gymnasium.registry:
    gymnasium.register(id=ENV_ID, entry_point="tt_mujoco.gym_env:TractorTrailerEnv")

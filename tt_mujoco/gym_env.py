"""A Gymnasium environment on the project's plant (optional extra: ``pip install tt-mujoco[gym]``).

:class:`TractorTrailerEnv` drives the same plant as :func:`tt_mujoco.sim.simulate` (the MuJoCo
model by default, or the reduced ODE), with the same reference targets, disturbance, noise and
faults, all taken from a :class:`~tt_mujoco.sim.Scenario`. Instead of a controller, the agent
chooses the wheel torques:

- **action**: the wheel torques ``(T_r, T_l)`` as fractions of the torque limit, a
  ``Box(-1, 1, (2,))`` (``action_units="torque"``: in N m, ``Box(-torque_limit,
  torque_limit)``); the actuators saturate, so values outside are clipped, as a real motor
  driver would.
- **observation**: the measurement layer (:class:`tt_mujoco.sim.parts.measure.Measurement`, its 19
  fields in order, with the scenario's measurement noise on v and omega and any sensor dropout
  applied), then for a train trailers 2..N (``x0_k, y0_k, theta0_k, phi_k, beta_k, v0_k``, as
  the time series' columns), then the path-frame errors of every unit against the reference
  path (``cross_track_tractor``, ``heading_error_tractor`` of the point P, and
  ``cross_track_trailer_k``, ``heading_error_trailer_k`` of each trailer's axle: the signed
  distance from the nearest path point, positive to the left of the path's direction, and
  the heading against the path's tangent: the vehicle faces along it, also when it backs up
  the path), those of
  the unit that leads the motion (``cross_track_lead``, ``heading_error_lead``: the tractor
  forward, the last trailer when reversing), and the tracking target ``(v_d, omega_d)``.
  :func:`observation_names` gives the names for N trailers, ``env.observation_names`` the
  environment's; :data:`OBSERVATION_NAMES` are the one-trailer vehicle's.
- **reward**, by ``task``: ``"velocity"`` (the default), the negative squared tracking error
  ``-(e_v^2 + e_omega^2)`` after the step, ``e = z - z_d`` with the true velocities, so that an
  episode's return is ``-N`` times ``rmse_v^2 + rmse_omega^2`` of ``metrics.json``;
  ``"path"``, following the path with the unit that leads the motion (the tractor forward, the
  last trailer backing up): the negative mean of its squared cross-track and heading errors
  and the speed error, each scaled by :data:`PATH_TASK_SCALES`, capped at 1 a step (an error
  of one scale or more costs 1), so an agent that stands still on the path still pays for its
  speed error, and no step costs more than one a failure leaves. A jackknife or a blow-up
  ends the episode
  (``terminated``) with the reward ``-(1 + steps left)``, as if every remaining step had an
  error of 1: ending early never pays; so does a unit touching a world's obstacle (status
  "collision"), and a user's path or disturbance that fails
  (``info["status"]`` "failed", ``info["message"]`` why).
- **truncated** when the scenario's duration is reached (``info["status"]`` is then "ok", as
  the finished run's ``metrics.json`` says).
- **info**: ``t``, ``leg`` (the leg of a planned maneuver that is driven, 0 for a run),
  ``status`` ("running", "ok", "jackknife", "diverged", "collision", "failed"), the errors
  ``e_v``, ``e_omega``, the target's derivatives ``v_d_dot``, ``omega_d_dot`` (what the
  project's controllers also use), ``slip_longitudinal`` (m/s) and ``etas``, the trailers'
  steering gains in force (a scheduled eta changes them; a model-based agent hands them to its
  model, as :meth:`controllers.base.Controller.steering_changed` does).

Every observation has finite bounds (:func:`observation_bounds`), each from a limit the
project keeps: positions within the reach of the path in the episode (``MAX_SPEED`` times the
duration, plus the train's length), headings wrapped to ``[-pi, pi]``, speeds within
``MAX_SPEED``, the yaw rate within the wheels' ``MAX_SPEED`` apart, the hitch angles within
``pi``. A state beyond them has blown up: the observation is clipped to them.

A planned maneuver with cusps (``Scenario(world=..., traj="plan")`` from a start the planner
reaches with a direction switch) is one episode of its legs, driven as ``python -m
tt_mujoco.run`` drives them (:mod:`tt_mujoco.sim.maneuver`, :mod:`tt_mujoco.gym_legs`): the
step that ends a leg returns the next leg's first observation (the train at rest where the
leg stopped, on a fresh plant; its path and the unit that leads its motion; its target), its
reward that of the step; the episode's time runs on; ``max_steps`` and the spaces cover every
leg as planned, and truncation comes at the end of the last.

Vectorised, the environment resets an episode that ended on the step after (gymnasium's
``AutoresetMode.NEXT_STEP``, ``metadata["autoreset_mode"]``). ``gymnasium.make_vec(ENV_ID,
num_envs=N)`` makes :class:`tt_mujoco.gym_vector.TractorTrailerVectorEnv`, whose episodes step
together in compiled code, the same numbers as this env's.

One step is one control period ``scenario.control_dt`` (default here 0.01 s: 10 physics
steps of 1 ms). The default scenario has no disturbance (``Scenario(disturbance="none")``);
pass any other: every scenario option works (reverse driving, the curvature-scheduled eta,
path feedback, faults, path hooks, ...), because the environment drives the same
:class:`~tt_mujoco.sim.loop.stepper.Stepper` as :func:`~tt_mujoco.sim.simulate`. The noise seed is
``reset(seed=...)``; the first reset without a seed uses the scenario's, so the same seed gives
the same episode on every route. Registered as ``tt_mujoco/TractorTrailer-v0``; vectorised
with ``gymnasium.make_vec(ENV_ID, num_envs=N)`` (the vector env above), or as Gymnasium's
vectors of this env with ``vectorization_mode="sync"`` (or "async").

**Rendering** needs ``render_mode="rgb_array"`` at construction (the MuJoCo plant only):
``render()`` then returns a 480 x 640 RGB frame of the current state. With
``render_mode=None`` it warns and returns None, as Gymnasium's environments do; before the
first ``reset()`` there is no state to draw, and it raises ``gymnasium.error.ResetNeeded``.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from numbers import Integral
from typing import ClassVar

import numpy as np

try:
    import gymnasium
    from gymnasium import spaces
except ImportError as err:  # pragma: no cover - depends on the optional extra
    raise ImportError("tt_mujoco.gym_env needs gymnasium: pip install 'tt-mujoco[gym]'") from err

import mujoco

from tt_mujoco import sim
from tt_mujoco.defaults import MAX_SPEED
from tt_mujoco.gym_legs import Legs, OwnScenario
from tt_mujoco.reference.feedback import path_errors
from tt_mujoco.registry import shown
from tt_mujoco.schema import Schema, check_typed
from tt_mujoco.sim.loop.episode import has_closed_form
from tt_mujoco.sim.loop.timeseries import train_columns
from tt_mujoco.sim.maneuver import leg_rng
from tt_mujoco.sim.parts.measure import Measurement
from tt_mujoco.sim.usercode import CheckedPath, path_label
from tt_mujoco.viz.offscreen import Offscreen

__all__ = [
    "ACTION_UNITS",
    "ENV_ID",
    "OBSERVATION_NAMES",
    "PATH_TASK_SCALES",
    "RESET_OPTIONS",
    "TASKS",
    "TractorTrailerEnv",
    "bounded",
    "observation_bounds",
    "observation_names",
    "reset_phi0_deg",
    "task_reward",
    "torques_of",
]

ENV_ID = "tt_mujoco/TractorTrailer-v0"

#: What ``reset(options=...)`` may hold.
RESET_OPTIONS = ("phi0_deg",)


def observation_names(n_trailers: int = 1) -> tuple[str, ...]:
    """The observation's names, in order, for a vehicle with ``n_trailers`` trailers."""
    units = ["tractor", *(f"trailer_{k}" for k in range(1, n_trailers + 1)), "lead"]
    errors = [f"{name}_{unit}" for unit in units for name in ("cross_track", "heading_error")]
    return (*Measurement._fields, *train_columns(n_trailers), *errors, "v_d", "omega_d")


#: The observation's names for the paper's vehicle (one trailer).
OBSERVATION_NAMES = observation_names(1)
#: The environment's default control period (s): 100 Hz is plenty for an agent.
DEFAULT_CONTROL_DT = 0.01
#: The action's units: fractions of the torque limit (the default), or N m.
ACTION_UNITS = ("normalized", "torque")
#: What the reward rewards: tracking the velocity target, or following the path.
TASKS = ("velocity", "path")
#: The path task's error scales: the leading unit's cross-track (m) and heading error (rad),
#: the speed error (m/s). An error of one scale costs as much as one of another.
PATH_TASK_SCALES = {"cross_track": 0.05, "heading_error": 0.1, "speed": 0.2}
#: The observation fields that are headings, wrapped to [-pi, pi] (a unit's own, or its error
#: against the path's tangent).
HEADINGS = ("theta", "theta0", "heading_error")


def _field(name: str) -> str:
    """An observation's quantity: ``x0_2`` is an ``x0``, ``cross_track_trailer_1`` a
    ``cross_track``."""
    for prefix in ("cross_track", "heading_error"):
        if name.startswith(prefix):
            return prefix
    base, _, k = name.rpartition("_")
    return base if k.isdigit() and base else name


def observation_bounds(names, params, reference: np.ndarray, duration: float):
    """``(low, high)`` of each observation in ``names``: what a state that has not blown up
    stays within, from the project's limits (``MAX_SPEED``, the wheels' radius ``r`` and half
    track ``d``) and the episode's reach of the path (``reference``, an ``(N, 2)`` polyline).

    Parameters
    ----------
    names : sequence of str
        :func:`observation_names`.
    params : Params
        The plant's parameters (the train's length, ``r``, ``d``).
    reference : ndarray
        The path as the episode can reach it.
    duration : float
        The episode's length (s).
    """
    reach = MAX_SPEED * duration + sum(t.L + t.L0 for t in params.trailers) + params.d
    (x_lo, y_lo), (x_hi, y_hi) = reference.min(axis=0), reference.max(axis=0)
    wheel_rate = MAX_SPEED / params.r
    bounds = {
        "x": (x_lo - reach, x_hi + reach),
        "y": (y_lo - reach, y_hi + reach),
        "x0": (x_lo - reach, x_hi + reach),
        "y0": (y_lo - reach, y_hi + reach),
        "cross_track": (-reach, reach),
        **dict.fromkeys(HEADINGS, (-math.pi, math.pi)),
        **dict.fromkeys(("phi", "beta"), (-math.pi, math.pi)),
        **dict.fromkeys(("v", "v0", "v_d"), (-MAX_SPEED, MAX_SPEED)),
        **dict.fromkeys(("omega", "omega_d"), (-MAX_SPEED / params.d, MAX_SPEED / params.d)),
        **dict.fromkeys(("theta_l", "theta_r"), (-wheel_rate * duration, wheel_rate * duration)),
        **dict.fromkeys(("theta_l_dot", "theta_r_dot"), (-wheel_rate, wheel_rate)),
        **dict.fromkeys(
            ("slip_lateral", "slip_lateral_trailer", "slip_left", "slip_right"),
            (-2.0 * MAX_SPEED, 2.0 * MAX_SPEED),
        ),
    }
    pairs = [bounds[_field(name)] for name in names]
    return np.array([p[0] for p in pairs]), np.array([p[1] for p in pairs])


def scenario_overrides(
    overrides: dict, schema: Schema = sim.SCHEMA, where: str = "TractorTrailerEnv"
) -> dict:
    """The env's keyword arguments as checked Scenario values: the option schema's checks and
    "did you mean", as the command line, scenario files and sweeps have.

    Raises
    ------
    ValueError
        An unknown name (with the nearest) or a bad value, named, with ``where`` (the env
        that was given it).
    """
    return schema.values(overrides, where)


def torques_of(action, shape: tuple, action_units: str, limit: float) -> np.ndarray:
    """The agent's ``action`` (one ``(T_r, T_l)``, or a batch of them: ``shape``) as wheel
    torques (N m), from fractions of the torque ``limit`` (``action_units="normalized"``) or
    N m.

    Raises
    ------
    ValueError
        An action not of ``shape`` or not finite, named, with what is allowed.
    """
    try:  # real numbers of the action space's shape: no complex part or column dropped
        given = np.asarray(action)
        real = given.dtype.kind in "iuf" and given.shape == shape
        torques = given.astype(float) if real else None
    except (TypeError, ValueError):
        torques = None
    if torques is None or not np.all(np.isfinite(torques)):
        name, count = ("action", "two") if shape == (2,) else ("actions", str(shape))
        units = (
            ", fractions of the torque limit in [-1, 1]"
            if action_units == "normalized"
            else " in N m"
        )
        raise ValueError(
            f"{name}={shown(action)} is not allowed: give {count} finite numbers (T_r, T_l)" + units
        )
    return torques * limit if action_units == "normalized" else torques


def reset_phi0_deg(scenario: sim.Scenario, options: dict | None) -> float | None:
    """The initial articulation (deg) that ``reset(options=...)`` asks, checked; None for the
    scenario's own start (backing up: the trailers on the path).

    Raises
    ------
    ValueError
        An option ``reset`` does not take, or a ``phi0_deg`` the scenario refuses, named.
    """
    refused, allowed = f"options={shown(options)} is not allowed", ", ".join(RESET_OPTIONS)
    if options is not None and not isinstance(options, Mapping):
        raise ValueError(f"{refused}: give a dict of reset options ({allowed}) or None")
    unknown = sorted(set(options or {}) - set(RESET_OPTIONS), key=str)
    if unknown:
        raise ValueError(f"{refused}: {unknown[0]!r} is not a reset option (allowed: {allowed})")
    phi0_deg = (options or {}).get("phi0_deg", scenario.phi0_deg)
    if phi0_deg == scenario.phi0_deg:
        return None
    dataclasses.replace(scenario, phi0_deg=phi0_deg).validate()
    return phi0_deg


def checked_seed(seed, label: str = "seed") -> int | None:
    """``reset``'s ``seed`` as the run's: None, or an integer the option schema allows (any
    integer type, NumPy's too), so a seed the command line refuses (a bool, beyond a TOML
    integer) is refused here as well and every seed an env takes reproduces on every route.

    Raises
    ------
    ValueError
        Naming the seed and what is allowed.
    """
    if seed is None:
        return None
    if isinstance(seed, Integral) and not isinstance(seed, bool | np.bool_):
        seed = int(seed)
    checked = sim.SCHEMA["seed"].parse(seed, label)
    check_typed(seed, checked, label)  # "3" is text, not a seed
    return checked


def bounded(observation, headings, low, high) -> np.ndarray:
    """A copy of ``observation`` (one, or a batch along the leading axes) with its headings
    (the boolean mask ``headings``) wrapped to [-pi, pi] and every value clipped to its bounds
    ``(low, high)``: a state beyond them has blown up."""
    out = np.array(observation, dtype=np.float64)
    out[..., headings] = np.remainder(out[..., headings] + math.pi, 2 * math.pi) - math.pi
    return np.clip(out, low, high)


def task_reward(task: str, v, omega, target, lead):
    """The reward of ``task`` after a step (see the module), of one episode (floats) or of a
    batch (arrays, elementwise): the true ``v``, ``omega``, the ``target`` ``(v_d, omega_d)``
    and the ``lead`` unit's ``(cross_track, heading_error)``."""
    e_v = v - target[0]
    if task == "velocity":
        e_w = omega - target[1]
        return -(e_v * e_v + e_w * e_w)
    scales = PATH_TASK_SCALES
    a = lead[0] / scales["cross_track"]
    b = lead[1] / scales["heading_error"]
    c = e_v / scales["speed"]
    mean = (a * a + b * b + c * c) / 3
    return -np.where(mean < 1.0, mean, 1.0)  # min(1.0, mean): an error of NaN costs 1 too


class TractorTrailerEnv(OwnScenario, gymnasium.Env):
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
    action_units : {"normalized", "torque"}
        The action as fractions of the torque limit in ``[-1, 1]`` (the default), or as
        torques in N m.
    task : {"velocity", "path"}
        What the reward rewards (see the module): tracking ``(v_d, omega_d)``, or following
        the path with the leading unit.
    **overrides
        Scenario fields to replace, e.g. ``traj="circle", plant="reduced"``.
    """

    metadata: ClassVar[dict] = {
        "render_modes": ["rgb_array"],
        "render_fps": 30,
        "autoreset_mode": gymnasium.vector.AutoresetMode.NEXT_STEP,
    }

    def __init__(
        self,
        scenario: sim.Scenario | None = None,
        render_mode=None,
        action_units: str = "normalized",
        task: str = "velocity",
        **overrides,
    ):
        if scenario is None:
            scenario = sim.Scenario(disturbance="none", control_dt=DEFAULT_CONTROL_DT)
        if overrides:
            scenario = dataclasses.replace(scenario, **scenario_overrides(overrides))
        if render_mode not in (None, *self.metadata["render_modes"]):
            raise ValueError(f"render_mode={render_mode!r} is not allowed: use None or 'rgb_array'")
        if render_mode is not None and scenario.plant != "mujoco":
            raise ValueError("render_mode='rgb_array' needs plant='mujoco'")
        if action_units not in ACTION_UNITS:
            raise ValueError(
                f"action_units={action_units!r} is not allowed: use one of {ACTION_UNITS}"
            )
        if task not in TASKS:
            raise ValueError(f"task={task!r} is not allowed: use one of {TASKS}")
        self.task = task
        self._own(scenario)
        self.render_mode = render_mode
        self._legs = Legs(sim.build(scenario))
        #: The episode's legs: more than one for a planned maneuver with cusps.
        self.n_legs = self._legs.count
        first = self._legs.first
        self.n_trailers = first.plant_params.n_trailers
        self._t0 = 0.0
        self._first_stepper = sim.Stepper(first)
        self._use_leg(0, first, self._first_stepper)
        self.nominal = first.nominal
        self.plant_params = first.plant_params
        #: The episode's length (s): a maneuver's, every leg's as planned.
        self.duration = self._legs.duration
        limit = self.nominal.torque_limit
        self.observation_names = observation_names(self.n_trailers)
        self.action_units = action_units
        #: the torque limit (N m) a normalised action is a fraction of
        self.torque_limit = limit
        bound = 1.0 if action_units == "normalized" else limit
        self.action_space = spaces.Box(-bound, bound, shape=(2,), dtype=np.float32)
        reach = self._legs.reach()
        self._low, self._high = observation_bounds(
            self.observation_names, self.plant_params, reach, self.duration
        )
        self.observation_space = spaces.Box(self._low, self._high, dtype=np.float64)
        self._headings = np.array([_field(n) in HEADINGS for n in self.observation_names])
        self.dt = scenario.control_dt
        #: The episode's control steps: a maneuver's, every leg's as planned.
        self.max_steps = self._legs.steps
        self._seeded = False
        self._renderer = None
        self._episode_seed = scenario.seed

    def _use_leg(self, index: int, built, stepper) -> None:
        """Drive leg ``index`` of the episode (``built``, with ``stepper``): its path, its
        target, its direction (the unit that leads)."""
        self._leg, self._built, self._stepper = index, built, stepper
        self.path, self.target = built.path, built.target
        self._reverse = bool(built.scenario.reverse)
        asked = self.path
        if not has_closed_form(asked):  # a user's path: guarded and checked, as the step asks it
            asked = CheckedPath(asked, path_label(built))
        self._pose_at, self._curvature = asked.pose_at, asked.curvature_and_rate
        # Each unit's nearest path point, warm-started from the target's start.
        self._unit_s = [float(self.target.start_s)] * (1 + self.n_trailers)

    # --- gymnasium API -----------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict | None = None):
        """Start an episode at the path start (as ``simulate``). ``options`` may hold
        ``phi0_deg``, the initial articulation (default the scenario's)."""
        if seed is None and not self._seeded:
            seed = self._scenario.seed
        seed = checked_seed(seed)
        phi0_deg = reset_phi0_deg(self._scenario, options)
        super().reset(seed=seed)
        self._seeded = True
        if self._legs.count > 1:  # the later legs' noise: the maneuver's of this seed
            self._episode_seed = seed if seed is not None else int(self.np_random.integers(2**63))
        self._use_leg(0, self._legs.first, self._first_stepper)
        self._t0 = 0.0
        self._stepper.reset(self.np_random, phi0_deg=phi0_deg)
        self.close()  # a new plant: the renderer is made again for its model
        obs = self._sense()
        return obs, self._info("running")

    def step(self, action):
        if self._stepper.plant is None:
            raise RuntimeError("call reset() before step()")
        a = torques_of(action, (2,), self.action_units, self.torque_limit)
        stepper = self._stepper
        leg_left = self._leg_steps_left()
        steps_left = leg_left + self._legs.steps_after(self._leg)
        try:
            if not stepper.actuate(float(a[0]), float(a[1])):
                raise RuntimeError("the episode is over: call reset()")
            obs = self._sense()
        except sim.StopRun as stop:
            return self._stopped(stop.status, stop.message, steps_left)
        reward = self._reward()
        if leg_left <= 0 and self._leg + 1 < self._legs.count:
            try:  # the train at rest where this leg stopped, the next leg's target
                obs = self._next_leg()
            except ValueError as err:  # it cannot start there: the maneuver stops as failed
                return self._stopped("failed", str(err), steps_left)
        truncated = steps_left <= 0
        return obs, float(reward), False, truncated, self._info("ok" if truncated else "running")

    def steps_left(self) -> int:
        """Control steps left in the episode after the coming one (every later leg's as
        planned)."""
        return self._leg_steps_left() + self._legs.steps_after(self._leg)

    def _leg_steps_left(self) -> int:
        """Control steps left in the leg that is driven, after the coming one."""
        return self._built.steps - self._stepper.k - 1

    def _stopped(self, status: str, message: str, steps_left: int):
        """The step that ends the episode early: the last observation, the penalty."""
        info = {"t": self._t, "status": status, "message": message, "leg": self._leg}
        return self._last_obs, -(1.0 + steps_left), True, False, info

    def _next_leg(self) -> np.ndarray:
        """Start the maneuver's next leg where this one stopped (the maneuver's way: a fresh
        plant at rest, the noise of the episode's seed and the leg): its first observation."""
        index = self._leg + 1
        built = self._legs.next(index, self._stepper.measurement)
        self._t0 = self._t + self.dt  # the maneuver's joined time runs on
        stepper = sim.Stepper(built)
        self._use_leg(index, built, stepper)
        stepper.reset(leg_rng(self._episode_seed, index))
        self.close()  # a new plant: the renderer is made again for its model
        return self._sense()

    @property
    def _t(self) -> float:
        """The episode's time (s): a maneuver's runs on over its legs."""
        return self._t0 + self._stepper.k * self.dt

    def render(self):
        """An RGB image (480 x 640) of the MuJoCo plant from the chase camera. Headless like
        ``run``: the OpenGL backend is chosen by :func:`tt_mujoco.viz.gl.select_gl_backend`
        (EGL, else OSMesa), not by a display.

        Raises
        ------
        gymnasium.error.ResetNeeded
            Before the first :meth:`reset`: there is no state to draw yet.
        """
        if self.render_mode is None:
            gymnasium.logger.warn(
                "render() was called with render_mode=None: make the environment with "
                "render_mode='rgb_array' to get frames"
            )
            return None
        if self._stepper.plant is None:
            raise gymnasium.error.ResetNeeded(
                "render() before reset(): call reset() first, then render() draws its state"
            )
        model, data = self._stepper.plant.model, self._stepper.plant.data
        if self._renderer is None:
            self._renderer = Offscreen(model, 640, 480, maxgeom=1000)
            self._camera = mujoco.MjvCamera()
            self._camera.type = mujoco.mjtCamera.mjCAMERA_FIXED
            self._camera.fixedcamid = model.camera("chase").id
            self._options = mujoco.MjvOption()
        mujoco.mjv_updateScene(
            model,
            data,
            self._options,
            None,
            self._camera,
            mujoco.mjtCatBit.mjCAT_ALL,
            self._renderer.scene,
        )
        return self._renderer.render()

    def last_measurement(self):
        """The measurement of the last step (:class:`tt_mujoco.sim.parts.measure.Measurement`: true
        poses, the scenario's noise on v and omega)."""
        return self._me

    def last_axle_pose(self) -> tuple[float, float, float]:
        """``(x, y, theta)`` of the last trailer's axle at the last step."""
        me = self._me
        if self.n_trailers == 1:
            return me.x0, me.y0, me.theta0
        row = me.train[-1]
        return row[0], row[1], row[2]

    def close(self):
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    # --- helpers -----------------------------------------------------------------------------
    def _sense(self) -> np.ndarray:
        """Measurement (noisy v, omega; held during a dropout), trailers 2..N, every unit's
        path-frame errors and the target at this step."""
        seen, ref = self._stepper.sense()
        me = self._stepper.measurement
        self._me, self._ref = me, ref
        train = [value for row in seen.train for value in row] if self.n_trailers > 1 else []
        errors = self._path_errors(me)
        lead = errors[-2:] if self._reverse else errors[:2]
        self._lead = lead
        obs = [*seen, *train, *errors, *lead, ref.v_d, ref.omega_d]
        obs = bounded(obs, self._headings, self._low, self._high)
        self._last_obs = obs
        return obs.copy()

    def _path_errors(self, me) -> list[float]:
        """``[cross_track, heading_error]`` of the tractor's P and of each trailer's axle, in
        order, against the reference path (true poses: the paper's noise is on v, omega)."""
        poses = [(me.x, me.y, me.theta), (me.x0, me.y0, me.theta0)]
        poses += [(row[0], row[1], row[2]) for row in getattr(me, "train", ())]
        out = []
        for i, (x, y, theta) in enumerate(poses):
            s, e_y, e_psi = path_errors(
                self._pose_at, self._curvature, self._unit_s[i], x, y, theta
            )
            self._unit_s[i] = s
            out += [e_y, e_psi]
        return out

    def _reward(self) -> float:
        """The step's reward for the env's task (see the module), after the step."""
        me, ref = self._me, self._ref
        return float(task_reward(self.task, me.v, me.omega, (ref.v_d, ref.omega_d), self._lead))

    def _info(self, status: str) -> dict:
        me, ref = self._me, self._ref
        return {
            "t": self._t,
            "leg": self._leg,
            "status": status,
            "e_v": me.v - ref.v_d,
            "e_omega": me.omega - ref.omega_d,
            "v_d_dot": ref.v_d_dot,
            "omega_d_dot": ref.omega_d_dot,
            "slip_longitudinal": max(abs(me.slip_left), abs(me.slip_right)),
            "etas": self._stepper.plant_etas,
        }


if ENV_ID not in gymnasium.registry:  # make_vec's default: the vector env (tt_mujoco.gym_vector)
    gymnasium.register(
        id=ENV_ID,
        entry_point="tt_mujoco.gym_env:TractorTrailerEnv",
        vector_entry_point="tt_mujoco.gym_vector:TractorTrailerVectorEnv",
    )

"""A goal-conditioned Gymnasium environment: take the train's last axle to a world's goal
(optional extra: ``pip install tt-mujoco[gym]``).

:class:`TractorTrailerGoalEnv` is the maneuver of ``--world NAME --traj plan`` as a task for an
agent that chooses the wheel torques. Each episode starts where the world's start ranges draw
it for the episode's seed (:func:`tt_mujoco.world.plan.start_pose`, as a planned run does) and
steps the same plant as :class:`~tt_mujoco.gym_env.TractorTrailerEnv`, on the path the planner
finds from that start, which the observation measures its errors against (a guide the agent
may use or ignore). Episodes start only where the planner backs in (or drives in) with one leg:
a start with no plan or with a cusp is passed over for the next seed drawn.

- **observation**: a dict, as goal-conditioned learning (hindsight relabelling) asks:
  ``observation`` (the :class:`~tt_mujoco.gym_env.TractorTrailerEnv` observation, its bounds
  from the world's bounds, not the episode's path, so the space is the same every episode),
  ``achieved_goal`` (the last axle's ``x, y, cos(theta), sin(theta)``) and ``desired_goal``
  (the goal's).
- **reward**: :meth:`TractorTrailerGoalEnv.compute_reward` of the achieved and desired goal,
  vectorised over leading dimensions. ``"sparse"`` (the default): 0 where the last axle is
  within the goal's tolerances (position and heading, ``world.goal``), -1 elsewhere;
  ``"dense"``: minus the position error plus the train's length times the heading error (m).
  A contact, a jackknife or a blow-up ends the episode (``terminated``); that step's reward
  counts once for every step the episode had left (``info["steps_left"]``), so ending early
  never pays, and the relabelled reward keeps it.
- **terminated** also when the train rests in the goal (within its tolerances, the tractor
  slower than :data:`REST_SPEED`); **truncated** after ``episode_s`` seconds.
- **info**: the inner env's, with ``is_success`` (within the tolerances), ``failed`` and
  ``steps_left``.

The same seed gives the same start, plan and noise as ``python -m tt_mujoco.run --world ...
--traj plan --seed SEED``. Registered as ``tt_mujoco/TractorTrailerGoal-v0``.
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
    raise ImportError("tt_mujoco.gym_goal needs gymnasium: pip install 'tt-mujoco[gym]'") from err

from tt_mujoco import sim
from tt_mujoco.gym_env import (
    DEFAULT_CONTROL_DT,
    TractorTrailerEnv,
    checked_seed,
    observation_bounds,
    observation_names,
    scenario_overrides,
)
from tt_mujoco.gym_legs import OwnScenario
from tt_mujoco.registry import shown
from tt_mujoco.world.builtin import parse_world
from tt_mujoco.world.plan import PLAN, PlanError, train_length

__all__ = ["GOAL_ENV_ID", "REST_SPEED", "REWARD_TYPES", "TractorTrailerGoalEnv"]

GOAL_ENV_ID = "tt_mujoco/TractorTrailerGoal-v0"
#: The reward's kinds (see the module).
REWARD_TYPES = ("sparse", "dense")
#: Below this speed (m/s) a train within the goal's tolerances has arrived.
REST_SPEED = 0.05
#: An episode's length (s): longer than any plan of the named worlds takes at cruise speed.
EPISODE_S = 60.0
#: How many seeds are drawn for an episode before its world is called unplannable.
SEED_DRAWS = 100


class TractorTrailerGoalEnv(OwnScenario, gymnasium.Env):
    """Wheel-torque control of the tractor-trailer to a world's goal (see the module).

    Parameters
    ----------
    scenario : Scenario, optional
        Its ``world`` (which must have a goal and a start), plant, noise, steering, timing;
        ``traj`` is ``"plan"``. Default: ``Scenario(world="loading_bay", traj="plan",
        reverse=True, disturbance="none", control_dt=0.01)``.
    reward_type : {"sparse", "dense"}
    episode_s : float
        The episode's length (s).
    action_units : {"normalized", "torque"}
        As :class:`~tt_mujoco.gym_env.TractorTrailerEnv`'s.
    **overrides
        Scenario fields to replace, e.g. ``world="yard", trailers=2``.
    """

    metadata: ClassVar[dict] = {
        "render_modes": [],
        "autoreset_mode": gymnasium.vector.AutoresetMode.NEXT_STEP,
    }

    def __init__(
        self,
        scenario: sim.Scenario | None = None,
        reward_type: str = "sparse",
        episode_s: float = EPISODE_S,
        action_units: str = "normalized",
        **overrides,
    ):
        if scenario is None:
            scenario = sim.Scenario(
                world="loading_bay",
                reverse=True,
                disturbance="none",
                control_dt=DEFAULT_CONTROL_DT,
            )
        overrides = {**overrides, "traj": PLAN}
        scenario = dataclasses.replace(
            scenario, **scenario_overrides(overrides, where=type(self).__name__)
        )
        scenario.validate()
        if reward_type not in REWARD_TYPES:
            raise ValueError(
                f"reward_type={reward_type!r} is not allowed: use one of {REWARD_TYPES}"
            )
        if not (isinstance(episode_s, int | float) and math.isfinite(episode_s) and episode_s > 0):
            raise ValueError(f"episode_s={episode_s!r} is not allowed: give a positive number (s)")
        world = parse_world(scenario.world)
        if world is None or world.goal is None or world.start is None:
            raise ValueError(
                f"world={scenario.world!r} is not allowed: the goal env needs a world with a "
                "goal and a start"
            )
        steps = round(episode_s / scenario.control_dt)
        self._own(dataclasses.replace(scenario, duration=steps * scenario.control_dt))
        self.reward_type, self.episode_s, self.action_units = reward_type, episode_s, action_units
        self.world = world
        p = scenario.plant_params()
        self.train_length = train_length(p)
        goal = world.goal
        heading = math.radians(goal.heading_deg)
        self.desired_goal = np.array([goal.x, goal.y, math.cos(heading), math.sin(heading)])
        self.position_tolerance = goal.position_tolerance
        self.heading_tolerance = math.radians(goal.heading_tolerance_deg)
        x_min, x_max, y_min, y_max = world.bounds or (goal.x, goal.x, goal.y, goal.y)
        corners = np.array([[x_min, y_min], [x_max, y_max]])
        names = observation_names(p.n_trailers)
        self._low, self._high = observation_bounds(names, p, corners, self._scenario.duration)
        reach = self._high[names.index("x")] - x_max
        goal_low = np.array([x_min - reach, y_min - reach, -1.0, -1.0])
        goal_high = np.array([x_max + reach, y_max + reach, 1.0, 1.0])
        self.observation_space = spaces.Dict(
            {
                "observation": spaces.Box(self._low, self._high, dtype=np.float64),
                "achieved_goal": spaces.Box(goal_low, goal_high, dtype=np.float64),
                "desired_goal": spaces.Box(goal_low, goal_high, dtype=np.float64),
            }
        )
        bound = 1.0 if action_units == "normalized" else p.torque_limit
        self.action_space = spaces.Box(-bound, bound, shape=(2,), dtype=np.float32)
        self.observation_names = names
        self._env: TractorTrailerEnv | None = None
        self._seeded = False

    # --- gymnasium API -----------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict | None = None):
        """Start an episode: at the start of ``seed`` (a run's of that seed) where the planner
        finds a one-leg plan from it, else, as without a seed, at the next start drawn from
        the env's random stream that has one (``info["seed"]`` names it). It takes no
        ``options``."""
        if options:
            raise ValueError(
                f"options={shown(options)} is not allowed: this env's reset takes none (its start "
                "is drawn in the world, by the seed)"
            )
        if seed is None and not self._seeded:
            seed = self._scenario.seed
        seed = checked_seed(seed)
        super().reset(seed=seed)
        self._seeded = True
        candidates = [int(seed)] if seed is not None else []
        candidates += [int(self.np_random.integers(2**31)) for _ in range(SEED_DRAWS)]
        for episode_seed in candidates:
            env = self._episode(episode_seed)
            if env is not None:
                break
        else:
            raise RuntimeError(
                f"none of {len(candidates)} starts drawn in world {self.world.name!r} has a "
                "plan with one leg"
            )
        if self._env is not None:
            self._env.close()
        self._env = env
        obs, info = env.reset(seed=episode_seed)
        info = {**info, "seed": episode_seed}
        observation = self._observation(obs)
        return observation, self._goal_info(info, observation, failed=False, steps_left=0)

    def step(self, action):
        if self._env is None:
            raise RuntimeError("call reset() before step()")
        env = self._env
        steps_left = env.steps_left()
        obs, _, terminated, truncated, info = env.step(action)
        failed = bool(terminated)  # the inner env ends early only on a failure
        observation = self._observation(obs)
        info = self._goal_info(info, observation, failed, steps_left if failed else 0)
        reward = float(self.compute_reward(observation["achieved_goal"], self.desired_goal, info))
        if not failed and info["is_success"] and abs(env.last_measurement().v) < REST_SPEED:
            terminated = True
        return observation, reward, terminated, truncated, info

    def compute_reward(self, achieved_goal, desired_goal, info):
        """The reward of reaching ``achieved_goal`` when ``desired_goal`` was asked (arrays
        of 4 values on their last axis, any leading shape), ``info`` a dict or an array of
        them (a failure's reward counts for the steps it left)."""
        achieved, desired = np.asarray(achieved_goal, float), np.asarray(desired_goal, float)
        if self.reward_type == "sparse":
            base = -(~self._within(achieved, desired)).astype(float)
        else:
            distance, heading = self._errors(achieved, desired)
            base = -(distance + self.train_length * heading)
        return base * (1.0 + self._steps_left(info, np.shape(base)))

    def close(self):
        if self._env is not None:
            self._env.close()

    # --- helpers -----------------------------------------------------------------------------
    def _episode(self, seed: int) -> TractorTrailerEnv | None:
        """The inner env of an episode of ``seed``, or None where its start has no one-leg
        plan."""
        try:
            env = TractorTrailerEnv(
                dataclasses.replace(self._scenario, seed=seed), action_units=self.action_units
            )
        except PlanError:
            return None
        if env.n_legs > 1:  # a goal episode is one leg: a start with a cusp is passed over
            env.close()
            return None
        return env

    def _observation(self, obs) -> dict:
        pose = self._env.last_axle_pose()
        achieved = np.array([pose[0], pose[1], math.cos(pose[2]), math.sin(pose[2])])
        space = self.observation_space["achieved_goal"]
        return {
            "observation": np.clip(obs, self._low, self._high),
            "achieved_goal": np.clip(achieved, space.low, space.high),
            "desired_goal": self.desired_goal.copy(),
        }

    def _errors(self, achieved, desired):
        """The position error (m) and the heading error (rad, in [0, pi])."""
        distance = np.hypot(achieved[..., 0] - desired[..., 0], achieved[..., 1] - desired[..., 1])
        dot = achieved[..., 2] * desired[..., 2] + achieved[..., 3] * desired[..., 3]
        cross = achieved[..., 2] * desired[..., 3] - achieved[..., 3] * desired[..., 2]
        return distance, np.abs(np.arctan2(cross, dot))

    @staticmethod
    def _steps_left(info, shape) -> np.ndarray:
        if isinstance(info, dict):
            return np.full(shape, float(info.get("steps_left", 0)))
        return np.array([float(i.get("steps_left", 0)) for i in np.ravel(info)]).reshape(shape)

    def _within(self, achieved, desired):
        """Whether each achieved goal is within the goal's tolerances of the desired one."""
        distance, heading = self._errors(achieved, desired)
        return (distance <= self.position_tolerance) & (heading <= self.heading_tolerance)

    def _goal_info(self, info: dict, observation: dict, failed: bool, steps_left: int) -> dict:
        success = bool(self._within(observation["achieved_goal"], self.desired_goal))
        return {
            **info,
            "is_success": success and not failed,
            "failed": failed,
            "steps_left": steps_left,
        }


if GOAL_ENV_ID not in gymnasium.registry:
    gymnasium.register(id=GOAL_ENV_ID, entry_point="tt_mujoco.gym_goal:TractorTrailerGoalEnv")

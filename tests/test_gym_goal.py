"""The goal-conditioned env (tt_mujoco.gym_goal) and the gym env's path task: rewards that are
functions of the goals (so relabelling keeps them), success as the run's goal, the same seed
as the command line's, and gymnasium's checker."""

import math

import numpy as np
import pytest

gymnasium = pytest.importorskip("gymnasium")

from gymnasium.utils.env_checker import check_env  # noqa: E402

from tt_mujoco import gym_env, gym_goal  # noqa: E402
from tt_mujoco.sim import Scenario, build  # noqa: E402
from tt_mujoco.vehicle.params import Params  # noqa: E402
from tt_mujoco.world.builtin import parse_world  # noqa: E402
from tt_mujoco.world.plan import PlanError, planned  # noqa: E402


@pytest.fixture(scope="module")
def env():
    return gym_goal.TractorTrailerGoalEnv(plant="reduced")


def test_gymnasium_env_checker_passes(env):
    check_env(env, skip_render_check=True)


def test_a_seeds_episode_starts_where_the_run_of_that_seed_does(env):
    obs, info = env.reset(seed=1)
    assert info["seed"] == 1
    built = build(Scenario(world="loading_bay", traj="plan", reverse=True, seed=1))
    x, y, _ = built.initial_pose
    names = env.observation_names
    observed = obs["observation"]
    assert observed[names.index("x")] == pytest.approx(x, abs=1e-9)
    assert observed[names.index("y")] == pytest.approx(y, abs=1e-9)
    goal = parse_world("loading_bay").goal
    heading = math.radians(goal.heading_deg)
    np.testing.assert_allclose(
        obs["desired_goal"], [goal.x, goal.y, math.cos(heading), math.sin(heading)]
    )


def test_episodes_start_only_where_one_leg_backs_in(env):
    world, p = parse_world("loading_bay"), Params()
    for _ in range(5):
        _, info = env.reset()
        plan = planned(world, p, info["seed"], True)  # a plan, with one leg
        assert plan.cusps == 0
    cusped = next(s for s in range(100) if _cusps(world, p, s))
    _, info = env.reset(seed=cusped)
    assert info["seed"] != cusped  # passed over for the seed's stream's next start


def _cusps(world, p, seed) -> bool:
    try:
        return planned(world, p, seed, True).cusps > 0
    except PlanError:
        return False


@pytest.mark.parametrize("reward_type", ["sparse", "dense"])
def test_the_reward_is_the_goals_and_vectorised(reward_type):
    env = gym_goal.TractorTrailerGoalEnv(plant="reduced", reward_type=reward_type)
    goal = env.desired_goal
    rng = np.random.default_rng(0)
    achieved = np.array(goal) + rng.normal(0.0, [0.01, 0.01, 0.02, 0.02], (5, 7, 4))
    achieved[..., 2:] /= np.linalg.norm(achieved[..., 2:], axis=-1, keepdims=True)
    desired = np.broadcast_to(goal, achieved.shape)
    batch = env.compute_reward(achieved, desired, {})
    assert batch.shape == (5, 7)
    one = [env.compute_reward(a, goal, {}) for a in achieved.reshape(-1, 4)]
    np.testing.assert_array_equal(batch.reshape(-1), one)
    assert env.compute_reward(goal, goal, {}) == 0.0
    far = np.array([goal[0] + 1.0, goal[1], goal[2], goal[3]])
    # 1 m off: -1 either way (sparse: missed; dense: 1 m)
    assert env.compute_reward(far, goal, {}) == pytest.approx(-1.0)
    turned = np.array([goal[0], goal[1], -goal[3], goal[2]])  # a quarter turn off
    expected = -1.0 if reward_type == "sparse" else -env.train_length * math.pi / 2
    assert env.compute_reward(turned, goal, {}) == pytest.approx(expected)
    # a failure counts for every step it left; a list of infos per sample
    failed = env.compute_reward(
        np.stack([far, far]), np.stack([goal, goal]), [{}, {"steps_left": 9}]
    )
    np.testing.assert_allclose(failed, [-1.0, -10.0])


def test_success_is_within_the_goals_tolerances(env):
    goal = env.desired_goal
    inside = np.array([goal[0] + 0.9 * env.position_tolerance, goal[1], goal[2], goal[3]])
    outside = np.array([goal[0] + 1.1 * env.position_tolerance, goal[1], goal[2], goal[3]])
    assert env.compute_reward(inside, goal, {}) == 0.0
    assert env.compute_reward(outside, goal, {}) == -1.0


def test_a_failure_ends_the_episode_and_costs_its_steps(env):
    env.reset(seed=3)
    total, steps = 0.0, 0
    while True:
        _, reward, terminated, truncated, info = env.step(np.array([1.0, -1.0]))  # spin
        total += reward
        steps += 1
        if terminated or truncated:
            break
    assert terminated and info["failed"] and not info["is_success"]
    assert info["status"] in ("jackknife", "collision", "diverged")
    # sparse: -1 for every step the episode had, those it never took included
    assert total == pytest.approx(-env._env.max_steps)


def test_the_path_task_rewards_the_leading_units_errors():
    env = gym_env.TractorTrailerEnv(traj="circle", plant="reduced", duration=0.5, task="path")
    obs, _ = env.reset(seed=0)
    names = env.observation_names
    scales = gym_env.PATH_TASK_SCALES
    for _ in range(20):
        obs, reward, *_ = env.step(np.array([0.2, 0.1]))
        e_y = obs[names.index("cross_track_lead")] / scales["cross_track"]
        e_psi = obs[names.index("heading_error_lead")] / scales["heading_error"]
        me = env.last_measurement()
        e_v = (me.v - obs[names.index("v_d")]) / scales["speed"]
        assert reward == pytest.approx(-min(1.0, (e_y**2 + e_psi**2 + e_v**2) / 3), rel=1e-9)
    with pytest.raises(ValueError, match="task"):
        gym_env.TractorTrailerEnv(task="docking")


def test_made_by_its_id():
    env = gymnasium.make(gym_goal.GOAL_ENV_ID, plant="reduced", world="yard")
    obs, info = env.reset(seed=0)
    assert set(obs) == {"observation", "achieved_goal", "desired_goal"}
    assert "is_success" in info
    env.close()


def test_reset_refuses_options_it_does_not_take(env):
    with pytest.raises(ValueError, match=r"options=\{'phi0_deg': 5\} is not allowed: this env's"):
        env.reset(seed=1, options={"phi0_deg": 5})


def test_a_bad_keyword_names_the_env_it_was_given_to():
    with pytest.raises(ValueError, match=r"TractorTrailerGoalEnv: unknown key 'task'"):
        gym_goal.TractorTrailerGoalEnv(plant="reduced", task="path")

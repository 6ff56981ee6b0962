"""tt_mujoco.gym_legs: a planned maneuver with a cusp is one episode of the Gym env, driven leg
by leg as ``python -m tt_mujoco.run`` drives it: the same plant, the same noise, bit for bit."""

import dataclasses

import numpy as np
import pytest

pytest.importorskip("gymnasium")

from tt_mujoco import gym_env
from tt_mujoco.gym_legs import Legs, leg_start
from tt_mujoco.sim import Scenario, build, simulate

BASE = dict(
    world="loading_bay", traj="plan", reverse=True, disturbance="none", control_dt=0.01,
    noise_snr_db=20.0,
)  # fmt: skip


def _cusped(**extra) -> Scenario:
    """The first seed whose start the planner reaches with a cusp."""
    seed = next(s for s in range(100) if build(Scenario(**BASE, **extra, seed=s)).plan.cusps)
    return Scenario(**BASE, **extra, seed=seed)


@pytest.mark.parametrize("plant", ["reduced", "mujoco"])
def test_the_cli_maneuver_replayed_through_the_env_is_the_same_run(plant):
    """The run's applied torques, step by step, through the env: every observed position and
    the noisy speed are the run's rows, the leg's last row swapped for the next leg's first."""
    scenario = _cusped(plant=plant)
    reference = simulate(scenario)
    assert reference.status == "ok" and reference.metrics["world"]["plan"]["cusps"] == 1
    ts = reference.timeseries
    env = gym_env.TractorTrailerEnv(scenario, action_units="torque")
    assert env.n_legs == 2 and env.max_steps >= len(ts["t"]) - 2
    names = list(env.observation_names)
    x, y, v = (names.index(n) for n in ("x", "y", "v"))
    obs, info = env.reset(seed=scenario.seed)
    row, legs_seen, done = 0, [info["leg"]], False
    while not done:
        assert (obs[x], obs[y], obs[v]) == (ts["x"][row], ts["y"][row], ts["v_meas"][row]), row
        obs, reward, terminated, truncated, info = env.step([ts["T_r"][row], ts["T_l"][row]])
        assert not terminated and np.isfinite(reward)
        row += 1 if info["leg"] == legs_seen[-1] else 2  # the next leg's first row
        legs_seen.append(info["leg"])
        assert info["t"] == pytest.approx(ts["t"][row], abs=1e-9)
        done = truncated
    assert row == len(ts["t"]) - 1 and info["status"] == "ok"
    assert sorted(set(legs_seen)) == [0, 1]


def test_the_legs_cover_the_plan():
    scenario = _cusped(plant="reduced")
    first = build(scenario)
    legs = Legs(first)
    assert legs.count == len(first.plan.legs) == 2
    assert legs.steps == sum(b.steps for b in legs.builds) and legs.steps_after(1) == 0
    assert [b.scenario.reverse for b in legs.builds] == [leg.reverse for leg in first.plan.legs]
    assert Legs(build(Scenario(traj="circle", duration=1.0))).count == 1


def test_the_next_leg_starts_where_the_measurement_is():
    class Train:  # a two-trailer train's measurement: its second hitch in the row
        x, y, theta, phi = 1.0, 2.0, 0.5, 0.1
        train = ((0.0, 0.0, 0.0, -0.2, 0.0, 0.0),)

    assert leg_start(Train) == ((1.0, 2.0, 0.5), (0.1, -0.2))


def _single(scenario):
    return gym_env.TractorTrailerEnv(scenario)


def _vector(scenario):
    from tt_mujoco.gym_vector import TractorTrailerVectorEnv

    return TractorTrailerVectorEnv(2, scenario)


def _goal(scenario):
    from tt_mujoco.gym_goal import TractorTrailerGoalEnv

    return TractorTrailerGoalEnv(dataclasses.replace(scenario, world="loading_bay", reverse=True))


@pytest.mark.parametrize("make", [_single, _vector, _goal])
def test_every_env_owns_its_scenario(make):
    """The caller's scenario changed after the env is made, or the copy the env gives out: its
    first episode is still the one of the scenario it was made with (the seed read at reset is
    the env's own)."""

    def scenario():
        return Scenario(plant="reduced", duration=1.0, seed=3, noise_snr_db=20.0)

    def first(env):
        obs = env.reset()[0]
        return obs["observation"] if isinstance(obs, dict) else obs

    expected = first(make(scenario()))
    given = scenario()
    env = make(given)
    given.seed = 99
    env.scenario.seed = 77
    np.testing.assert_array_equal(first(env), expected)
    assert env.scenario.seed == 3

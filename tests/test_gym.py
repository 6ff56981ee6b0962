"""The Gymnasium environment: API conformance, and that it is the same plant as ``simulate``."""

import dataclasses
import math
import re

import numpy as np
import pytest

gymnasium = pytest.importorskip("gymnasium")

from gymnasium.utils.env_checker import check_env  # noqa: E402
from tt_mujoco.controllers import make_controller, reduced_model  # noqa: E402

from tt_mujoco import gym_env  # noqa: E402
from tt_mujoco.sim import Scenario, simulate  # noqa: E402


@pytest.mark.filterwarnings("error")  # not one warning: normalised actions, finite bounds
@pytest.mark.parametrize(
    "options",
    [{}, {"plant": "reduced", "reverse": True, "traj": "circle"}, {"noise_snr_db": 20.0}],
)
def test_gymnasium_env_checker_passes(options):
    env = gym_env.TractorTrailerEnv(duration=0.5, **options)
    check_env(env, skip_render_check=True)
    assert env.action_space.low.tolist() == [-1.0, -1.0] and env.action_space.high.tolist() == [
        1.0,
        1.0,
    ]
    assert np.all(np.isfinite(env.observation_space.low))
    assert np.all(np.isfinite(env.observation_space.high))


@pytest.mark.parametrize("plant", ["mujoco", "reduced"])
def test_every_observation_stays_within_its_bounds(plant):
    # random actions, a train that jackknifes, circles that wind the heading past pi
    env = gym_env.TractorTrailerEnv(traj="circle", plant=plant, trailers=2, duration=3.0)
    rng = np.random.default_rng(0)
    for episode in range(2):
        obs, _ = env.reset(seed=episode)
        seen = [obs]
        while True:
            obs, _, terminated, truncated, info = env.step(rng.uniform(-1, 1, 2))
            seen.append(obs)
            if terminated or truncated:
                break
        assert all(env.observation_space.contains(o) for o in seen), info["status"]
        headings = [i for i, n in enumerate(env.observation_names) if n.startswith("theta0")]
        assert np.all(np.abs(np.array(seen)[:, headings]) <= np.pi)


def test_a_normalised_action_is_a_fraction_of_the_torque_limit():
    # 0.5 of the 15 N m limit is 7.5 N m exactly: the same episode both ways, bit for bit
    limit = Scenario().nominal_params().torque_limit
    runs = []
    for units, action in (("normalized", [0.5, -0.25]), ("torque", [0.5 * limit, -0.25 * limit])):
        env = gym_env.TractorTrailerEnv(traj="circle", duration=0.2, action_units=units)
        env.reset(seed=0)
        runs.append([env.step(np.array(action))[0] for _ in range(10)])
    assert np.array_equal(runs[0], runs[1])
    with pytest.raises(ValueError, match="action_units='nm' is not allowed"):
        gym_env.TractorTrailerEnv(action_units="nm")


# a complex part, a column vector and booleans were read as numbers, dropping or guessing
BAD_ACTIONS = [None, "abc", [1.0], [[1.0, 2.0, 3.0]], [np.nan, 0.0], [0.5 + 1j, 0.5]]
BAD_ACTIONS += [[[0.5], [0.5]], [True, False]]


@pytest.mark.parametrize("action", BAD_ACTIONS)
def test_a_bad_action_is_named(action):
    env = gym_env.TractorTrailerEnv(traj="circle", duration=0.2)
    env.reset(seed=0)
    with pytest.raises(ValueError, match=r"action=.* is not allowed: give two finite numbers"):
        env.step(action)


def test_registered_and_makes_the_reduced_plant_too():
    env = gymnasium.make(gym_env.ENV_ID, traj="circle", plant="reduced", duration=0.2)
    obs, _ = env.reset(seed=3)
    assert obs.shape == (len(gym_env.OBSERVATION_NAMES),)
    obs, _, terminated, _, info = env.step(np.zeros(2, dtype=np.float32))
    assert info["status"] == "running" and not terminated
    assert np.all(np.isfinite(obs))
    env.close()


def test_reward_is_negative_squared_tracking_error_and_episode_truncates():
    env = gym_env.TractorTrailerEnv(traj="circle", duration=0.3)
    env.reset(seed=0)
    names = gym_env.OBSERVATION_NAMES
    steps = 0
    while True:
        obs, reward, terminated, truncated, info = env.step(np.array([1.0, 1.0]) / 15.0)
        steps += 1
        o = dict(zip(names, obs, strict=True))
        # No noise: the observed v, omega are the true ones the reward uses.
        e_v, e_omega = o["v"] - o["v_d"], o["omega"] - o["omega_d"]
        assert reward == pytest.approx(-(e_v**2 + e_omega**2), rel=1e-12, abs=1e-300)
        assert reward == -(info["e_v"] ** 2 + info["e_omega"] ** 2)
        if terminated or truncated:
            break
    assert truncated and not terminated
    assert info["status"] == "ok"  # the run finished, as metrics.json would say
    assert steps == round(0.3 / gym_env.DEFAULT_CONTROL_DT)
    assert info["t"] == pytest.approx(0.3)


def test_same_seed_same_observations_with_noise():
    def rollout(seed):
        env = gym_env.TractorTrailerEnv(duration=0.2, noise_snr_db=20.0)
        obs, _ = env.reset(seed=seed)
        seen = [obs]
        for _ in range(20):
            seen.append(env.step(np.array([2.0, 1.0]) / 15.0)[0])
        return np.array(seen)

    a, b, c = rollout(7), rollout(7), rollout(8)
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)  # the noise follows the seed


def test_jackknife_terminates_with_a_penalty_worse_than_any_tracking():
    # The paper's eta = 3 jackknifes forward (docs/model.md Section 3); start close to it and push
    # hard.
    env = gym_env.TractorTrailerEnv(eta="paper", duration=5.0)
    env.reset(seed=0, options={"phi0_deg": 20.0})
    for _ in range(500):
        _, reward, terminated, truncated, info = env.step(np.array([1.0, -1.0]))
        if terminated or truncated:
            break
    assert terminated and info["status"] == "jackknife"
    assert reward <= -1.0


def _drive_with_ismc_sta(scenario) -> list[dict]:
    """The observations of an episode of ``scenario`` driven through the env by the ISMC-STA
    law on the nominal model (a train's model takes every hitch angle), as dicts by name."""
    env = gym_env.TractorTrailerEnv(scenario, action_units="torque")
    nominal = scenario.nominal_params()
    ctrl = make_controller("ismc_sta", reduced_model(nominal), torque_limit=nominal.torque_limit)
    ctrl.reset()
    names = env.observation_names
    hitches = ["phi", *(f"phi_{k}" for k in range(2, env.n_trailers + 1))]
    obs, info = env.reset(seed=scenario.seed)  # same noise stream as simulate's default_rng
    rows = []
    while True:
        o = dict(zip(names, obs, strict=True))
        rows.append(o)
        phi = o["phi"] if env.n_trailers == 1 else tuple(o[h] for h in hitches)
        if scenario.eta_schedule:  # the scheduled gains reach the model, as in simulate
            ctrl.steering_changed(info["etas"])
        torques = ctrl.step(
            env.dt, phi, o["v"], o["omega"], o["v_d"], o["omega_d"],
            info["v_d_dot"], info["omega_d_dot"],
        )  # fmt: skip
        obs, _, terminated, truncated, info = env.step(np.array(torques))
        if terminated or truncated:
            rows.append(dict(zip(names, obs, strict=True)))
            return rows


@pytest.mark.parametrize(
    "extra",
    [
        {},
        {"reverse": True, "eta": "paper"},
        {"eta_schedule": True, "traj": "circle"},
        {"path_feedback": {}},
        {"plant": "reduced", "reverse": True, "eta": "paper", "path_feedback": {}},
    ],
    ids=["plain", "reverse", "eta_schedule", "path_feedback", "reduced-reverse-feedback"],
)
def test_env_is_the_simulate_plant(extra):
    """The ISMC-STA controller driven through the env reproduces ``simulate`` exactly, for
    every loop option (the env drives the same stepper)."""
    scenario = Scenario(
        traj="s_curve", duration=1.0, disturbance="matched", control_dt=0.01, noise_snr_db=20.0
    )
    scenario = dataclasses.replace(scenario, **extra)
    reference = simulate(scenario).timeseries
    rows = _drive_with_ismc_sta(scenario)
    xs, vs = [r["x"] for r in rows], [r["v"] for r in rows]
    assert len(xs) == len(reference["t"])
    assert np.array_equal(np.array(xs), reference["x"])
    assert np.array_equal(np.array(vs), reference["v_meas"])  # noisy v, bit for bit
    assert math.isfinite(xs[-1])


def test_render_works_without_a_display():
    # As `run` does: EGL (or OSMesa) chosen by the project, whatever MUJOCO_GL or DISPLAY say.
    import os
    import subprocess
    import sys

    code = (
        "from tt_mujoco.gym_env import TractorTrailerEnv\n"
        "from tt_mujoco.viz.render import RenderUnavailable\n"
        "env = TractorTrailerEnv(render_mode='rgb_array', duration=0.2)\n"
        "env.reset(seed=0)\n"
        "try:\n"
        "    a = env.render()\n"
        "except RenderUnavailable:\n"
        "    print('unavailable'); raise SystemExit(0)\n"
        "env.step([2.0, 2.0]); b = env.render(); env.close()\n"
        "print(a.shape, int(a.std() > 5), int((a != b).any()))\n"
    )
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "MUJOCO_GL")}
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
    assert proc.returncode == 0, proc.stderr[-1500:]
    if proc.stdout.strip() == "unavailable":
        pytest.skip("no OpenGL backend on this machine")
    assert proc.stdout.split() == ["(480,", "640,", "3)", "1", "1"]  # an image that changes


@pytest.mark.filterwarnings("error")
def test_a_train_env_passes_the_checker_and_observes_every_trailer():
    env = gym_env.TractorTrailerEnv(trailers=3, duration=0.5, traj="circle")
    check_env(env, skip_render_check=True)
    names = env.observation_names
    assert names == gym_env.observation_names(3)
    for k in (2, 3):
        for field in ("phi", "beta", "x0", "y0", "theta0", "v0"):
            assert f"{field}_{k}" in names
        assert f"cross_track_trailer_{k}" in names and f"heading_error_trailer_{k}" in names
    obs, _ = env.reset(seed=0)
    o = dict(zip(names, obs, strict=True))
    # On the path at the start: the tractor's errors are nil, every trailer's match its own.
    assert abs(o["cross_track_tractor"]) < 1e-9 and abs(o["heading_error_tractor"]) < 1e-9
    assert o["cross_track_lead"] == o["cross_track_tractor"]


def test_path_frame_errors_follow_a_shifted_start_and_the_lead_when_reversing():
    env = gym_env.TractorTrailerEnv(traj="circle", duration=0.5, reverse=True, eta="paper")
    obs, _ = env.reset(seed=0)
    o = dict(zip(env.observation_names, obs, strict=True))
    assert o["cross_track_lead"] == o["cross_track_trailer_1"]
    assert o["heading_error_lead"] == o["heading_error_trailer_1"]
    assert abs(o["heading_error_tractor"]) < 1e-9  # it faces along the path, backing up


@pytest.mark.parametrize("plant", ["mujoco", "reduced"])
def test_a_train_driven_through_the_env_is_simulate_bit_for_bit(plant):
    scenario = Scenario(
        traj="s_curve", duration=0.6, trailers=3, disturbance="none", control_dt=0.01,
        noise_snr_db=20.0, seed=4, plant=plant,
    )  # fmt: skip
    reference = simulate(scenario).timeseries
    rows = _drive_with_ismc_sta(scenario)
    assert len(rows) == len(reference["t"])
    for name in ("x", "y", "phi", "phi_2", "phi_3", "beta_3", "x0_3", "v0_2"):
        assert np.array_equal([r[name] for r in rows], reference[name]), name
    assert np.array_equal([r["v"] for r in rows], reference["v_meas"])


def test_vectorised_through_make_vec():
    envs = gymnasium.make_vec(
        gym_env.ENV_ID, num_envs=2, vectorization_mode="sync", traj="circle",
        plant="reduced", duration=0.2, trailers=2,
    )  # fmt: skip
    obs, _ = envs.reset(seed=[1, 2])
    assert obs.shape == (2, len(gym_env.observation_names(2)))
    obs, reward, terminated, _, _ = envs.step(np.ones((2, 2)))
    assert reward.shape == (2,) and not terminated.any()
    envs.close()


def test_render_explains_itself_before_reset_and_without_a_render_mode():
    env = gym_env.TractorTrailerEnv(duration=0.2, render_mode="rgb_array")
    with pytest.raises(gymnasium.error.ResetNeeded, match="call reset"):
        env.render()
    plain = gym_env.TractorTrailerEnv(duration=0.2)
    plain.reset(seed=0)
    with pytest.warns(UserWarning, match="render_mode='rgb_array'"):
        assert plain.render() is None


def test_an_unknown_field_gets_a_did_you_mean():
    with pytest.raises(ValueError, match="did you mean 'trailers'"):
        gym_env.TractorTrailerEnv(trailer=2)


def test_the_physical_options_reach_the_env():
    # A grade, motors, a delay, wind and an ice patch: the env's episode is the stepper's.
    options = {
        "traj": "circle", "duration": 0.2, "terrain": "slope:5:90", "actuator": "dc_motor",
        "sensor_delay": 0.01, "wind": "8:0:2", "ground": ["band:0:1:0.1"],
    }  # fmt: skip
    env = gym_env.TractorTrailerEnv(**options, action_units="torque")
    env.reset(seed=1)
    env.step(np.full(2, 1.0, dtype=np.float32))
    stepper = env._stepper
    lag = stepper.built.plant_params.motor_lag  # one 10 ms step of the motors' 5 ms lag
    assert stepper.motors.torques[0] == pytest.approx(1.0 - math.exp(-0.01 / lag))
    for _ in range(19):
        obs, _, terminated, _, _ = env.step(np.full(2, 1.0, dtype=np.float32))
    assert not terminated and np.all(np.isfinite(obs))
    assert stepper.plant.model.opt.gravity[1] < 0  # the grade rises along +y
    with pytest.raises(ValueError, match="did you mean 'terrain'"):
        gym_env.TractorTrailerEnv(terain="slope:5")


def test_a_users_path_that_fails_mid_episode_ends_it_as_failed(tmp_path):
    # it was a traceback out of step(); now the episode ends, saying why
    parts = tmp_path / "parts.py"
    parts.write_text(
        "from tt_mujoco.reference.paths import ArcsPath\n\n"
        "class P(ArcsPath):\n    def pose_at(self, s):\n        if s > 0.3:\n"
        "            raise RuntimeError('no pose here')\n        return super().pose_at(s)\n\n"
        "def p():\n    return P('arc', (0.0, 0.0, 0.0), [(10.0, 0.5)])\n"
    )
    env = gym_env.TractorTrailerEnv(traj=f"{parts}:p", plant="reduced", duration=3.0)
    env.reset(seed=0)
    for _ in range(300):
        _, _, terminated, truncated, info = env.step(np.array([0.3, 0.3]))
        if terminated or truncated:
            break
    assert terminated and info["status"] == "failed" and "no pose here" in info["message"]


def test_reset_refuses_an_option_it_does_not_know():
    # a misspelt option was dropped in silence: the episode started as if it had not been given
    env = gym_env.TractorTrailerEnv(plant="reduced", duration=1.0)
    with pytest.raises(ValueError, match=r"'phi0' is not a reset option \(allowed: phi0_deg\)"):
        env.reset(seed=0, options={"phi0": 20.0})
    env.reset(seed=0, options={"phi0_deg": 5.0})  # the one it takes
    for options in ("phi0_deg", ["phi0_deg"], 5.0):  # not a mapping: said so, not its items
        with pytest.raises(ValueError, match=r"give a dict of reset options"):
            env.reset(seed=0, options=options)


@pytest.mark.parametrize(
    ("seed", "named"),
    [(2**63, "seed=9223372036854775808"), (-1, "seed=-1"), (True, "seed=True"), ("3", "seed='3'")],
)
@pytest.mark.parametrize("make", ["single", "goal"])
def test_reset_takes_the_seeds_a_run_takes_and_names_the_others(make, seed, named):
    """A seed the command line refuses (beyond a TOML integer, a bool, text) would start an
    episode that no other route repeats: every env refuses it as the option schema does."""
    from tt_mujoco import gym_goal

    if make == "single":
        env = gym_env.TractorTrailerEnv(plant="reduced", duration=1.0)
    else:
        env = gym_goal.TractorTrailerGoalEnv(plant="reduced")
    with pytest.raises(ValueError, match=re.escape(named) + " is not allowed"):
        env.reset(seed=seed)
    env.reset(seed=np.int64(3))  # any integer type

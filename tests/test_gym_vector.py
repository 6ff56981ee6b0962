"""tt_mujoco.gym_vector: the vector env is the single env, episode by episode, bit for bit, on
both routes (compiled, CPython), and ``simulate`` when it replays a run's torques."""

import numpy as np
import pytest

gymnasium = pytest.importorskip("gymnasium")

from tt_mujoco import gym_env  # noqa: E402
from tt_mujoco.gym_vector import TractorTrailerVectorEnv  # noqa: E402
from tt_mujoco.sim import Scenario, simulate  # noqa: E402

PATH_PARTS = (
    "from tt_mujoco.reference.paths import ArcsPath\n\n"
    "class P(ArcsPath):\n    def pose_at(self, s):\n        if s > {limit}:\n"
    "            raise RuntimeError('no pose here')\n        return super().pose_at(s)\n\n"
    "def p():\n    return P('arc', (0.0, 0.0, 0.0), [(10.0, 0.5)])\n"
)


def _episodes(n: int, steps: int, seed: int = 5, spread=(-0.4, 0.7), **options):
    """Everything the vector env of ``n`` returns over ``steps`` random actions (wide enough
    to jackknife some episodes, which then reset): the actions and, per step, the observation,
    reward, ends and status of each episode."""
    env = TractorTrailerVectorEnv(n, **options)
    obs, info = env.reset(seed=seed)
    actions = np.random.default_rng(1).uniform(*spread, size=(steps, n, 2))
    out = [(obs, np.zeros(n), np.zeros(n, bool), np.zeros(n, bool), info["status"])]
    for a in actions:
        obs, reward, terminated, truncated, info = env.step(a)
        out.append((obs, reward, terminated, truncated, info["status"]))
    return env, actions, out


def _single_episodes(i: int, actions, seed: int = 5, **options):
    """Episode ``i`` of the vector env, driven as the single env (reset by hand after an
    end, as NEXT_STEP does)."""
    env = gym_env.TractorTrailerEnv(**options)
    obs, info = env.reset(seed=seed + i)
    out, ended = [(obs, 0.0, False, False, info["status"])], False
    for a in actions[:, i]:
        if ended:
            obs, info = env.reset()
            out.append((obs, 0.0, False, False, info["status"]))
            ended = False
            continue
        obs, reward, terminated, truncated, info = env.step(a)
        out.append((obs, reward, terminated, truncated, info["status"]))
        ended = terminated or truncated
    return out


def _assert_same(vector, single, i: int) -> None:
    for j, (batch, one) in enumerate(zip(vector, single, strict=True)):
        assert np.array_equal(batch[0][i], one[0]), (j, "observation")
        assert batch[1][i] == one[1], (j, "reward")
        assert (batch[2][i], batch[3][i], batch[4][i]) == one[2:], (j, "ends")


SCENARIOS = {
    "s_curve": dict(traj="s_curve", duration=2.0),
    "reduced-train-payload": dict(
        traj="circle", plant="reduced", trailers=2, faults=["payload:t=0.5"], duration=2.0
    ),
    "reverse-path-task": dict(traj="s_curve", reverse=True, task="path", duration=2.0),
    "noise-delay-dropout-schedule": dict(
        traj="circle",
        noise_snr_db=20.0,
        sensor_delay=0.02,
        faults=["dropout:t=0.5"],
        eta_schedule="curvature",
        trailers=3,
        duration=2.0,
    ),
    "world": dict(traj="s_curve", world="loading_bay", duration=3.0),
}


@pytest.mark.parametrize("name", list(SCENARIOS))
def test_each_episode_is_the_single_env_bit_for_bit(name):
    options = SCENARIOS[name]
    env, actions, vector = _episodes(3, 260, **options)
    assert env.compiled
    statuses = {status for step in vector for status in step[4]}
    for i in range(env.num_envs):
        _assert_same(vector, _single_episodes(i, actions, **options), i)
    assert "running" in statuses


def test_the_episodes_end_and_reset_as_the_single_env_does():
    # random actions: some jackknife (a penalty), some reach the end (truncated, "ok")
    options = dict(traj="circle", duration=0.8, reverse=True)
    env, actions, vector = _episodes(4, 160, spread=(-1.0, 1.0), **options)
    statuses = {status for step in vector for status in step[4]}
    assert {"ok", "jackknife"} <= statuses
    for i in range(env.num_envs):
        _assert_same(vector, _single_episodes(i, actions, **options), i)
    # the step after an end resets: reward 0, not ended, the episode's time back at 0
    ends = [(j, i) for j, step in enumerate(vector[:-1]) for i in np.flatnonzero(step[2] | step[3])]
    assert ends
    for j, i in ends:
        following = vector[j + 1]
        assert following[1][i] == 0.0 and not following[2][i] and not following[3][i]
        assert following[4][i] == "running"


def test_cpython_runs_the_same_step_without_the_compiled_loop(monkeypatch):
    options = dict(traj="s_curve", trailers=2, noise_snr_db=20.0, duration=1.0)
    env, _, compiled = _episodes(2, 120, **options)
    assert env.compiled
    monkeypatch.setenv("TT_MUJOCO_COMPILED", "0")
    with pytest.warns(UserWarning, match=r"steps in CPython \(the same numbers, slower\)"):
        env, _, interpreted = _episodes(2, 120, **options)
    assert not env.compiled
    for a, b in zip(compiled, interpreted, strict=True):
        assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])
        assert np.array_equal(a[4], b[4])


@pytest.mark.parametrize("plant", ["mujoco", "reduced"])
def test_replaying_a_runs_torques_is_the_run(plant):
    scenario = Scenario(
        traj="s_curve", duration=1.0, disturbance="none", control_dt=0.01, noise_snr_db=20.0,
        seed=3, plant=plant,
    )  # fmt: skip
    run = simulate(scenario).timeseries
    env = TractorTrailerVectorEnv(2, scenario=scenario, action_units="torque")
    obs, _ = env.reset(seed=[3, 3])
    names = env.observation_names
    x, v = names.index("x"), names.index("v")
    xs, vs = [obs[:, x]], [obs[:, v]]
    for T_r, T_l in zip(run["T_r"][:-1], run["T_l"][:-1], strict=True):
        obs, _, terminated, _, _ = env.step([[T_r, T_l], [T_r, T_l]])
        assert not terminated.any()
        xs.append(obs[:, x])
        vs.append(obs[:, v])
    for i in range(2):
        assert np.array_equal([row[i] for row in xs], run["x"])
        assert np.array_equal([row[i] for row in vs], run["v_meas"])  # noisy v, bit for bit


def test_spaces_infos_and_make_vec():
    env = gymnasium.make_vec(gym_env.ENV_ID, num_envs=3, traj="circle", duration=0.3)
    assert isinstance(env, TractorTrailerVectorEnv)
    assert env.metadata["autoreset_mode"] == gymnasium.vector.AutoresetMode.NEXT_STEP
    assert env.single_action_space == gym_env.TractorTrailerEnv().action_space
    assert env.action_space.shape == (3, 2)
    obs, info = env.reset(seed=0)
    assert env.observation_space.contains(obs)
    rng = np.random.default_rng(0)
    for _ in range(40):
        obs, reward, terminated, truncated, info = env.step(rng.uniform(-1, 1, (3, 2)))
        assert env.observation_space.contains(obs) and reward.shape == (3,)
        assert all(info[f"_{name}"].all() for name in ("t", "status", "e_v", "etas"))
        assert all(info["message"][terminated]) and not any(info["message"][~terminated])
    # NEXT_STEP through truncation: "ok" at the end
    env = TractorTrailerVectorEnv(2, traj="circle", duration=0.05)
    env.reset(seed=0)
    for _ in range(env.max_steps):
        _, _, _, truncated, info = env.step(np.full((2, 2), 0.2))
    assert truncated.all() and list(info["status"]) == ["ok", "ok"]


def test_a_users_path_that_fails_ends_its_episode_as_failed(tmp_path):
    parts = tmp_path / "parts.py"
    parts.write_text(PATH_PARTS.format(limit=0.3))
    options = dict(traj=f"{parts}:p", plant="reduced", duration=3.0)
    env = TractorTrailerVectorEnv(2, **options)
    env.reset(seed=0)
    for _ in range(300):
        _, reward, terminated, _, info = env.step(np.full((2, 2), 0.3))
        if terminated.any():
            break
    assert terminated.all() and list(info["status"]) == ["failed", "failed"]
    assert "no pose here" in info["message"][0]
    assert reward[0] == -(env.max_steps - info["t"][0] / env.dt)
    # on the step the single env stops it, with its last observation: the path fails where a
    # unit's errors ask its pose, after the step's target read its curvature
    env, actions, vector = _episodes(2, 60, **options)
    for i in range(env.num_envs):
        _assert_same(vector, _single_episodes(i, actions, **options), i)
    assert {"failed"} <= {status for step in vector for status in step[4]}


@pytest.mark.parametrize(
    ("make", "named"),
    [
        (lambda: TractorTrailerVectorEnv(0), "num_envs=0"),
        (lambda: TractorTrailerVectorEnv(True), "num_envs=True"),
        (lambda: TractorTrailerVectorEnv(2.5), "num_envs=2.5"),
        # a slip of a few digits: named before NumPy is asked for 201 GiB
        (lambda: TractorTrailerVectorEnv(10**9), r"num_envs=1000000000 is not allowed"),
        (lambda: TractorTrailerVectorEnv(2, traj="scurve"), "did you mean 's_curve'"),
    ],
)
def test_a_bad_construction_is_named(make, named):
    with pytest.raises(ValueError, match=named):
        make()


def test_bad_actions_seeds_and_options_are_named():
    env = TractorTrailerVectorEnv(2, traj="circle", duration=0.5)
    with pytest.raises(ValueError, match=r"seed=\[1, 2, 3\] is not allowed"):
        env.reset(seed=[1, 2, 3])
    # each episode's seed is one a run takes (the option schema's), the last one too
    with pytest.raises(ValueError, match=r"seed \+ 1=9223372036854775808 is not allowed"):
        env.reset(seed=2**63 - 1)
    with pytest.raises(ValueError, match=r"seed\[1\]=True is not allowed"):
        env.reset(seed=[1, True])
    with pytest.raises(ValueError, match=r"seed='12' is not allowed: give an int"):
        env.reset(seed="12")
    with pytest.raises(ValueError, match="'phi' is not a reset option"):
        env.reset(options={"phi": 3.0})
    env.reset(seed=0)
    for bad in (np.zeros((3, 2)), np.array([[0.1, np.nan], [0.0, 0.0]]), "fast"):
        with pytest.raises(ValueError, match=r"\(2, 2\) finite numbers"):
            env.step(bad)

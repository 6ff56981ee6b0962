"""The vector Gym env against its physics floor: MuJoCo's C rollout of the torques it applied.

    python benchmarks/bench_vector_env.py [--envs 8 64] [--steps 2000] [--sync 8]

For each ``--envs N``: :class:`tt_mujoco.gym_vector.TractorTrailerVectorEnv` (the env's
default scenario on the MuJoCo plant, the circle) is reset and stepped ``--steps`` times with
the torques the project's ISMC-STA applied in a run of the same scenario (a drive that
neither stops nor jackknifes, checked), once to warm up and once timed. Then the same
torques, held over each control period, are replayed from the episodes' initial states by
``mujoco.rollout`` on one thread (the floor: the physics alone), which must end in the env's
own final states, bit for bit. Printed: env steps per second, the floor's, and their ratio
(1.0: the env at the floor; it runs on one core), the median ratio of ``--tries`` pairs
each timed one right after the other. ``--sync N`` also times Gymnasium's synchronous vector
of N single envs on the same actions, against the same floor, for comparison.
"""

from __future__ import annotations

import argparse
import time

import mujoco
import numpy as np
from mujoco import rollout

import tt_mujoco.gym_env as gym_env
from tt_mujoco import sim
from tt_mujoco.gym_vector import TractorTrailerVectorEnv

FULL = mujoco.mjtState.mjSTATE_FULLPHYSICS
SCENARIO = {"traj": "circle", "duration": 40.0}


def actions_for(n: int, steps: int) -> np.ndarray:
    """``steps`` actions for each of ``n`` episodes: the torques the project's ISMC-STA applied
    in a run of the env's scenario (a drive that neither stops nor jackknifes), as fractions
    of the torque limit."""
    scenario = sim.Scenario(disturbance="none", control_dt=gym_env.DEFAULT_CONTROL_DT, **SCENARIO)
    built = sim.build(scenario)
    result, limit = sim.simulate(built), built.nominal.torque_limit
    torques = np.stack([result.timeseries["T_r"], result.timeseries["T_l"]], axis=1)[:steps]
    if len(torques) < steps:
        raise SystemExit(f"--steps {steps}: the run has {len(torques)} control steps")
    return np.repeat((torques / limit)[:, None, :], n, axis=1)


def time_vector(env, actions: np.ndarray):
    """(seconds, the episodes' first states) of ``len(actions)`` steps of the vector ``env``,
    after a warm-up."""
    for _ in range(2):  # a warm-up, then the timed run
        env.reset(seed=0)
        states = np.array([_state(env, i) for i in range(env.num_envs)])
        warm = np.array(
            [env._steppers[i].plant.data.qacc_warmstart.copy() for i in range(env.num_envs)]
        )
        start = time.perf_counter()
        for a in actions:
            _, _, terminated, truncated, _ = env.step(a)
        seconds = time.perf_counter() - start
        if terminated.any() or truncated.any() or (env._status != "running").any():
            raise SystemExit("an episode ended during the benchmark: choose fewer --steps")
    return seconds, (states, warm)


def _state(env, i: int) -> np.ndarray:
    plant = env._steppers[i].plant
    state = np.empty(mujoco.mj_stateSize(plant.model, FULL))
    mujoco.mj_getState(plant.model, plant.data, state, FULL)
    return state


def floor(env, start_states, actions: np.ndarray) -> float:
    """Seconds of the C rollout (one thread) of the torques the env applied; checks that it
    ends in the env's final states."""
    plant = env._steppers[0].plant
    m = plant.model
    n, substeps = env.num_envs, env._built.substeps
    limit = env.torque_limit
    control = np.zeros((n, len(actions), m.nu))
    control[:, :, plant._act_r] = actions[:, :, 0].T * limit
    control[:, :, plant._act_l] = actions[:, :, 1].T * limit
    control = np.repeat(control, substeps, axis=1)
    states, warm = start_states
    data = mujoco.MjData(m)
    start = time.perf_counter()
    out, _ = rollout.rollout(m, data, states, control, initial_warmstart=warm)
    seconds = time.perf_counter() - start
    for i in range(n):
        if not np.array_equal(out[i, -1], _state(env, i)):
            raise SystemExit(f"the rollout does not reproduce episode {i}")
    return seconds


def time_sync(n: int, actions: np.ndarray) -> float:
    import gymnasium

    env = gymnasium.make_vec(gym_env.ENV_ID, n, vectorization_mode="sync", **SCENARIO)
    env.reset(seed=0)
    start = time.perf_counter()
    for a in actions:
        env.step(a)
    return time.perf_counter() - start


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--envs", type=int, nargs="+", default=[8, 64])
    parser.add_argument("--steps", type=int, default=2000)
    parser.add_argument("--sync", type=int, nargs="*", default=[8])
    parser.add_argument("--tries", type=int, default=3)
    args = parser.parse_args(argv)
    for n in sorted({*args.envs, *args.sync}):
        actions = actions_for(n, args.steps)
        env = TractorTrailerVectorEnv(n, **SCENARIO)
        pairs = []  # (env, floor) seconds, taken one right after the other: --tries pairs
        for _ in range(args.tries):
            seconds, states = time_vector(env, actions)
            pairs.append((seconds, floor(env, states, actions)))
        seconds, c_floor = sorted(pairs, key=lambda pair: pair[1] / pair[0])[len(pairs) // 2]
        steps = n * args.steps
        if n in args.envs:
            print(
                f"vector env, {n} episodes x {args.steps} steps ({env._built.substeps} physics "
                f"steps each, compiled: {env.compiled}): {steps / seconds:,.0f} env steps/s; "
                f"C rollout {steps / c_floor:,.0f}; env at {c_floor / seconds:.2f} of the floor "
                f"(the median of {args.tries} pairs)"
            )
        if n in args.sync:
            seconds = time_sync(n, actions)
            print(
                f"gymnasium.make_vec sync, {n} single envs x {args.steps} steps: "
                f"{steps / seconds:,.0f} env steps/s; at {c_floor / seconds:.2f} of the floor"
            )


if __name__ == "__main__":
    main()

"""Train a policy on the Gymnasium env's path task with Stable-Baselines3's PPO, and report
what it reached beside the project's own controller on the same scenario.

    pip install -e ".[gym,rl]"
    python examples/train_ppo.py [--steps 300000] [--traj circle] [--reverse] [--seed 0]

The task (``TractorTrailerEnv(task="path")``): the agent sets the wheel torques every 10 ms and
is rewarded for keeping the unit that leads the motion on the path, facing along it, at the
target speed (``tt_mujoco.gym_env.PATH_TASK_SCALES``). The reduced plant (the paper's ODE), no
disturbance, no noise. After training, one deterministic episode of the policy is measured
as ``metrics.json`` measures a run (the leading unit's cross-track rms and the episode's
status), and so is ISMC-STA on the same scenario through ``tt_mujoco.simulate``.
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

try:
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize
except ImportError:  # an optional extra: say how to get it
    sys.exit('this example needs Stable-Baselines3: pip install -e ".[gym,rl]"')

import tt_mujoco
from tt_mujoco.gym_env import TractorTrailerEnv


def episode(env, act) -> tuple[float, str, int]:
    """``(leading cross-track rms (m), status, steps)`` of one episode driven by ``act``."""
    obs, info = env.reset(seed=0)
    lead = env.observation_names.index("cross_track_lead")
    errors = []
    while True:
        obs, _, terminated, truncated, info = env.step(act(obs))
        errors.append(obs[lead])
        if terminated or truncated:
            return float(np.sqrt(np.mean(np.square(errors)))), info["status"], len(errors)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=300_000, help="training steps")
    parser.add_argument("--traj", default="circle")
    parser.add_argument("--reverse", action="store_true")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    scenario = tt_mujoco.Scenario(
        traj=args.traj,
        reverse=args.reverse,
        plant="reduced",
        disturbance="none",
        control_dt=0.01,
        seed=args.seed,
    )
    env = TractorTrailerEnv(scenario, task="path")
    # The observations' scales differ by orders of magnitude (positions, wheel angles, errors):
    # PPO learns on running-normalised ones, as Stable-Baselines3 recommends.
    venv = VecNormalize(DummyVecEnv([lambda: TractorTrailerEnv(scenario, task="path")]))
    model = PPO("MlpPolicy", venv, seed=args.seed, verbose=0)
    began = time.perf_counter()
    model.learn(total_timesteps=args.steps)
    trained = time.perf_counter() - began
    venv.training = False

    def act(obs):
        return model.predict(venv.normalize_obs(obs), deterministic=True)[0]

    rms, status, steps = episode(env, act)
    reference = tt_mujoco.simulate(scenario)
    key = "leading_cross_track_rms"
    print(
        f"PPO, {args.steps} steps on the path task ({args.traj}"
        f"{', backing up' if args.reverse else ''}, reduced plant), trained in {trained:.0f} s"
    )
    print(f"  policy:   leading unit {1000 * rms:.1f} mm rms off the path, {status}, {steps} steps")
    print(
        f"  ISMC-STA: leading unit {1000 * reference.metrics[key]:.1f} mm rms off the path, "
        f"{reference.status}"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())

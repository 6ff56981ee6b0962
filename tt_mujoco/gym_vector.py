"""A vector of the Gymnasium environment whose episodes step in compiled code (optional extra:
``pip install tt-mujoco[gym]``).

:class:`TractorTrailerVectorEnv` is ``num_envs`` episodes of
:class:`~tt_mujoco.gym_env.TractorTrailerEnv`'s task, each its own plant, stepped together: one
call of the compiled kernel per episode and step (:mod:`tt_mujoco.sim.loop.agent_step`:
the torques applied, the plant advanced, the next step sensed and observed), and the rewards,
the observations' wrapping and clipping and the infos computed for the whole batch in NumPy.
Its observations, rewards, ends and statuses are those of the single environment stepped
with the same actions from the same seed, bit for bit (``tests/test_gym_vector.py``); its
spaces are the single environment's, batched.

- **seeds**: ``reset(seed=s)`` seeds episode ``i`` with ``s + i`` (a sequence gives each its
  own), as ``gymnasium.make_vec``'s vectors do; the first reset without a seed is
  ``reset(seed=scenario.seed)``. An episode reset later draws from its own generator.
- **autoreset**: ``AutoresetMode.NEXT_STEP`` (``metadata["autoreset_mode"]``): the step after
  an episode ended resets it and returns its first observation, with a reward of 0, not
  terminated nor truncated, and ignores its action.
- **info**: arrays over the episodes: ``t``, ``status`` ("running", "ok" at truncation,
  "jackknife", "diverged", "collision", "failed"), ``message`` (why it stopped, else ""),
  ``e_v``, ``e_omega``, ``v_d_dot``, ``omega_d_dot``, ``slip_longitudinal``, ``etas`` (each
  episode's trailers' gains in force); each with its ``_name`` mask (all true).

The compiled step is numba's, compiled once into the compiled-code cache on the first use of
a new version of the sources (about a minute), then loaded. Without numba (or with
``TT_MUJOCO_COMPILED=0``) CPython runs the same step's source, with the same numbers, slower:
:attr:`TractorTrailerVectorEnv.compiled` says which runs. A planned maneuver with cusps (more
than one leg) is refused: vectorise the single environment for it (``gymnasium.make_vec(ENV_ID,
num_envs=N, vectorization_mode="sync")``).

``gymnasium.make_vec("tt_mujoco/TractorTrailer-v0", num_envs=N, **options)`` makes this vector
env (the registered ``vector_entry_point``); ``vectorization_mode="sync"`` or ``"async"`` make
Gymnasium's vectors of single envs instead.
"""

from __future__ import annotations

from numbers import Integral
from typing import ClassVar

import numpy as np

try:
    import gymnasium
    from gymnasium.utils import seeding
    from gymnasium.vector.utils import batch_space
except ImportError as err:  # pragma: no cover - depends on the optional extra
    raise ImportError("tt_mujoco.gym_vector needs gymnasium: pip install 'tt-mujoco[gym]'") from err

from tt_mujoco import sim
from tt_mujoco.gym_env import (
    TractorTrailerEnv,
    bounded,
    checked_seed,
    reset_phi0_deg,
    task_reward,
    torques_of,
)
from tt_mujoco.gym_legs import OwnScenario
from tt_mujoco.registry import shown
from tt_mujoco.sim.loop import agent_step, closed_loop, compiled, outcome
from tt_mujoco.sim.loop.agent_step import (
    AUX_OMEGA,
    AUX_OMEGA_D,
    AUX_OMEGA_D_DOT,
    AUX_SLIP_LEFT,
    AUX_SLIP_RIGHT,
    AUX_V,
    AUX_V_D,
    AUX_V_D_DOT,
)
from tt_mujoco.sim.loop.step import PAYLOAD, RAISED, RUNNING
from tt_mujoco.sim.loop.stepper import Stepper

__all__ = ["MAX_ENVS", "TractorTrailerVectorEnv"]

#: The most episodes one vector env steps: 65,536 simulations hold several GB already, and a
#: larger number is a slip (10**9 asked NumPy for 201 GiB).
MAX_ENVS = 1 << 16


class TractorTrailerVectorEnv(OwnScenario, gymnasium.vector.VectorEnv):
    """``num_envs`` episodes of :class:`~tt_mujoco.gym_env.TractorTrailerEnv` stepped together
    in compiled code (see the module).

    Parameters
    ----------
    num_envs : int
        How many episodes, 1 to :data:`MAX_ENVS`.
    scenario, action_units, task, **overrides
        As :class:`~tt_mujoco.gym_env.TractorTrailerEnv`'s (no rendering).

    Raises
    ------
    ValueError
        A bad ``num_envs``, option or scenario, named; a maneuver with cusps.
    """

    metadata: ClassVar[dict] = {
        "render_modes": [],
        "autoreset_mode": gymnasium.vector.AutoresetMode.NEXT_STEP,
    }

    def __init__(
        self,
        num_envs: int = 8,
        scenario: sim.Scenario | None = None,
        action_units: str = "normalized",
        task: str = "velocity",
        **overrides,
    ):
        if (
            isinstance(num_envs, bool)
            or not isinstance(num_envs, Integral)
            or not 1 <= num_envs <= MAX_ENVS
        ):
            raise ValueError(
                f"num_envs={shown(num_envs)} is not allowed: give an integer in [1, {MAX_ENVS}] "
                "(each env is a simulation of its own, with its own memory)"
            )
        single = TractorTrailerEnv(scenario, action_units=action_units, task=task, **overrides)
        if single.n_legs > 1:
            raise ValueError(
                f"a maneuver of {single.n_legs} legs (a direction switch) is not stepped by the "
                "vector env: vectorise the single env, gymnasium.make_vec('tt_mujoco/"
                "TractorTrailer-v0', num_envs=N, vectorization_mode='sync')"
            )
        self.num_envs = int(num_envs)
        self.task = task
        self._own(single._scenario)
        self.observation_names = single.observation_names
        self.single_observation_space = single.observation_space
        self.single_action_space = single.action_space
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.dt, self.max_steps = single.dt, single.max_steps
        self._low, self._high = single._low, single._high
        self._headings, self.torque_limit = single._headings, single.torque_limit
        self._action_units = action_units
        self._built = single._built
        self._reverse = bool(self._built.scenario.reverse)
        self._start_s = float(single.target.start_s)
        self._kernel = _kernel()
        #: Whether the episodes step in compiled code (else CPython runs the same source).
        self.compiled = self._kernel is not None
        n, size = self.num_envs, len(self.observation_names)
        self._raw = np.zeros((n, size))  # the observations as computed, before wrap and clip
        self._aux = np.zeros((n, len(agent_step.AUX_FIELDS)))
        self._unit_s = np.zeros((n, 1 + single.n_trailers))
        self._steppers = [Stepper(self._built) for _ in range(n)]
        self._rngs: list = [None] * n
        self._args: list = [None] * n
        self._k = [0] * n
        self._ended = np.zeros(n, dtype=bool)
        self._status = np.full(n, "running", dtype=object)
        self._message = np.full(n, "", dtype=object)
        self._act = self._sense = None
        self._seeded = False
        self._phi0_deg = None

    # --- gymnasium API -------------------------------------------------------------------
    def reset(self, *, seed=None, options: dict | None = None):
        """Start every episode at the path start; ``seed`` an int (episode ``i`` gets
        ``seed + i``), a sequence of one per episode, or None. ``options`` may hold
        ``phi0_deg``, the initial articulation of every episode."""
        phi0_deg = reset_phi0_deg(self._scenario, options)
        seeds = self._seeds(seed)
        self._phi0_deg = phi0_deg
        for i, one in enumerate(seeds):
            if one is not None or self._rngs[i] is None:
                self._rngs[i] = seeding.np_random(one)[0]
            self._start(i)
        self._ended[:] = False
        self._status[:], self._message[:] = "running", ""
        return self._observations(), self._infos()

    def step(self, actions):
        """Step every episode with its action (a ``(num_envs, 2)`` array, as the single env's
        action each); an episode that ended on the last step is reset instead (NEXT_STEP).
        ``(observations, rewards, terminated, truncated, info)``, arrays over the episodes."""
        shape = (self.num_envs, 2)
        torques = torques_of(actions, shape, self._action_units, self.torque_limit).tolist()
        n, steps = self.num_envs, self._built.steps
        rewards = np.zeros(n)
        terminated, truncated = np.zeros(n, dtype=bool), np.zeros(n, dtype=bool)
        started = self._ended.copy()
        # what an episode that stops keeps: its last observation (as the single env), not
        # the part of a new one written before the stop
        last_raw, last_aux = self._raw.copy(), self._aux.copy()
        penalties = {}
        act, ks, args = self._act, self._k, self._args
        for i in range(n):
            if started[i]:  # ended on the last step: reset now (NEXT_STEP)
                self._start(i)
                self._status[i], self._message[i] = "running", ""
                continue
            k = ks[i]
            try:
                code = act(k, torques[i][0], torques[i][1], *args[i])
                if code == PAYLOAD:
                    code = self._after_payload(i, k)
                if code != RUNNING:
                    self._stop(i, code, k)
            except sim.StopRun as stop:
                self._raw[i], self._aux[i] = last_raw[i], last_aux[i]
                self._status[i], self._message[i] = stop.status, stop.message
                terminated[i] = True
                penalties[i] = -float(steps - k)  # -(1 + the steps left after this one)
                continue
            ks[i] = k + 1
            if k + 1 >= steps:
                truncated[i] = True
                self._status[i] = "ok"
        running = ~(started | terminated)
        rewards[running] = self._rewards()[running]
        for i, penalty in penalties.items():
            rewards[i] = penalty
        self._ended = terminated | truncated
        return self._observations(), rewards, terminated, truncated, self._infos()

    def close(self, **kwargs):
        """Nothing to release: the plants go with the environment."""

    # --- the episodes ------------------------------------------------------------------------
    def _start(self, i: int) -> None:
        """Reset episode ``i`` from its generator and sense its first step."""
        stepper = self._steppers[i]
        stepper.reset(self._rngs[i], phi0_deg=self._phi0_deg)
        episode = stepper.begin_agent(self._kernel)
        self._unit_s[i] = self._start_s
        agent = agent_step.AgentRecord(self._reverse, self._unit_s[i], self._raw[i], self._aux[i])
        self._args[i] = (episode, agent)
        self._k[i] = 0
        if self._act is None:
            self._entry_points(self._args[i])
        try:
            code = self._sense(0, *self._args[i])
            if code != RUNNING:
                self._stop(i, code, 0)
        except sim.StopRun as stop:
            raise ValueError(f"episode {i} cannot start: {stop.message}") from None

    def _entry_points(self, args: tuple) -> None:
        """The agent's step and first sense: compiled for these records, or CPython's."""
        if self._kernel is None:
            self._act, self._sense = agent_step.act_then_sense, agent_step.sense_and_observe
            return
        self._sense = compiled.entry_point(self._kernel.agent_sense, (0, *args))
        self._act = compiled.entry_point(self._kernel.agent_act, (0, 0.0, 0.0, *args))

    def _after_payload(self, i: int, k: int) -> int:
        """A payload placed on the reduced plant at step ``k`` of episode ``i``: its constants
        changed, the step advanced, the next step sensed; the stop code."""
        stepper = self._steppers[i]
        advance = (
            closed_loop.advance_after_payload
            if self._kernel is None
            else self._kernel.advance_after_payload
        )
        code, episode = stepper.agent_after_payload(k, advance)
        self._args[i] = (episode, self._args[i][1])
        if code != RUNNING:
            return code
        return self._sense(k + 1, *self._args[i])

    def _stop(self, i: int, code: int, k: int) -> None:
        """Episode ``i`` stopped at step ``k`` with ``code``: raise its StopRun."""
        stop_record, stepper = self._args[i][0][5], self._steppers[i]
        raised = stepper.hook_failure() if code == RAISED else None
        if raised is not None:  # Python code the kernel called back
            raise raised
        status, message = outcome.outcome(code, stop_record, stepper, None, k)
        raise sim.StopRun(status, message)

    # --- the batch ---------------------------------------------------------------------------
    def _seeds(self, seed) -> list:
        if seed is None and not self._seeded:
            seed = self._scenario.seed
        self._seeded = True
        if seed is None:
            return [None] * self.num_envs
        if isinstance(seed, Integral) and not isinstance(seed, bool):
            first = checked_seed(seed)
            return [checked_seed(first + i, f"seed + {i}") for i in range(self.num_envs)]
        seeds = list(seed) if isinstance(seed, list | tuple | np.ndarray) else None
        if seeds is None or len(seeds) != self.num_envs:
            raise ValueError(
                f"seed={shown(seed)} is not allowed: give an int, None, or one per episode "
                f"({self.num_envs})"
            )
        return [checked_seed(one, f"seed[{i}]") for i, one in enumerate(seeds)]

    def _observations(self) -> np.ndarray:
        """The batch's observations: headings wrapped to [-pi, pi], clipped to the bounds."""
        return bounded(self._raw, self._headings, self._low, self._high)

    def _rewards(self) -> np.ndarray:
        """Every episode's reward for the env's task after its step (the single env's)."""
        aux, lead = self._aux, len(self.observation_names) - 4  # the leading unit's errors
        target = (aux[:, AUX_V_D], aux[:, AUX_OMEGA_D])
        errors = (self._raw[:, lead], self._raw[:, lead + 1])
        return task_reward(self.task, aux[:, AUX_V], aux[:, AUX_OMEGA], target, errors)

    def _etas(self) -> np.ndarray:
        """Each episode's trailers' gains in force: a schedule's, else the constant ones."""
        if self._steppers[0].scheduler is not None:
            return np.array([stepper.plant_etas for stepper in self._steppers])
        return np.repeat(np.array([self._built.plant_params.etas]), self.num_envs, axis=0)

    def _infos(self) -> dict:
        aux = self._aux
        info = {
            "t": np.array(self._k, dtype=float) * self.dt,
            "status": self._status.copy(),
            "message": self._message.copy(),
            "e_v": aux[:, AUX_V] - aux[:, AUX_V_D],
            "e_omega": aux[:, AUX_OMEGA] - aux[:, AUX_OMEGA_D],
            "v_d_dot": aux[:, AUX_V_D_DOT].copy(),
            "omega_d_dot": aux[:, AUX_OMEGA_D_DOT].copy(),
            "slip_longitudinal": np.maximum(
                np.abs(aux[:, AUX_SLIP_LEFT]), np.abs(aux[:, AUX_SLIP_RIGHT])
            ),
            "etas": self._etas(),
        }
        mask = np.ones(self.num_envs, dtype=bool)
        return {**info, **{f"_{name}": mask for name in info}}


def _kernel():
    """The compiled kernel's module, or None where CPython runs the step (numba absent or
    turned off; a kernel that cannot load)."""
    why = compiled.unavailable()
    if why is None:
        try:
            return compiled.kernel()
        except Exception as err:  # a damaged cache: set aside, CPython runs the same step
            why = compiled.set_aside_cache(err)
    gymnasium.logger.warn(f"the vector env steps in CPython (the same numbers, slower): {why}")
    return None

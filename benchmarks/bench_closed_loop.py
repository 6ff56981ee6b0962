"""Closed-loop speed against the physics floor: the replay of the run's own inputs.

Run: ``python benchmarks/bench_closed_loop.py [--noise-snr-db DB]``. For the main run (10 s
S-curve, ISMC-STA, dynamic target, the paper's disturbance, no video, 1 ms step) it

1. runs the closed loop on the MuJoCo plant, recording every ``mj_step`` input (ctrl,
   qfrc_applied, xfrc_applied) and the initial state;
2. replays those inputs open-loop from that state with MuJoCo's C rollout (``mujoco.rollout``,
   one thread, no Python per step): MuJoCo is deterministic, so the replay ends in exactly the
   run's final state (checked), and its cost is the physics of that episode;
3. prints the closed loop's steps/s (the compiled loop of :mod:`tt_mujoco.sim.loop.compiled`, and
   the Python loop beside it), the replay's, and their ratio (issue 13's goal: >= 0.8);
4. runs the same scenario on the reduced plant and prints its steps/s against the MuJoCo loop
   (goal: >= 5);
5. prints the per-part cost of one control step of the Python loop (what every scenario the
   compiled loop does not take runs), from timers around each part of a run.

Ratios are taken in one process, so a busy machine moves both sides alike.
"""

import argparse
import contextlib
import os
import time

os.environ.setdefault("TT_MUJOCO_COMPILE_NOW", "1")  # compile here, not in the background
from collections import defaultdict

import mujoco
import numpy as np

from tt_mujoco.sim import Scenario, Stepper, build
from tt_mujoco.sim.loop import closed_loop as closed_loop_module
from tt_mujoco.sim.loop import target_step
from tt_mujoco.sim.simulate import run_episode


@contextlib.contextmanager
def python_loop():
    """The Python loop instead of the compiled one (TT_MUJOCO_COMPILED=0)."""
    before = os.environ.get("TT_MUJOCO_COMPILED")
    os.environ["TT_MUJOCO_COMPILED"] = "0"
    try:
        yield
    finally:
        if before is None:
            del os.environ["TT_MUJOCO_COMPILED"]
        else:
            os.environ["TT_MUJOCO_COMPILED"] = before


@contextlib.contextmanager
def recording_mj_step(data, inputs: list):
    """Record ``data``'s ctrl, qfrc_applied and xfrc_applied before every ``mj_step`` that
    CPython's step makes (:func:`tt_mujoco.sim.loop.closed_loop.mj_step`; the compiled loop gives
    the same numbers bit for bit): ``(ctrl, qfrc, xfrc, 1)`` per physics step."""
    step = closed_loop_module.mj_step

    def recording(model_address, data_address):
        inputs.append((data.ctrl.copy(), data.qfrc_applied.copy(), data.xfrc_applied.copy(), 1))
        step(model_address, data_address)

    closed_loop_module.mj_step = recording
    try:
        yield
    finally:
        closed_loop_module.mj_step = step


def closed_loop(scenario: Scenario, record: bool):
    """(wall seconds of the control loop, steps, recorded inputs, initial state, final qpos).

    Record under :func:`python_loop`: the recording wraps CPython's ``mj_step``."""
    built = build(scenario)
    stepper = Stepper(built)
    stepper.reset(np.random.default_rng(scenario.seed))
    ctrl = built.new_controller()
    ctrl.reset()
    inputs, initial = [], None
    plant = stepper.plant
    recorder = contextlib.nullcontext()
    if record:
        d = plant.data
        initial = (d.qpos.copy(), d.qvel.copy(), d.act.copy(), d.time)
        recorder = recording_mj_step(d, inputs)
    with recorder:
        start = time.perf_counter()
        status, _ = run_episode(stepper, ctrl)
        wall = time.perf_counter() - start
    final = plant.data.qpos.copy() if hasattr(plant, "data") else None
    return wall, stepper.steps, inputs, initial, final, plant, status


#: What a replay's control vector holds per physics step: the actuators' ctrl, qfrc_applied and
#: xfrc_applied, as the closed loop set them.
CONTROL_SPEC = (
    mujoco.mjtState.mjSTATE_CTRL
    | mujoco.mjtState.mjSTATE_QFRC_APPLIED
    | mujoco.mjtState.mjSTATE_XFRC_APPLIED
)


def replay(plant, inputs, initial) -> tuple[float, np.ndarray]:
    """Wall seconds of MuJoCo's C rollout (``mujoco.rollout``, one thread) of ``inputs`` from
    ``initial`` on a fresh MjData, and the final qpos: the episode's physics floor."""
    from mujoco import rollout

    m = plant.model
    d = mujoco.MjData(m)
    d.qpos[:], d.qvel[:], d.act[:] = initial[0], initial[1], initial[2]
    d.time = initial[3]
    mujoco.mj_forward(m, d)
    full = mujoco.mjtState.mjSTATE_FULLPHYSICS
    state = np.empty(mujoco.mj_stateSize(m, full))
    mujoco.mj_getState(m, d, state, full)
    per_step = np.concatenate(
        [np.concatenate([u, q, x.ravel()])[None].repeat(n, axis=0) for u, q, x, n in inputs]
    )
    warm = d.qacc_warmstart.copy()[None]
    start = time.perf_counter()
    states, _ = rollout.rollout(
        m, d, state[None], per_step[None], control_spec=CONTROL_SPEC, initial_warmstart=warm
    )
    seconds = time.perf_counter() - start
    mujoco.mj_setState(m, d, states[0, -1], full)
    return seconds, d.qpos.copy()


def compiled_replay(plant, inputs, initial) -> float:
    """Wall seconds to replay ``inputs`` with the ``mj_step`` calls made from compiled code, as
    the compiled loop makes them: the physics share of a compiled control step."""
    from numba import njit

    from tt_mujoco.sim.loop import closed_loop, compiled

    compiled.kernel()  # which compiles closed_loop.mj_step as a call of MuJoCo's symbol
    mj_step = closed_loop.mj_step

    @njit
    def run(m, d, ctrl, qfrc, ctrls, qfrcs, substeps):
        for k in range(ctrls.shape[0]):
            ctrl[:] = ctrls[k]
            qfrc[:] = qfrcs[k]
            for _ in range(substeps):
                mj_step(m, d)

    m = plant.model
    ctrls = np.array([u for u, _, _, _ in inputs])
    qfrcs = np.array([q for _, q, _, _ in inputs])
    best = np.inf
    for _ in range(4):  # the first call compiles
        d = mujoco.MjData(m)
        d.qpos[:], d.qvel[:], d.act[:] = initial[0], initial[1], initial[2]
        d.time = initial[3]
        mujoco.mj_forward(m, d)
        start = time.perf_counter()
        run(m._address, d._address, d.ctrl, d.qfrc_applied, ctrls, qfrcs, inputs[0][3])
        best = min(best, time.perf_counter() - start)
    return best


def parts(scenario: Scenario) -> dict[str, float]:
    """Microseconds per control step spent in each part of a run of CPython's step
    (:mod:`tt_mujoco.sim.loop.closed_loop`)."""
    built = build(scenario)
    stepper = Stepper(built)
    stepper.reset(np.random.default_rng(scenario.seed))
    ctrl = built.new_controller()
    ctrl.reset()
    spent = defaultdict(float)
    # (the module the step reaches it through, its name): label
    names = {
        (closed_loop_module, "sense_step"): "sense (total)",
        (closed_loop_module, "_sense"): "  the measurement",
        (target_step, "update_target"): "  the target",
        (closed_loop_module, "law_step"): "law",
        (closed_loop_module, "actuate_step"): "actuate (total)",
        (closed_loop_module, "mj_step"): "  mj_step",
    }
    originals = {key: getattr(*key) for key in names}

    def timed(label, fn):
        def wrapper(*args):
            t0 = time.perf_counter()
            try:
                return fn(*args)
            finally:
                spent[label] += time.perf_counter() - t0

        return wrapper

    for (module, name), label in names.items():
        setattr(module, name, timed(label, originals[module, name]))
    try:
        t0 = time.perf_counter()
        run_episode(stepper, ctrl)
        spent["whole control step"] = time.perf_counter() - t0
    finally:
        for (module, name), fn in originals.items():
            setattr(module, name, fn)
    n = stepper.steps
    return {k: 1e6 * v / n for k, v in spent.items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--noise-snr-db", type=float, default=None)
    args = parser.parse_args()
    scenario = Scenario(traj="s_curve", duration=10.0, noise_snr_db=args.noise_snr_db)
    with python_loop():
        _, steps, inputs, initial, recorded_final, plant, status = closed_loop(scenario, True)
    assert status == "ok", status
    closed_loop(scenario, record=False)  # loads (or, after an install, compiles) the kernel
    runs = [closed_loop(scenario, record=False) for _ in range(3)]
    loop_compiled = min(run[0] for run in runs)
    final = runs[0][4]
    floor, replay_final = replay(plant, inputs, initial)
    same = float(np.max(np.abs(replay_final - final)))
    same_python = float(np.max(np.abs(recorded_final - final)))
    floor = min([floor] + [replay(plant, inputs, initial)[0] for _ in range(2)])
    with python_loop():
        loop_python = min(closed_loop(scenario, record=False)[0] for _ in range(3))
    reduced_scenario = Scenario(**{**scenario.to_dict(), "plant": "reduced"})
    closed_loop(reduced_scenario, False)
    reduced = min(closed_loop(reduced_scenario, False)[0] for _ in range(3))
    with python_loop():
        reduced_python = min(closed_loop(reduced_scenario, False)[0] for _ in range(3))
    noise = "no noise" if args.noise_snr_db is None else f"{args.noise_snr_db:g} dB noise"
    print(f"10 s S-curve, ISMC-STA, paper disturbance, {noise}: {steps} control steps")
    print(f"replay reproduces the run: final qpos difference {same:.1e}")
    print(f"compiled and Python loop agree: final qpos difference {same_python:.1e}")
    print(f"  C rollout of its own inputs (the floor) {steps / floor:10,.0f} steps/s")
    print(f"  closed loop, MuJoCo plant, compiled      {steps / loop_compiled:10,.0f} steps/s")
    print(f"  closed loop, MuJoCo plant, Python loop   {steps / loop_python:10,.0f} steps/s")
    print(f"  closed loop, reduced plant, compiled     {steps / reduced:10,.0f} steps/s")
    print(f"  closed loop, reduced plant, Python loop  {steps / reduced_python:10,.0f} steps/s")
    print(f"ratio closed loop / replay: {floor / loop_compiled:.3f} (goal >= 0.8)")
    print(f"ratio reduced / MuJoCo loop: {loop_compiled / reduced:.3f} (goal >= 5)")
    print(
        f"compiled / Python loop: MuJoCo {loop_python / loop_compiled:.2f}x faster, reduced "
        f"{reduced_python / reduced:.2f}x"
    )
    physics = compiled_replay(plant, inputs, initial)
    us = 1e6 / steps
    print(
        f"per control step (us), compiled loop: {loop_compiled * us:.2f} = mj_step called from "
        f"compiled code {physics * us:.2f} (its replay) + the rest "
        f"{(loop_compiled - physics) * us:.2f}"
    )
    print("per control step (us), Python loop, MuJoCo plant:")
    with python_loop():
        for name, us in parts(scenario).items():
            print(f"  {name:28s} {us:7.2f}")


if __name__ == "__main__":
    main()

"""The physics floor itself: MuJoCo solver settings, their cost and their accuracy (no assertions).

    python benchmarks/bench_physics_settings.py

For each setting it reports, on the closed-loop inputs of the main run with 20 dB noise (the
sweep's episode, where the contact solver works hardest) replayed open-loop:

- the cost of a physics step (us) and its ratio to the project's settings, in this process;
- the mean constraint-solver and line-search iterations per step;

and the accuracy figures the model is validated on (``python -m tt_mujoco.validate``):

- the final P error of the analytic kinematics after a weaving drive (bound 2 mm),
- the largest |beta - eta phi| there (bound 1e-4 rad),
- the largest |dv| and |d omega| of open-loop torques against the reduced ODE (bounds 5e-4 m/s,
  5e-3 rad/s);

and, closed loop, the metrics of the paper's S-curve run and of the 20 dB noise episode under
each setting, as ratios to the project's settings' (the open-loop checks above drive smoothly,
where every setting converges to the same answer; the closed loop is where they part).

A setting is applied to every model compiled while it is measured (the mass matrix does not
depend on the solver, so the inertia check is not repeated).
"""

import copy
import os
import time
from contextlib import contextmanager

import mujoco
import numpy as np

from tt_mujoco import validate
from tt_mujoco.sim import Scenario, Stepper, build, simulate
from tt_mujoco.sim.parts import physics
from tt_mujoco.sim.simulate import run_episode
from tt_mujoco.vehicle.params import Params

SETTINGS = {
    "project (Newton, elliptic, tol 1e-8)": {},
    "tolerance 1e-6": {"tolerance": 1e-6},
    "iterations 4": {"iterations": 4},
    "line-search iterations 10": {"ls_iterations": 10},
    "CG solver": {"solver": mujoco.mjtSolver.mjSOL_CG},
    "PGS solver": {"solver": mujoco.mjtSolver.mjSOL_PGS},
    "pyramidal cones": {"cone": mujoco.mjtCone.mjCONE_PYRAMIDAL},
    "no warm start": {"disableflags": mujoco.mjtDisableBit.mjDSBL_WARMSTART},
}


def _apply(model, options: dict) -> None:
    for name, value in options.items():
        if name == "disableflags":
            value = model.opt.disableflags | value
        setattr(model.opt, name, value)


@contextmanager
def model_options(options: dict):
    """Every model compiled inside gets ``options`` (fields of ``MjModel.opt``)."""
    original = physics.compile_model

    def compile_with(*args):
        model = original(*args)
        _apply(model, options)
        return model

    physics.compile_model = compile_with
    try:
        yield
    finally:
        physics.compile_model = original


def recorded_inputs(scenario: Scenario):
    """An episode's mj_step inputs and initial state (its own settings), recorded before every
    ``mj_step`` of CPython's step (the compiled loop gives the same numbers)."""
    from bench_closed_loop import recording_mj_step

    os.environ["TT_MUJOCO_COMPILED"] = "0"
    try:
        built = build(scenario)
        stepper = Stepper(built)
        stepper.reset(np.random.default_rng(0))
        plant, d = stepper.plant, stepper.plant.data
        initial = (d.qpos.copy(), d.qvel.copy())
        inputs = []
        ctrl = built.new_controller()
        ctrl.reset()
        with recording_mj_step(d, inputs):
            run_episode(stepper, ctrl)
    finally:
        os.environ.pop("TT_MUJOCO_COMPILED", None)
    return plant.model, initial, [(ctrl_, qfrc) for ctrl_, qfrc, _, _ in inputs]


def replay_once(model, initial, inputs, options: dict) -> tuple[float, float, float]:
    """(seconds, mean solver iterations, mean line-search iterations) of one replay."""
    m = copy.copy(model)
    _apply(m, options)
    d = mujoco.MjData(m)
    d.qpos[:], d.qvel[:] = initial
    mujoco.mj_forward(m, d)
    iters = lsiters = 0
    start = time.perf_counter()
    for u, q in inputs:
        d.ctrl[:] = u
        d.qfrc_applied[:] = q
        mujoco.mj_step(m, d)
        iters += int(d.solver_niter[0])
        lsiters += int(d.solver[0].neval)
    return time.perf_counter() - start, iters / len(inputs), lsiters / len(inputs)


def replay_costs(recording, rounds: int = 3) -> dict[str, tuple[float, float, float]]:
    """Per setting: (us a step, mean solver iterations, mean line-search iterations), the best
    of ``rounds`` replays, the settings taking turns in each round (the machine drifts)."""
    model, initial, inputs = recording
    runs = {name: [] for name in SETTINGS}
    for _ in range(rounds):
        for name, options in SETTINGS.items():
            runs[name].append(replay_once(model, initial, inputs, options))
    return {
        name: (1e6 * min(r[0] for r in got) / len(inputs), got[0][1], got[0][2])
        for name, got in runs.items()
    }


#: MuJoCo's own stage timers, in the order a step runs them (mjData.timer).
STAGES = (
    ("position: kinematics", "mjTIMER_POS_KINEMATICS"),
    ("position: inertia", "mjTIMER_POS_INERTIA"),
    ("position: collision", "mjTIMER_POS_COLLISION"),
    ("position: make constraints", "mjTIMER_POS_MAKE"),
    ("position: project", "mjTIMER_POS_PROJECT"),
    ("velocity", "mjTIMER_VELOCITY"),
    ("actuation", "mjTIMER_ACTUATION"),
    ("constraint solver", "mjTIMER_CONSTRAINT"),
    ("advance (integrator)", "mjTIMER_ADVANCE"),
)


def stage_profile(model, initial, inputs) -> dict[str, float]:
    """Microseconds a step in each stage of ``mj_step`` (MuJoCo's timers), and the whole step."""
    d = mujoco.MjData(model)
    d.qpos[:], d.qvel[:] = initial
    mujoco.mj_forward(model, d)
    for i in range(len(d.timer)):
        d.timer[i].duration, d.timer[i].number = 0.0, 0
    for u, q in inputs:
        d.ctrl[:] = u
        d.qfrc_applied[:] = q
        mujoco.mj_step(model, d)

    def us(name: str) -> float:
        timer = d.timer[int(getattr(mujoco.mjtTimer, name))]
        return 1e6 * timer.duration / len(inputs)

    out = {label: us(name) for label, name in STAGES}
    out["whole step"] = us("mjTIMER_STEP")
    return out


#: The closed-loop episodes each setting runs (replayed for the cost, run for the metrics), and
#: the metrics compared.
EPISODES = {
    "noisy": Scenario(traj="s_curve", duration=10.0, noise_snr_db=20.0),
    "paper": Scenario(traj="s_curve"),
}
CLOSED_LOOP_METRICS = ("rmse_lateral", "rmse_omega", "slip_lateral_max", "eq_violation_max")


def closed_loop_metrics(options: dict) -> dict[str, dict]:
    """Each episode's metrics with ``options`` applied to its model."""
    with model_options(options):
        return {name: simulate(scenario).metrics for name, scenario in EPISODES.items()}


def main() -> None:
    recordings = {name: recorded_inputs(scenario) for name, scenario in EPISODES.items()}
    model, initial, inputs = recordings["noisy"]
    print("where a step of the project's settings goes (MuJoCo's timers, us a step):")
    profile = stage_profile(model, initial, inputs)
    for label, value in profile.items():
        print(f"  {label:28s} {value:6.2f}  ({100 * value / profile['whole step']:4.1f} %)")
    costs = {name: replay_costs(recording) for name, recording in recordings.items()}
    base = {name: cost[next(iter(SETTINGS))][0] for name, cost in costs.items()}
    print(
        f"{len(inputs)} steps of the 20 dB noise episode and "
        f"{len(recordings['paper'][2])} of the paper's run replayed per setting"
    )
    print(
        f"{'setting':38s} {'us/step':>8s} {'ratio':>6s} {'iter':>5s} {'ls':>5s} "
        f"{'paper':>6s} {'P err mm':>9s} {'|b-ep|':>8s} {'|dv|':>8s} {'|dw|':>8s}"
    )
    for name, options in SETTINGS.items():
        us, iters, ls = costs["noisy"][name]
        with model_options(options):
            kin = validate.check_kinematics(Params(), +1)
            dyn = validate.check_dynamics(Params())
        print(
            f"{name:38s} {us:8.2f} {us / base['noisy']:6.3f} {iters:5.2f} {ls:5.2f} "
            f"{costs['paper'][name][0] / base['paper']:6.3f} "
            f"{1e3 * kin['final_P_error_m']:9.3f} {kin['eq_violation_max_rad']:8.1e} "
            f"{dyn['v_max_abs_diff']:8.1e} {dyn['omega_max_abs_diff']:8.1e}"
        )
    baseline = closed_loop_metrics({})
    others = {name: closed_loop_metrics(o) for name, o in list(SETTINGS.items())[1:]}
    for episode in EPISODES:
        print(f"closed loop, {episode} episode: each setting's metrics over the project's")
        print(f"{'setting':38s}" + "".join(f" {m:>17s}" for m in CLOSED_LOOP_METRICS))
        values = (f" {baseline[episode][m]:17.4e}" for m in CLOSED_LOOP_METRICS)
        print(f"{'project (absolute)':38s}" + "".join(values))
        for name, got in others.items():
            ratios = (got[episode][m] / baseline[episode][m] for m in CLOSED_LOOP_METRICS)
            print(f"{name:38s}" + "".join(f" {r:17.3f}" for r in ratios))


if __name__ == "__main__":
    main()

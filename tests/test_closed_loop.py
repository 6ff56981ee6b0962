"""The closed loop's step (tt_mujoco.sim.loop.closed_loop) is one source: CPython runs it on the
records, the kernel compiles it, and both give the same numbers bit for bit."""

from __future__ import annotations

import math
import textwrap

import numpy as np
import pytest
from tt_mujoco.controllers.plain import PlainLawController

from tt_mujoco.reference.path_base import HOOKED_PATH
from tt_mujoco.sim import Scenario, build
from tt_mujoco.sim.loop import closed_loop, compiled, records
from tt_mujoco.sim.loop.compiled_law import compile_law
from tt_mujoco.sim.loop.law import PYTHON
from tt_mujoco.sim.loop.stepper import Stepper
from tt_mujoco.sim.parts.measure import TRAIN_FIELDS

STEPS = 1500

CASES = [
    dict(traj="s_curve", noise_snr_db=20.0, seed=5),
    dict(traj="circle", plant="reduced", trailers=3, eta="path", noise_snr_db=20.0),
    dict(
        traj="s_curve",
        path_feedback={},
        sensor_delay=0.004,
        actuator="dc_motor",
        faults=["dropout:t=0.2,duration=0.3", "actuator:t=0.6,wheel=left"],
    ),
    dict(
        traj="s_curve", trailers=2, disturbance="wrench", wind="6:90:2", ground=["rect:0:0:2:2:0.2"]
    ),
    dict(traj="s_curve", reverse=True, controller="pid", faults=["payload:t=0.5,factor=2"]),
    dict(traj="cycloid", eta="scheduled", controller="smc", plant="reduced", trailers=2),
    # a user's compiled plain-number law: it reads the records through their addresses
    dict(
        traj="s_curve",
        controller="examples/kanayama.py:kanayama_law",
        noise_snr_db=20.0,
        sensor_delay=0.003,
        faults=["dropout:t=0.5,duration=0.2"],
    ),
]


def _records(options) -> tuple:
    """A reset episode's stepper and its records, with a log of :data:`STEPS` rows."""
    built = build(Scenario(duration=3.0, **options))
    stepper = Stepper(built)
    stepper.reset(np.random.default_rng(built.scenario.seed))
    controller = built.new_controller()
    controller.reset()
    plain = isinstance(controller, PlainLawController)
    user = compile_law(type(controller)) if plain else compiled.kernel().no_user_law
    loop, plant, law, target, stop = stepper.begin(controller, user, kernel=compiled.kernel())
    log = records.LogRecord(
        measurement=np.empty((STEPS, len(records.MEASUREMENT_DTYPE))),
        loop=np.empty(STEPS, dtype=records.LOG_DTYPE),
        train=np.empty((STEPS, loop.n_trailers - 1, len(TRAIN_FIELDS))),
        etas=np.empty((STEPS if plant.steering.kind else 0, loop.n_trailers)),
    )
    return stepper, (loop, plant, law, target, log, stop)


def _values(elements, fields) -> np.ndarray:
    """The fields of a structured array's elements, or of its interpreted twin's."""
    if isinstance(elements, np.ndarray):
        return np.array(elements.tolist(), dtype=float).reshape(len(elements), len(fields))
    return np.array([[getattr(element, name) for name in fields] for element in elements])


def _state(stepper, plant, law, target, log) -> dict:
    final = plant.ode_state if not plant.mujoco else stepper.plant.data.qpos
    return {
        "measurement": log.measurement.copy(),
        "loop": _values(log.loop, records.LOG_DTYPE.names),
        "train": log.train.copy(),
        "etas": log.etas.copy(),
        "final": np.array(final, dtype=float),
        "target": _values(target.state, records.TARGET_FIELDS),
        "law": np.array(law.state, dtype=float),
    }


@pytest.mark.parametrize("options", CASES, ids=lambda c: "-".join(map(str, c.values())))
def test_cpython_runs_the_compiled_step_bit_for_bit(monkeypatch, options):
    monkeypatch.setenv("TT_MUJOCO_COMPILE_NOW", "1")
    stepper, args = _records(options)
    stopped = compiled.kernel().run_chunk(0, STEPS - 1, *args)
    fast = _state(stepper, *args[1:5])

    stepper, args = _records(options)
    args = records.interpreted(args)
    assert closed_loop.run_steps(0, STEPS - 1, *args) == stopped
    slow = _state(stepper, *args[1:5])
    rows = stopped[1]  # the rows logged before a stop (the log's others are not written)
    for name in ("measurement", "loop", "train", "etas"):
        fast[name], slow[name] = fast[name][:rows], slow[name][:rows]
    assert fast.keys() == slow.keys()
    for name, values in fast.items():
        np.testing.assert_array_equal(values, slow[name], err_msg=name)


def test_records_read_by_cpython_hold_the_same_fields():
    record = records.new_record(records.STOP_FIELDS, v=2.5, hitch=3.0)
    (element,) = records.interpreted(record)
    assert (element.v, element.hitch, element.phi) == (2.5, 3.0, 0.0)
    element.phi = 1.0  # a plain attribute, written as the step writes it
    assert element.phi == 1.0 and record[0]["phi"] == 0.0
    limits = records.Limits(1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0)
    assert records.interpreted(limits) == limits


# What only CPython's step runs, wired through the step's hooks: each written here as a user's
# path, disturbance and controller class that compute what a built-in one does, so that a run
# with the hook must equal the built-in run to the last bit.
USER_PARTS = textwrap.dedent(
    """
    import math

    from tt_mujoco.controllers.ismc_sta import IsmcStaController
    from tt_mujoco.reference.paths import ArcsPath
    from tt_mujoco.sim.parts.disturbances import paper_disturbance_of


    class UsersArcs(ArcsPath):
        \"\"\"The S-curve as a user's path class: no closed form for the kernel.\"\"\"


    def users_s_curve():
        R = 1.5
        return UsersArcs("s_curve", (0.0, 0.0, 0.0), [(math.pi * R, 1 / R), (math.pi * R, -1 / R)])


    def users_paper(t):
        return paper_disturbance_of(t)


    class UsersIsmc(IsmcStaController):
        \"\"\"ISMC-STA as a user's class: the loop calls its Python compute.\"\"\"
    """
)

HOOKED = [
    # a path without closed form, under path feedback and the path schedule
    (
        dict(traj="s_curve", path_feedback={}, eta="path", noise_snr_db=20.0),
        dict(traj="{parts}:users_s_curve"),
    ),
    # a user's disturbance, matched and as a wrench
    (dict(traj="s_curve", trailers=2), dict(disturbance_model="{parts}:users_paper")),
    (
        dict(traj="s_curve", disturbance="wrench"),
        dict(disturbance_model="{parts}:users_paper"),
    ),
    # a controller class, on a scheduled train seen through noise, a delay and a dropout
    (
        dict(
            traj="s_curve",
            trailers=2,
            eta="path",
            noise_snr_db=20.0,
            sensor_delay=0.003,
            faults=["dropout:t=0.5,duration=0.2"],
        ),
        dict(controller="{parts}:UsersIsmc"),
    ),
]


@pytest.mark.parametrize("route", ["0", "1"], ids=["cpython", "compiled"])
@pytest.mark.parametrize("options, hooked", HOOKED, ids=["path", "matched", "wrench", "class"])
def test_a_hooked_part_runs_the_step_as_the_built_in_one(
    tmp_path, monkeypatch, options, hooked, route
):
    from tt_mujoco.sim import simulate
    from tt_mujoco.sim.loop.stepper import Stepper

    # Both on CPython's step, or both compiled (the hook called back from the kernel).
    monkeypatch.setenv("TT_MUJOCO_COMPILED", route)
    monkeypatch.setenv("TT_MUJOCO_COMPILE_NOW", "1")
    parts = tmp_path / "parts.py"
    parts.write_text(USER_PARTS)
    hooked = {key: value.format(parts=parts) for key, value in hooked.items()}
    scenario = Scenario(duration=2.5, **options)
    built = build(Scenario(duration=2.5, **{**options, **hooked}))
    stepper = Stepper(built)
    stepper.reset(np.random.default_rng(built.scenario.seed))
    loop, _, law, target, _ = stepper.begin(built.new_controller())
    hooks = (law.kind == PYTHON, target.path_kind == HOOKED_PATH)
    hooks += (loop.disturbance_hook is not None,)
    assert sum(hooks) == 1  # the hook under test, and only it, is in the step's records
    built_in, user = simulate(scenario), simulate(built)
    assert (user.status, user.message) == (built_in.status, built_in.message)
    assert built_in.timeseries.keys() == user.timeseries.keys()
    for name, column in built_in.timeseries.items():
        np.testing.assert_array_equal(user.timeseries[name], column, err_msg=name)
    assert len(user.timeseries["t"]) > 400 and math.isfinite(user.metrics["cross_track_rms"])

"""The closed loop's step (tt_mujoco.sim.closed_loop) is one source: CPython runs it on the
records, the kernel compiles it, and both give the same numbers bit for bit."""

from __future__ import annotations

import numpy as np
import pytest
from tt_mujoco.controllers.plain import PlainLawController

from tt_mujoco.sim import Scenario, build, closed_loop, compiled, records
from tt_mujoco.sim.measure import TRAIN_FIELDS
from tt_mujoco.sim.stepper import Stepper

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
    user = compiled.compile_law(type(controller)) if plain else compiled.kernel().no_user_law
    loop, plant, law, target, stop = compiled.episode_records(stepper, controller, user)
    log = records.LogRecord(
        measurement=np.empty((STEPS, len(records.MEASUREMENT_DTYPE))),
        loop=np.empty(STEPS, dtype=records.LOG_DTYPE),
        train=np.empty((STEPS, loop.n_trailers - 1, len(TRAIN_FIELDS))),
        etas=np.empty((STEPS if plant.steering.kind else 0, loop.n_trailers)),
    )
    return stepper, (loop, plant, law, target, log, stop)


def _interpreted_steps(loop, plant, law, target, log, stop_record) -> tuple[int, int]:
    """Steps 0 .. STEPS - 1 in CPython, the halves around the built-in law, as the kernel's
    chunk loop runs them: ``(status, k)``."""
    stop, got = stop_record[0], law.reading[0]
    for k in range(STEPS):
        code = closed_loop.sense_step(k, k, loop, plant, law, target, log, stop)
        if code != closed_loop.RUNNING:
            return code, k
        out = closed_loop.law_step(law, got.v, got.omega, loop.dt, loop.limits.torque_limit)
        assert out[0] == closed_loop.LAW_OK
        got.T_r, got.T_l, got.u1, got.u2 = out[1:]
        code = closed_loop.actuate_step(k, k, loop, plant, law, target, log, stop)
        if code != closed_loop.RUNNING:
            return code, k
    return closed_loop.RUNNING, STEPS


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
    assert _interpreted_steps(*args) == stopped
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

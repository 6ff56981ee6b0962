"""The law's part of the step (tt_mujoco.sim.loop.law): built-in laws take their gains and memory by
name, the kernel's written-out dispatch runs each as the Python form does, and the record gives
a controller's memory back as it took it."""

from __future__ import annotations

import typing

import numpy as np
import pytest
from tt_mujoco.controllers import base, compiled_laws

from tt_mujoco.sim.loop import law
from tt_mujoco.vehicle.params import Params


@pytest.mark.parametrize("cls", law.LAW_CLASSES, ids=lambda cls: cls.name)
def test_a_built_in_law_declares_its_gains_and_state_by_name(cls):
    assert all(tuple(preset) == cls.GAINS._fields for preset in cls.PRESETS.values())
    assert cls.STATE() == (0.0,) * len(cls.STATE._fields)
    controller = cls(base.reduced_model(Params()), gains={cls.GAINS._fields[0]: 1.25})
    assert type(controller.law_gains) is cls.GAINS and type(controller.law_state) is cls.STATE
    assert controller.law_gains[0] == 1.25  # the user's gain, by its name


def test_presets_whose_keys_are_not_the_gains_fields_are_refused():
    class Gains(typing.NamedTuple):
        k: float

    with pytest.raises(TypeError, match=r"PRESETS\['p'\] has the keys \('q',\)"):
        type("Wrong", (base.VelocityController,), {"GAINS": Gains, "PRESETS": {"p": {"q": 1.0}}})


def test_law_classes_are_the_compiled_laws_in_registration_order():
    assert law.LAW_CLASSES == tuple(compiled_laws().values())
    assert law.LAWS == tuple(cls.LAW for cls in law.LAW_CLASSES)
    assert law.USER == len(law.LAWS) and law.PYTHON == law.USER + 1


@pytest.mark.parametrize("saturated", [False, True])
def test_the_written_out_dispatch_runs_each_law_as_run_law_does(saturated):
    # the kernel's form of run_law, run by CPython, gives the same outputs and the same state
    # written back, to the bit, for random gains, memory and measurements
    written_out = law.run_law_written_out()
    rng = np.random.default_rng(7)
    for kind, cls in enumerate(law.LAW_CLASSES):
        for _ in range(20):
            tracking = base.Tracking(*rng.normal(size=6))
            model = base.Nominal(*rng.normal(size=2), 1.0, *rng.normal(scale=0.2, size=2), 1.0)
            saturation = base.Saturation(float(rng.uniform(0.5, 2.0)), saturated, True)
            gains = rng.uniform(0.1, 5.0, size=len(cls.GAINS._fields))
            state = rng.normal(size=len(cls.STATE._fields))
            if "has_prev" in cls.STATE._fields:
                state[cls.STATE._fields.index("has_prev")] = float(rng.integers(2))
            ours, theirs = state.copy(), state.copy()
            out = law.run_law(kind, 0.001, tracking, model, ours, gains, saturation)
            again = written_out(kind, 0.001, tracking, model, theirs, gains, saturation)
            assert out == again and ours.tobytes() == theirs.tobytes()
            # and as the law itself, called with its named records
            step = cls.LAW(0.001, tracking, model, cls.STATE(*state), cls.GAINS(*gains), saturation)
            assert tuple(step[:-1]) == out and tuple(step.state) == tuple(ours)


@pytest.mark.parametrize("cls", law.LAW_CLASSES, ids=lambda cls: cls.name)
def test_the_record_takes_a_controllers_memory_and_gives_it_back(cls):
    controller = cls(base.reduced_model(Params()))
    controller.law_state = cls.STATE(*(0.5 + i for i in range(len(cls.STATE._fields))))
    steering = type("Steering", (), {"etas": np.array(Params().etas)})()
    record = law.law_record(controller, Params(), None, steering, None)
    assert record.kind == law.LAW_CLASSES.index(cls)
    assert record.gains.tolist() == list(controller.law_gains)
    assert record.state.tolist() == list(controller.law_state)
    record.state[:] = -record.state
    law.hand_law_back(controller, record)
    assert type(controller.law_state) is cls.STATE
    assert list(controller.law_state) == [-(0.5 + i) for i in range(len(cls.STATE._fields))]

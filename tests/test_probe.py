"""tt_mujoco.sim.probe: a user's controller tried once before the run, on the state and the
target the run's first step gives it, without the episode's tables."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tt_mujoco.sim import Scenario
from tt_mujoco.sim.build import build
from tt_mujoco.sim.loop import stepper as stepper_mod
from tt_mujoco.sim.loop.stepper import Stepper
from tt_mujoco.sim.probe import check_user_code

KANAYAMA = f"{Path(__file__).resolve().parents[1]}/examples/kanayama.py:KanayamaTracker"


def _first_look(built, steps):
    probe = Stepper(built, steps=steps)
    probe.reset(np.random.default_rng(0))
    return probe.sense()


@pytest.mark.parametrize(
    "scenario",
    [
        Scenario(traj="s_curve", noise_snr_db=20.0),
        Scenario(traj="circle", reverse=True, plant="reduced"),
        Scenario(trailers=3, traj="s_curve", disturbance="none"),
        Scenario(world="loading_bay", traj="plan", reverse=True, seed=3),
        Scenario(traj="cycloid", plant="reduced", faults=["dropout:t=0,duration=1"]),
    ],
    ids=["noisy", "reverse", "train", "plan", "fault"],
)
def test_the_first_step_alone_gives_what_the_runs_first_step_gives(scenario):
    """What the probe shows the controller (made for one step) is the run's first step's."""
    built = build(scenario)
    short, whole = _first_look(built, 1), _first_look(built, None)
    for shown, expected in zip(short, whole, strict=True):
        assert _values(shown) == _values(expected)


def _values(obj) -> dict:
    """A measurement's or a reference's numbers by name (the path object left out)."""
    if hasattr(obj, "_fields"):
        return dict(zip(obj._fields, obj, strict=True))
    names = [n.lstrip("_") for n in obj.__slots__ if n != "path"]
    return {n: getattr(obj, n) for n in names}


def test_the_check_makes_the_first_steps_records_only(monkeypatch):
    """A 600 s run's tables are not built for one call: the check takes milliseconds."""
    made = []
    original = stepper_mod.Stepper.__init__

    def spy(self, built, steps=None):
        made.append(steps)
        original(self, built, steps)

    monkeypatch.setattr(stepper_mod.Stepper, "__init__", spy)
    check_user_code(build(Scenario(controller=KANAYAMA, duration=600.0)))
    assert made == [1]

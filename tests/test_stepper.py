"""tt_mujoco.sim.loop.stepper: an episode's constants are made when it is reset."""

from __future__ import annotations

import numpy as np

from tt_mujoco.sim import Scenario
from tt_mujoco.sim.build import build
from tt_mujoco.sim.loop import episode
from tt_mujoco.sim.loop.stepper import Stepper


def test_the_speed_profiles_table_is_made_at_reset_with_the_noise(monkeypatch):
    """The targets of every step are an episode constant, as its noise is: the reset makes
    them, and the records made for the loop (inside its wall time) find them made."""
    built = build(Scenario(traj="s_curve", duration=2.0, noise_snr_db=20.0))
    episode._PROFILES.clear()
    stepper = Stepper(built)
    stepper.reset(np.random.default_rng(0))
    profile = episode.inner_target(built.target).profile

    def no_more(self, t):
        raise AssertionError("the profile was tabled again after the reset")

    monkeypatch.setattr(type(profile), "state", no_more)
    target = stepper.begin(None).target
    assert len(target.profile) == stepper.steps + 1

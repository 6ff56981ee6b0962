"""The one setup path (tt_mujoco.sim.build): what it refuses before any work."""

from __future__ import annotations

import pytest


@pytest.mark.parametrize("given", ["s_curve", None, 3, {"traj": "circle"}])
def test_build_refuses_what_is_not_a_scenario_naming_it(given):
    from tt_mujoco.sim import build, simulate

    for route in (build, simulate):
        with pytest.raises(TypeError, match=r"is not allowed: give a tt_mujoco.sim.Scenario"):
            route(given)

"""tt-mujoco: an off-axle tractor-trailer with passive trailer steering, in contact physics.

The Python API (:mod:`tt_mujoco.api`)::

    import tt_mujoco

    run = tt_mujoco.simulate(tt_mujoco.Scenario(traj="s_curve", controller="nmpc"))
    print(run.status, run.metrics["cross_track_rms"])
    frame = run.to_pandas()

The names below load on first use, so ``import tt_mujoco`` stays light.
"""

from __future__ import annotations

__all__ = ["Run", "Scenario", "load_scenario", "simulate"]


def __getattr__(name: str):
    if name in ("Run", "load_scenario", "simulate"):
        from tt_mujoco import api

        return getattr(api, name)
    if name == "Scenario":
        from tt_mujoco.sim import Scenario

        return Scenario
    raise AttributeError(f"module 'tt_mujoco' has no attribute {name!r}")

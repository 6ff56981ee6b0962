"""The legs of a Gymnasium episode (:class:`tt_mujoco.gym_env.TractorTrailerEnv`): one for a
run, or for a plan without a cusp; each leg of a planned maneuver with cusps
(:mod:`tt_mujoco.sim.maneuver`), driven one after the other as ``python -m tt_mujoco.run``
drives them.

A leg starts where the last one stopped: a fresh plant, at rest, at the tractor's pose and
hitch angles of the last one's final measurement (:func:`leg_start`, the maneuver's
:func:`~tt_mujoco.sim.maneuver.final_state` of the same row); its noise comes from the
episode's seed and its index, as the maneuver's does.
"""

from __future__ import annotations

import copy
import dataclasses

import numpy as np

from tt_mujoco.sim.build import Build, LegStart, build, drawn_polyline

__all__ = ["Legs", "OwnScenario", "leg_start"]


class OwnScenario:
    """An env's scenario, its own: copied when the env is made (:meth:`_own`), so that later
    changes to the caller's object do not reach its episodes (a seed or a start angle read at
    ``reset``), and given out as a copy (``env.scenario``): make a new env to change it."""

    _scenario = None

    def _own(self, scenario):
        self._scenario = copy.deepcopy(scenario)

    @property
    def scenario(self):
        """The env's scenario (a copy: the env's own is fixed when it is made)."""
        return copy.deepcopy(self._scenario)


def leg_start(measurement) -> tuple[tuple, tuple]:
    """``(pose, phis)`` of a measurement (:class:`~tt_mujoco.sim.parts.measure.Measurement`,
    a train's with its rows): the tractor's ``(x, y, theta)`` and phi_1..phi_N, where the
    next leg starts."""
    pose = (measurement.x, measurement.y, measurement.theta)
    # a train's rows: x0_k, y0_k, theta0_k, phi_k, beta_k, v0_k of trailers 2..N
    phis = (measurement.phi, *(row[3] for row in getattr(measurement, "train", ())))
    return pose, phis


class Legs:
    """The legs of the episodes of ``first`` (a :class:`~tt_mujoco.sim.build.Build`; of a plan,
    its first leg's), each planned from the plan's own starts (their lengths in steps and
    what they can reach fix the env's spaces)."""

    def __init__(self, first: Build):
        plan = first.plan
        self.first = first
        self.plan = plan if plan is not None and plan.cusps else None
        self.builds = [first]
        self.maneuver = None
        if self.plan is not None:
            self.maneuver = dataclasses.replace(first.scenario, reverse=plan.legs[-1].reverse)
            self.builds += [
                build(self.maneuver, LegStart(plan, i)) for i in range(1, len(plan.legs))
            ]

    @property
    def count(self) -> int:
        return len(self.builds)

    @property
    def steps(self) -> int:
        """The episode's control steps, every leg's as planned."""
        return sum(built.steps for built in self.builds)

    @property
    def duration(self) -> float:
        return sum(built.duration for built in self.builds)

    def reach(self) -> np.ndarray:
        """Every leg's reference path as its run can reach it, one after the other."""
        return np.vstack([drawn_polyline(built.path, built.duration) for built in self.builds])

    def steps_after(self, index: int) -> int:
        """The planned control steps of the legs after leg ``index``."""
        return sum(built.steps for built in self.builds[index + 1 :])

    def next(self, index: int, measurement) -> Build:
        """Leg ``index`` (1 or more), starting where the last leg's final ``measurement`` is.

        Raises
        ------
        ValueError
            The leg cannot start there (a unit outside the world's bounds, ...), as the
            maneuver's leg could not.
        """
        pose, phis = leg_start(measurement)
        return build(self.maneuver, LegStart(self.plan, index, pose, phis))

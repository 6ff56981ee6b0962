"""The step's own target code (``target_step.target_step_of``) on the record of a scenario's
target, driven by hand: the tests of the targets, the path feedback and backing up call what
the run calls."""

from __future__ import annotations

from tt_mujoco.sim import Scenario, build
from tt_mujoco.sim.loop import episode, records, target_step


class SteppedTarget:
    """A scenario's target as the step holds it: :meth:`step` is one control step at any time
    ``t`` (the speed profile's state there), :attr:`state` the record's state after it."""

    def __init__(self, **scenario):
        self.built = build(Scenario(**scenario))
        self.target = self.built.target
        self.profile = episode.inner_target(self.target).profile
        self.record = records.interpreted(episode.target_record(self.built, 1))

    @property
    def state(self):
        """The target record's state: ``s``, ``kappa``, ``s_near``, ``e_y``, ``e_psi``, ..."""
        return self.record.state[0]

    def step(self, t: float, dt: float, v: float, pose=(0.0, 0.0, 0.0)):
        """``(v_d, omega_d, v_d_dot, omega_d_dot)`` at ``t``, the measured speed ``v`` and
        ``pose`` (x, y, theta), ``dt`` after the last step."""
        reference = self.profile.state(float(t))
        return target_step.target_step_of(self.record, reference, float(v), dt, pose)

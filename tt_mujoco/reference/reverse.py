"""Driving a path backwards, trailer first."""

from __future__ import annotations

from tt_mujoco.reference.paths import Pose
from tt_mujoco.reference.targets import Target

__all__ = ["ReverseTarget", "reverse_targets_of"]


def reverse_targets_of(kappa: float, rate: float, v: float, v_ref: float, a_ref: float):
    """``(v_d, omega_d, v_d_dot, omega_d_dot)`` reversing at speed ``v`` (<= 0) where the path
    has curvature ``kappa`` and rate ``dkappa/ds``: d/dt kappa(s_path) v = kappa' v^2 + kappa
    v_dot, with v_dot ~ -a_ref (the compiled episode shares it)."""
    return -v_ref, kappa * v, -a_ref, rate * v * v - kappa * a_ref


class ReverseTarget(Target):
    """Drive a target's path backwards: from where the forward run would end, back to its start.

    The tractor faces along the path and reverses (v < 0), so the trailer leads. The kinematics
    are those of the forward targets with the sign of v: the path's arc length runs as
    ``s_path = s_end + int v dt``, and ``omega = kappa(s_path) v`` keeps P on the path (heading
    along the path's tangent, moving backwards). For a dynamic target (paper eq. 33) s_path
    integrates the measured v; for a static one (eq. 32) ``s_path = s_end - s_ref(t)``.
    ``v_d = -v_ref(t)``.

    Parameters
    ----------
    target : tt_mujoco.reference.targets.Target
        The forward target (its path, speed profile, kind and duration are reused).
    stop_s : float
        Where on the path the run stops backing (m): the profile's distance is driven back to
        it from ``s_end``. 0: the path's start (a planned leg into a short bay stops beyond it,
        :attr:`tt_mujoco.world.plan.Leg.stop_s`).
    """

    def __init__(self, target, stop_s: float = 0.0):
        self.forward = target
        self.kind = target.kind
        travel = target.profile.distance(target.duration)
        self.s_end = min(target.path.length, stop_s + travel)
        super().__init__(target.path, target.profile, target.duration)

    @property
    def initial_pose(self):
        """Start pose: the path at ``s_end``, heading along the path (the vehicle backs up)."""
        return Pose(*self.path.pose_at(self.s_end))

    @property
    def start_s(self) -> float:
        """Backing up, a run starts at the path's far end, ``s_end``."""
        return self.s_end

    def reference_speed(self, t):
        return -self.forward.reference_speed(t)

    def reference_yaw_rate(self, t):
        s_ref, v_ref = self.profile.distance(t), self.profile.speed(t)
        return self.path.curvature(self.s_end - s_ref) * -v_ref

    def reference_pose(self, t):
        """Pose of the path where P should be at time t, reversing on schedule: the heading is
        the path's tangent, which the tractor faces while backing up (float or array t)."""
        if isinstance(t, float | int):
            return self.path.pose_at(self.s_end - self._profile_state(float(t))[0])
        return self.path.pose(self.s_end - self.profile.distance(t))

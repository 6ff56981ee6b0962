"""Paths, a metric and a disturbance given in code, for ``--traj``, ``--metric`` and
``--disturbance-model`` (see the README).

    python -m tt_mujoco.run --traj examples/user_parts.py:lane_change \
        --path-option width=0.8 --metric examples/user_parts.py:final_position_error \
        --disturbance-model examples/user_parts.py:headwind_gusts
    python -m tt_mujoco.run --traj examples/user_parts.py:slalom --path-option k_max=0.4
"""

import math

import numpy as np

from tt_mujoco.reference.path_base import ReferencePath
from tt_mujoco.reference.paths import from_waypoints


def lane_change(width: float = 0.5, length: float = 6.0):
    """A smooth lane change of ``width`` metres over ``length`` metres, as a fitted path."""
    x = np.linspace(0.0, length, 25)
    y = width / (1.0 + np.exp(-(x - length / 2.0) * 8.0 / length))
    return from_waypoints(x, y, name=f"lane_change_{width:g}")


class Slalom(ReferencePath):
    """A path given by its own formulas, which the loop calls back at every step: curvature
    ``kappa(s) = k_max sin(2 pi s / period)``, so heading ``k_max / w (1 - cos(w s))`` with
    ``w = 2 pi / period``, and a pose integrated once on a 1 mm grid (trapezoids)."""

    def __init__(self, k_max: float = 0.5, period: float = 6.0, length: float = 12.0):
        super().__init__("slalom", length)
        self.k_max, self.w = float(k_max), 2.0 * math.pi / float(period)
        s = np.linspace(0.0, self.length, int(round(self.length / 0.001)) + 1)
        heading = self._heading(s)

        def integrated(f):
            return np.concatenate([[0.0], np.cumsum(np.diff(s) * 0.5 * (f[1:] + f[:-1]))])

        self._grid = (s, integrated(np.cos(heading)), integrated(np.sin(heading)))

    def _heading(self, s):
        return self.k_max / self.w * (1.0 - np.cos(self.w * s))

    def _pose(self, s):
        grid, x, y = self._grid
        return np.interp(s, grid, x), np.interp(s, grid, y), self._heading(s)

    def _pose_at(self, s):
        return tuple(float(q) for q in self._pose(np.float64(s)))

    def _curvature(self, s):
        return self.k_max * np.sin(self.w * s)

    def _curvature_rate(self, s):
        return self.k_max * self.w * np.cos(self.w * s)

    def curvature_and_rate(self, s):
        clipped = min(max(s, 0.0), self.length)  # held beyond the ends, with no rate
        rate = self.k_max * self.w * math.cos(self.w * clipped) if clipped == s else 0.0
        return self.k_max * math.sin(self.w * clipped), rate


def slalom(k_max: float = 0.5, period: float = 6.0, length: float = 12.0):
    """:class:`Slalom`, for ``--traj examples/user_parts.py:slalom``."""
    return Slalom(k_max, period, length)


def final_position_error(timeseries, path):
    """Distance (m) from the tractor's final position to the path's end."""
    x_end, y_end, _ = path.pose_at(path.length)
    return math.hypot(timeseries["x"][-1] - x_end, timeseries["y"][-1] - y_end)


def headwind_gusts(t):
    """A disturbance ``t -> (a_v, a_omega)``: a steady 1 m/s^2 headwind with a 0.5 Hz gust."""
    return -1.0 - 0.5 * math.sin(math.pi * t), 0.0

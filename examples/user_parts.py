"""A path, a metric and a disturbance given in code, for ``--traj``, ``--metric`` and
``--disturbance-model`` (see the README).

    python -m tt_mujoco.run --traj examples/user_parts.py:lane_change \
        --path-option width=0.8 --metric examples/user_parts.py:final_position_error \
        --disturbance-model examples/user_parts.py:headwind_gusts
"""

import math

import numpy as np

from tt_mujoco.reference.paths import from_waypoints


def lane_change(width: float = 0.5, length: float = 6.0):
    """A smooth lane change of ``width`` metres over ``length`` metres, as a fitted path."""
    x = np.linspace(0.0, length, 25)
    y = width / (1.0 + np.exp(-(x - length / 2.0) * 8.0 / length))
    return from_waypoints(x, y, name=f"lane_change_{width:g}")


def final_position_error(timeseries, path):
    """Distance (m) from the tractor's final position to the path's end."""
    x_end, y_end, _ = path.pose_at(path.length)
    return math.hypot(timeseries["x"][-1] - x_end, timeseries["y"][-1] - y_end)


def headwind_gusts(t):
    """A disturbance ``t -> (a_v, a_omega)``: a steady 1 m/s^2 headwind with a 0.5 Hz gust."""
    return -1.0 - 0.5 * math.sin(math.pi * t), 0.0

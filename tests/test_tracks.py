import numpy as np

from tt_mujoco.analysis.geometry import Polyline
from tt_mujoco.analysis.metrics import follower_offtrack
from tt_mujoco.analysis.tracks import MIN_SEGMENT, moves, new_vertices


def test_points_within_the_minimum_segment_are_one_vertex():
    points = np.array([[0.0, 0.0], [1e-170, 0.0], [1.0, 0.0], [1.0, 0.5 * MIN_SEGMENT]])
    assert new_vertices(points).tolist() == [True, False, True, False]
    line = Polyline(points)
    assert line.vertices.tolist() == [[0.0, 0.0], [1.0, 0.0]]
    assert np.all(np.isfinite(line.project(np.array([[0.5, 0.2]])).distance))


def test_a_track_that_drifts_by_less_than_a_segment_does_not_move():
    # Before: a tractor drifting by 1e-170 m was taken to have moved, and the polyline of its
    # driven path divided by its squared length, 0 (a reduced-plant run with Ird = 1e8).
    standing = np.zeros((21, 2))
    standing[1:, 0] = 1e-170
    assert not moves(standing)
    assert moves(np.array([[0.0, 0.0], [0.0, 1e-6]]))
    ts = {
        "x": standing[:, 0],
        "y": standing[:, 1],
        "x0": standing[:, 0] - 0.7,
        "y0": standing[:, 1],
    }
    assert np.all(np.isnan(follower_offtrack(ts)))

"""tt_mujoco.viz.scene: the drawn lines' simplification."""

from __future__ import annotations

import numpy as np
import pytest

from tt_mujoco.viz.scene import simplified


def _distance_to_polyline(points: np.ndarray, line: np.ndarray) -> np.ndarray:
    """Each point's distance to the nearest segment of ``line``."""
    a, b = line[:-1], line[1:]
    d = b - a
    q = points[:, None, :] - a[None]
    t = np.clip(np.einsum("psk,sk->ps", q, d) / np.einsum("sk,sk->s", d, d), 0.0, 1.0)
    return np.linalg.norm(q - t[..., None] * d[None], axis=2).min(axis=1)


@pytest.mark.parametrize("tolerance", [1e-3, 1e-2])
def test_an_arc_keeps_every_point_within_the_tolerance_with_chords_near_the_sagitta_bound(
    tolerance,
):
    R, turn = 1.5, np.pi
    angles = np.linspace(0.0, turn, 2001)
    arc = R * np.column_stack([np.cos(angles), np.sin(angles)])
    kept = simplified(arc, tolerance)
    assert kept[0] == 0 and kept[-1] == len(arc) - 1
    assert _distance_to_polyline(arc, arc[kept]).max() <= tolerance
    # A chord c is c^2 / (8 R) off the arc at its middle: the fewest chords within the
    # tolerance are R turn / sqrt(8 R tolerance); bisection keeps at most twice as many.
    fewest = R * turn / np.sqrt(8.0 * R * tolerance)
    assert fewest <= len(kept) - 1 <= 2.0 * fewest


def test_a_straight_line_keeps_its_ends_and_a_reversal_keeps_its_turning_point():
    line = np.column_stack([np.linspace(0.0, 1.0, 50), np.zeros(50)])
    assert simplified(line, 1e-6).tolist() == [0, 49]
    # out and back along the same line: the turning point is on the chord's line, not on it
    back = np.vstack([line, line[-2::-1]])
    assert simplified(back, 1e-6).tolist() == [0, 49, 98]


def test_repeated_points_and_short_lines_are_kept_whole():
    assert simplified(np.zeros((5, 2)), 1e-3).tolist() == [0, 4]
    assert simplified(np.array([[0.0, 0.0], [1.0, 0.0]]), 1e-3).tolist() == [0, 1]
    assert simplified(np.array([[0.0, 0.0]]), 1e-3).tolist() == [0]

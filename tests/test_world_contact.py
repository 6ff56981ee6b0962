"""The contact check's geometry (tt_mujoco.world.contact) against brute force: the signed gap
between convex polygons, a unit's corners, and the least clearance over units and obstacles."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tt_mujoco.world import contact
from tt_mujoco.world.world import convex_ccw


def _polygon(rng, centre, size) -> np.ndarray:
    """A random convex polygon: 3-7 points on an ellipse, counter-clockwise."""
    angles = np.sort(rng.uniform(0, 2 * np.pi, rng.integers(3, 8)))
    if np.max(np.diff(np.r_[angles, angles[0] + 2 * np.pi])) > np.pi * 0.95:
        angles = np.linspace(0, 2 * np.pi, 5, endpoint=False) + angles[0]
    pts = np.c_[size[0] * np.cos(angles), size[1] * np.sin(angles)] + centre
    return convex_ccw(pts, "test polygon")


def _inside(poly, points) -> np.ndarray:
    """Whether each point is inside the counter-clockwise convex polygon."""
    edges = np.roll(poly, -1, axis=0) - poly
    rel = points[:, None, :] - poly[None, :, :]
    cross = edges[None, :, 0] * rel[..., 1] - edges[None, :, 1] * rel[..., 0]
    return np.all(cross >= 0, axis=1)


def _boundary(poly, per_edge=150) -> np.ndarray:
    u = np.linspace(0, 1, per_edge, endpoint=False)[:, None]
    nxt = np.roll(poly, -1, axis=0)
    return np.concatenate([a + u * (b - a) for a, b in zip(poly, nxt, strict=True)])


def _brute_gap(a, b) -> tuple[float, bool]:
    """The least distance between the boundaries' dense samplings, and whether they overlap."""
    pa, pb = _boundary(a), _boundary(b)
    overlap = bool(_inside(b, pa).any() or _inside(a, pb).any())
    return float(np.min(np.linalg.norm(pa[:, None, :] - pb[None, :, :], axis=2))), overlap


@settings(max_examples=150, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), dx=st.floats(-3, 3), dy=st.floats(-3, 3))
def test_gap_is_the_distance_apart_and_negative_on_overlap(seed, dx, dy):
    rng = np.random.default_rng(seed)
    a = _polygon(rng, (0.0, 0.0), rng.uniform(0.2, 1.0, 2))
    b = _polygon(rng, (dx, dy), rng.uniform(0.2, 1.0, 2))
    gap = contact.gap_of(a, len(a), b, len(b))
    brute, overlap = _brute_gap(a, b)
    if overlap:
        assert gap <= 0.0
        return
    assert gap > -1e-12
    # The samplings' least distance exceeds the true one by at most half a sampling step on
    # each polygon (edges under 2.1 m, 150 samples each: 7 mm each).
    assert gap <= brute + 1e-12
    assert brute - gap < 0.015


def test_gap_of_two_squares_is_exact():
    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    for shift, expected in (((1.5, 0.0), 0.5), ((1.0, 0.0), 0.0), ((2.0, 2.0), math.sqrt(2))):
        moved = square + shift
        assert contact.gap_of(square, 4, moved, 4) == pytest.approx(expected, abs=1e-15)
    # overlapping by 0.25 along x: minus the least depth along an edge normal
    assert contact.gap_of(square, 4, square + np.array([0.75, 0.1]), 4) == pytest.approx(-0.25)


@pytest.mark.parametrize("heading", [0.0, 0.3, -2.0, math.pi])
def test_unit_corners_are_the_box_turned_about_the_axle(heading):
    out = np.zeros((4, 2))
    contact.unit_corners_of(1.0, -2.0, heading, (-0.3, 0.225, 0.12), out)
    c, s = math.cos(heading), math.sin(heading)
    local = np.array([[0.225, -0.12], [0.225, 0.12], [-0.3, 0.12], [-0.3, -0.12]])
    expected = local @ np.array([[c, s], [-s, c]]) + (1.0, -2.0)
    np.testing.assert_allclose(out, expected, atol=1e-15)
    x, y = out.T
    assert 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y) > 0  # counter-clockwise


def _obstacles(rng, count: int, spread: float):
    """``count`` random convex polygons within ``spread`` of the origin, and their arrays as
    the step takes them: corners, sizes, enclosing circles."""
    polygons = [
        _polygon(rng, rng.uniform(-spread, spread, 2), rng.uniform(0.2, 0.6, 2))
        for _ in range(count)
    ]
    table = np.zeros((count, 7, 2))
    circles = np.zeros((count, 3))
    for o, poly in enumerate(polygons):
        table[o, : len(poly)] = poly
        centre = poly.mean(axis=0)
        circles[o] = (*centre, np.max(np.hypot(*(poly - centre).T)))
    return polygons, table, np.array([len(p) for p in polygons], dtype=np.int64), circles


def test_clearance_is_the_least_gap_over_units_and_obstacles():
    rng = np.random.default_rng(7)
    polygons, table, sizes, circles = _obstacles(rng, 9, 4.0)
    boxes = np.array([[-0.3, 0.225, 0.12], [-0.12, 0.4, 0.12]])
    for _ in range(50):
        poses = np.c_[rng.uniform(-4, 4, (2, 2)), rng.uniform(-np.pi, np.pi, 2)]
        got = contact.clearance_of(poses, boxes, table, sizes, circles, np.zeros((4, 2)))
        gaps = []
        for u in range(2):
            corners = np.zeros((4, 2))
            contact.unit_corners_of(*poses[u], boxes[u], corners)
            gaps += [(contact.gap_of(corners, 4, p, len(p)), u, o) for o, p in enumerate(polygons)]
        assert got == min(gaps)


def test_a_capped_clearance_is_the_least_of_the_cap_and_the_clearance():
    rng = np.random.default_rng(11)
    _, table, sizes, circles = _obstacles(rng, 6, 3.0)
    boxes = np.array([[-0.3, 0.225, 0.12]])
    for _ in range(100):
        poses = np.array([[*rng.uniform(-3, 3, 2), rng.uniform(-np.pi, np.pi)]])
        exact, *_ = contact.clearance_of(poses, boxes, table, sizes, circles, np.zeros((4, 2)))
        for cap in (0.05, 0.5):
            capped, unit, _ = contact.clearance_of(
                poses, boxes, table, sizes, circles, np.zeros((4, 2)), cap
            )
            assert capped == pytest.approx(min(exact, cap), abs=1e-12)
            assert (unit == -1) == (exact >= cap)

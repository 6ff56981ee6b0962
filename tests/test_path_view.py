"""The path and the vehicle as a plain-number law sees them (controllers/path_view.py): the
table against the path's own formulas, the nearest point against a brute-force search, and the
compiled functions against their Python text, bit for bit."""

from __future__ import annotations

import math

import numpy as np
import pytest
from tt_mujoco.controllers import path_view
from tt_mujoco.controllers.path_view import path_nearest, path_pose_at, path_table

from tt_mujoco.reference.paths import get_path
from tt_mujoco.sim import Scenario

PATHS = ("s_curve", "circle", "cycloid")


@pytest.fixture(scope="module", params=PATHS)
def path(request):
    return get_path(request.param)


def test_the_table_holds_the_paths_pose_and_curvature(path):
    table = path_table(path)
    assert table.shape[0] == len(path_view.PATH_ROWS)
    assert table[0, 0] == 0.0 and table[0, -1] == pytest.approx(path.length, abs=1e-12)
    spacing = np.diff(table[0])
    assert np.all(spacing <= path_view.PATH_SPACING + 1e-12)
    x, _, theta = path.pose(table[0])
    np.testing.assert_allclose(table[1], x, atol=1e-12)
    np.testing.assert_allclose(np.cos(table[3]), np.cos(theta), atol=1e-12)
    np.testing.assert_allclose(table[4], path.curvature(table[0]), atol=1e-12)


def test_the_pose_between_samples_is_within_the_chords_sagitta(path):
    # Linear between samples 5 mm apart: the position strays from the arc by at most the
    # sagitta kappa ds^2 / 8; the heading by kappa ds / 2 (and the curvature's own change).
    table = path_table(path)
    rng = np.random.default_rng(0)
    s = rng.uniform(0.0, path.length, 400)
    kappa_max = float(np.max(np.abs(table[4])))
    ds = path_view.PATH_SPACING
    x, y, theta = path.pose(s)
    for k in range(s.size):
        px, py, ptheta, _ = path_pose_at(table, s[k])
        assert math.hypot(px - x[k], py - y[k]) <= kappa_max * ds * ds / 8.0 + 1e-12
        assert abs(math.remainder(ptheta - theta[k], 2 * math.pi)) <= kappa_max * ds + 1e-9
    # held at the ends beyond them
    assert path_pose_at(table, -1.0)[:2] == path_pose_at(table, 0.0)[:2]
    assert path_pose_at(table, path.length + 1.0)[:2] == path_pose_at(table, path.length)[:2]


def _brute_nearest(table, px, py):
    ax, ay = table[1, :-1], table[2, :-1]
    dx, dy = table[5, :-1], table[6, :-1]
    t = np.clip(((px - ax) * dx + (py - ay) * dy) * table[7, :-1], 0.0, 1.0)
    d2 = (px - ax - t * dx) ** 2 + (py - ay - t * dy) ** 2
    k = int(np.argmin(d2))
    return table[0, k] + t[k] * (table[0, 1] - table[0, 0]), math.sqrt(d2[k])


def test_the_nearest_point_is_the_brute_force_one_and_its_side_is_signed(path):
    table = path_table(path)
    rng = np.random.default_rng(1)
    for _ in range(60):
        s_true = rng.uniform(0.2, path.length - 0.2)
        x, y, theta, _ = path_pose_at(table, s_true)
        offset = rng.uniform(-0.15, 0.15)
        px, py = x - offset * math.sin(theta), y + offset * math.cos(theta)
        s, _, _, _, _, lateral = path_nearest(table, px, py, 0.0, 0.0)
        s_brute, distance = _brute_nearest(table, px, py)
        assert s == pytest.approx(s_brute, abs=1e-12)
        # the side is taken across the interpolated heading, which turns from the segment's
        # by at most kappa ds / 2: |lateral| = distance cos(that), to (kappa ds)^2 / 8
        kappa_ds = float(np.max(np.abs(table[4]))) * path_view.PATH_SPACING
        assert abs(lateral) == pytest.approx(distance, abs=distance * kappa_ds**2 / 8 + 1e-12)
        # a point put beside the path on its left is to the left (where no other part of the
        # path is nearer)
        if abs(s - s_true) < 1e-6:
            assert lateral == pytest.approx(offset, abs=1e-6)
        # searched around a nearby s, the same point
        windowed = path_nearest(table, px, py, s + 0.03, 0.1)
        assert windowed[0] == pytest.approx(s, abs=1e-12)


def test_a_window_keeps_the_lap_it_is_on():
    # a circle of two laps passes every point twice: a window around each lap finds its own
    table = path_table(get_path("circle", length=4 * math.pi))
    x, y, _, _ = path_pose_at(table, 1.0)
    x, y = 1.05 * x, 1.05 * y  # 5 cm off the path
    assert path_nearest(table, x, y, 1.05, 0.2)[0] == pytest.approx(1.0, abs=1e-3)
    lap_two = path_nearest(table, x, y, 2 * math.pi + 1.05, 0.2)[0]
    assert lap_two == pytest.approx(2 * math.pi + 1.0, abs=1e-3)


def test_the_compiled_functions_give_the_python_numbers_bit_for_bit(path):
    from numba import njit

    from tt_mujoco.sim.loop import compiled

    compiled.kernel()  # registers the law library with numba
    table = path_table(path)
    pose, nearest = (
        njit(lambda t, s: path_pose_at(t, s)),
        njit(lambda t, x, y, s, r: path_nearest(t, x, y, s, r)),
    )
    rng = np.random.default_rng(2)
    for _ in range(50):
        s = rng.uniform(-0.5, path.length + 0.5)
        assert pose(table, s) == path_pose_at(table, s)
        x, y = rng.uniform(-3, 3, 2)
        reach = float(rng.choice([0.0, 0.3]))
        assert nearest(table, x, y, s, reach) == path_nearest(table, x, y, s, reach)


def test_the_vehicle_record_names_the_nominal_vehicle_and_the_direction():
    one = Scenario(reverse=True).nominal_params()
    values = dict(zip(path_view.VEHICLE_FIELDS, path_view.vehicle_values(one, True), strict=True))
    assert (values["L"], values["L0"], values["eta"]) == (one.L, one.L0, one.eta)
    assert values["direction"] == -1.0 and values["n_trailers"] == 1.0
    three = Scenario(trailers=3).nominal_params()
    values = dict(
        zip(path_view.VEHICLE_FIELDS, path_view.vehicle_values(three, False), strict=True)
    )
    assert values["eta_last"] == three.etas[-1] and values["n_trailers"] == 3.0
    assert values["direction"] == 1.0

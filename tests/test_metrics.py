"""Metrics on hand-made time series with known answers (docs/model.md §11)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from matplotlib.path import Path

from tt_mujoco.analysis.metrics import (
    REQUIRED_COLUMNS,
    Polyline,
    compute_metrics,
    distance_to_polyline,
    max_abs,
    metric_unit,
    rmse,
    run_error_signals,
    signed_lateral_error,
    summary_table,
    trailer_offtrack,
)

# Every quantity below is computed by a few floating-point operations on numbers of order 1, so
# "exact" answers are checked to 1e-12 (measured errors are below 1e-14).
EXACT = 1e-12
TORQUE_LIMIT = 15.0


def make_series(n: int, dt: float = 0.01, **columns) -> dict[str, np.ndarray]:
    """All required columns and the reference heading: t = k dt, zeros elsewhere (a reference
    heading of 0: along +x), then the given overrides."""
    ts = {name: np.zeros(n) for name in (*REQUIRED_COLUMNS, "theta_ref")}
    ts["t"] = np.arange(n) * dt
    for name, value in columns.items():
        ts[name] = np.asarray(value, dtype=float)
    return ts


def straight_run(n: int = 501, offset: float = 0.1, trailer_offset: float = 0.0) -> dict:
    """Tractor along y = offset from x = 0 to 10; trailer 0.7 m behind, at y = trailer_offset."""
    x = np.linspace(0.0, 10.0, n)
    return make_series(
        n,
        x=x,
        y=np.full(n, offset),
        x_ref=x,
        y_ref=np.zeros(n),
        x0=x - 0.7,
        y0=np.full(n, trailer_offset),
    )


STRAIGHT_REFERENCE = np.column_stack([np.linspace(-1.0, 11.0, 61), np.zeros(61)])


def brute_force_distance(points, vertices, extend_ends=False):
    """Distance to every segment, minimum taken: the O(N M) reference."""
    a = vertices[:-1]
    d = vertices[1:] - a
    rel = points[:, None, :] - a
    t = np.einsum("ijk,jk->ij", rel, d) / np.einsum("jk,jk->j", d, d)
    lower = np.zeros(len(a))
    upper = np.ones(len(a))
    if extend_ends:
        lower[0], upper[-1] = -np.inf, np.inf
    t = np.clip(t, lower, upper)
    off = rel - t[..., None] * d
    return np.sqrt(np.einsum("ijk,ijk->ij", off, off).min(axis=1))


# ---------------------------------------------------------------------------------------------
# Helpers


def test_rmse_and_max_abs():
    assert rmse([3.0, -4.0]) == pytest.approx(math.sqrt(12.5), abs=EXACT)
    assert max_abs([-3.0, 2.0]) == 3.0
    assert math.isnan(rmse([])) and math.isnan(max_abs([]))
    assert math.isnan(rmse([1.0, math.nan]))


# ---------------------------------------------------------------------------------------------
# Lateral and position errors


def test_straight_offset_gives_exact_lateral_error():
    m = compute_metrics(straight_run(offset=0.1), STRAIGHT_REFERENCE, TORQUE_LIMIT)
    assert m["rmse_lateral"] == pytest.approx(0.1, abs=EXACT)
    assert m["max_lateral"] == pytest.approx(0.1, abs=EXACT)
    # The reference point is the foot of P: position error = lateral error here.
    assert m["rmse_position"] == pytest.approx(0.1, abs=EXACT)
    assert m["max_position"] == pytest.approx(0.1, abs=EXACT)
    # The trailer runs on the reference line itself.
    assert m["trailer_rmse_lateral"] == pytest.approx(0.0, abs=EXACT)
    assert m["trailer_max_lateral"] == pytest.approx(0.0, abs=EXACT)


def test_trailer_lateral_skips_samples_behind_the_path_start():
    # Reference from x = 0; the trailer, 0.7 m behind the tractor and 2 cm to the side, starts
    # behind it. Those samples are 0.7 m from the start point, not 0.7 m off the path.
    ts = straight_run(offset=0.0, trailer_offset=0.02)
    reference = np.column_stack([np.linspace(0.0, 11.0, 56), np.zeros(56)])
    m = compute_metrics(ts, reference, TORQUE_LIMIT)
    assert m["trailer_rmse_lateral"] == pytest.approx(0.02, abs=EXACT)
    assert m["trailer_max_lateral"] == pytest.approx(0.02, abs=EXACT)
    assert m["trailer_lateral_samples"] == np.count_nonzero(ts["x0"] > 0.0)
    # The tractor's own lateral error is literal: it starts on the path's first point.
    assert m["max_lateral"] == pytest.approx(0.0, abs=EXACT)
    signed, _ = signed_lateral_error(
        np.column_stack([ts["x0"], ts["y0"]]), reference, interior_only=True
    )
    assert np.all(np.isnan(signed[ts["x0"] <= 0.0]))
    np.testing.assert_allclose(signed[ts["x0"] > 0.0], 0.02, atol=EXACT)


def test_position_error_is_distance_to_reference_point():
    ts = straight_run(offset=0.0)
    ts["x_ref"] = ts["x"] + 0.03  # the tractor lags 3 cm behind its reference point
    ts["y_ref"] = np.full_like(ts["x"], 0.04)
    m = compute_metrics(ts, STRAIGHT_REFERENCE, TORQUE_LIMIT)
    assert m["rmse_position"] == pytest.approx(0.05, abs=EXACT)
    assert m["rmse_lateral"] == pytest.approx(0.0, abs=EXACT)


def test_circle_lateral_error_within_chord_error():
    n_vertices = 200
    radius, tractor_radius = 1.0, 1.05
    angles = np.linspace(0.0, 2.0 * np.pi, n_vertices + 1)
    reference = radius * np.column_stack([np.cos(angles), np.sin(angles)])
    # The polygon lies inside the unit circle (distance >= 0.05) and contains the circle of
    # radius R cos(pi/n): distance <= 0.05 + sagitta. Both bounds are attained.
    sagitta = radius * (1.0 - math.cos(math.pi / n_vertices))
    n = 400  # even samples sit on the vertices, odd ones on the chord midpoints
    theta = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    ts = make_series(
        n,
        x=tractor_radius * np.cos(theta),
        y=tractor_radius * np.sin(theta),
        x_ref=radius * np.cos(theta),
        y_ref=radius * np.sin(theta),
        x0=np.cos(theta),
        y0=np.sin(theta),
    )
    m = compute_metrics(ts, reference, TORQUE_LIMIT)
    assert 0.05 - EXACT <= m["rmse_lateral"] <= 0.05 + sagitta + EXACT
    assert 0.05 - EXACT <= m["max_lateral"] <= 0.05 + sagitta + EXACT
    # The samples on chord midpoints attain the upper bound, the others the lower one.
    assert m["max_lateral"] == pytest.approx(0.05 + sagitta, abs=EXACT)
    assert m["rmse_lateral"] < 0.05 + sagitta - 0.1 * sagitta
    d = distance_to_polyline(np.column_stack([ts["x"], ts["y"]]), reference)
    assert d.min() == pytest.approx(0.05, abs=EXACT)  # at the vertices


# ---------------------------------------------------------------------------------------------
# Velocity errors, saturation, diagnostics


def test_sinusoidal_velocity_errors_have_known_rms():
    n, dt = 400, 0.01  # four whole periods of 1 s, 100 samples each
    t = np.arange(n) * dt
    amp_v, amp_w = 0.3, 0.2
    ts = make_series(
        n,
        dt=dt,
        v=0.8 + amp_v * np.sin(2 * np.pi * t),
        v_d=np.full(n, 0.8),
        omega=0.5 + amp_w * np.cos(2 * np.pi * t),
        omega_d=np.full(n, 0.5),
        v_meas=np.full(n, 99.0),  # measured speeds must not enter the errors
    )
    m = compute_metrics(ts, STRAIGHT_REFERENCE, TORQUE_LIMIT)
    # Over whole periods the mean of sin^2 sampled uniformly is exactly 1/2.
    assert m["rmse_v"] == pytest.approx(amp_v / math.sqrt(2), abs=EXACT)
    assert m["rmse_omega"] == pytest.approx(amp_w / math.sqrt(2), abs=EXACT)
    # The samples hit the peaks (k = 25 and k = 0).
    assert m["max_abs_v"] == pytest.approx(amp_v, abs=EXACT)
    assert m["max_abs_omega"] == pytest.approx(amp_w, abs=EXACT)
    assert m["steps"] == n and m["finite_samples"] == n
    assert m["sample_period_s"] == pytest.approx(dt, abs=EXACT)
    assert m["sim_time_s"] == pytest.approx(4.0, abs=EXACT)


def test_torque_saturation_fraction_counts_samples_once():
    n = 200
    t_r = np.ones(n)
    t_l = np.ones(n)
    t_r[0:30] = TORQUE_LIMIT  # clipped to exactly the limit: saturated
    t_r[30:40] = -20.0  # beyond the limit, negative: saturated
    t_r[40:50] = TORQUE_LIMIT * (1 - 1e-6)  # just inside: not saturated
    t_l[20:40] = 16.0  # overlaps the T_r samples: counted once
    t_l[150:160] = -15.5
    ts = make_series(n, T_r_cmd=t_r, T_l_cmd=t_l, T_r=np.clip(t_r, -15, 15))
    m = compute_metrics(ts, STRAIGHT_REFERENCE, TORQUE_LIMIT)
    assert m["torque_saturation_fraction"] == 50 / 200


def test_diagnostic_maxima():
    n = 100
    ts = make_series(
        n,
        phi=np.linspace(-0.1, 0.2, n),
        eq_violation=np.r_[np.zeros(n - 1), -3e-5],
        slip_lateral=np.r_[0.01, np.zeros(n - 1)],
        slip_lateral_trailer=np.r_[np.zeros(n - 1), -0.02],
        slip_left=np.r_[0.5, np.zeros(n - 1)],
        slip_right=np.r_[-0.7, np.zeros(n - 1)],
    )
    m = compute_metrics(ts, STRAIGHT_REFERENCE, TORQUE_LIMIT)
    assert m["eq_violation_max"] == 3e-5
    assert m["slip_lateral_max"] == 0.02
    assert m["slip_longitudinal_max"] == 0.7
    assert m["phi_max_abs_deg"] == pytest.approx(math.degrees(0.2), abs=EXACT)


# ---------------------------------------------------------------------------------------------
# Trailer off-tracking


def test_offtracking_zero_when_trailer_runs_on_tractor_path():
    # A straight drive at heading 30 deg, trailer 0.7 m behind on the same line.
    n = 400
    heading = np.array([math.cos(math.pi / 6), math.sin(math.pi / 6)])
    s = np.linspace(0.0, 6.0, n)
    p = s[:, None] * heading
    p0 = (s - 0.7)[:, None] * heading
    ts = make_series(n, x=p[:, 0], y=p[:, 1], x0=p0[:, 0], y0=p0[:, 1], x_ref=p[:, 0])
    m = compute_metrics(ts, p[[0, -1]], TORQUE_LIMIT)
    assert m["trailer_offtrack_rms"] == pytest.approx(0.0, abs=EXACT)
    assert m["trailer_offtrack_max"] == pytest.approx(0.0, abs=EXACT)
    # Only samples where P0 has passed P's starting point count (s - 0.7 > 0).
    assert m["trailer_offtrack_samples"] == np.count_nonzero(s - 0.7 > 0) == 353


def test_offtracking_known_offset_on_straight():
    ts = straight_run(offset=0.0, trailer_offset=0.03)
    m = compute_metrics(ts, STRAIGHT_REFERENCE, TORQUE_LIMIT)
    assert m["trailer_offtrack_rms"] == pytest.approx(0.03, abs=EXACT)
    assert m["trailer_offtrack_max"] == pytest.approx(0.03, abs=EXACT)
    assert m["trailer_offtrack_samples"] == np.count_nonzero(ts["x0"] > 0.0)
    # Before P0 passes the start, its distance to the start point is along-track spacing
    # (up to 0.7 m), which must not leak into the off-tracking.
    off = trailer_offtrack(
        np.column_stack([ts["x"], ts["y"]]), np.column_stack([ts["x0"], ts["y0"]])
    )
    assert np.all(np.isnan(off[ts["x0"] <= 0.0]))


def test_offtracking_on_circle_within_chord_error():
    # Tractor on R = 1 (counter-clockwise), trailer on R = 0.98, 0.7 rad behind: off-tracking
    # 0.02 m (inside). The tractor's path is the polygon of its samples, step h: for a point at
    # radius rho inside, the distance to a chord is R cos(h/2) - rho cos(delta), |delta| <= h/2,
    # so it lies in [0.02 - sagitta, 0.02 cos(h/2)], sagitta = R (1 - cos(h/2)).
    n = 600
    theta = np.linspace(0.0, 5.0, n)  # less than one lap: the path does not overlap itself
    step = theta[1] - theta[0]
    sagitta = 1.0 - math.cos(step / 2)
    ts = make_series(
        n,
        x=np.cos(theta),
        y=np.sin(theta),
        x0=0.98 * np.cos(theta - 0.7),
        y0=0.98 * np.sin(theta - 0.7),
    )
    m = compute_metrics(ts, np.column_stack([np.cos(theta), np.sin(theta)]), TORQUE_LIMIT)
    assert 0.02 - sagitta - EXACT <= m["trailer_offtrack_rms"] <= 0.02 * math.cos(step / 2) + EXACT
    assert 0.02 - sagitta - EXACT <= m["trailer_offtrack_max"] <= 0.02 * math.cos(step / 2) + EXACT
    assert m["trailer_offtrack_samples"] == np.count_nonzero(theta - 0.7 > 0)


def test_offtracking_ignores_path_the_tractor_drives_later():
    # Out along y = 0 to x = 4, a U-turn of radius 0.05, back along y = 0.1. During the outbound
    # leg the trailer runs on y = 0.1: on the tractor's *future* path, 0.1 m off its past path.
    out = np.column_stack([np.linspace(0.0, 4.0, 401), np.zeros(401)])
    a = np.linspace(-np.pi / 2, np.pi / 2, 31)[1:-1]
    turn = np.column_stack([4.0 + 0.05 * np.cos(a), 0.05 + 0.05 * np.sin(a)])
    back = np.column_stack([np.linspace(4.0, 0.0, 401), np.full(401, 0.1)])
    p = np.vstack([out, turn, back])
    p0 = p + np.array([-0.7, 0.1])  # only the outbound samples are checked
    off = trailer_offtrack(p, p0)
    outbound = off[:401]
    passed = outbound[~np.isnan(outbound)]
    assert passed.size == np.count_nonzero(out[:, 0] - 0.7 > 0)
    np.testing.assert_allclose(passed, 0.1, atol=EXACT)


def test_offtracking_undefined_when_reversing():
    # Reversing, the trailer leads: P0 is beyond the end of the path the tractor has driven, so
    # its distance to that path is along-track spacing, not off-tracking.
    x = np.linspace(0.0, -5.0, 300)
    p = np.column_stack([x, np.zeros(300)])
    off = trailer_offtrack(p, p + np.array([-0.7, 0.01]))
    assert np.all(np.isnan(off))


def test_offtracking_tractor_standing_still():
    p = np.zeros((10, 2))
    assert np.all(np.isnan(trailer_offtrack(p, p - [0.7, 0.0])))
    # A tractor that stands, then moves: the repeated start points are one vertex.
    p = np.vstack([np.zeros((20, 2)), np.column_stack([np.linspace(0.01, 2, 50), np.zeros(50)])])
    p0 = p + np.array([-0.7, 0.02])
    off = trailer_offtrack(p, p0)
    passed = off[~np.isnan(off)]
    np.testing.assert_allclose(passed, 0.02, atol=EXACT)
    assert passed.size == np.count_nonzero(p0[:, 0] > 0)


# ---------------------------------------------------------------------------------------------
# Non-finite data


def test_nan_truncated_series_uses_finite_prefix():
    n, k = 300, 180
    t = np.arange(n) * 0.01
    ts = make_series(
        n,
        x=np.linspace(0, 3, n),
        y=0.05 * np.sin(t),
        x_ref=np.linspace(0, 3, n),
        x0=np.linspace(-0.7, 2.3, n),
        v=0.1 * np.sin(3 * t),
        omega=0.2 * np.cos(t),
        T_r_cmd=np.where(t > 1.0, 20.0, 0.0),
        slip_left=0.01 * t,
    )
    ts["x"][k:] = np.nan
    ts["v"][k + 5 :] = np.inf
    ts["slip_left"][10] = np.nan  # a diagnostic NaN inside the prefix is skipped, not fatal
    m = compute_metrics(ts, STRAIGHT_REFERENCE, TORQUE_LIMIT)
    truncated = {name: col[:k] for name, col in ts.items()}
    expected = compute_metrics(truncated, STRAIGHT_REFERENCE, TORQUE_LIMIT)
    assert m["steps"] == n and expected["steps"] == k
    assert m["finite_samples"] == k
    for key, value in expected.items():
        if key != "steps":
            assert m[key] == value, key
    assert m["slip_longitudinal_max"] == pytest.approx(0.01 * t[k - 1], abs=EXACT)
    assert m["sim_time_s"] == pytest.approx(k * 0.01, abs=EXACT)


def test_all_nan_diagnostic_gives_nan_metric():
    ts = straight_run()
    ts["slip_left"][:] = np.nan
    ts["slip_right"][:] = np.nan
    m = compute_metrics(ts, STRAIGHT_REFERENCE, TORQUE_LIMIT)
    assert math.isnan(m["slip_longitudinal_max"])
    assert m["finite_samples"] == m["steps"]
    assert m["rmse_lateral"] == pytest.approx(0.1, abs=EXACT)


def test_run_diverged_at_first_sample():
    ts = straight_run(n=50)
    ts["y"][0] = np.nan
    m = compute_metrics(ts, STRAIGHT_REFERENCE, TORQUE_LIMIT)
    assert m["finite_samples"] == 0 and m["steps"] == 50
    assert m["sim_time_s"] == 0.0
    assert math.isnan(m["rmse_v"]) and math.isnan(m["max_lateral"])
    assert m["trailer_offtrack_samples"] == 0


# ---------------------------------------------------------------------------------------------
# Signed lateral error and exact projection


def test_signed_lateral_error_left_is_positive():
    path = np.column_stack([np.linspace(0.0, 10.0, 11), np.zeros(11)])
    points = np.array([[5.0, 0.2], [5.0, -0.2], [2.5, 0.0]])
    signed, arc = signed_lateral_error(points, path)
    np.testing.assert_allclose(signed, [0.2, -0.2, 0.0], atol=EXACT)
    np.testing.assert_allclose(arc, [5.0, 5.0, 2.5], atol=EXACT)
    # Driving the other way swaps the sides.
    signed_rev, arc_rev = signed_lateral_error(points, path[::-1])
    np.testing.assert_allclose(signed_rev, [-0.2, 0.2, 0.0], atol=EXACT)
    np.testing.assert_allclose(arc_rev, [5.0, 5.0, 7.5], atol=EXACT)
    # A single point gives scalars.
    s, a = signed_lateral_error([5.0, 0.2], path)
    assert np.ndim(s) == 0 and s == pytest.approx(0.2, abs=EXACT) and a == pytest.approx(5.0)


@pytest.mark.parametrize("orientation", [1, -1])
def test_signed_side_matches_inside_of_sharp_star(orientation):
    # A closed 7-pointed star with sharp spikes (hairpin vertices). For a counter-clockwise
    # outline the inside is on the left, so sign(signed distance) must equal inside/outside;
    # clockwise, the opposite. Points are sampled close to the vertices, where the side is
    # decided by the vertex tangent rule.
    k = np.arange(15)
    radius = np.where(k % 2 == 0, 1.0, 0.25)
    angle = orientation * 2 * np.pi * k / 14
    star = np.column_stack([radius * np.cos(angle), radius * np.sin(angle)])
    # Open and close the outline in the middle of an edge: the polyline's ends have no turn.
    middle = 0.5 * (star[0] + star[1])
    star = np.vstack([middle, star[1:], middle])
    rng = np.random.default_rng(3)
    near_vertices = star[rng.integers(0, 14, 3000)] + rng.normal(0.0, 0.02, (3000, 2))
    anywhere = rng.uniform(-1.3, 1.3, (3000, 2))
    points = np.vstack([near_vertices, anywhere])
    signed, _ = signed_lateral_error(points, star)
    inside = Path(star).contains_points(points)
    keep = np.abs(signed) > 1e-9  # the side of a point on the outline is not defined
    assert np.array_equal((signed[keep] > 0), inside[keep] == (orientation == 1))


def random_polylines(rng):
    """Paths that stress the search: sharp zigzags, random walks, mixed segment lengths."""
    yield np.column_stack([np.arange(300) * 0.01, (np.arange(300) % 2) * 0.4])  # zigzag
    yield np.cumsum(rng.normal(size=(500, 2)), axis=0)  # random walk, sharp turns
    a = np.sort(rng.uniform(0, 2 * np.pi, 200))
    ring = np.repeat(np.column_stack([np.cos(a), np.sin(a)]), rng.integers(1, 3, 200), axis=0)
    yield np.vstack([ring, [[5.0, 5.0]]])  # repeated vertices and one 6 m segment
    s = np.concatenate([np.linspace(0, 1, 400), 1 + np.cumsum(rng.uniform(0, 1e-6, 50))])
    yield np.column_stack([s, np.sin(3 * s)])  # a cluster of micro-segments at the end
    tau = np.linspace(np.pi / 4, np.pi / 4 + 1.5 * np.pi, 2001)
    yield np.column_stack([tau - np.sin(tau), 1 - np.cos(tau)])  # the cycloid


def test_projection_matches_brute_force():
    rng = np.random.default_rng(7)
    for vertices in random_polylines(rng):
        line = Polyline(vertices)
        scale = float(np.ptp(vertices, axis=0).max())
        # Near the vertices at scales from 1e-5 to 1 of the path size, and anywhere around it.
        spread = scale * 10.0 ** rng.uniform(-5, 0, (2000, 1))
        near = vertices[rng.integers(0, len(vertices), 2000)] + rng.normal(size=(2000, 2)) * spread
        around = rng.uniform(vertices.min(0) - scale, vertices.max(0) + scale, (500, 2))
        points = np.vstack([near, around])
        for extend_ends in (False, True):
            proj = line.project(points, extend_ends=extend_ends)
            expected = brute_force_distance(points, line.vertices, extend_ends)
            # Measured worst difference 4.5e-15 relative (rounding in the projection).
            np.testing.assert_allclose(proj.distance, expected, rtol=1e-12, atol=1e-14)
            # The foot is where the distance says, and at the stated arc length.
            np.testing.assert_allclose(
                np.hypot(*(points - proj.foot).T), proj.distance, rtol=1e-12, atol=1e-14
            )
            on_path = proj.arc_length.clip(0.0, line.length)
            foot_from_arc = np.column_stack(
                [
                    np.interp(on_path, line.arc_length, line.vertices[:, 0]),
                    np.interp(on_path, line.arc_length, line.vertices[:, 1]),
                ]
            )
            inside = (proj.arc_length >= 0) & (proj.arc_length <= line.length)
            np.testing.assert_allclose(foot_from_arc[inside], proj.foot[inside], atol=1e-9)


def test_projection_with_segment_count_matches_brute_force():
    rng = np.random.default_rng(11)
    vertices = np.cumsum(rng.normal(size=(400, 2)), axis=0)
    line = Polyline(vertices)
    points = vertices[rng.integers(0, 400, 1000)] + rng.normal(0.0, 0.3, (1000, 2))
    count = rng.integers(0, line.n_segments + 1, 1000)
    proj = line.project(points, segment_count=count)
    for i in range(0, 1000, 7):
        if count[i] == 0:
            expected = np.hypot(*(points[i] - vertices[0]))
        else:
            expected = brute_force_distance(points[i : i + 1], vertices[: count[i] + 1])[0]
        assert proj.distance[i] == pytest.approx(expected, rel=1e-12, abs=1e-14)


def test_extend_ends_measures_beyond_the_ends_perpendicular():
    path = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]])
    points = np.array([[3.0, 0.5], [-1.0, -0.2]])
    clamped = Polyline(path).project(points)
    np.testing.assert_allclose(clamped.distance, [math.hypot(1.0, 0.5), math.hypot(1.0, 0.2)])
    np.testing.assert_allclose(clamped.arc_length, [2.0, 0.0])
    signed, arc = signed_lateral_error(points, path, extend_ends=True)
    np.testing.assert_allclose(signed, [0.5, -0.2], atol=EXACT)
    np.testing.assert_allclose(arc, [3.0, -1.0], atol=EXACT)


def test_nonfinite_points_give_nan():
    proj = Polyline(STRAIGHT_REFERENCE).project(np.array([[1.0, 1.0], [np.nan, 0.0]]))
    assert proj.distance[0] == pytest.approx(1.0) and math.isnan(proj.distance[1])
    assert proj.segment[1] == -1


# ---------------------------------------------------------------------------------------------
# Input validation and the summary table


def test_bad_inputs_raise_value_error():
    ts = straight_run(n=20)
    ref = STRAIGHT_REFERENCE
    with pytest.raises(ValueError, match="eq_violation"):
        compute_metrics({k: v for k, v in ts.items() if k != "eq_violation"}, ref, 15.0)
    with pytest.raises(ValueError, match="length"):
        compute_metrics({**ts, "v": np.zeros(19)}, ref, 15.0)
    with pytest.raises(ValueError, match="1-D"):
        compute_metrics({**ts, "v": np.zeros((20, 2))}, ref, 15.0)
    with pytest.raises(ValueError, match="numeric"):
        compute_metrics({**ts, "v": ["a"] * 20}, ref, 15.0)
    for bad_limit in (0.0, -1.0, math.nan, math.inf, True, "15"):
        with pytest.raises(ValueError, match="torque_limit"):
            compute_metrics(ts, ref, bad_limit)
    with pytest.raises(ValueError, match="strictly increase"):
        compute_metrics({**ts, "t": np.r_[0.0, 0.0, np.arange(2, 20) * 0.01]}, ref, 15.0)
    with pytest.raises(ValueError, match="at least one sample"):
        compute_metrics({k: np.zeros(0) for k in ts}, ref, 15.0)
    with pytest.raises(ValueError, match="shape"):
        compute_metrics(ts, np.zeros((5, 3)), 15.0)
    with pytest.raises(ValueError, match="shape"):
        Polyline([[0.0, 0.0]])
    with pytest.raises(ValueError, match="distinct"):
        Polyline([[1.0, 2.0]] * 3)
    with pytest.raises(ValueError, match="finite"):
        Polyline([[0.0, 0.0], [np.nan, 1.0]])
    with pytest.raises(ValueError, match="points"):
        Polyline(ref).project(np.zeros((4, 3)))
    with pytest.raises(ValueError, match="segment_count"):
        Polyline(ref).project(np.zeros((2, 2)), segment_count=np.array([0, 99]))


def test_summary_table_is_aligned():
    metrics = {"rmse_v": 0.0147123456, "steps": 5000, "trailer_offtrack_rms": math.nan}
    text = summary_table(metrics, keys=("rmse_v", "steps", "trailer_offtrack_rms"))
    lines = text.splitlines()
    assert [line.split()[0] for line in lines] == ["rmse_v", "steps", "trailer_offtrack_rms"]
    assert [line.split()[1] for line in lines] == ["0.0147123", "5000", "nan"]
    assert [line.split()[2:] for line in lines] == [["m/s"], [], ["m"]]  # each metric's unit
    ends = {
        line.index(value) + len(value)
        for line, value in zip(lines, ("0.0147123", "5000", "nan"), strict=True)
    }
    assert len(ends) == 1  # values right-aligned in one column
    with pytest.raises(ValueError, match="wall_time_s"):
        summary_table(metrics, keys=("wall_time_s",))


@pytest.mark.parametrize(
    "options",
    [
        dict(trailers=3, faults=["dropout:t=0.2"]),
        dict(reverse=True, path_feedback={}),
        dict(reverse=True, eta=0.5),
    ],
)
def test_every_built_in_metric_has_a_unit(options):
    # generated from what runs report: a metric added without a unit fails here, and the
    # summary would print it bare
    from tt_mujoco.sim import Scenario, simulate

    run = simulate(Scenario(traj="circle", plant="reduced", duration=0.4, **options))
    numbers = [k for k, v in run.metrics.items() if isinstance(v, int | float)]
    assert numbers and all(metric_unit(k) is not None for k in numbers), [
        k for k in numbers if metric_unit(k) is None
    ]
    assert metric_unit("my_metric") is None  # a user's metric: no unit is made up for it


def test_default_summary_covers_compute_metrics_output():
    m = compute_metrics(straight_run(), STRAIGHT_REFERENCE, TORQUE_LIMIT)
    text = summary_table(m)
    assert "rmse_lateral" in text and "torque_saturation_fraction" in text


# ---------------------------------------------------------------------------------------------
# Definitions that mean the same on every path, start and direction (docs/metrics.md)

SPACING = 0.7  # L + L0


def _rest_then_straight(wiggle: float, n: int = 1201):
    """A tractor starting from rest at the origin (it rolls back 1e-6 m and wiggles sideways by
    ``wiggle`` first), then straight along +x; the trailer follows on the same line."""
    s = np.concatenate([np.zeros(50), np.linspace(0.0, 6.0, n - 50)])
    s[1:10] = -1e-6  # rolls back a hair
    x = s.copy()
    y = np.zeros(n)
    y[1:20] = wiggle * np.sin(np.arange(19))
    # The trailer is SPACING behind along the path it follows (x), on the line y = 0.
    return make_series(n, x=x, y=y, x_ref=x, y_ref=np.zeros(n), x0=x - SPACING, y0=np.zeros(n))


def test_offtracking_is_zero_on_a_straight_from_rest_whatever_the_start_wiggles():
    # The bug this replaces: a 1e-5 m wiggle at rest made the 0.7 m spacing count (max 0.700).
    for wiggle in (0.0, 1e-6, 1e-5):
        ts = _rest_then_straight(wiggle)
        m = compute_metrics(ts, STRAIGHT_REFERENCE, TORQUE_LIMIT)
        assert m["trailer_offtrack_max"] < 1e-4, wiggle  # the wiggle itself, not the spacing
        assert m["trailer_offtrack_samples"] == np.count_nonzero(ts["x0"] > 0.0)
        assert m["trailer_rmse_lateral"] == pytest.approx(0.0, abs=EXACT)


def test_offtracking_on_a_steady_circle_over_one_and_a_half_laps():
    # Tractor on R = 1, trailer on R0 = 0.98 (0.02 inside), 1.5 laps: the previous lap must not
    # serve (it is the same circle, so the number would hide it; the window is checked below).
    n = 3000
    a = np.linspace(0.0, 3.0 * np.pi, n)
    lag = 0.7
    p = np.column_stack([np.cos(a), np.sin(a)])
    p0 = 0.98 * np.column_stack([np.cos(a - lag), np.sin(a - lag)])
    ts = make_series(
        n, x=p[:, 0], y=p[:, 1], x_ref=p[:, 0], y_ref=p[:, 1], x0=p0[:, 0], y0=p0[:, 1]
    )
    ts["theta_ref"] = a + np.pi / 2
    circle = np.column_stack([np.cos(a), np.sin(a)])
    m = compute_metrics(ts, circle, TORQUE_LIMIT)
    sagitta = 1.0 - math.cos((a[1] - a[0]) / 2)
    assert m["trailer_offtrack_rms"] == pytest.approx(0.02, abs=sagitta)
    assert m["trailer_rmse_lateral"] == pytest.approx(0.02, abs=sagitta)
    assert m["cross_track_max"] < sagitta and m["along_track_max"] < EXACT


def _lemniscate(u):
    """Gerono's figure-eight (2 sin u, 2 sin u cos u): its two branches cross at the origin at
    right angles (u = 0, pi, 2 pi)."""
    r = np.column_stack([2.0 * np.sin(u), 2.0 * np.sin(u) * np.cos(u)])
    d = np.column_stack([2.0 * np.cos(u), 2.0 * np.cos(2.0 * u)])
    normal = np.column_stack([-d[:, 1], d[:, 0]]) / np.hypot(d[:, 0], d[:, 1])[:, None]
    return r, normal


def test_offtracking_on_a_figure_eight_uses_the_recent_path_only():
    # The trailer runs 0.02 m right of the tractor's track, 0.35 rad of the parameter behind.
    # Crossing the origin, it sits on the *other* branch, which the tractor drove half a loop
    # (about 3 m) earlier: measured against the whole driven path the off-tracking would dip to
    # 0 there; against the recent path it stays 0.02.
    n = 6000
    u = np.linspace(0.0, 2.0 * np.pi, n)
    p, _ = _lemniscate(u)
    r0, normal0 = _lemniscate(u - 0.35)
    p0 = r0 - 0.02 * normal0
    off = trailer_offtrack(p, p0)
    counted = ~np.isnan(off)
    near_crossing = counted & (np.abs(u - 0.35 - np.pi) < 0.05)
    assert near_crossing.sum() > 50
    chord = 4e-5  # the polygon of 6000 samples against the smooth curve
    np.testing.assert_allclose(off[counted], 0.02, atol=chord)


def test_reversing_the_follower_is_the_tractor():
    # Backing up along y = 0 towards -x, the trailer leads 0.7 m ahead; the tractor follows
    # 0.01 m to its side: the off-tracking is the tractor's, 0.01, never a spacing.
    n = 800
    x = np.linspace(0.0, -5.0, n)
    ts = make_series(
        n, x=x, y=np.full(n, 0.01), x_ref=x, y_ref=np.zeros(n), x0=x - SPACING, y0=np.zeros(n)
    )
    m = compute_metrics(ts, STRAIGHT_REFERENCE[::-1], TORQUE_LIMIT, reverse=True)
    assert m["offtrack_follower"] == "tractor"
    assert m["trailer_offtrack_rms"] == pytest.approx(0.01, abs=EXACT)
    assert m["trailer_offtrack_max"] == pytest.approx(0.01, abs=EXACT)
    assert m["trailer_offtrack_samples"] > 0.8 * n
    assert m["trailer_rmse_lateral"] == pytest.approx(0.0, abs=EXACT)


def test_reversing_a_train_every_unit_follows_the_one_ahead_of_it():
    # Backing up along y = 0 towards -x, trailer 3 leads; trailer 2 follows it 0.03 m to the
    # side, trailer 1 0.02 m and the tractor 0.01 m: each unit against the path the unit ahead
    # of it in the motion drove (the last trailer follows nothing).
    n = 1200
    x = np.linspace(0.0, -8.0, n)
    sides = {"x": 0.01, "x0": 0.02, "x0_2": 0.03, "x0_3": 0.0}
    columns = {}
    for k, (name, side) in enumerate(sides.items()):
        columns[name] = x - k * SPACING
        columns["y" + name[1:]] = np.full(n, side)
    for k in (2, 3):
        columns[f"phi_{k}"] = np.zeros(n)
    ts = make_series(n, x_ref=x, y_ref=np.zeros(n), **columns)
    m = compute_metrics(ts, STRAIGHT_REFERENCE[::-1], TORQUE_LIMIT, reverse=True)
    # the tractor 0.01 beside trailer 1's path, trailer 1 0.01 beside trailer 2's, trailer 2
    # 0.03 beside trailer 3's
    assert m["trailer_offtrack_max"] == pytest.approx(0.01, abs=EXACT)
    assert m["trailer_1_offtrack_max"] == pytest.approx(0.01, abs=EXACT)
    assert m["trailer_2_offtrack_max"] == pytest.approx(0.03, abs=EXACT)
    assert math.isnan(m["trailer_3_offtrack_max"])
    assert m["train_offtrack_max_worst"] == pytest.approx(0.03, abs=EXACT)
    forward = compute_metrics(ts, STRAIGHT_REFERENCE, TORQUE_LIMIT)
    assert "trailer_1_offtrack_max" not in forward


def test_overshoot_past_the_end_is_along_track_not_cross_track():
    # The reference ends at x = 5; P runs on to x = 5.066 on the line (0.066 m of overshoot)
    # while the reference point waits at the end.
    n = 600
    x = np.concatenate([np.linspace(0.0, 5.0, 500), np.linspace(5.0, 5.066, 100)])
    x_ref = np.minimum(x, 5.0)
    x_ref[500:] = 5.0
    ts = make_series(n, x=x, y=np.zeros(n), x_ref=x_ref, y_ref=np.zeros(n), x0=x - SPACING)
    reference = np.column_stack([np.linspace(0.0, 5.0, 51), np.zeros(51)])
    m = compute_metrics(ts, reference, TORQUE_LIMIT)
    assert m["max_lateral"] == pytest.approx(0.066, abs=1e-12)  # the paper's lateral: end-clamped
    assert m["cross_track_max"] == pytest.approx(0.0, abs=EXACT)
    assert m["along_track_max"] == pytest.approx(0.066, abs=1e-12)


def test_projection_with_a_window_matches_brute_force():
    # A path driven in laps (a circle three times): each point sees only segments first..count,
    # the recent path, as the off-tracking asks; the other laps pass within millimetres.
    rng = np.random.default_rng(5)
    angle = np.linspace(0.0, 6.0 * np.pi, 6000)
    radius = 1.0 + 0.002 * np.sin(7.0 * angle)
    vertices = np.column_stack([radius * np.cos(angle), radius * np.sin(angle)])
    line = Polyline(vertices)
    n = 600
    count = rng.integers(1, line.n_segments + 1, n)
    first = np.maximum(count - rng.integers(1, 2500, n), 0)
    points = vertices[np.maximum(count - rng.integers(0, 3000, n), 0)]
    points = points + rng.normal(0.0, 0.02, (n, 2))
    proj = line.project(points, segment_count=count, segment_first=first)
    for i in range(0, n, 5):
        expected = brute_force_distance(points[i : i + 1], vertices[first[i] : count[i] + 1])[0]
        assert proj.distance[i] == pytest.approx(expected, rel=1e-12, abs=1e-14)


# --- the compiled search: the same nearest points as the vectorised one -------------------------
@pytest.fixture(scope="module")
def compiled_projection():
    from tt_mujoco.analysis import geometry
    from tt_mujoco.sim.loop import compiled

    compiled.kernel()  # loading it hands its projection to the geometry module
    projection = geometry._COMPILED
    yield projection
    geometry.use_compiled_projection(projection)


def _both(compiled_projection, line, points, **options):
    from tt_mujoco.analysis import geometry

    geometry.use_compiled_projection(compiled_projection)
    fast = line.project(points, **options)
    geometry.use_compiled_projection(None)
    slow = line.project(points, **options)
    geometry.use_compiled_projection(compiled_projection)
    return fast, slow


def test_the_compiled_search_finds_the_vectorised_search_s_nearest_points(compiled_projection):
    rng = np.random.default_rng(17)
    cases = []
    for vertices in random_polylines(rng):
        scale = float(np.ptp(vertices, axis=0).max())
        spread = scale * 10.0 ** rng.uniform(-5, 0, (1500, 1))
        near = vertices[rng.integers(0, len(vertices), 1500)] + rng.normal(size=(1500, 2)) * spread
        around = rng.uniform(vertices.min(0) - scale, vertices.max(0) + scale, (300, 2))
        cases.append((vertices, np.vstack([near, around, [[np.nan, 0.0]]]), {}))
    # Laps with windows, as the off-tracking asks, and a path known up to some time.
    angle = np.linspace(0.0, 6.0 * np.pi, 6000)
    laps = (
        np.column_stack([np.cos(angle), np.sin(angle)]) * (1.0 + 0.002 * np.sin(7 * angle))[:, None]
    )
    count = rng.integers(1, 5999, 800)
    first = np.maximum(count - rng.integers(1, 2500, 800), 0)
    points = laps[np.maximum(count - rng.integers(0, 3000, 800), 0)] + rng.normal(0, 0.02, (800, 2))
    cases.append((laps, points, {"segment_count": count, "segment_first": first}))
    cases.append((laps, points, {"segment_count": rng.integers(0, 5999, 800)}))
    # A square: points on its diagonals are equally near two sides (ties go to the lower one).
    square = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0, 0]], dtype=float)
    cases.append((square, np.array([[0.5, 0.5], [0.25, 0.25], [0.75, 0.25], [2.0, 2.0]]), {}))
    # A straight path far from the origin, its chunks' chords on it: points on the path are at
    # distance 0 from every chunk they touch, ties the chord bound must not cut away.
    line = np.column_stack([1e4 + 0.001 * np.arange(200.0), np.full(200, -3e3)])
    on_line = line[rng.integers(0, 200, 300)]
    beside = on_line + np.column_stack([rng.normal(0, 1e-3, 300), rng.normal(0, 1e-9, 300)])
    cases.append((line, np.vstack([on_line, beside, line[::16]]), {}))
    # A time series beside a figure eight, a few samples a segment: the compiled search
    # certifies most samples by an earlier one's search (nearest_segments_of).
    angle = np.linspace(0.0, 2.0 * np.pi, 900)
    eight = np.column_stack([np.sin(angle), np.sin(angle) * np.cos(angle)])
    t = np.linspace(0.0, 1.0, 4000) * (len(eight) - 1)
    on_path = np.column_stack([np.interp(t, np.arange(len(eight)), c) for c in eight.T])
    cases.append((eight, on_path + rng.normal(0, 5e-4, on_path.shape), {}))
    for vertices, points, options in cases:
        line = Polyline(vertices)
        for extend_ends in (False, True):
            fast, slow = _both(
                compiled_projection, line, points, extend_ends=extend_ends, **options
            )
            for name in fast._fields:  # bit for bit, the segment chosen on ties included
                np.testing.assert_array_equal(
                    getattr(fast, name), getattr(slow, name), err_msg=name
                )


def test_every_point_of_a_chunk_lies_within_its_chord_reach():
    from tt_mujoco.analysis import nearest

    rng = np.random.default_rng(11)
    for vertices in random_polylines(rng):
        line = Polyline(vertices)
        table, n_seg = line.table, line.n_segments
        start = np.column_stack([table.chord_x, table.chord_y])
        chord = np.column_stack([table.chord_dx, table.chord_dy])
        for c in range(start.shape[0]):
            segments = np.arange(c * nearest.CHUNK, min(n_seg, (c + 1) * nearest.CHUNK))
            s = np.linspace(0.0, 1.0, 9)[:, None, None]
            points = line.vertices[segments] + s * (
                line.vertices[segments + 1] - line.vertices[segments]
            )
            rel = points.reshape(-1, 2) - start[c]
            t = np.clip(rel @ chord[c] * table.chord_inv_len2[c], 0.0, 1.0)
            stray = np.hypot(*(rel - t[:, None] * chord[c]).T)
            assert stray.max() <= table.chord_reach[c]
            # and the bound is not loose: the farthest vertex sets it
            assert table.chord_reach[c] <= stray.max() * (1 + 1e-8) + 1e-11 * np.abs(vertices).max()


def test_nearest_segment_of_is_the_brute_force_nearest_in_plain_python():
    from tt_mujoco.analysis import nearest
    from tt_mujoco.analysis.nearest import nearest_segment_of

    rng = np.random.default_rng(3)
    vertices = np.cumsum(rng.normal(size=(80, 2)), axis=0)
    line = Polyline(vertices)
    for point in rng.normal(0, 5, (60, 2)):
        lo, hi = sorted(rng.integers(0, line.n_segments + 1, 2))
        hi = max(hi, lo + 1)
        kept = np.empty(line.table.chord_x.size, np.int64)
        d2, seg, _, n_kept, lower = nearest_segment_of(
            point[0], point[1], lo, hi, False, line.table, lo, kept
        )
        expected = brute_force_distance(point[None], line.vertices[lo : hi + 1])[0]
        assert math.sqrt(d2) == pytest.approx(expected, rel=1e-12, abs=1e-14)
        assert lo <= seg < hi
        # every segment of the window outside the chunks it kept lies at least lower away
        outside = [
            s for s in range(lo, hi) if s // nearest.CHUNK not in set(kept[:n_kept].tolist())
        ]
        if outside:
            nearest_outside = min(
                brute_force_distance(point[None], line.vertices[s : s + 2])[0] for s in outside
            )
            assert lower <= nearest_outside * (1 + 1e-12)
        else:
            assert lower == math.inf


def test_a_time_series_is_searched_from_the_last_search_as_each_point_alone():
    """nearest_segments_of searches again only when a point has left what the last search
    certified: every point's nearest segment, d2 and t are those of a search of its own, bit
    for bit, on a path that passes near itself, with and without the end rays."""
    from tt_mujoco.analysis import nearest

    angle = np.linspace(0.0, 2.0 * np.pi, 900)
    eight = np.column_stack([np.sin(angle), np.sin(angle) * np.cos(angle)])  # crosses itself
    rng = np.random.default_rng(29)
    # a vehicle's samples: a few per segment, beside the path by a little noise
    t = np.linspace(0.02, 0.98, 4000) * (len(eight) - 1)
    on_path = np.column_stack([np.interp(t, np.arange(len(eight)), c) for c in eight.T])
    points = on_path + rng.normal(0, 5e-4, on_path.shape)
    line = Polyline(eight)
    n = len(points)
    full = []
    searched = nearest.nearest_segment_of

    def counted(*args):
        full.append(args)
        return searched(*args)

    for extend in (False, True):
        out = (np.empty(n), np.empty(n, np.int64), np.empty(n))
        window = (np.zeros(n, np.int64), np.full(n, line.n_segments, np.int64))
        full.clear()
        nearest.nearest_segment_of = counted
        try:
            nearest.nearest_segments_of(
                (points[:, 0], points[:, 1]), window, extend, line.table, out
            )
        finally:
            nearest.nearest_segment_of = searched
        assert 0 < len(full) < n / 4  # most points were certified by an earlier search
        kept = np.empty(line.table.chord_x.size, np.int64)
        for i, (x, y) in enumerate(points):
            alone = searched(x, y, 0, line.n_segments, extend, line.table, 0, kept)[:3]
            assert (out[0][i], out[1][i], out[2][i]) == alone


def test_lateral_error_from_the_cross_track_projection_is_the_projection_itself():
    from tt_mujoco.analysis.metrics import cross_track_and_lateral

    rng = np.random.default_rng(23)
    for vertices in random_polylines(rng):
        line = Polyline(vertices)
        scale = float(np.ptp(vertices, axis=0).max())
        points = rng.uniform(vertices.min(0) - scale, vertices.max(0) + scale, (800, 2))
        points = np.vstack([points, vertices[[0, -1]], [[np.nan, 1.0]]])
        cross, lateral = cross_track_and_lateral(line, points)
        np.testing.assert_array_equal(cross, line.project(points, extend_ends=True).signed_distance)
        np.testing.assert_array_equal(lateral, line.project(points).signed_distance)


def test_merged_metrics_of_a_run_cut_in_two_are_the_whole_runs():
    """merge_metrics: the metrics of consecutive pieces, each computed on its own rows, are
    those of the whole where a metric is a per-sample mean or maximum (the velocity errors,
    the saturation, the counts); each piece's path errors are against its own reference."""
    from tt_mujoco.analysis.metrics import merge_metrics
    from tt_mujoco.sim import Scenario, simulate

    result = simulate(Scenario(traj="s_curve", plant="reduced", duration=4.0, noise_snr_db=20.0))
    ts, line = result.timeseries, result.reference_polyline
    cut = len(ts["t"]) // 3
    pieces = [{k: v[:cut] for k, v in ts.items()}, {k: v[cut:] for k, v in ts.items()}]
    whole = compute_metrics(ts, line, 15.0)
    merged = merge_metrics([compute_metrics(piece, line, 15.0) for piece in pieces])
    for name in ("rmse_v", "rmse_omega", "max_abs_v", "torque_saturation_fraction"):
        assert merged[name] == pytest.approx(whole[name], rel=1e-12), name
    for name in ("steps", "finite_samples"):
        assert merged[name] == whole[name]
    assert merged["sim_time_s"] == pytest.approx(whole["sim_time_s"])
    # a path error is measured sample by sample against the same line: the same too
    assert merged["cross_track_rms"] == pytest.approx(whole["cross_track_rms"], rel=1e-9)
    assert merged["offtrack_follower"] == whole["offtrack_follower"]


@pytest.mark.parametrize("reverse", [False, True])
def test_metrics_given_the_runs_error_signals_are_the_metrics_that_measure_them(reverse):
    """run_error_signals is what compute_metrics measures (the figures draw it): handed over,
    the metrics are the same to the last bit, a diverged run's rows after its finite part NaN."""
    n, k = 400, 310
    t = np.arange(n) * 0.01
    x = np.linspace(0.0, 4.0, n)
    ts = make_series(
        n,
        x=x,
        y=0.05 * np.sin(t),
        x_ref=x,
        x0=x - 0.7,
        y0=0.02 * np.cos(2 * t),
        v=0.1 * np.sin(3 * t),
        omega=0.2 * np.cos(t),
        x0_2=x - 1.4,
        y0_2=0.03 * np.sin(t),
        phi_2=0.01 * t,
    )
    ts["x"][k:] = np.nan
    signals = run_error_signals(ts, STRAIGHT_REFERENCE, reverse)
    assert all(len(values) == n for values in signals.values())
    assert all(np.isnan(values[k:]).all() for values in signals.values())
    given = compute_metrics(ts, STRAIGHT_REFERENCE, TORQUE_LIMIT, reverse, signals)
    measured = compute_metrics(ts, STRAIGHT_REFERENCE, TORQUE_LIMIT, reverse)
    assert given.keys() == measured.keys()
    for key, value in measured.items():
        assert given[key] == value or (math.isnan(given[key]) and math.isnan(value)), key

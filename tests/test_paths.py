"""Reference path geometry (docs/model.md Section 7, paper Sections 6.1 and 6.3)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad

from tt_mujoco.reference import paths
from tt_mujoco.vehicle import steering
from tt_mujoco.vehicle.params import Params

L_CYCLOID = 8.0 * math.cos(math.pi / 8.0)


def _cycloid_point(t):
    tau = np.asarray(t) + math.pi / 4.0
    return tau - np.sin(tau), 1.0 - np.cos(tau), tau


def _figure_eight(n: int, A: float = 3.0):
    """Lemniscate of Gerono x = A sin t, y = A sin t cos t, closed, n intervals."""
    t = np.linspace(0.0, 2.0 * math.pi, n + 1)
    return A * np.sin(t), A * np.sin(t) * np.cos(t)


def _figure_eight_curvature(A: float = 3.0):
    """Exact (s, kappa) of the lemniscate on a fine grid, s from t = 0."""
    t = np.linspace(0.0, 2.0 * math.pi, 400_001)
    xd, yd = A * np.cos(t), A * np.cos(2 * t)
    xdd, ydd = -A * np.sin(t), -2 * A * np.sin(2 * t)
    speed = np.hypot(xd, yd)
    s = np.concatenate([[0.0], np.cumsum(0.5 * (speed[1:] + speed[:-1]) * np.diff(t))])
    return s, (xd * ydd - yd * xdd) / speed**3


def _write_csv(tmp_path, name, header, rows):
    file = tmp_path / name
    lines = [header] + [",".join(repr(float(v)) for v in row) for row in rows]
    file.write_text("\n".join(lines) + "\n")
    return file


def _all_paths(tmp_path=None):
    out = [paths.cycloid(), paths.s_curve(), paths.circle(), paths.circle(0.7, length=9.0)]
    x, y = _figure_eight(80)
    out.append(paths.from_waypoints(x, y, name="figure-eight"))
    return out


# --- cycloid ----------------------------------------------------------------------------------
def test_cycloid_length_is_8_cos_pi_8():
    path = paths.cycloid()
    assert path.length == pytest.approx(L_CYCLOID, abs=1e-12)
    assert path.length == pytest.approx(7.391, abs=5e-4)
    # Independent check: integrate |r'(tau)| = 2 sin(tau/2) of the paper's parameterisation.
    length, _ = quad(
        lambda tau: math.hypot(1 - math.cos(tau), math.sin(tau)), 0.25 * math.pi, 1.75 * math.pi
    )
    assert path.length == pytest.approx(length, rel=1e-12)


def test_cycloid_arc_length_closed_form_matches_quadrature():
    for t in np.linspace(0.0, 1.5 * math.pi, 13):
        numeric, _ = quad(lambda y: 2.0 * math.sin(y / 2.0 + math.pi / 8.0), 0.0, t)
        assert paths.cycloid_arc_length(t) == pytest.approx(numeric, abs=1e-12)


def test_cycloid_pose_at_s_of_t_is_the_papers_point():
    path = paths.cycloid()
    t = np.linspace(0.0, 1.5 * math.pi, 301)
    x, y, heading = path.pose(paths.cycloid_arc_length(t))
    xr, yr, tau = _cycloid_point(t)
    # arccos in the inverse s -> tau is well conditioned here (cos(tau/2) in [-0.39, 0.93]).
    np.testing.assert_allclose(x, xr, atol=1e-12)
    np.testing.assert_allclose(y, yr, atol=1e-12)
    np.testing.assert_allclose(heading, math.pi / 2.0 - tau / 2.0, atol=1e-12)


def test_cycloid_start_and_end():
    path = paths.cycloid()
    start = path.start_pose
    assert (start.x, start.y) == pytest.approx((0.0783, 0.2929), abs=1e-4)
    assert start.heading == pytest.approx(3.0 * math.pi / 8.0, abs=1e-12)
    end = path.end_pose
    xr, yr, _ = _cycloid_point(1.5 * math.pi)
    assert (end.x, end.y) == pytest.approx((float(xr), float(yr)), abs=1e-12)
    assert path.initial_pose == start


def test_cycloid_curvature_is_specs_closed_form_and_negative():
    path = paths.cycloid()
    s = np.linspace(0.0, path.length, 1001)
    spec = 1.0 / np.sqrt(16.0 - (4.0 * math.cos(math.pi / 8.0) - s) ** 2)  # model.md 7: |kappa|
    kappa = path.curvature(s)
    np.testing.assert_allclose(kappa, -spec, rtol=1e-13)
    # Independent: the parametric curvature (x'y'' - y'x'')/|r'|^3 of r(tau) at tau(s).
    t = np.linspace(0.0, 1.5 * math.pi, 101)
    _, _, tau = _cycloid_point(t)
    xd, yd, xdd, ydd = 1 - np.cos(tau), np.sin(tau), np.sin(tau), np.cos(tau)
    parametric = (xd * ydd - yd * xdd) / (xd**2 + yd**2) ** 1.5
    np.testing.assert_allclose(path.curvature(paths.cycloid_arc_length(t)), parametric, rtol=1e-12)
    assert np.all(kappa < 0)  # clockwise
    assert kappa.min() == pytest.approx(-1.0 / (4.0 * math.sin(math.pi / 8.0)), rel=1e-12)
    assert path.curvature(path.length / 2.0) == pytest.approx(-0.25, rel=1e-14)


def test_cycloid_paper_start_is_off_the_path():
    on = paths.cycloid("on_path")
    paper = paths.cycloid(start="paper")
    assert paper.initial_pose == pytest.approx((0.0, 0.0, math.pi / 4.0))
    assert paper.start_pose == on.start_pose  # same geometry
    assert math.hypot(on.start_pose.x, on.start_pose.y) == pytest.approx(0.3032, abs=1e-4)
    with pytest.raises(ValueError, match=r"start='origin'.*'on_path' or 'paper'"):
        paths.cycloid("origin")


# --- s-curve and circle ------------------------------------------------------------------------
def test_s_curve_curvature_jumps_at_pi_R():
    R = 1.5
    path = paths.s_curve(R)
    assert path.length == pytest.approx(2.0 * math.pi * R, rel=1e-15)
    jump = math.pi * R
    assert path.curvature(np.nextafter(jump, 0.0)) == 1.0 / R
    assert path.curvature(jump) == -1.0 / R
    s = np.linspace(0.0, path.length, 2001)
    expected = np.where(s < jump, 1.0 / R, -1.0 / R)
    np.testing.assert_array_equal(path.curvature(s), expected)
    np.testing.assert_array_equal(path.curvature_rate(s), 0.0)
    assert path.curvature_and_rate(jump) == (-1.0 / R, 0.0)
    assert path.curvature_and_rate(np.nextafter(jump, 0.0)) == (1.0 / R, 0.0)


def test_s_curve_geometry():
    R = 1.5
    path = paths.s_curve(R)
    assert path.start_pose == (0.0, 0.0, 0.0)
    x, y, heading = path.pose(math.pi * R)
    assert (x, y, heading) == pytest.approx((0.0, 2.0 * R, math.pi), abs=1e-12)
    end = path.end_pose
    assert (end.x, end.y, end.heading) == pytest.approx((0.0, 4.0 * R, 0.0), abs=1e-12)


def test_circle_geometry_and_length():
    path = paths.circle()
    assert path.length == pytest.approx(2.0 * math.pi, rel=1e-15)
    assert path.start_pose == pytest.approx((1.0, 0.0, math.pi / 2.0))
    s = np.linspace(0.0, path.length, 721)
    x, y, heading = path.pose(s)
    np.testing.assert_allclose(np.hypot(x, y), 1.0, atol=1e-14)
    np.testing.assert_allclose(heading, math.pi / 2.0 + s, atol=1e-13)  # continuous, unwrapped
    np.testing.assert_array_equal(path.curvature(s), 1.0)
    longer = paths.circle(2.0, length=20.0)
    assert longer.length == 20.0
    assert longer.curvature(19.0) == 0.5
    for bad in (0.0, -1.0, math.nan, math.inf, "1"):
        with pytest.raises(ValueError, match="R="):
            paths.circle(bad)
    with pytest.raises(ValueError, match="length=-2"):
        paths.circle(1.0, length=-2.0)


# --- properties every path must have -------------------------------------------------------------
def test_pose_is_consistent_with_heading_and_curvature(tmp_path):
    """d(x, y)/ds = e(heading), dheading/ds = kappa, dkappa/ds = curvature_rate (central FD)."""
    h = 1e-5
    for path in _all_paths(tmp_path):
        s = np.linspace(2 * h, path.length - 2 * h, 3001)
        if path.name == "s_curve":
            s = s[np.abs(s - path.length / 2.0) > 2 * h]  # not across the curvature jump
        x1, y1, h1 = path.pose(s + h)
        x0, y0, h0 = path.pose(s - h)
        _, _, heading = path.pose(s)
        tangent_error = np.hypot(
            (x1 - x0) / (2 * h) - np.cos(heading), (y1 - y0) / (2 * h) - np.sin(heading)
        )
        # FD truncation ~ h^2 kappa^2 / 6 ~ 1e-10 and rounding ~ 1e-16 / h ~ 1e-11; the spline's
        # Hermite inverse s -> u measured 9e-8 for the figure-eight at 80 waypoints.
        assert tangent_error.max() < 1e-6, path.name
        turn_error = np.abs((h1 - h0) / (2 * h) - path.curvature(s))
        assert turn_error.max() < 1e-6, path.name
        k1, k0 = path.curvature(s + h), path.curvature(s - h)
        rate = path.curvature_rate(s)
        rate_fd = (k1 - k0) / (2 * h)
        if isinstance(path, paths.SplinePath):
            # the rate jumps at the waypoints; skip FD stencils that straddle one
            knots = path._s_fine[::32]
            near = np.min(np.abs(s[:, None] - knots[None, :]), axis=1) < 2 * h
            rate, rate_fd = rate[~near], rate_fd[~near]
        assert np.max(np.abs(rate_fd - rate)) < 1e-5, path.name


def test_heading_is_continuous(tmp_path):
    for path in _all_paths(tmp_path):
        ds = 1e-3
        _, _, heading = path.pose(np.arange(0.0, path.length, ds))
        # mean value theorem: |dheading| <= max|kappa| ds; max_abs_curvature is sampled every
        # 1 mm and can miss the true peak by a hair (measured 1e-4 relative on the figure-eight)
        bound = path.max_abs_curvature * ds
        assert np.max(np.abs(np.diff(heading))) <= bound * (1 + 1e-3), path.name


def test_scalar_fast_path_matches_vectorised(tmp_path):
    for path in _all_paths(tmp_path):
        s = np.concatenate([np.linspace(-0.5, path.length + 0.5, 2003), [0.0, path.length]])
        fast = np.array([path.curvature_and_rate(float(q)) for q in s])
        # Closed forms: identical up to rounding. Splines: cubic Hermite per fine cell,
        # measured 6e-10 (kappa) and 5e-7 (rate) for the figure-eight at 80 waypoints.
        np.testing.assert_allclose(fast[:, 0], path.curvature(s), atol=1e-8, err_msg=path.name)
        np.testing.assert_allclose(fast[:, 1], path.curvature_rate(s), atol=5e-6, err_msg=path.name)


def test_scalar_pose_matches_vectorised(tmp_path):
    for path in _all_paths(tmp_path):
        s = np.concatenate([np.linspace(-0.5, path.length + 0.5, 2003), [0.0, path.length]])
        fast = np.array([path.pose_at(float(q)) for q in s])
        x, y, heading = path.pose(s)
        # closed forms: rounding only (1e-15); splines: cubic Hermite per fine cell, measured
        # 8e-12 m and 8e-11 rad for the figure-eight at 80 waypoints
        assert np.max(np.hypot(fast[:, 0] - x, fast[:, 1] - y)) < 1e-10, path.name
        assert np.max(np.abs(fast[:, 2] - heading)) < 1e-9, path.name
        assert isinstance(fast[0, 0], float)


def test_clamping_beyond_the_ends():
    for path in (paths.cycloid(), paths.s_curve(), paths.circle()):
        end, start = path.end_pose, path.start_pose
        x, y, heading = path.pose(path.length + 0.7)
        assert (x, y) == pytest.approx(
            (end.x + 0.7 * math.cos(end.heading), end.y + 0.7 * math.sin(end.heading)), abs=1e-12
        )
        assert heading == end.heading
        x, y, heading = path.pose(-0.3)
        assert (x, y) == pytest.approx(
            (start.x - 0.3 * math.cos(start.heading), start.y - 0.3 * math.sin(start.heading)),
            abs=1e-12,
        )
        assert path.curvature(path.length + 5.0) == path.curvature(path.length)
        assert path.curvature(-5.0) == path.curvature(0.0)
        assert path.curvature_rate(path.length + 1e-9) == 0.0
        assert path.curvature_rate(-1e-9) == 0.0
        assert path.curvature_and_rate(path.length + 1.0) == (path.curvature(path.length), 0.0)
    # the cycloid's rate is non-zero at the ends themselves (one-sided), 0 just beyond
    cyc = paths.cycloid()
    assert cyc.curvature_rate(0.0) == pytest.approx(cyc.curvature_and_rate(0.0)[1])
    assert cyc.curvature_rate(0.0) > 1.0


def test_vectorised_shapes():
    path = paths.s_curve()
    s = np.linspace(0.0, path.length, 12).reshape(3, 4)
    x, y, heading = path.pose(s)
    assert x.shape == y.shape == heading.shape == (3, 4)
    assert path.curvature(s).shape == (3, 4)
    assert isinstance(path.pose(1.0)[0], float)
    assert isinstance(path.curvature(1.0), float)
    np.testing.assert_allclose(x.ravel(), path.pose(s.ravel())[0])


def test_dense_polyline():
    path = paths.cycloid()
    poly = path.dense(0.01)
    assert poly.shape == (math.ceil(path.length / 0.01) + 1, 2)
    assert poly[0] == pytest.approx(path.start_pose[:2])
    assert poly[-1] == pytest.approx(path.end_pose[:2])
    assert np.max(np.hypot(*np.diff(poly, axis=0).T)) <= 0.01
    assert path.dense().shape[0] == math.ceil(path.length / 0.005) + 1
    with pytest.raises(ValueError, match="ds=0"):
        path.dense(0.0)


# --- dispatch ------------------------------------------------------------------------------------
def test_get_path_dispatch(tmp_path):
    assert isinstance(paths.get_path("cycloid"), paths.CycloidPath)
    assert paths.get_path("S-Curve", R=2.0).length == pytest.approx(4.0 * math.pi)
    assert paths.get_path("circle", length=7.0).length == 7.0
    assert paths.get_path("cycloid", start="paper").initial_pose.heading == math.pi / 4.0
    x, y = _figure_eight(40)
    file = _write_csv(tmp_path, "eight.csv", "x,y", zip(x, y, strict=True))
    assert paths.get_path(str(file)).name == "eight.csv"
    with pytest.raises(ValueError, match=r"'spiral'.*'cycloid', 's_curve', 'circle'.*\.csv"):
        paths.get_path("spiral")
    with pytest.raises(ValueError, match=r"radius.*allowed are R"):
        paths.get_path("s_curve", radius=2.0)


# --- CSV paths ------------------------------------------------------------------------------------
def test_csv_round_trip_closed_circle(tmp_path):
    R, n = 2.0, 24
    a = np.linspace(0.0, 2.0 * math.pi, n + 1)
    file = _write_csv(tmp_path, "circle.csv", "x,y", zip(R * np.cos(a), R * np.sin(a), strict=True))
    path = paths.from_csv(file)
    assert path.start_pose[:2] == pytest.approx((R, 0.0), abs=1e-12)
    assert path.start_pose.heading == pytest.approx(math.pi / 2.0, abs=2e-3)
    # Periodic cubic spline through 24 points: length 8e-5 short of 4 pi, curvature within
    # 2.9e-3 of 1/R (measured); tolerances just above.
    assert path.length == pytest.approx(2.0 * math.pi * R, abs=2e-4)
    s = np.linspace(0.0, path.length, 4001)
    assert np.max(np.abs(path.curvature(s) - 1.0 / R)) < 4e-3
    # closed: curvature continuous across the seam
    assert path.curvature(0.0) == pytest.approx(path.curvature(path.length), abs=1e-9)
    assert path.station_speeds is None


def test_csv_round_trip_figure_eight(tmp_path):
    x, y = _figure_eight(80)
    file = _write_csv(tmp_path, "eight.csv", "x,y", zip(x, y, strict=True))
    path = paths.from_csv(file)
    s_exact, k_exact = _figure_eight_curvature()
    # measured: length 1.3e-5 short, curvature within 0.030 of the exact (max |kappa| 1.6)
    assert path.length == pytest.approx(s_exact[-1], abs=3e-5)
    s = np.linspace(0.0, path.length, 4001)
    expected = np.interp(s * s_exact[-1] / path.length, s_exact, k_exact)
    assert np.max(np.abs(path.curvature(s) - expected)) < 0.04
    # the curvature changes sign (left lobe, right lobe)
    assert path.curvature(s).min() < -1.0 < 1.0 < path.curvature(s).max()


def test_csv_open_path_with_speed_column(tmp_path):
    a = np.linspace(0.0, 1.5 * math.pi, 19)
    v = np.linspace(0.0, 0.9, 19)
    rows = zip(v, 2.0 * np.cos(a), 2.0 * np.sin(a), strict=True)
    file = _write_csv(tmp_path, "arc.csv", "v, X ,y", rows)  # any order, spaces, case
    path = paths.from_csv(file)
    stations, speeds = path.station_speeds
    np.testing.assert_array_equal(speeds, v)
    assert stations[0] == 0.0 and stations[-1] == path.length
    # open (not-a-knot) ends: curvature error measured 0.023 with 18 intervals
    assert np.max(np.abs(path.curvature(np.linspace(0, path.length, 999)) - 0.5)) < 0.03


def test_smoothing_reduces_curvature_noise():
    rng = np.random.default_rng(0)
    a = np.linspace(0.0, 0.9 * 2.0 * math.pi, 61)[:-1]
    x = 2.0 * np.cos(a) + rng.normal(0.0, 0.003, a.size)
    y = 2.0 * np.sin(a) + rng.normal(0.0, 0.003, a.size)
    raw = paths.from_waypoints(x, y)
    smooth = paths.from_waypoints(x, y, smoothing=1e-2)
    s_raw = np.linspace(0.5, raw.length - 0.5, 2001)
    s_smooth = np.linspace(0.5, smooth.length - 0.5, 2001)
    # measured: 1.10 interpolating vs 0.070 smoothed (3 mm noise at 19 cm spacing)
    assert np.max(np.abs(raw.curvature(s_raw) - 0.5)) > 0.5
    assert np.max(np.abs(smooth.curvature(s_smooth) - 0.5)) < 0.1
    with pytest.raises(ValueError, match="smoothing=-1"):
        paths.from_waypoints(x, y, smoothing=-1.0)
    with pytest.raises(ValueError, match="at least 5 waypoints, got 4"):
        paths.from_waypoints(x[:4], y[:4], smoothing=1.0)


def _square(n=4):
    return [(0.0, 0.0), (1.0, 0.0), (2.0, 0.5), (3.0, 0.5), (4.0, 0.0)][:n]


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("", "is empty"),
        ("\n  \n", "is empty"),
        ("0,0\n1,0\n2,1\n3,1\n", r"header '0,0' \(line 1\).*x and y"),
        ("x,z\n0,0\n1,0\n2,1\n3,1\n", r"header 'x,z'"),
        ("x,y,speed\n0,0,1\n1,0,1\n2,1,1\n3,1,1\n", r"header 'x,y,speed'"),
        ("x,y,x\n0,0,0\n", r"header 'x,y,x'"),
        ("x,y\n0,0\n1,0\n2,1\n", r"3 waypoints is not allowed: a path needs at least 4"),
        ("x,y\n", r"0 waypoints"),
        ("x,y\n0,0\n1,nan\n2,1\n3,1\n", r"y=nan at line 3"),
        ("x,y\n0,0\n1,0\ninf,1\n3,1\n", r"x=inf at line 4"),
        ("x,y\n0,0\n1,0\n1,0\n3,1\n", r"line 3 and line 4 repeat the point \(x=1, y=0\)"),
        ("x,y\n0,0\n1,zero\n2,1\n3,1\n", r"y='zero' on line 3 is not a number"),
        ("x,y\n0,0\n1\n2,1\n3,1\n", r"line 3 has 1 fields"),
        ("x,y,v\n0,0,0.5\n1,0,-0.2\n2,1,1\n3,1,1\n", r"v=-0.2 at line 3.*>= 0"),
        ("x,y,v\n0,0,0\n1,0,0\n2,1,1\n3,1,1\n", r"v=0 at both line 2 and line 3"),
    ],
)
def test_csv_errors_name_the_bad_value(tmp_path, content, message):
    file = tmp_path / "bad.csv"
    file.write_text(content)
    with pytest.raises(ValueError, match=message):
        paths.from_csv(file)


def test_csv_missing_file(tmp_path):
    with pytest.raises(ValueError, match=r"'.*nowhere\.csv' does not exist"):
        paths.from_csv(tmp_path / "nowhere.csv")
    with pytest.raises(ValueError, match="does not exist"):
        paths.get_path(str(tmp_path / "nowhere.csv"))


def test_csv_curvature_beyond_the_vehicle_is_reported(tmp_path):
    # a circle of radius 0.3 m: kappa 3.33 > 2, wherever along it
    a = np.linspace(0.0, math.pi, 13)
    file = _write_csv(
        tmp_path, "tight.csv", "x,y", zip(0.3 * np.cos(a), 0.3 * np.sin(a), strict=True)
    )
    with pytest.raises(
        ValueError,
        match=r"kappa=3\.\d+ 1/m \(turn radius 0\.\d+ m\) at s=.*"
        r"between line \d+ .* and line \d+.*"
        r"\|kappa\| <= 2 1/m \(turn radius >= 0\.5 m\)",
    ):
        paths.from_csv(file)
    # allowed with a looser bound; and a tighter bound refuses a gentler path
    loose = paths.from_csv(file, max_curvature=4.0)
    # 12 intervals over a half circle: 3.353 mid-path, 3.484 at the not-a-knot ends (measured)
    assert loose.curvature(loose.length / 2.0) == pytest.approx(1 / 0.3, abs=0.03)
    assert loose.max_abs_curvature == pytest.approx(3.484, abs=1e-3)
    with pytest.raises(ValueError, match=r"kappa=3\.\d+ 1/m"):
        paths.get_path(str(file), max_curvature=3.0)
    with pytest.raises(ValueError, match="max_curvature=0"):
        paths.from_csv(file, max_curvature=0.0)


def test_csv_corner_is_located(tmp_path):
    # a right-angle corner at line 6 (x=2, y=0), the only tight spot: the spline's sharpest
    # bend is in an interval next to it
    rows = [(0, 0), (0.5, 0), (1, 0), (1.5, 0), (2, 0), (2, 0.5), (2, 1), (2, 1.5), (2, 2)]
    file = _write_csv(tmp_path, "corner.csv", "x,y", rows)
    with pytest.raises(ValueError, match=r"between line (5 \(x=1.5, y=0\)|6 \(x=2, y=0\))"):
        paths.from_csv(file)


# --- the curvature bound -------------------------------------------------------------------------
def test_default_curvature_bound_keeps_the_trailer_clear():
    """DEFAULT_MAX_CURVATURE (R_min = 0.5 m) against the steady-state articulation."""
    kappa = paths.DEFAULT_MAX_CURVATURE
    assert kappa == 2.0
    same_path = Params()  # eta = -1/7
    phi = steering.steady_articulation(kappa, same_path)
    assert math.degrees(phi) == pytest.approx(64.39, abs=0.01)  # below 90 deg: rod not across
    phi_one = steering.steady_articulation(1.0, same_path)
    assert math.degrees(phi_one) == pytest.approx(34.25, abs=0.01)
    assert steering.steady_articulation(-kappa, same_path) == pytest.approx(-phi, abs=1e-12)
    # the rod O-P0 would stand perpendicular to the tractor only beyond kappa = 3.016
    assert steering.steady_articulation(3.0, same_path) < math.pi / 2.0
    assert steering.steady_articulation(3.05, same_path) > math.pi / 2.0
    paper = Params(eta="paper")
    phi_paper = steering.steady_articulation(kappa, paper)
    assert math.degrees(phi_paper) == pytest.approx(-22.80, abs=0.01)
    assert abs(phi_paper) < paper.phi_singular
    # the residual really is zero (phi_dot = 0 with omega = kappa v, docs/model.md Section 2)
    eta, L, L0 = same_path.eta, same_path.L, same_path.L0
    residual = math.sin((eta - 1) * phi) + kappa * (
        L0 * math.cos(eta * phi) + L * math.cos((eta - 1) * phi)
    )
    assert abs(residual) < 1e-12
    assert math.isnan(steering.steady_articulation(1.0, Params(eta=1.0)))
    assert steering.steady_articulation(0.0) == 0.0


def test_a_path_class_that_leaves_a_hook_to_the_base_is_refused_naming_it(tmp_path):
    # the base's own hooks only raise NotImplementedError: such a class would fail mid-build
    # as if the bug were ours; it is refused when the factory gives it, naming what is missing
    from tt_mujoco.reference.path_base import PATH_HOOKS, ReferencePath, missing_hooks

    for name in paths.PATHS:  # every built-in gives every hook
        assert missing_hooks(type(paths.get_path(name))) == [], name
    assert missing_hooks(ReferencePath) == [hook for _, hook in PATH_HOOKS]
    file = tmp_path / "p.py"
    file.write_text(
        "from tt_mujoco.reference.paths import ReferencePath\n\n"
        "class Half(ReferencePath):\n"
        "    def pose_at(self, s):\n        return (s, 0.0, 0.0)\n\n"
        "    def curvature_and_rate(self, s):\n        return (0.0, 0.0)\n\n"
        "def p():\n    return Half('half', 10.0)\n"
    )
    with pytest.raises(ValueError, match=r"class Half does not implement _pose, _curvature, _cur"):
        paths.get_path(f"{file}:p")


def test_a_factory_that_raises_a_type_error_inside_is_its_failure_not_a_bad_option(tmp_path):
    from tt_mujoco.registry import HookError

    file = tmp_path / "p.py"
    file.write_text("def p(R=1.0):\n    return len(5)\n")
    with pytest.raises(HookError, match=r"line 2: TypeError: object of type 'int' has no len"):
        paths.get_path(f"{file}:p", R=2.0)
    with pytest.raises(ValueError, match=r"does not take the options \{'nope': 1\}"):
        paths.get_path(f"{file}:p", nope=1)

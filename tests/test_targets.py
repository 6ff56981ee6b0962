"""Speed profiles and tracking targets (docs/model.md Section 7, paper eqs. 32-34 and 37)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad
from target_steps import SteppedTarget

from tt_mujoco.reference import paths, targets
from tt_mujoco.reference.targets import (
    CycloidDynamicSpeed,
    CycloidStaticSpeed,
    DynamicTarget,
    RampSpeed,
    StaticTarget,
    StationSpeed,
    make_target,
)

L_CYCLOID = 8.0 * math.cos(math.pi / 8.0)
T_CYCLOID = 1.5 * math.pi


def _profiles():
    return [
        CycloidStaticSpeed(),
        CycloidDynamicSpeed(),
        RampSpeed(2.0 * math.pi * 1.5),
        RampSpeed(0.5),  # shorter than one ramp's worth: reduced peak
        RampSpeed.for_duration(10.0),
        StationSpeed([0.0, 1.0, 1.5, 4.0, 5.0], [0.0, 0.6, 0.9, 0.3, 0.0]),
    ]


# --- speed profiles --------------------------------------------------------------------------
def test_cycloid_static_speed_eq_32():
    prof = CycloidStaticSpeed()
    assert prof.duration == pytest.approx(T_CYCLOID)
    for t in (0.0, 1.0, 2.5, T_CYCLOID):
        assert prof.speed(t) == pytest.approx(2.0 * math.sin((t + math.pi / 4.0) / 2.0), abs=1e-15)
        assert prof.accel(t) == pytest.approx(math.cos((t + math.pi / 4.0) / 2.0), abs=1e-15)
    assert prof.speed(0.0) == pytest.approx(0.7654, abs=1e-4)  # a step from rest
    # its integral is the cycloid's arc length: covers the path exactly in 3 pi/2
    assert prof.distance(T_CYCLOID) == pytest.approx(L_CYCLOID, abs=1e-12)
    t = np.linspace(0.0, T_CYCLOID, 50)
    np.testing.assert_allclose(prof.distance(t), paths.cycloid_arc_length(t), atol=1e-14)


def test_cycloid_dynamic_speed_eq_34():
    prof = CycloidDynamicSpeed()
    assert prof.speed(0.0) == 0.0
    c = 2.0 * math.cos(math.pi / 8.0)
    for t in (0.5, 2.0, 4.0):
        assert prof.speed(t) == pytest.approx(c * t * math.exp(-t / 2.0), rel=1e-14)
    assert prof.speed(T_CYCLOID) == pytest.approx(0.825, abs=5e-4)  # as the paper says
    assert prof.speed(2.0) == pytest.approx(c * 2.0 / math.e, rel=1e-14)  # its maximum
    assert prof.accel(2.0) == pytest.approx(0.0, abs=1e-15)
    # it covers only 68.2 % of the path by 3 pi/2, and all of it as t -> inf
    assert prof.distance(T_CYCLOID) == pytest.approx(5.040, abs=1e-3)
    assert prof.distance(T_CYCLOID) / L_CYCLOID == pytest.approx(0.682, abs=1e-3)
    assert prof.distance(60.0) == pytest.approx(L_CYCLOID, abs=1e-9)
    # the closed form holds beyond 3 pi/2 (no hold)
    assert prof.speed(6.0) == pytest.approx(c * 6.0 * math.exp(-3.0), rel=1e-14)


def test_ramp_profile_covers_the_s_curve():
    length = 2.0 * math.pi * 1.5
    prof = RampSpeed(length, cruise=0.8, ramp_time=2.0)
    assert prof.duration == pytest.approx(length / 0.8 + 2.0, abs=1e-12)  # 13.78 s
    assert prof.duration == pytest.approx(13.781, abs=1e-3)
    assert prof.distance(prof.duration) == pytest.approx(length, abs=1e-12)
    assert prof.speed(0.0) == 0.0 and prof.speed(prof.duration) == 0.0
    assert prof.speed(5.0) == 0.8
    assert np.max(prof.accel(np.linspace(0, 2, 2001))) == pytest.approx(0.6, abs=1e-9)
    # the paper's 10 s would stop 6.4 m along, past the inflection at pi R = 4.71 m
    # (ramp 0.8 m, then cruise from 2 s to 10 s)
    assert prof.distance(10.0) == pytest.approx(0.8 + 0.8 * 8.0, abs=1e-12)


def test_ramp_for_duration_and_short_paths():
    circle_prof = RampSpeed.for_duration(10.0)
    assert circle_prof.duration == pytest.approx(10.0, abs=1e-12)
    assert circle_prof.total_distance == pytest.approx(6.4, abs=1e-12)
    short = RampSpeed.for_duration(3.0)  # ramps shortened to 1.5 s each
    assert short.ramp_time == 1.5 and short.duration == pytest.approx(3.0)
    assert short.total_distance == pytest.approx(0.8 * 1.5)
    tiny = RampSpeed(0.5)  # less than cruise * ramp_time = 1.6 m
    assert tiny.peak == pytest.approx(0.25) and tiny.cruise_time == pytest.approx(0.0, abs=1e-15)
    assert tiny.total_distance == pytest.approx(0.5, abs=1e-15)
    for bad in (0.0, -1.0, math.inf, math.nan):
        with pytest.raises(ValueError, match="distance="):
            RampSpeed(bad)
    with pytest.raises(ValueError, match="cruise=0"):
        RampSpeed(1.0, cruise=0.0)
    with pytest.raises(ValueError, match="ramp_time=-1"):
        RampSpeed(1.0, ramp_time=-1.0)


def test_station_profile():
    s = [0.0, 1.0, 1.5, 4.0, 5.0]
    v = [0.0, 0.6, 0.9, 0.3, 0.0]
    prof = StationSpeed(s, v)
    # reach each station at the given speed; constant acceleration in between
    expected_t = np.concatenate([[0.0], np.cumsum(2.0 * np.diff(s) / (np.add(v[:-1], v[1:])))])
    np.testing.assert_allclose(prof.distance(expected_t), s, atol=1e-12)
    np.testing.assert_allclose(prof.speed(expected_t), v, atol=1e-12)
    assert prof.duration == pytest.approx(expected_t[-1])
    assert prof.accel(0.1) == pytest.approx(0.6**2 / 2.0)
    with pytest.raises(ValueError, match="never 0 at two consecutive"):
        StationSpeed([0.0, 1.0, 2.0], [0.5, 0.0, 0.0])
    with pytest.raises(ValueError, match="increase strictly"):
        StationSpeed([0.0, 1.0, 1.0], [0.5, 0.5, 0.5])


def test_profiles_are_consistent():
    """accel = dv/dt and distance = int v (numerically), v continuous, scalar == vectorised."""
    for prof in _profiles():
        t = np.linspace(-1.0, prof.duration + 2.0, 4001)
        s, v, a = prof.states(t)
        fast = np.array([prof.state(float(q)) for q in t])
        np.testing.assert_allclose(fast[:, 0], s, atol=1e-12, err_msg=prof.name)
        np.testing.assert_allclose(fast[:, 1], v, atol=1e-12, err_msg=prof.name)
        np.testing.assert_allclose(fast[:, 2], a, atol=1e-12, err_msg=prof.name)
        inside = np.linspace(0.0, prof.duration, 2001)
        for t0, t1 in zip(inside[:-1:97], inside[97::97], strict=False):
            integral, _ = quad(prof.speed, t0, t1, limit=200, epsabs=1e-14, epsrel=1e-14)
            # measured <= 2e-15 (closed-form integrals against adaptive quadrature)
            assert prof.distance(t1) - prof.distance(t0) == pytest.approx(integral, abs=1e-13)
        h = 1e-6
        tt = inside[1:-1]
        fd = (prof.speed(tt + h) - prof.speed(tt - h)) / (2 * h)
        if isinstance(prof, StationSpeed):  # the acceleration steps at the stations
            keep = np.min(np.abs(tt[:, None] - prof._t[None, :]), axis=1) > 2 * h
            fd, tt = fd[keep], tt[keep]
        # central FD error ~ h^2 |v'''| / 6 + 1e-16 / h ~ 1e-10, except where a stencil straddles
        # a ramp's end: the smoothstep is C1, its jerk 6 v_c / T^2 = 1.2 m/s^3 steps there and the
        # error is up to h * 1.2 / 4 = 3e-7 (measured 3.0e-7)
        np.testing.assert_allclose(fd, prof.accel(tt), atol=5e-7, err_msg=prof.name)
        assert np.max(np.abs(np.diff(prof.speed(inside)))) < 0.01  # no jumps in v


def test_profiles_hold_after_their_end():
    prof = RampSpeed(3.0)
    assert prof.state(prof.duration + 5.0) == pytest.approx((3.0, 0.0, 0.0))
    static = CycloidStaticSpeed()
    s_end, v_end, _ = static.state(T_CYCLOID)
    assert static.state(T_CYCLOID + 2.0) == pytest.approx((s_end + 2.0 * v_end, v_end, 0.0))
    assert static.state(-1.0) == pytest.approx((-static.speed(0.0), static.speed(0.0), 0.0))


# --- static target --------------------------------------------------------------------------
# The targets' steps are the run's own (target_step.target_step_of), on the scenario's record.
def test_static_cycloid_target_is_eq_32_with_the_sign_restored():
    _, target, _ = make_target("cycloid", "static")
    assert isinstance(target, StaticTarget) and target.kind == "static"
    assert isinstance(target.profile, CycloidStaticSpeed)
    assert target.duration == pytest.approx(T_CYCLOID)
    stepped = SteppedTarget(traj="cycloid", target="static")
    for t in np.linspace(0.0, T_CYCLOID + 1.0, 211):
        v_d, omega_d, v_d_dot, omega_d_dot = stepped.step(float(t), 1e-3, 123.0)
        tau_half = (min(t, T_CYCLOID) + math.pi / 4.0) / 2.0
        assert v_d == pytest.approx(2.0 * math.sin(tau_half), abs=1e-14)
        # omega = kappa(s(t)) v(t) = -1/(4 sin(tau/2)) * 2 sin(tau/2) = -1/2 (paper prints +1/2)
        assert omega_d == pytest.approx(-0.5, abs=1e-14)
        assert omega_d_dot == pytest.approx(0.0, abs=1e-14)
        if t <= T_CYCLOID:
            assert v_d_dot == pytest.approx(math.cos(tau_half), abs=1e-14)
            assert stepped.state.s == pytest.approx(paths.cycloid_arc_length(t), abs=1e-13)


def test_static_target_on_s_curve_and_circle():
    stepped = SteppedTarget(traj="s_curve", target="static")
    R = 1.5
    prof = stepped.profile
    t_jump = None
    for t in np.arange(0.0, stepped.target.duration + 1e-9, 0.01):
        v_d, omega_d, v_d_dot, omega_d_dot = stepped.step(float(t), 0.01, -5.0)
        s_ref, v_ref, a_ref = prof.state(float(t))
        sign = 1.0 if s_ref < math.pi * R else -1.0
        if sign < 0 and t_jump is None:
            t_jump = t
        assert (v_d, v_d_dot) == (v_ref, a_ref)
        assert omega_d == pytest.approx(sign * v_ref / R, abs=1e-15)
        assert omega_d_dot == pytest.approx(sign * a_ref / R, abs=1e-15)
    # the inflection is reached at half the duration (symmetric profile)
    assert t_jump == pytest.approx(stepped.target.duration / 2.0, abs=0.011)
    v_d, omega_d, _, _ = SteppedTarget(traj="circle", target="static").step(5.0, 1e-3, 0.0)
    assert (v_d, omega_d) == pytest.approx((0.8, 0.8))


def test_static_target_derivative_matches_finite_differences():
    """omega_d_dot = kappa' v_ref^2 + kappa v_ref_dot (cycloid path with the eq. 34 speed)."""
    stepped = SteppedTarget(
        traj="cycloid", target="static", path_options={"speed_profile": "dynamic"}
    )
    assert isinstance(stepped.profile, CycloidDynamicSpeed)
    h = 1e-6
    for t in np.linspace(0.1, T_CYCLOID - 0.1, 37):
        _, w1, _, _ = stepped.step(t + h, h, 0.0)
        _, w0, _, _ = stepped.step(t - h, h, 0.0)
        v_d, omega_d, _, omega_d_dot = stepped.step(t, h, 0.0)
        # central FD error ~ h^2 |omega'''| + 1e-16 / h < 1e-9
        assert omega_d_dot == pytest.approx((w1 - w0) / (2 * h), abs=1e-8)
        s_ref = stepped.profile.distance(t)
        assert omega_d == pytest.approx(stepped.target.path.curvature(s_ref) * v_d, abs=1e-15)


# --- dynamic target --------------------------------------------------------------------------
def _dynamic(traj="cycloid", **kw):
    stepped = SteppedTarget(traj=traj, target="dynamic", **kw)
    assert isinstance(stepped.target, DynamicTarget) and stepped.target.kind == "dynamic"
    return stepped


def test_dynamic_target_integrates_the_measured_speed():
    """omega_d = kappa(s) v with s the trapezoidal integral of a given v history."""
    dt = 1e-3

    def v_meas(t):
        return 0.6 + 0.3 * math.sin(1.7 * t)

    def s_exact(t):
        return 0.6 * t + 0.3 / 1.7 * (1.0 - math.cos(1.7 * t))

    stepped = _dynamic()
    path = stepped.target.path
    n = round(T_CYCLOID / dt)
    for k in range(n + 1):
        t = k * dt
        v = v_meas(t)
        v_d, omega_d, v_d_dot, omega_d_dot = stepped.step(t, dt, v)
        if k == 0:
            assert stepped.state.s == 0.0
        # trapezoidal rule: error <= T dt^2 max|v''| / 12 = 4.7 * 1e-6 * 0.87 / 12 = 3.4e-7
        assert stepped.state.s == pytest.approx(s_exact(t), abs=4e-7)
        s = stepped.state.s
        kappa = path.curvature(s)
        assert omega_d == pytest.approx(kappa * v, rel=1e-14)
        assert v_d == pytest.approx(stepped.profile.speed(t), abs=1e-15)
        assert v_d_dot == pytest.approx(stepped.profile.accel(t), abs=1e-15)
        expected_dot = path.curvature_rate(s) * v * v + kappa * v_d_dot
        assert omega_d_dot == pytest.approx(expected_dot, rel=1e-12, abs=1e-15)
    # the same history from a new record: the same numbers (deterministic)
    first = stepped.state.s
    again = _dynamic()
    for k in range(n + 1):
        again.step(k * dt, dt, v_meas(k * dt))
    assert again.state.s == first


def test_dynamic_target_ignores_the_reference_speed_for_omega():
    """Standing still the yaw target is 0 whatever v_ref says; curvature error = e_omega / v."""
    stepped = _dynamic("s_curve")
    for k in range(3000):
        v_d, omega_d, _, _ = stepped.step(k * 1e-3, 1e-3, 0.0)
        assert omega_d == 0.0
    assert v_d > 0.5
    assert stepped.state.s == 0.0
    stepped = _dynamic("s_curve")
    stepped.step(0.0, 1e-3, 0.4)
    _, omega_d, _, _ = stepped.step(1e-3, 1e-3, 0.4)
    assert omega_d == pytest.approx(0.4 / 1.5)
    # a measured speed that drives past the inflection flips the sign of omega_d
    stepped = _dynamic("s_curve")
    for k in range(int(round(math.pi * 1.5 / 0.8 / 1e-3)) + 2):
        _, omega_d, _, _ = stepped.step(k * 1e-3, 1e-3, 0.8)
    assert stepped.state.s > math.pi * 1.5
    assert omega_d == pytest.approx(-0.8 / 1.5)


def test_dynamic_target_with_perfect_speed_tracking_follows_the_reference():
    """If v = v_ref, s follows s_ref and omega_d = kappa(s_ref) v_ref (the static target)."""
    dyn = _dynamic(path_options={"speed_profile": "static"})
    sta = SteppedTarget(traj="cycloid", target="static")
    dt = 1e-3
    worst = 0.0
    for k in range(round(T_CYCLOID / dt) + 1):
        t = k * dt
        v = sta.profile.speed(t)
        _, w_dyn, _, _ = dyn.step(t, dt, v)
        _, w_sta, _, _ = sta.step(t, dt, v)
        worst = max(worst, abs(w_dyn - w_sta))
    # trapezoid on v = 2 sin(tau/2): s error <= 4.7 * 1e-6 * 0.5 / 12 = 2e-7, times kappa' ~ 1
    assert dyn.state.s == pytest.approx(sta.state.s, abs=3e-7)
    assert worst < 1e-6


def test_logged_curvature_and_scalar_reference_point():
    stepped = _dynamic("s_curve")
    stepped.step(0.0, 1e-3, 0.0)
    assert stepped.state.kappa == pytest.approx(1 / 1.5)  # at rest at the start: kappa(0)
    stepped.step(1e-3, 1e-3, 20.0)  # s = 0.01 m
    assert stepped.state.kappa == pytest.approx(1 / 1.5)
    for k in range(800):
        stepped.step(2e-3 + k * 1e-3, 1e-3, 20.0)
    assert stepped.state.s > math.pi * 1.5
    assert stepped.state.kappa == pytest.approx(-1 / 1.5)
    stepped = SteppedTarget(traj="cycloid", target="static")
    stepped.step(1.0, 1e-3, 0.0)
    assert stepped.state.kappa == stepped.target.path.curvature(stepped.profile.distance(1.0))
    sta = stepped.target
    t = np.linspace(0.0, sta.duration + 1.0, 101)
    xs, ys = sta.reference_point(t)
    for ti, xi, yi in zip(t, xs, ys, strict=True):
        assert sta.reference_point(float(ti)) == pytest.approx((xi, yi), abs=1e-12)


def test_noise_free_reference_signals():
    for kind in ("static", "dynamic"):
        _, target, _ = make_target("cycloid", kind, speed_profile="static")
        t = np.linspace(0.0, T_CYCLOID, 41)
        np.testing.assert_array_equal(target.reference_speed(t), target.profile.speed(t))
        np.testing.assert_allclose(target.reference_yaw_rate(t), -0.5, atol=1e-14)
        for ti in t:
            assert target.reference_speed(float(ti)) == pytest.approx(target.profile.speed(ti))
            assert target.reference_yaw_rate(float(ti)) == pytest.approx(-0.5, abs=1e-14)
    _, circ, _ = make_target("circle", "dynamic")
    assert circ.reference_yaw_rate(5.0) == pytest.approx(0.8)


def test_reference_point():
    path, target, _ = make_target("s_curve", "dynamic")
    assert target.reference_point(0.0) == pytest.approx((0.0, 0.0))
    x, y = target.reference_point(target.duration)
    assert (x, y) == pytest.approx((0.0, 6.0), abs=1e-12)
    t = np.linspace(0.0, target.duration, 7)
    x, y = target.reference_point(t)
    px, py, _ = path.pose(target.profile.distance(t))
    np.testing.assert_array_equal(x, px)
    np.testing.assert_array_equal(y, py)
    # the dynamic cycloid's reference stops 5.04 m along at 3 pi/2
    cpath, cyc, _ = make_target("cycloid", "dynamic")
    assert cyc.reference_point(T_CYCLOID) == pytest.approx(cpath.pose(5.0399)[:2], abs=1e-3)


# --- factory ---------------------------------------------------------------------------------
def test_make_target_defaults():
    setup = make_target("cycloid")
    assert isinstance(setup, targets.TargetSetup)
    path, target, pose = setup
    assert target.kind == "dynamic" and isinstance(target.profile, CycloidDynamicSpeed)
    assert pose == path.start_pose
    _, _, paper_pose = make_target("cycloid", "static", start="paper")
    assert paper_pose == pytest.approx((0.0, 0.0, math.pi / 4.0))
    # the paper starts the S-curve and the circle on their paths (Section 6.3)
    for name in ("s_curve", "circle"):
        path, _, pose = make_target(name, start="paper")
        assert pose == path.start_pose
    path, target, _ = make_target("s_curve")
    assert target.duration == pytest.approx(13.781, abs=1e-3)
    assert make_target("s_curve", duration=10.0).target.duration == 10.0
    path, target, pose = make_target("circle")
    assert target.duration == 10.0
    assert path.length == pytest.approx(6.4)  # 1.02 laps
    assert pose == pytest.approx((1.0, 0.0, math.pi / 2.0))
    path, target, _ = make_target("circle", duration=20.0, R=2.0)
    assert target.profile.total_distance == pytest.approx(0.8 * 18.0)
    assert path.length == pytest.approx(0.8 * 18.0) and path.curvature(1.0) == 0.5
    path, _, _ = make_target("circle", duration=3.0)
    assert path.length == pytest.approx(2.0 * math.pi)  # at least one lap
    _, target, _ = make_target("cycloid", duration=15.0)
    assert target.duration == 15.0


def test_make_target_csv(tmp_path):
    a = np.linspace(0.0, math.pi, 13)
    plain = tmp_path / "arc.csv"
    plain.write_text(
        "x,y\n" + "\n".join(f"{2 * math.cos(q)!r},{2 * math.sin(q)!r}" for q in a) + "\n"
    )
    path, target, pose = make_target(str(plain), "static", cruise=0.5, ramp_time=1.0)
    assert isinstance(target.profile, RampSpeed)
    assert target.profile.peak == 0.5
    assert target.profile.total_distance == pytest.approx(path.length, abs=1e-12)
    assert pose == path.start_pose
    with_v = tmp_path / "arc_v.csv"
    with_v.write_text(
        "x,y,v\n"
        + "\n".join(
            f"{2 * math.cos(q)!r},{2 * math.sin(q)!r},{0.1 + 0.05 * i}" for i, q in enumerate(a)
        )
        + "\n"
    )
    path, target, _ = make_target(str(with_v), "dynamic")
    assert isinstance(target.profile, StationSpeed)
    assert target.profile.total_distance == pytest.approx(path.length, abs=1e-12)
    assert target.profile.speed(0.0) == pytest.approx(0.1)
    assert target.profile.speed(target.duration) == pytest.approx(0.7)


def test_make_target_errors():
    with pytest.raises(ValueError, match=r"kind='open_loop' is not allowed: use 'dynamic' or"):
        make_target("cycloid", "open_loop")
    with pytest.raises(ValueError, match=r"'eight'.*'cycloid', 's_curve', 'circle'"):
        make_target("eight")
    with pytest.raises(ValueError, match=r"R not allowed for path 'cycloid'.*start, speed_profile"):
        make_target("cycloid", R=2.0)
    with pytest.raises(ValueError, match=r"start='origin' is not allowed"):
        make_target("circle", start="origin")
    with pytest.raises(ValueError, match=r"speed_profile='fast'"):
        make_target("cycloid", speed_profile="fast")
    for bad in (0.0, -1.0, math.nan, "10"):
        with pytest.raises(ValueError, match="duration="):
            make_target("s_curve", duration=bad)
    with pytest.raises(ValueError, match=r"cruise=-0\.8"):
        make_target("circle", cruise=-0.8)
    with pytest.raises(ValueError, match="R=0"):
        make_target("circle", R=0.0)
    with pytest.raises(ValueError, match="does not exist"):
        make_target("missing.csv")

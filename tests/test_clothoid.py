"""The clothoid path family (tt_mujoco/reference/paths.py: ClothoidPath, clothoid)."""

import math

import numpy as np
import pytest
from scipy.special import fresnel

from tt_mujoco import run
from tt_mujoco.reference.path_base import read_from_tables
from tt_mujoco.reference.paths import ClothoidPath, clothoid, get_path
from tt_mujoco.sim import Scenario, simulate


def test_the_curvature_runs_linearly_and_continuously_through_the_turn():
    path = clothoid(R=1.5, angle_deg=90.0, transition=1.0, straight=1.0)
    s = np.linspace(0.0, path.length, 20001)
    kappa = path.curvature(s)
    assert np.abs(np.diff(kappa)).max() < 1.5 * (s[1] - s[0]) / (1.5 * 1.0)  # rate 1/(R T)
    assert kappa.max() == pytest.approx(1.0 / 1.5) and kappa[0] == kappa[-1] == 0.0
    assert path.end_pose.heading == pytest.approx(math.pi / 2.0, abs=1e-14)
    # a symmetric left turn of 90 deg ends where x and y are equal
    assert path.end_pose.x == pytest.approx(path.end_pose.y, abs=1e-12)


def test_the_clothoid_is_the_fresnel_integral():
    # On the entry clothoid kappa = a u (a = 1 / (R T)), so the position from its start is
    # sqrt(pi / a) (C, S)(u sqrt(a / pi)). The quadrature (8-point Gauss-Legendre per 1 cm cell)
    # is exact to rounding for so smooth an integrand: measured 1.6e-15 m over the whole
    # clothoid; the bound allows the sum of 100 cells' rounding.
    R, T = 1.5, 1.0
    path = clothoid(R=R, transition=T, straight=1.0)
    scale = math.sqrt(math.pi * R * T)
    u = np.linspace(0.0, T, 101)
    S, C = fresnel(u / scale)
    x, y, heading = path.pose(1.0 + u)
    np.testing.assert_allclose(x, 1.0 + scale * C, rtol=0, atol=1e-13)
    np.testing.assert_allclose(y, scale * S, rtol=0, atol=1e-13)
    np.testing.assert_allclose(heading, u * u / (2.0 * R * T), rtol=0, atol=1e-15)


def test_a_right_turn_mirrors_a_left_one():
    left, right = clothoid(angle_deg=120.0), clothoid(angle_deg=-120.0)
    s = np.linspace(0.0, left.length, 501)
    xl, yl, hl = left.pose(s)
    xr, yr, hr = right.pose(s)
    np.testing.assert_allclose(xr, xl, atol=1e-14)
    np.testing.assert_allclose(yr, -yl, atol=1e-14)
    np.testing.assert_allclose(hr, -hl, atol=1e-14)


def test_the_steps_tables_hold_the_geometry():
    # The step reads the path from its fine cells (as a spline's): the curvature's line is
    # exact there, and the cubic Hermite pose is within h^4 max|r''''| / 384 of the path,
    # about 1e-11 m for 1 cm cells at kappa 1/1.5 (measured 3.5e-11 m).
    path = clothoid()
    assert read_from_tables(path) and path.STEP_KIND == ClothoidPath.STEP_KIND
    s = np.linspace(-0.3, path.length + 0.3, 4001)
    x, y, heading = path.pose(s)
    at = np.array([path.pose_at(float(q)) for q in s])
    assert np.hypot(at[:, 0] - x, at[:, 1] - y).max() < 1e-10
    assert np.abs(at[:, 2] - heading).max() < 1e-12
    rates = np.array([path.curvature_and_rate(float(q)) for q in s])
    np.testing.assert_allclose(rates[:, 0], path.curvature(s), rtol=0, atol=1e-14)
    np.testing.assert_allclose(rates[:, 1], path.curvature_rate(s), rtol=0, atol=1e-12)


def test_a_user_subclass_is_called_back_not_read_from_tables():
    class Shifted(ClothoidPath):
        def curvature_and_rate(self, s):
            return 0.0, 0.0

    path = Shifted("shifted", (0.0, 0.0, 0.0), [(1.0, 0.0, 1.0)])
    assert not read_from_tables(path)


def test_continuous_curvature_asks_no_jump_of_the_yaw_rate():
    # The S-curve's curvature step asks omega_d to jump by 2 v / R = 1.07 rad/s; here its step
    # is v^2 kappa' dt = 0.43 mrad/s per 1 ms step at cruise (0.8 m/s, kappa' = 1/1.5 1/m^2).
    # ISMC-STA then holds the tractor within 0.24 mm rms of the path, against 9.5 mm on the
    # S-curve (docs/controller_comparison.md); the bound allows the solver's changes.
    result = simulate(Scenario(traj="clothoid", disturbance="none"))
    omega_d = result.timeseries["omega_d"]
    assert result.status == "ok" and np.abs(np.diff(omega_d)).max() < 1e-3
    assert result.metrics["cross_track_rms"] < 1e-3


@pytest.mark.parametrize(
    ("options", "match"),
    [
        ({"transition": 3.0}, r"transition=3\.0 is not allowed .* use transition <= 2\.35619"),
        ({"angle_deg": 0.0}, r"angle_deg=0\.0 is not allowed"),
        ({"angle_deg": 400}, r"angle_deg=400 is not allowed"),
        ({"straight": -1.0}, r"straight=-1\.0 are not allowed"),
        ({"R": float("nan")}, r"R=nan is not allowed"),
        ({"radius": 2.0}, r"radius not allowed for path 'clothoid': allowed are R, angle_deg"),
    ],
)
def test_bad_shapes_are_refused_naming_the_value(options, match):
    with pytest.raises(ValueError, match=match):
        get_path("clothoid", **options)


def test_the_command_refuses_a_bad_shape_before_the_run(tmp_path, capsys):
    out = tmp_path / "run"
    argv = ["--traj", "clothoid", "--path-option", "transition=9", "--no-video", "--no-plots"]
    assert run.main([*argv, "--out", str(out)]) == 2
    assert "transition=9" in capsys.readouterr().err and not out.exists()

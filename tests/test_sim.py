"""The closed loop on both plants (issue: closed loop, must-show 2-5)."""

import itertools

import numpy as np
import pytest

from tt_mujoco.sim import Scenario, simulate
from tt_mujoco.sim.build import build

PATHS = ("cycloid", "s_curve", "circle")
CONTROLLERS = ("ismc_sta", "pid", "fbl")
TARGETS = ("dynamic", "static")
PLANTS = ("mujoco", "reduced")


@pytest.fixture(scope="module")
def grid():
    """Every path x controller x target on both plants, paper disturbances, same_path eta.

    Table 3's comparison uses the paper's Section 6.2 ISMC-STA gains for ISMC-STA."""
    results = {}
    for path, ctrl, target, plant in itertools.product(PATHS, CONTROLLERS, TARGETS, PLANTS):
        gains = "paper_6_2" if ctrl == "ismc_sta" else None
        scenario = Scenario(traj=path, controller=ctrl, gains=gains, target=target, plant=plant)
        results[path, ctrl, target, plant] = simulate(scenario)
    return results


def test_every_combination_completes_without_divergence(grid):
    failed = {k: r.message for k, r in grid.items() if r.status != "ok"}
    assert not failed
    for r in grid.values():
        assert r.metrics["finite_samples"] == r.metrics["steps"]
        assert r.metrics["sim_time_s"] == pytest.approx(r.config["target"]["duration_s"], abs=2e-3)


@pytest.mark.parametrize("plant", PLANTS)
def test_ismc_sta_beats_pid_and_fbl_on_cycloid(grid, plant):
    # Paper Table 3. Measured (reduced / MuJoCo), see the issue note for the full table.
    ismc = grid["cycloid", "ismc_sta", "dynamic", plant].metrics
    for other in ("pid", "fbl"):
        m = grid["cycloid", other, "dynamic", plant].metrics
        assert ismc["rmse_v"] < m["rmse_v"]
        assert ismc["rmse_omega"] < m["rmse_omega"]


@pytest.mark.parametrize("plant", PLANTS)
def test_dynamic_target_beats_static_on_s_curve_position(plant):
    # Paper Table 4 (0.0091 vs 0.0261 m), Section 6.1 gains. Ours (measured, MuJoCo / reduced):
    # 0.01412 vs 0.01446 / 0.01417 vs 0.01452 m: a 2.4 % gain, because our static target is the
    # exact time-parameterised reference and ISMC-STA holds v so well that s barely drifts.
    dynamic = simulate(Scenario(traj="s_curve", target="dynamic", plant=plant))
    static = simulate(Scenario(traj="s_curve", target="static", plant=plant))
    assert dynamic.metrics["rmse_position"] < 0.99 * static.metrics["rmse_position"]
    assert dynamic.metrics["max_position"] < static.metrics["max_position"]


@pytest.mark.parametrize("path", ("s_curve", "circle"))
@pytest.mark.parametrize("ctrl", CONTROLLERS)
def test_plants_agree_where_traction_holds(grid, path, ctrl):
    # On the gentle paths the tyres stay far from their traction limit (lateral creep at most
    # 19 mm/s, measured), so contact physics and the reduced ODE should agree: measured
    # relative differences of the position error <= 3.2 % and of e_v <= 2.7 %.
    # Bounds: 15 % / 25 %.
    mj = grid[path, ctrl, "dynamic", "mujoco"].metrics
    rd = grid[path, ctrl, "dynamic", "reduced"].metrics
    assert mj["slip_lateral_max"] < 0.03
    assert mj["rmse_position"] == pytest.approx(rd["rmse_position"], rel=0.15)
    assert mj["rmse_v"] == pytest.approx(rd["rmse_v"], rel=0.25)


def test_paper_eta_jackknifes_forward_and_keeps_partial_results():
    result = simulate(Scenario(traj="s_curve", eta="paper", plant="mujoco"))
    assert result.status == "jackknife"
    assert "jackknife at t=" in result.message
    n = result.metrics["steps"]
    assert 100 < n < 5000  # stopped early (measured at t = 1.13 s), samples kept
    assert len(result.timeseries["t"]) == n


def test_reduced_plant_jackknifes_too():
    result = simulate(Scenario(traj="s_curve", eta="paper", plant="reduced"))
    assert result.status == "jackknife"
    assert result.metrics["steps"] < 5000


def test_user_csv_path_from_rest_offtracking_agrees_with_trailer_cross_track(tmp_path):
    # A new user's path: 3 m straight, then a quarter circle of 1.5 m, started from rest. The
    # trailer's off-tracking (against the tractor's own track) and its cross-track (against the
    # reference path) measure the same thing here, since the tractor holds the path to 0.4 mm:
    # they must agree to a few mm, and neither may count the 0.7 m start spacing (before the
    # fix: off-tracking rms 0.16 m, max 0.70 m). Measured: 7.67 and 7.58 mm rms.
    x = np.concatenate([np.linspace(0, 3, 16), 3 + 1.5 * np.sin(np.linspace(0.1, np.pi / 2, 12))])
    y = np.concatenate([np.zeros(16), 1.5 - 1.5 * np.cos(np.linspace(0.1, np.pi / 2, 12))])
    csv = tmp_path / "user.csv"
    csv.write_text("x,y\n" + "".join(f"{a},{b}\n" for a, b in zip(x, y, strict=True)))
    m = simulate(Scenario(traj=str(csv))).metrics
    assert m["trailer_offtrack_max"] < 0.05
    assert abs(m["trailer_offtrack_rms"] - m["trailer_rmse_lateral"]) < 0.002
    assert m["trailer_offtrack_samples"] == m["trailer_lateral_samples"] > 0


def test_a_mujoco_warning_stops_the_run_before_the_reset_state_is_logged():
    # MuJoCo resets the state when a warning fires: the run stops at the first one, and no row
    # of the reset state (the model's default pose at the origin) is logged. The cycloid starts
    # at (0.078, 0.293), so a reset row would show. Before: warnings were checked every 64
    # steps, and up to 63 reset rows were logged and counted.
    built = build(Scenario(traj="cycloid", duration=1.0))
    # a friction far beyond Params' range (which refuses it), set past the check only to make
    # MuJoCo warn at its first step
    object.__setattr__(built.plant_params, "friction", 1e300)
    result = simulate(built)
    assert result.status == "diverged" and "MuJoCo warning" in result.message
    ts = result.timeseries
    assert 1 <= len(ts["t"]) <= 2  # the steps before the failing one
    assert np.all(np.hypot(ts["x"] - 0.0783, ts["y"] - 0.2929) < 1e-3)

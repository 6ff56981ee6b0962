"""A train of trailers through every route: the stepper and both plants, the CLI's outputs and
video, a config file's [[trailers]] tables, a sweep, and the same seed giving the same numbers."""

from __future__ import annotations

import json
import math
import tomllib

import numpy as np
import pytest

from tt_mujoco import outputs, run
from tt_mujoco.sim import Scenario, simulate
from tt_mujoco.sim.loop.timeseries import COLUMNS, train_columns
from tt_mujoco.sweep import runs as sweep_runs


@pytest.fixture(scope="module")
def circle_runs():
    """3 trailers on the circle for 6 s, no disturbance, on both plants."""
    return {
        plant: simulate(
            Scenario(traj="circle", trailers=3, plant=plant, disturbance="none", duration=6.0)
        )
        for plant in ("mujoco", "reduced")
    }


def test_both_plants_log_every_trailer_and_agree(circle_runs):
    # Measured: every axle P_k within 0.93 mm and every hitch within 4.4e-4 rad between the
    # plants over 6 s (contact creep); beta_k - eta_k phi_k within 5.6e-6 rad in MuJoCo.
    a, b = (circle_runs[p].timeseries for p in ("mujoco", "reduced"))
    etas = circle_runs["mujoco"].scenario.plant_params().etas
    assert train_columns(3) == tuple(
        f"{name}_{k}" for k in (2, 3) for name in ("x0", "y0", "theta0", "phi", "beta", "v0")
    )
    for k in (2, 3):
        gap = np.hypot(a[f"x0_{k}"] - b[f"x0_{k}"], a[f"y0_{k}"] - b[f"y0_{k}"])
        assert gap.max() < 2e-3
        assert np.abs(a[f"phi_{k}"] - b[f"phi_{k}"]).max() < 2e-3
        assert np.abs(a[f"beta_{k}"] - etas[k - 1] * a[f"phi_{k}"]).max() < 1e-4
        assert np.all(b[f"beta_{k}"] == etas[k - 1] * b[f"phi_{k}"])


def test_metrics_per_trailer_and_worst_over_the_train(circle_runs):
    m = circle_runs["mujoco"].metrics
    for k in (2, 3):
        for name in ("offtrack_rms", "offtrack_max", "rmse_lateral", "phi_max_abs_deg"):
            assert math.isfinite(m[f"trailer_{k}_{name}"])
    rms = [m["trailer_offtrack_rms"], m["trailer_2_offtrack_rms"], m["trailer_3_offtrack_rms"]]
    assert m["train_offtrack_rms_worst"] == max(rms)
    assert m["train_phi_max_abs_deg"] >= m["phi_max_abs_deg"]


def test_one_trailer_logs_no_train_columns():
    result = simulate(Scenario(traj="circle", plant="reduced", duration=0.5))
    assert set(result.timeseries) == set(COLUMNS)
    assert not any(k.startswith(("trailer_2", "train_")) for k in result.metrics)


def test_a_jackknife_of_a_trailer_behind_the_first_stops_the_run():
    # Trailer 1 plain and stable forward, trailer 2 with the paper's eta = 3: trailer 2 folds.
    scenario = Scenario(
        traj="s_curve", trailers=2, eta=0.0, train=[{"eta": 3.0}], disturbance="none"
    )
    result = simulate(scenario)
    assert result.status == "jackknife"
    assert "jackknife at t=" in result.message and "hitch 2:" in result.message
    assert len(result.timeseries["phi_2"]) == result.metrics["steps"]


def test_cli_toml_and_sweep_give_the_same_numbers(tmp_path):
    # The same train and seed by the command line, a config file's [[trailers]] tables and a
    # sweep's trailer<k>.<field> options: identical metrics.
    base = ["--traj", "circle", "--plant", "reduced", "--duration", "4", "--noise-snr", "20"]
    flags = ["--no-video", "--no-plots", "--quiet", "--seed", "3"]
    cli_out = tmp_path / "cli"
    config = tmp_path / "train.toml"
    config.write_text(
        'traj = "circle"\nplant = "reduced"\nduration = 4.0\nnoise_snr = 20.0\nseed = 3\n'
        "[[trailers]]\neta = 0.0\n[[trailers]]\nL0 = 0.5\n"
    )
    assert run.main([*base, *flags, "--trailers", "3", "--out", str(cli_out)]) == 0
    toml_out = tmp_path / "toml"
    assert run.main(["--config", str(config), *flags[:3], "--out", str(toml_out)]) == 0
    written = (toml_out / "config.toml").read_text()
    assert tomllib.loads(written)["trailers"] == 3
    assert tomllib.loads(written)["train"] == [{"eta": 0.0}, {"L0": 0.5}]
    toml_metrics = json.loads((toml_out / "metrics.json").read_text())
    assert toml_metrics["config"]["nominal_params"]["train"][0]["eta"] == 0.0
    options = {"traj": "circle", "plant": "reduced", "duration": 4.0, "noise_snr_db": 20.0}
    options |= {"seed": 3, "trailers": 3, "trailer2.eta": 0.0, "trailer3.L0": 0.5}
    swept = sweep_runs.run_one(options)
    for key in ("rmse_v", "trailer_2_offtrack_max", "trailer_3_phi_max_abs_deg"):
        assert swept["metrics"][key] == toml_metrics[key], swept["error"]
    ts = outputs.read_timeseries(cli_out / "timeseries.parquet")
    assert {"x0_3", "y0_3", "theta0_3", "phi_3", "beta_3", "v0_3"} <= set(ts)
    cli_metrics = json.loads((cli_out / "metrics.json").read_text())
    assert cli_metrics["trailer_3_phi_max_abs_deg"] == pytest.approx(
        math.degrees(np.abs(ts["phi_3"]).max())
    )


@pytest.mark.parametrize(
    ("argv", "fragment"),
    [
        (["--trailers", "0"], "--trailers: '0' is not allowed"),
        (["--trailers", "9"], "--trailers: '9' is not allowed"),
    ],
)
def test_bad_train_options_exit_2_naming_the_value(tmp_path, capsys, argv, fragment):
    out = tmp_path / "bad"
    assert run.main([*argv, "--out", str(out), "--quiet", "--no-video"]) == 2
    assert fragment in capsys.readouterr().err
    assert not out.exists()


def test_video_shows_every_trailer_and_trace(tmp_path):
    from tt_mujoco.viz.render import RunRenderer, RunScene, VideoFormat

    result = simulate(
        Scenario(traj="s_curve", trailers=3, plant="reduced", disturbance="none", duration=2.0)
    )
    params = result.scenario.plant_params()
    scene = RunScene(params, result.reference_polyline)
    with RunRenderer(result.timeseries, scene, VideoFormat(160, 120)) as r:
        frame = r.n_frames - 1
        r.render_frame(frame)
        # One trace per axle (P, P0, P0_2, P0_3), in four colours.
        assert len(r._units) == 4
        assert len({tuple(c) for c in r._unit_rgba}) == 4
        image = r.render_frame(frame, rewrite=True)
    assert image.shape == (120, 160, 3)
    camera = r.camera_at(frame)
    mid = 0.5 * (result.timeseries["x"][-1] + result.timeseries["x0_3"][-1])
    assert camera["lookat"][0] == pytest.approx(mid, abs=0.05)


def test_scheduled_steering_puts_every_trailer_on_the_circle():
    # The exact gains of the circle's curvature (R = 1.5 m) for all three trailers against the
    # constant small-curvature limits: the reduced plant's steady off-tracking of trailer 3 falls
    # from 0.97 mm (the limit's kappa^3 term, docs/model.md Section 12) to 0.3 um (measured).
    common = dict(traj="circle", trailers=3, plant="reduced", disturbance="none", duration=20.0)
    common["path_options"] = {"R": 1.5}
    fixed = simulate(Scenario(**common))
    scheduled = simulate(Scenario(**common, eta_schedule=True))
    assert scheduled.status == fixed.status == "ok"
    steady = fixed.timeseries["t"] > 15.0
    radius = {
        name: np.hypot(r.timeseries["x0_3"], r.timeseries["y0_3"])[steady] - 1.5
        for name, r in (("fixed", fixed), ("scheduled", scheduled))
    }
    assert np.abs(radius["fixed"]).mean() > 5e-4
    assert np.abs(radius["scheduled"]).mean() < 1e-5

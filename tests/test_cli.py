"""CLI smoke tests: outputs exist, and agree with metrics recomputed from the time series."""

import json
import subprocess
import sys

import numpy as np
import pytest

from tt_mujoco import outputs, run
from tt_mujoco.analysis import metrics
from tt_mujoco.reference import paths


@pytest.fixture(scope="module")
def s_curve_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("cli") / "run"
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "tt_mujoco.run",
            "--traj",
            "s_curve",
            "--no-video",
            "--quiet",
            "--duration",
            "6",
            "--out",
            str(out),
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    return out, proc


def test_cli_writes_outputs(s_curve_run):
    out, proc = s_curve_run
    assert proc.returncode == 0, proc.stderr
    for name in ("metrics.json", "timeseries.parquet", "path.png", "errors.png"):
        assert (out / name).stat().st_size > 0, name
    assert "rmse_position" in proc.stdout  # the printed summary table
    doc = json.loads((out / "metrics.json").read_text())
    for key in (
        "rmse_v",
        "max_abs_v",
        "rmse_omega",
        "max_abs_omega",
        "rmse_lateral",
        "max_lateral",
        "rmse_position",
        "max_position",
        "trailer_rmse_lateral",
        "trailer_offtrack_rms",
        "eq_violation_max",
        "slip_lateral_max",
        "torque_saturation_fraction",
        "steps",
        "sim_time_s",
        "wall_time_s",
    ):
        assert key in doc, key
    assert doc["config"]["scenario"]["traj"] == "s_curve"
    assert doc["status"] == "ok"
    # every note is one line on the console and an entry in metrics.json, the same words
    printed = [line[6:] for line in proc.stdout.splitlines() if line.startswith("note: ")]
    assert printed == doc["notes"]


def test_a_run_the_python_loop_takes_says_why(tmp_path):
    # a short run takes the Python loop: the console and metrics.json say so, with the reason
    out = tmp_path / "short"
    proc = subprocess.run(
        [
            *(sys.executable, "-m", "tt_mujoco.run", "--traj", "circle", "--duration", "0.5"),
            *("--no-video", "--no-plots", "--out", str(out)),
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    notes = json.loads((out / "metrics.json").read_text())["notes"]
    assert len(notes) == 1 and "Python loop ran" in notes[0] and "500 control steps" in notes[0]
    assert f"note: {notes[0]}" in proc.stdout.splitlines()


def test_metrics_agree_with_timeseries(s_curve_run):
    out, _ = s_curve_run
    doc = json.loads((out / "metrics.json").read_text())
    ts = outputs.read_timeseries(out / "timeseries.parquet")
    again = metrics.compute_metrics(ts, paths.get_path("s_curve").dense(), 15.0)
    for key, value in again.items():
        if isinstance(value, float) and np.isfinite(value):
            # The CSV holds every float with repr precision: agreement is exact up to
            # summation order.
            assert doc[key] == pytest.approx(value, rel=1e-12, abs=1e-15), key
    assert len(ts["t"]) == doc["steps"]


def test_cli_refuses_to_overwrite(s_curve_run):
    out, _ = s_curve_run
    before = (out / "metrics.json").read_bytes()
    code = run.main(["--traj", "s_curve", "--no-video", "--quiet", "--out", str(out)])
    assert code == 2
    assert (out / "metrics.json").read_bytes() == before


def test_cli_jackknife_exit_code(tmp_path):
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "tt_mujoco.run",
            "--traj",
            "s_curve",
            "--eta",
            "paper",
            "--no-video",
            "--no-plots",
            "--quiet",
            "--out",
            str(tmp_path / "jk"),
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 3
    assert "jackknife at t=" in proc.stderr
    assert "Traceback" not in proc.stderr
    # What was computed is kept.
    assert (tmp_path / "jk" / "timeseries.parquet").stat().st_size > 0
    assert json.loads((tmp_path / "jk" / "metrics.json").read_text())["status"] == "jackknife"


def test_help_lists_every_option():
    text = run.build_parser().format_help()
    for opt in (
        "--traj",
        "--controller",
        "--target",
        "--plant",
        "--eta",
        "--no-disturbance",
        "--noise-snr",
        "--param-scale",
        "--duration",
        "--seed",
        "--out",
        "--no-video",
    ):
        assert opt in text


def test_cli_steering_and_feedback_options_reach_the_scenario(tmp_path):
    out = tmp_path / "opts"
    code = run.main(
        [
            "--traj",
            "circle",
            "--plant",
            "reduced",
            "--duration",
            "2",
            "--eta",
            "scheduled",
            "--path-feedback",
            "--no-video",
            "--no-plots",
            "--quiet",
            "--out",
            str(out),
        ]
    )
    assert code == 0
    doc = json.loads((out / "metrics.json").read_text())
    scenario = doc["config"]["scenario"]
    assert scenario["eta_schedule"] == "curvature"
    assert scenario["path_feedback"] == {}
    assert scenario["reverse"] is False
    # The scheduled gain at kappa = 1 is the exact same-path gain, not the constant -1/7.
    ts = outputs.read_timeseries(out / "timeseries.parquet")
    assert ts["beta"][-1] / ts["phi"][-1] == pytest.approx(-0.14714, abs=1e-4)
    # config.toml repeats it.
    again = tmp_path / "again"
    assert run.main(["--config", str(out / "config.toml"), "--out", str(again)]) == 0
    assert (again / "timeseries.parquet").read_bytes() == (out / "timeseries.parquet").read_bytes()


def test_a_run_without_figures_imports_no_plotting_and_no_pandas(tmp_path):
    # docs/performance.md: start-up sets a short run's time, so the CLI imports matplotlib only
    # where it draws, never pandas (pa.array would), and a CSV path's SciPy parts only for one.
    out = tmp_path / "run"
    code = (
        "import sys; from tt_mujoco import run; "
        f"assert run.main(['--plant', 'reduced', '--duration', '3', '--no-video', '--no-plots', "
        f"'--quiet', '--out', {str(out)!r}]) == 0; "
        "print(sorted(m for m in ('matplotlib', 'pandas', 'scipy.interpolate', 'scipy.integrate') "
        "if m in sys.modules))"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120
    )
    assert done.stdout.strip().splitlines()[-1] == "[]", done.stdout
    assert (out / "timeseries.parquet").is_file() and (out / "metrics.json").is_file()

"""The sensors' delay (Scenario.sensor_delay, --sensor-delay): what the loops see, and when."""

import json
import subprocess
import sys

import numpy as np
import pytest
from tt_mujoco.controllers import Controller

from tt_mujoco import run
from tt_mujoco.sim import Scenario, build, simulate


class Recorder(Controller):
    """Drive with a constant push and log what was seen."""

    name = "recorder"

    def compute(self, t, measurement, reference):
        self.log("seen_x", measurement.x)
        self.log("seen_v", measurement.v)
        return 1.0, 0.8


@pytest.mark.parametrize("plant", ["mujoco", "reduced"])
def test_the_controller_sees_the_readings_of_the_delay_ago(plant):
    scenario = Scenario(
        controller=f"{__file__}:Recorder", traj="circle", duration=0.5, plant=plant,
        disturbance="none", sensor_delay=0.02,
    )  # fmt: skip
    ts = simulate(scenario).timeseries
    d = 20
    np.testing.assert_array_equal(ts["ctrl_seen_x"][d:], ts["x"][:-d])
    np.testing.assert_array_equal(ts["ctrl_seen_v"][d:], ts["v"][:-d])
    assert (ts["ctrl_seen_x"][:d] == ts["x"][0]).all()  # the first reading until then
    np.testing.assert_array_equal(ts["v_meas"], ts["ctrl_seen_v"])


def test_no_delay_leaves_the_run_as_it_was():
    base = {"traj": "circle", "duration": 0.5, "noise_snr_db": 25.0, "seed": 2}
    a = simulate(Scenario(**base)).timeseries
    b = simulate(Scenario(sensor_delay=0.0, **base)).timeseries
    for name in a:
        np.testing.assert_array_equal(a[name], b[name])


@pytest.mark.parametrize(
    ("delay", "named"),
    [(-0.01, "-0.01"), (0.0125, "whole multiple"), (2.0, "shorter than the run"),
     (float("nan"), "nan")],
)  # fmt: skip
def test_a_bad_delay_is_refused(delay, named):
    with pytest.raises(ValueError, match="sensor_delay") as err:
        build(Scenario(traj="circle", duration=1.0, sensor_delay=delay))
    assert named in str(err.value)


def test_the_cli_refuses_a_delay_longer_than_the_run(tmp_path, capsys):
    out = tmp_path / "r"
    argv = ["--sensor-delay", "5", "--duration", "1", "--no-video", "--no-plots", "--out", str(out)]
    assert run.main(argv) == 2
    assert "sensor_delay=5.0 s" in capsys.readouterr().err and not out.exists()


def test_ismc_sta_holds_the_s_curve_with_a_20_ms_delay(tmp_path):
    # Measured (MuJoCo, no disturbance): cross-track rms 9.5 mm without a delay, 9.8 mm with 20 ms.
    out = tmp_path / "delay"
    args = ["--traj", "s_curve", "--no-disturbance", "--sensor-delay", "0.02", "--no-video"]
    args += ["--no-plots", "--quiet", "--out", str(out)]
    done = subprocess.run([sys.executable, "-m", "tt_mujoco.run", *args], capture_output=True)
    assert done.returncode == 0, done.stderr
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["status"] == "ok" and metrics["cross_track_rms"] < 0.015
    assert metrics["config"]["scenario"]["sensor_delay"] == 0.02

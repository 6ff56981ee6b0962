"""The DC motor actuator (tt_mujoco/sim/parts/motors.py): its lag, its limits, on every route."""

import json
import math
import subprocess
import sys

import pytest
from tt_mujoco.controllers import Controller

from tt_mujoco import run
from tt_mujoco.sim import Scenario, build, simulate
from tt_mujoco.sim.parts.motors import DcMotors, available_torque
from tt_mujoco.vehicle.params import Params


class Step(Controller):
    """A torque step at t = 0: ``level`` N m on both wheels."""

    name = "step"
    PRESETS = {"default": {"level": 5.0}}  # noqa: RUF012

    def compute(self, t, measurement, reference):
        return self._gains["level"], self._gains["level"]


def _step(level: float, params=None, plant: str = "mujoco"):
    scenario = Scenario(
        controller=f"{__file__}:Step", gains={"level": level}, actuator="dc_motor",
        disturbance="none", duration=0.1, plant=plant, params=params or {},
    )  # fmt: skip
    return simulate(scenario)


@pytest.mark.parametrize("plant", ["mujoco", "reduced"])
def test_a_torque_step_reaches_63_percent_after_the_time_constant(plant):
    result = _step(5.0, plant=plant)
    ts = result.timeseries
    lag = Params().motor_lag
    k = round(lag / result.scenario.control_dt) - 1  # the torque over the step ending at lag
    assert ts["T_r"][k] == pytest.approx(5.0 * (1 - math.exp(-1)), rel=0.05)
    assert ts["T_r_cmd"][k] == 5.0 and ts["T_r"][-1] == pytest.approx(5.0, rel=1e-6)


def test_at_the_current_limit_the_motor_gives_the_limit():
    params = {"motor_current_limit": 10.0}  # 10 A x 0.5 N m/A = 5 N m at the wheel
    ts = _step(12.0, params).timeseries
    assert ts["T_r"][-1] == pytest.approx(5.0, rel=1e-6)  # 20 lags: e^-20 of the step left
    assert max(ts["T_r"]) <= 5.0 + 1e-12


def test_the_supply_voltage_limits_the_torque_at_speed():
    p = Params()
    per_amp = p.motor_gear * p.motor_kt
    assert available_torque(0.0, p) == (15.0, 15.0)
    # where the back-EMF eats the supply, driving on gets nothing and braking gets the limit
    stall = p.motor_voltage / (p.motor_kt * p.motor_gear)
    assert available_torque(stall, p) == (0.0, 15.0)
    # in between: what the voltage left over the resistance drives
    omega = 0.9 * stall
    expected = per_amp * (p.motor_voltage - p.motor_kt * p.motor_gear * omega) / p.motor_resistance
    assert available_torque(omega, p)[0] == pytest.approx(min(15.0, expected))
    assert available_torque(-omega, p) == available_torque(omega, p)[::-1]


def test_the_lag_is_exact_over_a_step():
    p = Params(motor_lag=0.02)
    motors = DcMotors(p, 0.001)
    for k in range(1, 41):
        T_r, T_l = motors.deliver(2.0, -2.0, 0.0, 0.0)
        assert T_r == pytest.approx(2.0 * (1 - math.exp(-k * 0.001 / 0.02)), rel=1e-12)
        assert T_l == -T_r


def test_bad_actuator_values_are_refused(tmp_path, capsys):
    with pytest.raises(ValueError, match="actuator='servo' is not allowed"):
        build(Scenario(actuator="servo"))
    out = tmp_path / "r"
    base = ["--no-video", "--no-plots", "--out", str(out)]
    assert run.main(["--actuator", "servo", *base]) == 2
    assert "'servo'" in capsys.readouterr().err and not out.exists()
    assert run.main(["--actuator", "dc_motor", "--param", "motor_lag=-0.01", *base]) == 2
    assert "motor_lag=-0.01" in capsys.readouterr().err and not out.exists()


def test_the_cli_and_the_sweep_give_the_api_numbers(tmp_path):
    options = {"traj": "circle", "duration": 0.5, "actuator": "dc_motor", "plant": "reduced"}
    direct = simulate(Scenario(**options)).metrics["rmse_v"]
    cli = tmp_path / "cli"
    args = ["--traj", "circle", "--duration", "0.5", "--actuator", "dc_motor", "--plant"]
    args += ["reduced", "--no-video", "--no-plots", "--quiet", "--out", str(cli)]
    done = subprocess.run([sys.executable, "-m", "tt_mujoco.run", *args], capture_output=True)
    assert done.returncode == 0, done.stderr
    assert json.loads((cli / "metrics.json").read_text())["rmse_v"] == direct
    sweep = tmp_path / "sweep"
    args = ["traj=circle", "duration=0.5", "actuator=dc_motor", "plant=reduced", "seed=0"]
    done = subprocess.run(
        [sys.executable, "-m", "tt_mujoco.sweep", *args, "--repeats", "1", "--out", str(sweep)],
        capture_output=True,
    )
    assert done.returncode == 0, done.stderr
    assert "dc_motor" in (sweep / "runs.csv").read_text()


def test_the_defaults_give_the_torque_limit_up_to_84_rad_per_s():
    # docs/model.md Section 17 quotes 84 rad/s, 1.68 m/s on the paper's wheels
    p = Params()
    assert available_torque(83.99, p)[0] == 15.0 > available_torque(84.01, p)[0]
    assert f"{84 * p.r:.2f}" == "1.68"

"""The ground's grade (tt_mujoco/sim/parts/terrain.py): gravity in the plane's frame, on every
route."""

import csv
import json
import math
import subprocess
import sys

import numpy as np
import pytest
from tt_mujoco.controllers import Controller

from tt_mujoco import run
from tt_mujoco.sim import Scenario, build, simulate
from tt_mujoco.sim.parts.terrain import GRAVITY, Terrain, parse_terrain
from tt_mujoco.vehicle.params import Params


class Zero(Controller):
    """No torque: the vehicle is left to the grade."""

    name = "zero"

    def compute(self, t, measurement, reference):
        return 0.0, 0.0


class Hold(Controller):
    """Hold the tractor where it stands: a PID law on its travel along its heading (N, per
    wheel pair, turned into two equal wheel torques)."""

    name = "hold"

    def reset(self):
        self.travel = self.area = 0.0

    def compute(self, t, measurement, reference):
        dt = self.setup.control_dt
        self.travel += measurement.v * dt
        self.area += self.travel * dt
        force = -(2500.0 * measurement.v + 20000.0 * self.travel + 40000.0 * self.area)
        return force * self.setup.params.r / 2.0, force * self.setup.params.r / 2.0


def test_parse_terrain_reads_back_its_spec():
    assert parse_terrain("flat").flat
    terrain = parse_terrain(" slope : 5 : 90 ")
    assert (terrain.grade_deg, terrain.heading_deg) == (5.0, 90.0)
    assert parse_terrain(terrain.spec()) == terrain
    assert parse_terrain("slope:3") == Terrain(3.0, 0.0)


@pytest.mark.parametrize(
    ("text", "named"),
    [("slope:90", "90.0 deg"), ("slope:-1", "-1.0 deg"), ("slope:abc", "'slope:abc'"),
     ("hill:5", "'hill:5'"), ("slope:5:nan", "nan"), ("slope", "'slope'")],
)  # fmt: skip
def test_bad_terrain_is_refused_naming_the_value(text, named):
    with pytest.raises(ValueError, match="is not allowed") as err:
        parse_terrain(text)
    assert named in str(err.value)


@pytest.mark.parametrize(("grade", "heading"), [(0.0, 0.0), (10.0, 0.0), (20.0, 135.0)])
def test_gravity_keeps_its_magnitude_and_pulls_down_the_fall_line(grade, heading):
    g = np.array(Terrain(grade, heading).gravity)
    assert np.linalg.norm(g) == pytest.approx(GRAVITY, rel=1e-12)
    rise = np.array([math.cos(math.radians(heading)), math.sin(math.radians(heading)), 0.0])
    assert g @ rise == pytest.approx(-GRAVITY * math.sin(math.radians(grade)), abs=1e-12)


def _rolling(terrain: str, controller: type, duration: float = 2.0):
    # the circle starts at (1, 0) heading +y; a grade rising along 270 deg falls along +y
    scenario = Scenario(
        controller=f"{__file__}:{controller.__name__}", traj="circle", start="paper",
        disturbance="none", duration=duration, terrain=terrain,
    )  # fmt: skip
    return simulate(scenario)


def test_a_vehicle_left_on_a_10_degree_grade_rolls_down_as_a_rolling_body_does():
    # A train on pure rolling wheels: m_total a = m_total g sin(grade) - (4 Iw / r^2) a, so
    # a = g sin(grade) m_total / (m_total + 4 Iw / r^2). Measured: 0.42262 against 0.42267
    # (0.01 %); the bound is 2 %.
    result = _rolling("slope:10:270", Zero)
    assert result.status == "ok"
    ts = result.timeseries
    slope = np.polyfit(ts["t"][100:], ts["v"][100:], 1)[0]
    p = Params()
    mass = p.Mf + p.Mr + 4 * p.Mw + p.Mc1 + p.Mc2
    expected = GRAVITY * math.sin(math.radians(10.0)) * mass / (mass + 4 * p.Iw / p.r**2)
    assert slope == pytest.approx(expected, rel=0.02)
    assert (f"{slope:.5f}", f"{expected:.4f}") == ("0.42262", "0.4227")  # docs/model.md 16
    assert abs(ts["theta"][-1] - math.pi / 2) < 1e-6  # straight down the fall line


def test_held_by_its_controller_it_stays():
    result = _rolling("slope:10:270", Hold, duration=4.0)
    ts = result.timeseries
    assert result.status == "ok"
    travel = np.hypot(ts["x"] - ts["x"][0], ts["y"] - ts["y"][0])
    assert travel.max() < 5e-3 and travel[-1] < 5e-4 and abs(ts["v"][-1]) < 1e-3
    # the torque it takes: the weight's pull along the grade on the wheels' radius
    p = Params()
    mass = p.Mf + p.Mr + 4 * p.Mw + p.Mc1 + p.Mc2
    pull = mass * GRAVITY * math.sin(math.radians(10.0)) * p.r
    assert (ts["T_r"][-1] + ts["T_l"][-1]) == pytest.approx(-pull, rel=0.02)
    assert f"{pull:.3f}" == "1.124"  # docs/model.md Section 16


def test_ismc_sta_tracks_the_s_curve_on_a_5_degree_grade():
    # The grade rising along the S-curve's start (heading 0). Measured: 9.4 mm rms (flat ground:
    # 9.5 mm); the bound is 2 cm.
    result = simulate(Scenario(traj="s_curve", terrain="slope:5:0", disturbance="none"))
    assert result.status == "ok"
    assert result.metrics["cross_track_rms"] < 0.02
    assert f"{1e3 * result.metrics['cross_track_rms']:.1f}" == "9.4"  # docs/scenarios.md
    report = result.metrics["terrain"]
    assert report["grade_deg"] == 5.0
    assert report["equivalent_delta1"] == pytest.approx(GRAVITY * math.sin(math.radians(5)))
    assert math.isfinite(report["torque_sum_mean"])


def test_the_reduced_plant_refuses_a_grade():
    with pytest.raises(ValueError, match="flat ground only"):
        build(Scenario(plant="reduced", terrain="slope:5"))


def test_the_cli_refuses_a_bad_grade_and_writes_nothing(tmp_path, capsys):
    out = tmp_path / "run"
    argv = ["--terrain", "slope:90", "--no-video", "--no-plots", "--out", str(out)]
    assert run.main(argv) == 2
    assert "90.0 deg" in capsys.readouterr().err and not out.exists()


@pytest.mark.parametrize("terrain", ["slope:8:45", "rough:0.01:0.5:2"])
def test_every_route_gives_the_same_numbers(tmp_path, terrain):
    options = {"traj": "circle", "duration": 1.0, "terrain": terrain, "seed": 4}
    direct = simulate(Scenario(noise_snr_db=30.0, **options)).metrics["rmse_v"]
    toml = tmp_path / "s.toml"
    toml.write_text(
        f'traj = "circle"\nduration = 1.0\nterrain = "{terrain}"\nseed = 4\nnoise_snr_db = 30.0\n'
    )
    cli = tmp_path / "cli"
    args = ["--config", str(toml), "--no-video", "--no-plots", "--quiet", "--out", str(cli)]
    done = subprocess.run([sys.executable, "-m", "tt_mujoco.run", *args], capture_output=True)
    assert done.returncode == 0, done.stderr
    assert json.loads((cli / "metrics.json").read_text())["rmse_v"] == direct
    sweep = tmp_path / "sweep"
    args = ["traj=circle", "duration=1", f"terrain={terrain}", "noise_snr_db=30"]
    args += ["--repeats", "1", "--out", str(sweep)]
    done = subprocess.run([sys.executable, "-m", "tt_mujoco.sweep", *args], capture_output=True)
    assert done.returncode == 0, done.stderr
    with open(sweep / "runs.csv") as f:
        row = next(csv.DictReader(f))
    assert row["terrain"] == terrain
    again = {**options, "seed": int(row["seed"])}
    assert float(row["rmse_v"]) == simulate(Scenario(noise_snr_db=30.0, **again)).metrics["rmse_v"]
    pytest.importorskip("gymnasium")
    from tt_mujoco.gym_env import TractorTrailerEnv

    env = TractorTrailerEnv(terrain=terrain, traj="circle", plant="mujoco", duration=1.0)
    env.reset(seed=0)
    model, built = env._stepper.plant.model, env._stepper.built
    if terrain.startswith("slope"):
        np.testing.assert_allclose(model.opt.gravity, Terrain(8, 45).gravity)
    else:  # the run's own ground, placed as the CLI's run placed it
        assert np.array_equal(
            model.hfield_data, build(Scenario(**options)).new_plant().model.hfield_data
        )
        assert built.relief.heights.size == model.hfield_data.size

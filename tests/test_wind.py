"""Wind on the bodies (tt_mujoco/sim/parts/wind.py): the drag law, the gusts, a push that physics
says."""

import math
import subprocess
import sys

import numpy as np
import pytest
from tt_mujoco.controllers import Controller

from tt_mujoco import run
from tt_mujoco.sim import Scenario, build, simulate
from tt_mujoco.sim.parts.wind import AIR_DENSITY, GUST_TIME, Wind, drag_force, parse_wind
from tt_mujoco.vehicle.params import Params


class Zero(Controller):
    name = "zero"

    def compute(self, t, measurement, reference):
        return 0.0, 0.0


def test_parse_wind_reads_back_its_spec():
    assert parse_wind("none").calm
    wind = parse_wind("8:90:2")
    assert (wind.speed, wind.direction_deg, wind.gust_std) == (8.0, 90.0, 2.0)
    assert parse_wind(wind.spec()) == wind and parse_wind("5") == Wind(5.0, 0.0, 0.0)


@pytest.mark.parametrize(
    ("text", "named"),
    [("-3", "-3.0 m/s"), ("100", "100.0 m/s"), ("5:x", "'5:x'"), ("5:0:-1", "-1.0 m/s"),
     ("1:2:3:4", "'1:2:3:4'"), ("inf", "inf")],
)  # fmt: skip
def test_bad_wind_is_refused_naming_the_value(text, named):
    with pytest.raises(ValueError, match="is not allowed") as err:
        parse_wind(text)
    assert named in str(err.value)


def test_drag_is_quadratic_in_the_air_speed_relative_to_the_body():
    fx, fy = drag_force(10.0, 0.0, 2.0, -6.0, 0.05)
    rel = np.array([8.0, 6.0])
    np.testing.assert_allclose([fx, fy], 0.5 * AIR_DENSITY * 0.05 * 10.0 * rel, rtol=1e-12)
    assert drag_force(3.0, 4.0, 3.0, 4.0, 0.05) == (0.0, 0.0)


def test_gusts_have_their_std_and_time_constant():
    dt = 0.01
    speeds = Wind(5.0, 0.0, 2.0).speeds(np.random.default_rng(3), 400_000, dt)
    gust = speeds - 5.0
    assert gust.std() == pytest.approx(2.0, rel=0.03)  # 4000 s: about 2000 independent gusts
    lag = round(GUST_TIME / dt)
    correlation = np.corrcoef(gust[:-lag], gust[lag:])[0, 1]
    assert correlation == pytest.approx(math.exp(-1), abs=0.03)


def test_a_parked_vehicle_is_pushed_as_its_drag_and_inertia_say():
    # At rest in a 20 m/s wind along its heading (the circle starts heading +y), the drag on
    # both bodies pushes the train, whose inertia along its heading is m + 4 Iw / r^2.
    scenario = Scenario(
        controller=f"{__file__}:Zero", traj="circle", start="paper", disturbance="none",
        duration=0.3, wind="20:90",
    )  # fmt: skip
    ts = simulate(scenario).timeseries
    p = Params()
    force = 0.5 * AIR_DENSITY * (p.drag_area_tractor + p.drag_area_trailer) * 20.0**2
    mass = p.Mf + p.Mr + 4 * p.Mw + p.Mc1 + p.Mc2 + 4 * p.Iw / p.r**2
    accel = np.polyfit(ts["t"][:100], ts["v"][:100], 1)[0]
    assert accel == pytest.approx(force / mass, rel=0.02)
    assert (f"{force:.1f}", f"{mass:g}") == ("17.2", "133")  # docs/model.md Section 18


def test_the_same_seed_gives_the_same_gusts_and_another_seed_others():
    base = {"traj": "circle", "duration": 0.5, "disturbance": "none", "wind": "10:0:4"}
    a = simulate(Scenario(seed=1, **base)).timeseries["omega"]
    b = simulate(Scenario(seed=1, **base)).timeseries["omega"]
    c = simulate(Scenario(seed=2, **base)).timeseries["omega"]
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)


def test_wind_leaves_the_noise_stream_as_it_was():
    base = {"traj": "circle", "duration": 0.5, "noise_snr_db": 20.0, "seed": 5}
    calm = simulate(Scenario(**base)).timeseries
    windy = simulate(Scenario(wind="0:0:1", **base)).timeseries
    # the same draws: v_meas - v agrees to the round-off of subtracting different speeds
    np.testing.assert_allclose(
        calm["v_meas"] - calm["v"], windy["v_meas"] - windy["v"], rtol=0, atol=1e-14
    )


def test_bad_wind_is_refused_before_the_run(tmp_path, capsys):
    with pytest.raises(ValueError, match="no aerodynamics"):
        build(Scenario(plant="reduced", wind="5"))
    out = tmp_path / "r"
    assert run.main(["--wind", "-2", "--no-video", "--no-plots", "--out", str(out)]) == 2
    assert "-2.0 m/s" in capsys.readouterr().err and not out.exists()
    sweep = tmp_path / "s"
    args = ["traj=circle", "duration=0.3", "wind=4:90:1", "--repeats", "1", "--out", str(sweep)]
    done = subprocess.run([sys.executable, "-m", "tt_mujoco.sweep", *args], capture_output=True)
    assert done.returncode == 0, done.stderr
    assert "4:90:1" in (sweep / "runs.csv").read_text()


def test_a_negative_drag_area_is_refused_naming_it(tmp_path, capsys):
    out = tmp_path / "r"
    argv = ["--wind", "5", "--param", "drag_area_trailer=-0.1", "--no-video", "--no-plots"]
    assert run.main([*argv, "--out", str(out)]) == 2
    assert "drag_area_trailer=-0.1" in capsys.readouterr().err and not out.exists()


def test_a_lever_gives_the_drag_a_yaw_moment_about_the_centre_of_mass():
    from tt_mujoco.sim.parts.wind import drag_moment

    assert drag_moment(0.5, 0.0, 0.0, 10.0) == pytest.approx(5.0)  # a side force ahead: +z
    assert drag_moment(0.5, math.pi / 2, 10.0, 0.0) == pytest.approx(-5.0)
    assert drag_moment(0.0, 1.0, 3.0, 4.0) == 0.0
    assert drag_moment(-0.2, 0.0, 7.0, 0.0) == 0.0  # along the heading: no moment


def test_the_wind_moment_reaches_the_bodies_and_turns_a_parked_tractor_its_way(monkeypatch):
    from tt_mujoco.sim.parts import wind

    seen = []
    blow = wind.blow_of  # what CPython's step calls (the controller is a class)

    def watched(mj, wrench, gusts):
        blow(mj, wrench, gusts)
        tractor, trailer = gusts[:3].tolist(), gusts[3:].tolist()
        seen.append((tractor, trailer, mj.xfrc_applied[mj.tractor_body, 5]))

    monkeypatch.setattr(wind, "blow_of", watched)
    base = {  # the wind blows across the circle's start heading (+y)
        "controller": f"{__file__}:Zero", "traj": "circle", "start": "paper",
        "disturbance": "none", "duration": 0.5, "wind": "20:0",
    }  # fmt: skip
    plain = simulate(Scenario(**base)).timeseries
    assert all(t[2] == 0.0 and tr[2] == 0.0 for t, tr, _ in seen)  # no lever, no moment
    seen.clear()
    turned = {}
    for lever in (0.2, -0.2):
        ts = simulate(Scenario(**base, params={"drag_centre_tractor": lever})).timeseries
        tractor, _, applied = seen[-1]
        assert applied == tractor[2] != 0.0
        turned[lever] = ts["theta"][-1] - plain["theta"][-1]
    # Wind toward +x on a tractor heading +y pushes a point ahead of it clockwise.
    assert turned[0.2] < 0.0 < turned[-0.2]
    np.testing.assert_array_equal(
        simulate(Scenario(**base, params={"drag_centre_tractor": 0.0})).timeseries["theta"],
        plain["theta"],
    )


def test_a_lever_beyond_reason_is_refused_naming_it():
    with pytest.raises(ValueError, match=r"drag_centre_trailer=20\.0 is not allowed"):
        Params(drag_centre_trailer=20.0)

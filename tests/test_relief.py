"""A ramp and a rough ground (tt_mujoco/sim/parts/relief.py): the scene's geoms are the height
function, the vehicle rests on every wheel, the physics of the climb, every route."""

import math

import mujoco
import numpy as np
import pytest

from tt_mujoco import run
from tt_mujoco.sim import Scenario, build, simulate
from tt_mujoco.sim.build import drawn_polyline
from tt_mujoco.sim.parts.physics import Vehicle, wheel_geoms
from tt_mujoco.sim.parts.relief import (
    MAX_RELIEF_NODES,
    SAMPLES_PER_WAVELENGTH,
    RampRelief,
    RoughRelief,
)
from tt_mujoco.sim.parts.terrain import GRAVITY, Ramp, Rough, parse_terrain
from tt_mujoco.vehicle.mjcf import vehicle_xml
from tt_mujoco.vehicle.params import Params
from tt_mujoco.viz.scene import pose_vehicle


def _relief(terrain: str, traj: str = "s_curve", trailers: int = 1):
    built = build(Scenario(traj=traj, terrain=terrain, trailers=trailers))
    return built, built.relief


def test_specs_read_back():
    assert parse_terrain(" ramp : 2 : 5 ") == Ramp(2.0, 5.0)
    assert parse_terrain("ramp:2:5:1.5") == Ramp(2.0, 5.0, 1.5)
    assert parse_terrain("rough:0.01:0.5") == Rough(0.01, 0.5, 0)
    assert parse_terrain("rough:0.01:0.5:7") == Rough(0.01, 0.5, 7)
    for text in ("ramp:2:5", "ramp:2:5:1.5", "rough:0.01:0.5:7"):
        assert parse_terrain(parse_terrain(text).spec()) == parse_terrain(text)


@pytest.mark.parametrize(
    "text, named",
    [
        ("ramp:-1:5", "start_s=-1.0"),
        ("ramp:1:0", "grade 0.0 deg"),
        ("ramp:1:45", "grade 45.0 deg"),
        ("ramp:1:5:0", "length=0.0"),
        ("ramp:1", "'ramp:1'"),
        ("rough:0:1", "amplitude=0.0"),
        ("rough:0.5:1", "amplitude=0.5"),
        ("rough:0.01:0.01", "wavelength=0.01"),
        ("rough:0.01:1:1.5", "seed '1.5'"),
        ("rough:0.01:1:-1", "seed=-1"),
        ("rough:0.01:nan", "wavelength=nan"),
    ],
)
def test_bad_specs_are_refused_naming_the_value(text, named):
    with pytest.raises(ValueError, match="not allowed") as info:
        parse_terrain(text)
    assert named in str(info.value)


def test_the_flat_ground_model_has_no_uneven_joints():
    params = Scenario(trailers=2).plant_params()
    assert "hitch_roll" not in vehicle_xml(params)
    xml = vehicle_xml(params, uneven=True)
    assert xml.count('name="hitch_roll') == 2 and xml.count('name="hitch_pitch') == 1


@pytest.mark.parametrize("terrain", ["ramp:2:8", "ramp:2:8:1.2", "rough:0.02:0.4:3"])
def test_the_scene_ground_is_the_height_function(terrain):
    built, relief = _relief(terrain)
    vehicle = Vehicle(built.plant_params, relief)
    m, d = vehicle.model, vehicle.data
    mujoco.mj_kinematics(m, d)
    rng = np.random.default_rng(0)
    polyline = drawn_polyline(built.path, built.duration)
    low, high = polyline.min(axis=0) - 1.0, polyline.max(axis=0) + 1.0
    points = rng.uniform(low, high, size=(300, 2))
    ground = np.zeros(6, dtype=np.uint8)
    ground[0] = 1  # the world's geoms are in group 0; the vehicle's bodies are excluded below
    body = m.body("tractor").id
    hit = np.zeros(1, dtype=np.int32)
    heights = relief.height(points[:, 0], points[:, 1])
    for (x, y), h in zip(points, heights, strict=True):
        distance = mujoco.mj_ray(m, d, np.array([x, y, 5.0]), np.array([0, 0, -1.0]), ground, 1,
                                 body, hit)  # fmt: skip
        assert m.body_rootid[m.geom_bodyid[hit[0]]] == 0  # the ground, not the vehicle
        # the ramp's boxes are exact to rounding; the heightfield stores float32 heights
        tolerance = 1e-9 if isinstance(relief, RampRelief) else 1e-7 * 2 * 0.02 * 4
        assert 5.0 - distance == pytest.approx(h, abs=tolerance)


def test_a_rough_ground_is_its_seed_s():
    _, a = _relief("rough:0.02:0.4:3")
    _, b = _relief("rough:0.02:0.4:3")
    _, c = _relief("rough:0.02:0.4:4")
    assert isinstance(a, RoughRelief)
    assert np.array_equal(a.heights, b.heights) and not np.allclose(a.heights, c.heights)
    assert np.abs(a.heights).max() == pytest.approx(0.02, rel=1e-12)
    assert a.spacing == 0.4 / SAMPLES_PER_WAVELENGTH


def test_a_ramp_beyond_the_path_and_a_too_fine_ground_are_refused():
    with pytest.raises(ValueError, match=r"start_s=50.0 m is not allowed: the run reaches 9.42"):
        build(Scenario(traj="s_curve", terrain="ramp:50:5"))
    with pytest.raises(ValueError, match=f"at most {MAX_RELIEF_NODES} are allowed"):
        build(Scenario(traj="s_curve", terrain="rough:0.01:0.05"))
    with pytest.raises(ValueError, match="flat ground only"):
        build(Scenario(traj="s_curve", terrain="rough:0.01:0.5", plant="reduced"))


@pytest.mark.parametrize(
    "terrain, trailers", [("rough:0.02:0.3:5", 1), ("rough:0.02:0.3:5", 3), ("ramp:0:10", 2)]
)
def test_the_vehicle_starts_at_rest_on_every_wheel(terrain, trailers):
    built, _ = _relief(terrain, trailers=trailers)
    plant = built.new_plant()
    m, d = plant.model, plant.data
    wheels = set(wheel_geoms(m))
    touching = set()
    for contact in d.contact[: d.ncon]:
        pair = {int(contact.geom1), int(contact.geom2)}
        assert len(pair & wheels) == 1  # a wheel on the ground, nothing else
        touching |= pair & wheels
        assert -1e-5 < contact.dist <= 0.0  # the static penetration of the soft contact
    assert touching == wheels and len(wheels) == 2 * (trailers + 1)
    assert np.array_equal(d.qpos[:2], built.initial_pose[:2])
    assert np.abs(d.qvel).max() == 0.0  # the dynamic target starts from rest


def _line_csv(tmp_path):
    path = tmp_path / "line.csv"
    path.write_text("x,y\n" + "".join(f"{x:g},0\n" for x in np.linspace(0.0, 8.0, 81)))
    return path


@pytest.mark.parametrize("grade", [5.0, 10.0])
def test_driving_up_the_ramp_at_steady_speed_takes_the_weight_s_pull(tmp_path, grade):
    # On the incline at constant speed the wheels' torque holds the weight's pull along it:
    # (T_r + T_l) / r = m_total g sin(grade). Measured: within 0.035 % (5 and 10 deg), the
    # rest being the speed's ripple; held to 0.5 %.
    result = simulate(
        Scenario(traj=str(_line_csv(tmp_path)), terrain=f"ramp:1:{grade:g}", disturbance="none")
    )
    assert result.status == "ok"
    ts = result.timeseries
    steady = (ts["x0"] > 1.05) & (np.abs(ts["v_d_dot"]) < 1e-12)  # the whole train climbing
    assert steady.sum() > 5000
    p = Params()
    mass = p.Mf + p.Mr + 4 * p.Mw + p.Mc1 + p.Mc2
    pull = mass * GRAVITY * math.sin(math.radians(grade)) * p.r
    torque = ts["T_r"][steady] + ts["T_l"][steady]
    assert torque.mean() == pytest.approx(pull, rel=0.005)
    report = result.metrics["terrain"]
    assert report["ramp_foot_xy"] == [1.0, 0.0] and report["ramp_heading_deg"] == 0.0
    assert report["t_ramp_reached"] == pytest.approx(2.25, abs=0.01)


@pytest.mark.parametrize("trailers", [1, 3])
def test_ismc_sta_tracks_the_s_curve_on_a_rough_ground(trailers):
    # 1 cm bumps of 0.5 m: measured 9.8 / 8.9 mm rms (N = 1 / 3; flat ground: 9.5 / 9.5 mm);
    # held to the 2 cm, as on a grade.
    result = simulate(
        Scenario(traj="s_curve", terrain="rough:0.01:0.5", disturbance="none", trailers=trailers)
    )
    assert result.status == "ok"
    assert result.metrics["cross_track_rms"] < 0.02
    assert result.metrics["terrain"]["grid_nodes"] > 10_000


def test_a_frame_poses_the_vehicle_on_the_ground():
    built, relief = _relief("rough:0.02:0.4:3", trailers=2)
    vehicle = Vehicle(built.plant_params, relief)
    m, d = vehicle.model, vehicle.data
    wheels = wheel_geoms(m)
    for x, y, theta in [(0.0, 0.0, 0.0), (1.0, 2.0, 1.0), (-0.5, 4.0, 2.5)]:
        pose_vehicle(vehicle, x, y, theta, 0.1, 0.0, np.zeros(6), [(0.05, 0.0)])
        centres = d.geom_xpos[wheels]
        gaps = centres[:, 2] - relief.height(centres[:, 0], centres[:, 1]) - built.plant_params.r
        # no wheel sunk (to the slope's cos), some wheel touching, none far above
        assert gaps.min() > -2e-3 and gaps.min() < 2e-3 and gaps.max() < 2 * 0.02
        assert np.allclose(d.qpos[:2], [x, y])


def test_the_video_builds_the_run_s_ground_and_draws_the_vehicle_on_it():
    from tt_mujoco.viz import render

    terrain = "ramp:0.5:15"
    result = simulate(Scenario(traj="s_curve", terrain=terrain, duration=4.0))
    ts, line, params = result.timeseries, result.reference_polyline, result.scenario.plant_params()
    try:
        video = render.VideoFormat(160, 120, 10.0, "overview")
        flat = render.RunRenderer(ts, render.RunScene(params, line), video)
        ramp = render.RunRenderer(ts, render.RunScene(params, line, terrain=terrain), video)
    except render.RenderUnavailable as exc:
        pytest.skip(str(exc))
    with flat as f, ramp as r:
        assert r.relief == build(Scenario(traj="s_curve", terrain=terrain, duration=4.0)).relief
        last = r.n_frames - 1
        assert (
            np.abs(f.render_frame(last).astype(int) - r.render_frame(last).astype(int)).mean() > 1
        )
        tractor = r.vehicle.data.xpos[r.model.body("tractor").id]
        assert tractor[2] > params.r + 0.05  # up the ramp, not drawn at the floor's height


def test_the_cli_refuses_a_bad_relief_and_writes_nothing(tmp_path, capsys):
    for terrain, named in [("rough:0.01:0.01", "wavelength=0.01"), ("ramp:50:5", "start_s=50")]:
        out = tmp_path / "run"
        argv = ["--terrain", terrain, "--no-video", "--no-plots", "--out", str(out)]
        assert run.main(argv) == 2
        assert named in capsys.readouterr().err and not out.exists()

"""The MJCF model: generated files, menagerie-style stepping test, steering sign, parameters."""

import math

import mujoco
import numpy as np
import pytest

from tt_mujoco.sim.parts.physics import Vehicle
from tt_mujoco.vehicle import mjcf as model
from tt_mujoco.vehicle import reduced
from tt_mujoco.vehicle.params import Params, same_path_eta


def test_checked_in_models_match_generator():
    # `python -m tt_mujoco.model` regenerates them; a stale file fails here.
    assert (model.MODELS_DIR / model.VEHICLE_FILE).read_text() == model.vehicle_xml(Params())
    assert (model.MODELS_DIR / model.SCENE_FILE).read_text() == model.scene_xml()


def test_scene_steps_with_random_controls_without_warnings():
    # mujoco_menagerie's model test: load the scene file, 1 s of random controls in ctrlrange.
    m = mujoco.MjModel.from_xml_path(str(model.MODELS_DIR / model.SCENE_FILE))
    _step_random_controls(m, seed=0)


def _step_random_controls(m: mujoco.MjModel, seed: int) -> None:
    """1 s of random controls inside ctrlrange: no warning, a finite state."""
    d = mujoco.MjData(m)
    rng = np.random.default_rng(seed)
    lo, hi = m.actuator_ctrlrange[:, 0], m.actuator_ctrlrange[:, 1]
    for _ in range(int(1.0 / m.opt.timestep)):
        d.ctrl[:] = rng.uniform(lo, hi)
        mujoco.mj_step(m, d)
    assert np.all(d.warning.number == 0), [w.number for w in d.warning]
    assert np.all(np.isfinite(d.qpos))


def test_mass_layout_totals():
    p = Params()
    veh = Vehicle(p)
    assert veh.model.body_subtreemass[veh.model.body("tractor").id] == pytest.approx(33.0)
    assert p.total_mass == 33.0


def test_equality_sign_gives_beta_equal_eta_phi():
    # Drive a turn: the hitch swings, and MuJoCo's beta must follow +eta*phi, not -eta*phi.
    p = Params(eta=-3.0)
    veh = Vehicle(p)
    veh.set_state(v=0.3)
    for _ in range(1500):
        veh.set_torque(0.5, -0.1)
        mujoco.mj_step(veh.model, veh.data)
    me = veh.measure()
    assert abs(me.phi) > math.radians(2)
    assert me.beta == pytest.approx(p.eta * me.phi, abs=1e-4)
    # And phi_dot agrees with SPEC's formula in sign and size.
    phi_dot = -veh.data.qvel[veh.layout.hitch_v]
    assert phi_dot == pytest.approx(np.dot(reduced.phi_rate(me.phi, p), (me.v, me.omega)), rel=0.02)


def test_static_normal_load_per_tractor_wheel():
    # docs/model.md Section 5: about 88 N per tractor wheel.
    veh = Vehicle(Params())
    veh.set_state()
    for _ in range(200):
        mujoco.mj_step(veh.model, veh.data)
    force = np.zeros(6)
    loads = {}
    for i in range(veh.data.ncon):
        c = veh.data.contact[i]
        mujoco.mj_contactForce(veh.model, veh.data, i, force)
        loads[veh.model.geom(c.geom2).name] = force[0]
    assert loads["tractor_wheel_left"] == pytest.approx(88.6, abs=0.5)
    assert sum(loads.values()) == pytest.approx(33.0 * 9.81, rel=1e-3)


def test_presets():
    assert Params(eta="paper").eta == 3.0
    assert Params().eta == pytest.approx(-1.0 / 7.0)
    assert Params().steering == "same_path"
    assert Params(eta="1.5").eta == 1.5
    assert Params(eta="-3").eta == -3.0
    assert Params(eta="1e-3").eta == 1e-3
    assert Params(eta="same-path").steering == "same_path"
    assert same_path_eta(0.3, 0.4) == pytest.approx(-1.0 / 7.0)


@pytest.mark.parametrize(
    ("kwargs", "fragment"),
    [
        ({"Mf": 0.0}, "Mf=0.0"),
        ({"L": -1}, "L=-1"),
        ({"Iw": float("nan")}, "Iw=nan"),
        ({"r": 0.15}, "r=0.15"),
        ({"eta": "banana"}, "eta='banana'"),
        ({"eta": float("inf")}, "eta=inf"),
        ({"timestep": 0.5}, "timestep=0.5"),
        ({"Iw": 0.05}, "Iw=0.05"),
        # a pair that does not fit names both: either may be the one given
        ({"L0": 0.005}, "r=0.02 with L0=0.005"),
        ({"L0": 1e-9}, "L0=1e-09 is not allowed: it must be a finite number in [0.001, 100] m"),
        ({"L": 0.01}, "r=0.02 with L=0.01"),
        ({"d": 0.01}, "r=0.02 with d=0.01"),
    ],
)
def test_bad_params_name_the_field(kwargs, fragment):
    with pytest.raises(ValueError, match="not allowed") as err:
        Params(**kwargs)
    assert fragment in str(err.value)


def test_scaled_params():
    p = Params().scaled(1.2)
    assert p.Mf == pytest.approx(10.8)
    assert p.Iw == pytest.approx(0.012)
    assert p.L == 0.3
    assert p.eta == Params().eta


def test_compiled_models_are_private_copies():
    from tt_mujoco.sim.parts.physics import compile_model

    a = compile_model(Params())
    a.body_mass[a.body("trailer_body").id] = 99.0
    b = compile_model(Params())
    assert b.body_mass[b.body("trailer_body").id] == 6.0
    assert compile_model(Params(Mr=7.0)).body_mass[b.body("trailer_body").id] == 7.0


def test_export_for_other_parameters_and_never_over_files(tmp_path, capsys):
    from tt_mujoco import model as model_cli

    out = tmp_path / "long"
    assert model_cli.main(["--out", str(out), "--param", "L0=0.5", "--eta", "paper"]) == 0
    m = mujoco.MjModel.from_xml_path(str(out / "scene.xml"))
    assert m.eq_data[m.equality("steering").id][1] == -3.0  # polycoef = -eta
    assert "L0 = 0.5" in (out / "tractor_trailer.xml").read_text()
    assert (out / "tractor_trailer.urdf").is_file()
    assert model_cli.main(["--out", str(out)]) == 2
    assert "not an empty folder" in capsys.readouterr().err
    assert model_cli.main(["--out", str(tmp_path / "bad"), "--param", "L0=-1"]) == 2
    assert not (tmp_path / "bad").exists()
    capsys.readouterr()
    # a bad value is named first, with --out or without it
    for argv, named in ((["--trailers", "99"], "trailers=99"), (["--eta", "abc"], "eta='abc'")):
        assert model_cli.main(argv) == 2
        assert named in capsys.readouterr().err


@pytest.mark.parametrize("n", [2, 3])
def test_train_scene_steps_with_random_controls_without_warnings(n):
    p = Params().with_trailers(n)
    m = mujoco.MjModel.from_xml_string(
        model.scene_xml(), assets={model.VEHICLE_FILE: model.vehicle_xml(p).encode()}
    )
    _step_random_controls(m, seed=n)
    assert m.neq == n
    assert m.body_subtreemass[m.body("tractor").id] == pytest.approx(p.total_mass)


def test_every_trailers_equality_gives_beta_equal_eta_phi():
    # Signs pinned per hitch with gains of both signs on the three trailers.
    p = Params(eta=-3.0).with_trailers(3, [{"eta": 2.0}, {"eta": -1.5}])
    veh = Vehicle(p)
    veh.set_state(v=0.3)
    for _ in range(1500):
        veh.set_torque(0.6, -0.1)
        mujoco.mj_step(veh.model, veh.data)
    me = veh.measure()
    assert me.beta == pytest.approx(p.eta * me.phi, abs=1e-4)
    for (*_, phi, beta, _v0), t in zip(me.train, p.train, strict=True):
        assert abs(phi) > math.radians(1)
        assert beta == pytest.approx(t.eta * phi, abs=1e-4)
    # The measured axles are MuJoCo's sites P0_k.
    for k, row in enumerate(me.train, start=2):
        mujoco.mj_kinematics(veh.model, veh.data)
        assert row[:2] == pytest.approx(veh.data.site(f"P0_{k}").xpos[:2], abs=1e-9)


def test_single_trailer_model_text_unchanged_by_the_train_code():
    # N = 1 is today's model, bit for bit: the train adds text only for N >= 2.
    assert model.vehicle_xml(Params().with_trailers(1)) == model.vehicle_xml(Params())
    assert "trailer_2" in model.vehicle_xml(Params().with_trailers(2))


def test_export_a_train(tmp_path):
    from tt_mujoco import model as model_cli

    out = tmp_path / "train"
    assert model_cli.main(["--out", str(out), "--trailers", "3"]) == 0
    m = mujoco.MjModel.from_xml_path(str(out / "scene.xml"))
    assert m.eq_data[m.equality("steering_3").id][1] == pytest.approx(13 / 119)
    assert "trailer_wheel_left_3" in (out / "tractor_trailer.urdf").read_text()
    assert model_cli.main(["--trailers", "2"]) == 2  # models/ keeps the default vehicle

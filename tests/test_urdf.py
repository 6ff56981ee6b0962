"""The URDF export against the MJCF it mirrors and docs/model.md §1 and 4."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import mujoco
import numpy as np
import pytest
import yourdfpy

from tt_mujoco.sim.parts.physics import Vehicle
from tt_mujoco.vehicle import reduced
from tt_mujoco.vehicle.mjcf import AXLE_MASS, MODELS_DIR
from tt_mujoco.vehicle.params import Params
from tt_mujoco.vehicle.urdf import STEER_LIMIT, URDF_FILE, urdf_xml, wheel_joint_name

LINKS = (
    "tractor",
    "tractor_rod",
    "tractor_wheel_left",
    "tractor_wheel_right",
    "trailer",
    "trailer_body",
    "trailer_axle",
    "trailer_wheel_left",
    "trailer_wheel_right",
)
WHEELS = ("tractor_wheel_left", "tractor_wheel_right", "trailer_wheel_left", "trailer_wheel_right")

# Same-path default, the paper's unstable +3, its mirror -3 (pins signs), and a plain trailer.
ETAS = ("same_path", "paper", -3.0, 0.0)

# Both sides compose the same few rigid transforms in double precision from the same decimal
# numbers (lengths <= 0.4 m, world positions <= 5 m), so they agree to round-off: measured
# worst 1.1e-15 m (positions) and 7.8e-16 (rotation-matrix entries) over ETAS x 30 configs.
# 1e-12 leaves a 1000x margin and still catches any modelling difference (a 1 um offset or a
# wrong sign is 1e-6 or more).
FK_TOL = 1e-12

# URDF against the closed-form SPEC geometry (tractor at the origin, lengths <= 0.5 m):
# measured worst 1.1e-16 rad and 1.7e-16 m over ETAS x 30 angles; 1e-14 leaves ~60x.
ANGLE_TOL = 1e-14
POS_TOL = 1e-14


def load(p: Params, tmp_path) -> yourdfpy.URDF:
    path = tmp_path / URDF_FILE
    path.write_text(urdf_xml(p))
    return yourdfpy.URDF.load(str(path), build_scene_graph=True, load_meshes=False)


def mimic_multiplier_for(p: Params) -> float:
    """steer = -eta * hitch: q_hitch = -phi and q_steer = beta = eta * phi (docs/model.md §5)."""
    return -p.eta


@pytest.mark.parametrize("eta", ETAS)
def test_loads_valid_with_the_mjcf_links(eta, tmp_path):
    p = Params(eta=eta)
    urdf = load(p, tmp_path)
    assert urdf.validate()
    assert urdf.base_link == "tractor"
    assert set(urdf.link_map) == set(LINKS)
    model = Vehicle(p).model
    mjcf_bodies = {model.body(i).name for i in range(1, model.nbody)}  # 0 is the world
    assert set(urdf.link_map) == mjcf_bodies
    # SDFormat (Gazebo) rejects a joint and a link of the same name.
    assert not set(urdf.link_map) & set(urdf.joint_map)
    # steer follows hitch through <mimic>, so it is not an independent joint.
    assert sorted(urdf.actuated_joint_names) == sorted(
        ["hitch", *(wheel_joint_name(w) for w in WHEELS)]
    )
    text = urdf_xml(p)
    assert "CANNOT BE EXPRESSED IN URDF" in text
    assert "KINEMATIC ONLY" in text


@pytest.mark.parametrize("eta", ETAS)
def test_masses_and_inertias_equal_params_and_mjcf(eta, tmp_path):
    p = Params(eta=eta)
    urdf = load(p, tmp_path)
    mass = {name: link.inertial.mass for name, link in urdf.link_map.items()}
    # Paper Section 6.1 masses, with the MJCF's AXLE_MASS moved from the trailer wheels.
    expected = {
        "tractor": p.Mf,
        "tractor_rod": p.Mc1,
        "tractor_wheel_left": p.Mw,
        "tractor_wheel_right": p.Mw,
        "trailer": p.Mc2,
        "trailer_body": p.Mr,
        "trailer_axle": AXLE_MASS,
        "trailer_wheel_left": p.Mw - AXLE_MASS / 2,
        "trailer_wheel_right": p.Mw - AXLE_MASS / 2,
    }
    assert mass == pytest.approx(expected, rel=1e-15)
    assert sum(mass.values()) == pytest.approx(33.0, rel=1e-14)
    assert sum(mass.values()) == pytest.approx(p.total_mass, rel=1e-14)

    # Centre of mass and inertia tensor of every link equal MuJoCo's compiled body values.
    model = Vehicle(p).model
    for name, link in urdf.link_map.items():
        body = model.body(name)
        assert link.inertial.mass == pytest.approx(float(body.mass[0]), rel=1e-15)
        np.testing.assert_allclose(link.inertial.origin[:3, 3], body.ipos, atol=1e-15)
        R = np.zeros(9)
        mujoco.mju_quat2Mat(R, body.iquat)
        R = R.reshape(3, 3)
        mj_tensor = R @ np.diag(body.inertia) @ R.T
        urdf_tensor = link.inertial.origin[:3, :3] @ link.inertial.inertia
        np.testing.assert_allclose(urdf_tensor, mj_tensor, rtol=1e-12, atol=1e-18, err_msg=name)


def test_joint_frames_give_link_lengths_and_limits(tmp_path):
    p = Params(L=0.35, L0=0.5, d=0.24, torque_limit=12.0, eta="paper")
    urdf = load(p, tmp_path)
    joints = urdf.joint_map
    hitch, steer = joints["hitch"], joints["steer"]
    np.testing.assert_array_equal(hitch.origin[:3, 3], [-p.L, 0, 0])
    np.testing.assert_array_equal(steer.origin[:3, 3], [-p.L0, 0, 0])
    assert np.linalg.norm(hitch.origin[:3, 3]) == p.L
    assert np.linalg.norm(steer.origin[:3, 3]) == p.L0
    assert (hitch.parent, hitch.child) == ("tractor", "trailer")
    assert (steer.parent, steer.child) == ("trailer", "trailer_axle")
    np.testing.assert_array_equal(hitch.axis, [0, 0, 1])
    np.testing.assert_array_equal(steer.axis, [0, 0, 1])
    # The kinematic singularity |eta phi| = pi/2 (docs/model.md Section 2) bounds both.
    assert hitch.limit.upper == pytest.approx(math.pi / 6, rel=1e-15)
    assert hitch.limit.lower == -hitch.limit.upper
    assert (steer.limit.lower, steer.limit.upper) == (-STEER_LIMIT, STEER_LIMIT)
    assert hitch.limit.effort == steer.limit.effort == 0.0  # passive
    assert joints["tractor_rod_joint"].type == joints["trailer_body_joint"].type == "fixed"
    for wheel in WHEELS:
        joint = joints[wheel_joint_name(wheel)]
        assert joint.type == "continuous"
        assert joint.child == wheel
        np.testing.assert_array_equal(joint.axis, [0, 1, 0])
        side = 1 if wheel.endswith("left") else -1
        np.testing.assert_array_equal(joint.origin[:3, 3], [0, side * p.d / 2, 0])
    for wheel in WHEELS[:2]:
        assert joints[wheel_joint_name(wheel)].limit.effort == p.torque_limit
    for wheel in WHEELS[2:]:
        assert joints[wheel_joint_name(wheel)].limit is None  # passive, unlimited


@pytest.mark.parametrize(
    ("eta", "hitch_limit"), [(3.0, math.pi / 6), (-0.5, math.pi), (0.0, math.pi)]
)
def test_hitch_limit_is_the_singularity_or_a_full_fold(eta, hitch_limit, tmp_path):
    p = Params(eta=eta)
    hitch = load(p, tmp_path).joint_map["hitch"]
    assert hitch.limit.upper == pytest.approx(hitch_limit, rel=1e-15)
    # Through the mimic the hitch range never leaves the steering range.
    assert abs(mimic_multiplier_for(p)) * hitch.limit.upper <= STEER_LIMIT * (1 + 1e-15)


def test_wheel_collisions_are_spheres_and_only_wheels_collide(tmp_path):
    p = Params(r=0.03)
    urdf = load(p, tmp_path)
    for name, link in urdf.link_map.items():
        if name in WHEELS:
            (collision,) = link.collisions
            assert collision.geometry.sphere.radius == p.r
            np.testing.assert_array_equal(collision.origin, np.eye(4))
        else:
            assert link.collisions == []
        assert link.visuals, f"{name} has no visual"


def test_gazebo_friction_is_params_friction():
    p = Params(friction=0.7)
    root = ET.fromstring(urdf_xml(p))
    refs = {g.get("reference"): g for g in root.findall("gazebo")}
    assert set(refs) == set(WHEELS)
    for g in refs.values():
        assert float(g.findtext("mu1")) == float(g.findtext("mu2")) == 0.7


@pytest.mark.parametrize("eta", ETAS)
def test_forward_kinematics_match_mujoco(eta, tmp_path):
    """Every link pose relative to the tractor, 30 random configurations, with the tractor at a
    random world pose; MuJoCo's steer is set to -eta * hitch and the URDF's comes from <mimic>."""
    p = Params(eta=eta)
    urdf = load(p, tmp_path)
    vehicle = Vehicle(p)
    model, data = vehicle.model, vehicle.data

    def qadr(joint: str) -> int:
        return int(model.jnt_qposadr[model.joint(joint).id])

    rng = np.random.default_rng(20240611)
    hitch_limit = urdf.joint_map["hitch"].limit.upper
    tractor = model.body("tractor").id
    for _ in range(30):
        q_hitch = rng.uniform(-hitch_limit, hitch_limit)
        spins = rng.uniform(-math.pi, math.pi, len(WHEELS))
        theta = rng.uniform(-math.pi, math.pi)
        mujoco.mj_resetData(model, data)
        data.qpos[0:3] = rng.uniform(-5, 5, 3)
        data.qpos[3:7] = [math.cos(theta / 2), 0, 0, math.sin(theta / 2)]
        data.qpos[qadr("hitch")] = q_hitch
        data.qpos[qadr("steer")] = -p.eta * q_hitch
        cfg = {"hitch": q_hitch}
        for wheel, spin in zip(WHEELS, spins, strict=True):
            data.qpos[qadr(wheel)] = spin
            cfg[wheel_joint_name(wheel)] = spin
        mujoco.mj_kinematics(model, data)
        urdf.update_cfg(cfg)

        R_tractor = data.xmat[tractor].reshape(3, 3)
        for link in LINKS:
            body = model.body(link).id
            pos = R_tractor.T @ (data.xpos[body] - data.xpos[tractor])
            rot = R_tractor.T @ data.xmat[body].reshape(3, 3)
            T = urdf.get_transform(link, "tractor")
            np.testing.assert_allclose(T[:3, 3], pos, rtol=0, atol=FK_TOL, err_msg=link)
            np.testing.assert_allclose(T[:3, :3], rot, rtol=0, atol=FK_TOL, err_msg=link)


@pytest.mark.parametrize("eta", ETAS)
def test_mimic_gives_the_passive_steering(eta, tmp_path):
    """beta = eta * phi (paper eq. 2) and the docs/model.md Section 1/4 geometry, MuJoCo-free."""
    p = Params(eta=eta)
    urdf = load(p, tmp_path)
    mimic = urdf.joint_map["steer"].mimic
    assert mimic.joint == "hitch"
    assert mimic.multiplier == mimic_multiplier_for(p)
    assert mimic.offset == 0.0

    rng = np.random.default_rng(7)
    phi_max = min(p.phi_singular, math.pi)
    for phi in rng.uniform(-phi_max, phi_max, 30):
        urdf.update_cfg({"hitch": -phi})  # q_hitch = -phi
        trailer = urdf.get_transform("trailer", "tractor")
        axle_in_trailer = urdf.get_transform("trailer_axle", "trailer")
        phi_urdf = -math.atan2(trailer[1, 0], trailer[0, 0])
        beta = math.atan2(axle_in_trailer[1, 0], axle_in_trailer[0, 0])
        assert phi_urdf == pytest.approx(math.remainder(phi, 2 * math.pi), abs=ANGLE_TOL)
        assert beta == pytest.approx(p.eta * phi, abs=ANGLE_TOL)
        assert urdf.cfg[urdf.actuated_joint_names.index("hitch")] == -phi

        # Tractor at the origin heading +x: O, P0 from docs/model.md Section 1, wheels at
        # P0 +- (d/2) n(alpha) with alpha = theta0 + beta (Section 4).
        O, P0, theta0 = reduced.trailer_pose(0.0, 0.0, 0.0, phi, p)
        alpha = theta0 + p.eta * phi
        n_alpha = np.array([-math.sin(alpha), math.cos(alpha)])
        np.testing.assert_allclose(trailer[:2, 3], O, atol=POS_TOL)
        np.testing.assert_allclose(
            urdf.get_transform("trailer_axle", "tractor")[:2, 3], P0, atol=POS_TOL
        )
        for side, wheel in ((1, "trailer_wheel_left"), (-1, "trailer_wheel_right")):
            centre = urdf.get_transform(wheel, "tractor")[:2, 3]
            np.testing.assert_allclose(centre, P0 + side * p.d / 2 * n_alpha, atol=POS_TOL)


def test_bad_params_rejected():
    with pytest.raises(ValueError, match="p='paper' is not allowed"):
        urdf_xml("paper")


@pytest.mark.skipif(
    not (MODELS_DIR / URDF_FILE).exists(), reason="models/tractor_trailer.urdf not generated yet"
)
def test_checked_in_urdf_is_current():
    assert (MODELS_DIR / URDF_FILE).read_text() == urdf_xml(Params()), (
        "models/tractor_trailer.urdf is stale: run `python -m tt_mujoco.model`"
    )


def test_a_trains_urdf_mirrors_its_mjcf(tmp_path):
    # Three trailers: the URDF's links are the MJCF's bodies, with the same masses, centres of
    # mass and inertias, every hitch and steering joint, and the same forward kinematics.
    p = Params().with_trailers(3, [{"eta": 0.5}])
    urdf = load(p, tmp_path)
    assert urdf.validate()
    vehicle = Vehicle(p)
    model, data = vehicle.model, vehicle.data
    assert set(urdf.link_map) == {model.body(i).name for i in range(1, model.nbody)}
    for name, link in urdf.link_map.items():
        body = model.body(name)
        assert link.inertial.mass == pytest.approx(float(body.mass[0]), rel=1e-15)
        np.testing.assert_allclose(link.inertial.origin[:3, 3], body.ipos, atol=1e-15)
    assert sum(link.inertial.mass for link in urdf.link_map.values()) == pytest.approx(
        p.total_mass, rel=1e-14
    )
    for k, t in zip((2, 3), p.train, strict=True):
        mimic = urdf.joint_map[f"steer_{k}"].mimic
        assert mimic.joint == f"hitch_{k}" and mimic.multiplier == pytest.approx(-t.eta)
    rng = np.random.default_rng(7)
    vehicle.set_state(phi=tuple(rng.uniform(-0.3, 0.3, 3)))
    cfg = {"hitch": -vehicle.measure().phi}
    for k, row in enumerate(vehicle.measure().train, start=2):
        cfg[f"hitch_{k}"] = -row[3]
    urdf.update_cfg(cfg)
    mujoco.mj_kinematics(model, data)
    tractor = model.body("tractor").id
    R = data.xmat[tractor].reshape(3, 3)
    for k in (2, 3):
        body = model.body(f"trailer_axle_{k}").id
        expected = R.T @ (data.xpos[body] - data.xpos[tractor])
        got = urdf.get_transform(f"trailer_axle_{k}", "tractor")[:3, 3]
        np.testing.assert_allclose(got, expected, atol=FK_TOL)

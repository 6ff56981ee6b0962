"""MuJoCo's N-trailer model against the train's reduced model (tt_mujoco.validate_train), for
N = 1, 2, 3, judged by the single trailer's bounds (tt_mujoco.validate.BOUNDS)."""

from __future__ import annotations

import pytest

from tt_mujoco import validate
from tt_mujoco.validate_train import (
    check_bias,
    check_energy,
    check_inertia,
    check_jackknife,
    check_kinematics,
    train_params,
)

# Measured on the three presets (python -m tt_mujoco.validate --trailers 2 and 3): projected mass
# matrix <= 8.2e-14 (round-off), bias forces <= 2.7e-9 (limited by the finite difference of the
# selection matrix), every axle within 0.75 mm after 7.4 m, |beta_k - eta_k phi_k| <= 4.3e-7,
# energy balance <= 1.2e-13. The bounds are the single trailer's, unchanged.
INERTIA_BOUND = validate.BOUNDS["inertia"][0][1]  # 1e-12
BIAS_BOUND = validate.BOUNDS["coriolis"][0][1]  # 1e-7
KINEMATICS = {quantity: bound for quantity, bound, _ in validate.BOUNDS["kinematics"]}


@pytest.mark.parametrize("n", [1, 2, 3])
@pytest.mark.parametrize("eta", ["same_path", 0.0, "paper"])
def test_projected_mass_matrix_and_bias_forces(n, eta):
    p = train_params(n, eta)
    assert check_inertia(p, samples=30)["max_rel_error"] < INERTIA_BOUND
    assert check_bias(p, samples=15)["max_rel_error"] < BIAS_BOUND


@pytest.mark.parametrize("n", [1, 2, 3])
def test_kinematics_reproduce_every_axle_after_six_metres(n):
    row = check_kinematics(train_params(n))
    assert row["distance_m"] > KINEMATICS["distance_m"]  # 6 m
    assert row["final_P_error_m"] < KINEMATICS["final_P_error_m"]  # 2 mm
    for k in range(1, n + 1):
        assert row[f"final_P_{k}_error_m"] < KINEMATICS["final_P0_error_m"]
    assert row["phi_dot_rel_rms_error"] < KINEMATICS["phi_dot_rel_rms_error"]
    assert row["eq_violation_max_rad"] < KINEMATICS["eq_violation_max_rad"]  # 1e-4


@pytest.mark.parametrize("n", [2, 3])
@pytest.mark.parametrize("forced", [False, True])
def test_energy_equals_work(n, forced):
    assert check_energy(train_params(n), forced)["rel_error"] < 1e-6


def test_jackknife_findings_of_a_three_trailer_train():
    # Forward, same-path and plain trailers hold every hitch near its start (1 deg); the paper's
    # eta = 3 jackknifes. Reversing, every one of them jackknifes, eta = 3 included: it holds a
    # single trailer reversing (docs/model.md Section 3) but not a train.
    same = train_params(3)
    assert not check_jackknife(same, +1)["jackknife_mujoco"]
    assert not check_jackknife(same, +1)["jackknife_reduced"]
    assert check_jackknife(train_params(3, "paper"), +1)["jackknife_mujoco"]
    reverse = check_jackknife(train_params(3, "paper"), -1)
    assert reverse["jackknife_mujoco"] and reverse["jackknife_reduced"]
    single = check_jackknife(train_params(1, "paper"), -1)
    assert not single["jackknife_mujoco"] and not single["jackknife_reduced"]


def test_validate_cli_writes_the_train_report(tmp_path, capsys):
    out = tmp_path / "v2"
    assert validate.main(["--out", str(out), "--trailers", "2"]) == 0
    text = (out / "report.md").read_text()
    assert "with 2 trailers" in text and "Verdict: 15 of 15 bounds hold." in text
    assert validate.main(["--out", str(tmp_path / "v9"), "--trailers", "9"]) == 2
    assert "--trailers 9 is not allowed" in capsys.readouterr().err

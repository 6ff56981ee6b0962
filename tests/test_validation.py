"""MuJoCo model against the analytic reduced model (issue: foundation, checks 1-5).

Thresholds are the measured values (``python -m tt_mujoco.validate``) with a stated margin.
"""

import math

import numpy as np
import pytest

from tt_mujoco import validate
from tt_mujoco.vehicle import reduced
from tt_mujoco.vehicle.params import Params

PRESETS = {"paper": Params(eta="paper"), "same_path": Params(), "plain": Params(eta=0.0)}


@pytest.mark.parametrize("name", PRESETS)
def test_projected_mass_matrix_equals_reduced(name):
    # Same mass layout body for body: only round-off remains (measured 5e-15..6e-15).
    result = validate.check_inertia(PRESETS[name], samples=100)
    assert result["max_rel_error"] < 1e-12


@pytest.mark.parametrize("name", PRESETS)
def test_coriolis_matches_mujoco_bias(name):
    # Limited by the central difference (h = 1e-6) for dSfull/dt: measured 3e-9..8e-9.
    assert validate.check_coriolis(PRESETS[name], samples=30)["max_rel_error"] < 1e-7


def _workless_error(phi, V, p):
    """A wrong Coriolis term that does no work: adds k * omega * Omega V (V^T Omega V = 0)."""
    v, omega = V
    return reduced.coriolis_force(phi, V, p) + 5.0 * omega * np.array([-omega, v])


def test_energy_check_is_blind_to_workless_term_but_bias_check_is_not():
    p = Params()
    # The wrong model still balances energy exactly ...
    assert validate.check_energy(p, forced=True, coriolis=_workless_error)["rel_error"] < 1e-8
    # ... but MuJoCo's own bias forces expose it (error of order 1, against 1e-8 when right).
    assert validate.check_coriolis(p, samples=10, coriolis=_workless_error)["max_rel_error"] > 1e-2


@pytest.mark.parametrize("name", PRESETS)
@pytest.mark.parametrize("forced", [False, True])
def test_energy_equals_work(name, forced):
    # DOP853 at 1e-12 tolerances: measured 3e-16..6e-14.
    result = validate.check_energy(PRESETS[name], forced=forced)
    assert result["rel_error"] < 1e-6
    if not forced:
        assert result["work_J"] == 0.0


@pytest.mark.parametrize(("name", "direction"), [("same_path", +1), ("paper", -1)])
def test_kinematics_long_run(name, direction):
    result = validate.check_kinematics(PRESETS[name], direction)
    assert result["distance_m"] > 6.0
    # Measured at 1 ms: 0.75 mm for both P and P0 after 7.5 m (contact creep, docs/model.md Section
    # 5).
    assert result["final_P_error_m"] < 2e-3
    assert result["final_P0_error_m"] < 2e-3
    # Measured 0.17 % / 0.27 %.
    assert result["phi_dot_rel_rms_error"] < 0.02
    # Measured 4e-7 / 1.1e-6 rad: the coupling's solref is 2 steps.
    assert result["eq_violation_max_rad"] < 1e-4


@pytest.mark.parametrize("name", PRESETS)
def test_dynamics_mujoco_vs_reduced(name):
    result = validate.check_dynamics(PRESETS[name])
    # Measured over 2 s: |dv| <= 3.0e-4 m/s; |d omega| <= 3.3e-4 (paper, reverse),
    # 2.4e-3 (same_path), 3.1e-3 rad/s (plain). The reduced model forbids slip; MuJoCo's soft
    # contacts creep laterally (max 2.5e-3 m/s here) and that creep shows up directly in the
    # yaw rate, which swings over 3.2 rad/s in these runs (0.1 % of the range). Bounds: about
    # 1.6x the worst measured value.
    assert result["v_max_abs_diff"] < 5e-4
    assert result["omega_max_abs_diff"] < 5e-3
    assert result["v_range"] > 0.5  # the runs really exercise the dynamics


def test_paper_eta_jackknifes_forward_in_both_models():
    result = validate.check_jackknife(PRESETS["paper"])
    # Measured: 2.389 s (MuJoCo) and 2.387 s (reduced).
    assert result["t_over_20deg_mujoco_s"] is not None
    assert result["t_over_20deg_mujoco_s"] < 3.0
    assert result["t_over_20deg_reduced_s"] is not None
    assert result["t_over_20deg_reduced_s"] < 3.0
    assert math.isclose(
        result["t_over_20deg_mujoco_s"], result["t_over_20deg_reduced_s"], abs_tol=0.05
    )


def test_same_path_eta_stays_bounded_forward():
    result = validate.check_jackknife(PRESETS["same_path"])
    # The 0.5 deg initial articulation does not grow (measured max 0.635 deg).
    assert result["phi_max_abs_deg_mujoco"] < 1.0
    assert result["phi_max_abs_deg_reduced"] < 1.0


def test_report_gives_a_verdict_per_bound_and_never_none():
    # A synthetic result: one bound broken, one jackknife that never happened.
    results = {
        "inertia": [{"eta": 3.0, "samples": 100, "max_rel_error": 2e-15}],
        "energy": [{"eta": 3.0, "forced": True, "rel_error": 1e-3}],
        "jackknife": [
            {"eta": 3.0, "t_over_20deg_mujoco_s": 2.4, "t_over_20deg_reduced_s": None},
            {"eta": -1 / 7, "phi_max_abs_deg_mujoco": 0.6, "phi_max_abs_deg_reduced": 0.6},
        ],
    }
    checks = validate.verdicts(results)
    failed = {(c["check"], c["quantity"]) for c in checks if not c["pass"]}
    assert failed == {("energy", "rel_error"), ("jackknife", "t_over_20deg_reduced_s")}
    text = validate.validation_markdown(results)
    assert "**Verdict: 4 of 6 bounds hold; FAILED: energy.rel_error" in text
    assert "None" not in text and "| never |" in text


def test_the_kinematic_error_is_first_order_in_the_timestep():
    # Contact softness has a time constant of two steps, so the creep, and the kinematic error
    # after the same drive, scale with the timestep (docs/validation.md quotes these).
    errors = {
        dt: validate.check_kinematics(Params(timestep=dt), +1)["final_P_error_m"]
        for dt in (0.0005, 0.001, 0.002)
    }
    assert errors[0.001] / errors[0.0005] == pytest.approx(2.0, rel=0.05)
    assert errors[0.002] / errors[0.001] == pytest.approx(2.0, rel=0.05)
    shown = " / ".join(f"{1e3 * e:.2f}" for e in errors.values())
    assert shown == "0.38 / 0.75 / 1.50"  # mm, docs/validation.md


@pytest.mark.parametrize(
    ("options", "at"),
    [({}, "1.142"), ({"disturbance_limit": "none"}, "1.130"), ({"disturbance": "none"}, "1.115")],
)
def test_the_papers_eta_jackknifes_forward_whatever_the_disturbance(options, at):
    from tt_mujoco.sim import Scenario, simulate

    result = simulate(Scenario(traj="s_curve", eta="paper", **options))
    assert result.status == "jackknife"
    assert f"jackknife at t={at} s" in result.message  # docs/validation.md

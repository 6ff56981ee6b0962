"""The sliding-mode law with a boundary layer (controllers/smc.py): by hand, its reaching and
boundary-layer behaviour on the exact error dynamics, and its compiled form."""

from __future__ import annotations

import numpy as np
import pytest
from tt_mujoco.controllers import CONTROLLERS, compiled_laws, make_controller
from tt_mujoco.controllers.smc import SmcController, smc_law

from tt_mujoco.sim import Scenario, build, simulate
from tt_mujoco.sim.loop import compiled
from tt_mujoco.sim.loop.kernel_sources import LAWS

F = np.array([0.1, -0.2])
G = np.array([[0.4, 0.3], [2.0, -3.0]])
K = np.array([10.0, 10.0])
PHI = np.array([0.05, 0.05])


def fake_model(phi, v, omega):
    return F[0], F[1], G[0, 0], G[0, 1], G[1, 0], G[1, 1]


def test_law_by_hand_inside_and_outside_the_layer():
    """u = g^-1 (z_d_dot - f - K sat(e / Phi)): e_v outside the layer (the full switching
    gain), e_omega inside it (the linear part)."""
    ctrl = make_controller("smc", fake_model, torque_limit=1e9)
    v, om, vd, wd, vdd, wdd = 0.40, 0.32, 0.5, 0.3, 0.2, -0.1
    e = np.array([v - vd, om - wd])
    r = np.array([vdd, wdd]) - F - K * np.clip(e / PHI, -1.0, 1.0)
    torques = ctrl.step(0.001, 0.0, v, om, vd, wd, vdd, wdd)
    np.testing.assert_allclose(torques, np.linalg.solve(G, r), rtol=1e-13)
    assert ctrl.state() == {"sat_v": -1.0, "sat_omega": pytest.approx(0.02 / 0.05)}


def _error_run(delta, e0, steps, dt=0.001):
    """The exact model z_dot = f + g tau + delta under the law, by explicit Euler from the
    error ``e0`` on a constant target: the errors after each step."""
    ctrl = make_controller("smc", fake_model, torque_limit=1e9)
    z, errors = np.array(e0, dtype=float), []
    for _ in range(steps):
        tau = np.array(ctrl.step(dt, 0.0, z[0], z[1], 0.0, 0.0, 0.0, 0.0))
        z = z + dt * (F + G @ tau + delta)
        errors.append(z.copy())
    return np.array(errors)


def test_reaching_at_k_minus_delta_then_settling_at_phi_delta_over_k():
    """Outside the layer each channel's error falls by dt (k - Delta) a step; inside it the
    error settles where -k e / phi + Delta = 0, e = phi Delta / k (the Euler map's fixed
    point, reached geometrically at the rate 1 - dt k / phi). Tolerances: the solve g^-1 and
    the products round at 1e-16 of the torques (about 10), so 1e-12 m/s bounds the error."""
    delta = np.array([3.5, -1.5])  # the paper's Delta1 mean and a yaw disturbance
    dt = 0.001
    errors = _error_run(delta, (1.0, -0.5), 3000, dt)
    reaching = dt * (K - np.abs(delta))
    np.testing.assert_allclose(errors[0], [1.0 - reaching[0], -0.5 + reaching[1]], atol=1e-12)
    outside = np.abs(errors[1:, 0]) > PHI[0]
    np.testing.assert_allclose(np.diff(errors[:, 0])[outside], -reaching[0], atol=1e-12)
    np.testing.assert_allclose(errors[-1], PHI * delta / K, atol=1e-12)


def test_without_the_reaching_condition_the_error_leaves_the_layer():
    """k below |Delta|: the law cannot hold the layer; the error grows by dt (|Delta| - k)
    a step once it saturates sat()."""
    delta = np.array([14.0, 0.0])
    errors = _error_run(delta, (0.0, 0.0), 1000)
    assert errors[-1, 0] > PHI[0]
    np.testing.assert_allclose(np.diff(errors[-100:, 0]), 0.001 * (14.0 - K[0]), atol=1e-12)


def test_the_law_is_a_compiled_one_from_its_registry_line():
    """Registered in controllers/__init__.py, the law joins the compiled loop's list in the
    registry's order: nothing else names it."""
    assert compiled_laws()["smc"] is SmcController is CONTROLLERS["smc"]
    assert LAWS == tuple(cls.LAW for cls in compiled_laws().values())
    # its place in the list is its registry line's, whatever is registered after it
    assert LAWS.index(smc_law) == list(compiled_laws()).index("smc")


@pytest.mark.parametrize(
    "options",
    [
        dict(traj="s_curve", noise_snr_db=20.0, duration=3.0),
        dict(traj="cycloid", plant="reduced", trailers=2, duration=3.0),
    ],
)
def test_compiled_and_python_loops_agree_bit_for_bit(monkeypatch, options):
    monkeypatch.setenv("TT_MUJOCO_COMPILE_NOW", "1")
    scenario = Scenario(controller="smc", **options)
    built = build(scenario)
    assert compiled.unsupported(built, built.new_controller()) is None
    outcomes = []
    run_compiled = compiled.run_compiled

    def spied(*args, **kwargs):
        outcomes.append(run_compiled(*args, **kwargs))
        return outcomes[-1]

    monkeypatch.setattr(compiled, "run_compiled", spied)
    monkeypatch.setenv("TT_MUJOCO_COMPILED", "0")
    python = simulate(scenario)
    monkeypatch.setenv("TT_MUJOCO_COMPILED", "1")
    fast = simulate(scenario)
    assert len(outcomes) == 1 and outcomes[0] is not None  # the second run ran compiled
    assert python.status == fast.status == "ok"
    assert python.timeseries.keys() == fast.timeseries.keys()
    for name, column in python.timeseries.items():
        np.testing.assert_array_equal(column, fast.timeseries[name], err_msg=name)

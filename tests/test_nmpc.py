"""The NMPC controller (controllers/nmpc.py) and its QP (controllers/mpc_qp.py)."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
from tt_mujoco.controllers.mpc_qp import QpWeights, TrackingQP

from tt_mujoco.sim import Scenario, simulate

pytest.importorskip("osqp")


def _unconstrained_plan(A, B, c, x0, refs, Q, r_du, r_u, u_prev, H):
    """The same tracking problem solved densely: x = F x0 + G u + h, then least squares."""
    nx, nu = B.shape
    F = np.zeros((H * nx, nx))
    G = np.zeros((H * nx, H * nu))
    h = np.zeros(H * nx)
    x_free, offset = x0.copy(), np.zeros(nx)
    for k in range(H):
        x_free = A @ x_free
        offset = A @ offset + c
        F[k * nx : (k + 1) * nx] = np.linalg.matrix_power(A, k + 1)
        h[k * nx : (k + 1) * nx] = offset
        for j in range(k + 1):
            G[k * nx : (k + 1) * nx, j * nu : (j + 1) * nu] = np.linalg.matrix_power(A, k - j) @ B
    W = np.kron(np.eye(H), np.diag(Q))
    D = np.eye(H * nu) - np.eye(H * nu, k=-nu)  # u_k - u_(k-1)
    d0 = np.zeros(H * nu)
    d0[:nu] = u_prev
    hessian = G.T @ W @ G + r_du * D.T @ D + r_u * np.eye(H * nu)
    gradient = G.T @ W @ (F @ x0 + h - refs.ravel()) - r_du * D.T @ d0
    return np.linalg.solve(hessian, -gradient).reshape(H, nu)


def test_the_qp_equals_the_dense_least_squares_plan_when_no_bound_is_active():
    # A double integrator per input, a constant drift c: with bounds far away, OSQP's sparse
    # program must give the plan of the dense normal equations.
    H, dt = 12, 0.1
    A = np.array([[1.0, dt, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0, 0, 1.0, dt], [0, 0, 0, 1.0]])
    B = np.array([[0.0, 0.0], [dt, 0.0], [0.0, 0.0], [0.0, dt]])
    c = np.array([0.0, 0.01, 0.0, -0.02])
    Q = np.array([10.0, 1.0, 5.0, 0.5])
    x0 = np.array([0.3, -0.1, -0.2, 0.05])
    refs = np.tile([0.0, 0.0, 0.1, 0.0], (H, 1))
    weights = QpWeights(tuple(Q), r_du=0.3, r_u=0.01, rho=1e4, rho1=1.0)
    qp = TrackingQP(4, 2, H, weights, u_max=1e3, bounded=[0])
    plan = qp.solve(x0, [A] * H, [B] * H, [c] * H, refs, (0.2, -0.1), bounds=[10.0])
    assert plan.ok
    expected = _unconstrained_plan(A, B, c, x0, refs, Q, 0.3, 0.01, np.array([0.2, -0.1]), H)
    np.testing.assert_allclose(plan.inputs, expected, atol=2e-4)  # OSQP's eps_abs 1e-5, scaled
    np.testing.assert_allclose(plan.states[0], x0, atol=1e-6)


def test_the_qp_keeps_the_input_bound():
    H = 5
    A, B = np.eye(1), np.eye(1)
    weights = QpWeights((100.0,), r_du=0.0, r_u=0.0, rho=1e4, rho1=1.0)
    qp = TrackingQP(1, 1, H, weights, u_max=0.5, bounded=[0])
    plan = qp.solve(
        np.zeros(1), [A] * H, [B] * H, [np.zeros(1)] * H, np.full((H, 1), 9.0), [0], [20]
    )
    assert plan.ok
    assert np.abs(plan.inputs).max() == pytest.approx(0.5, abs=1e-4)


def _run(**fields):
    scenario = Scenario(traj="s_curve", controller="nmpc", disturbance="none", **fields)
    return simulate(scenario)


@pytest.mark.parametrize("plant", ["reduced", "mujoco"])
def test_nmpc_tracks_the_s_curve_within_5_mm(plant):
    # The bound; measured 0.6-0.7 mm rms, 3.2-3.4 mm max on both plants.
    result = _run(plant=plant)
    m = result.metrics
    assert result.status == "ok"
    assert m["cross_track_rms"] < 5e-3
    report = m["controller"]
    assert report["solves"] == pytest.approx(m["sim_time_s"] / report["sample_dt_s"], abs=2)
    assert report["solve_failures"] == 0
    assert 0 < report["solve_ms_median"] <= report["solve_ms_max"]


@pytest.mark.parametrize("plant", ["reduced", "mujoco"])
def test_nmpc_backs_one_trailer_along_the_s_curve_without_a_jackknife(plant):
    # Measured: tractor 2.5-3.1 mm rms, the leading trailer's axle 11.7 mm rms.
    result = _run(plant=plant, reverse=True)
    assert result.status == "ok", result.message
    assert result.metrics["leading_cross_track_rms"] < 0.02


def test_a_missing_solver_is_refused_as_bad_input(tmp_path):
    out = tmp_path / "run"
    code = (
        "import sys; sys.modules['osqp'] = None\n"
        "from tt_mujoco.run import main\n"
        "sys.exit(main(['--controller', 'nmpc', '--no-video', '--no-plots', "
        f"'--out', {str(out)!r}]))"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 2, done.stderr
    assert "pip install 'tt-mujoco[mpc]'" in done.stderr
    assert not out.exists()


def test_metrics_json_carries_the_solve_times(tmp_path):
    out = tmp_path / "run"
    args = ["--controller", "nmpc", "--plant", "reduced", "--duration", "1", "--no-video"]
    args += ["--no-plots", "--out", str(out)]
    done = subprocess.run([sys.executable, "-m", "tt_mujoco.run", *args], capture_output=True)
    assert done.returncode == 0, done.stderr
    report = json.loads((out / "metrics.json").read_text())["controller"]
    assert set(report) == {"solves", "solve_ms_median", "solve_ms_max", "solve_failures",
                           "sample_dt_s"}  # fmt: skip
    assert report["solves"] in (25, 26)  # samples at t = 0, 0.04, ..., 1 s
    assert report["solve_failures"] == 0


class _Reporting:
    def __init__(self, report):
        self._report = report

    def report(self):
        if isinstance(self._report, Exception):
            raise self._report
        return self._report


@pytest.mark.parametrize(
    ("given", "kept", "error"),
    [
        (
            {"n": np.int64(3), "x": np.float64(1.5), "gone": float("nan")},
            {"n": 3, "x": 1.5, "gone": None},
            None,
        ),
        ({"bad": "text"}, {}, "is not a number"),
        ([1, 2], {}, "not a dict"),
        (RuntimeError("boom"), {}, "RuntimeError: boom"),
    ],
)
def test_a_controller_report_is_kept_as_strict_json_numbers_or_as_an_error(given, kept, error):
    from tt_mujoco.sim.simulate import controller_report

    report, message = controller_report(_Reporting(given))
    assert report == kept
    json.dumps(report, allow_nan=False)
    assert (message is None) if error is None else (error in message)


def test_a_sweep_runs_the_nmpc_and_keeps_its_solve_columns(tmp_path):
    out = tmp_path / "sweep"
    args = ["controller=nmpc", "plant=reduced", "duration=0.5", "--repeats", "1"]
    done = subprocess.run(
        [sys.executable, "-m", "tt_mujoco.sweep", *args, "--out", str(out)], capture_output=True
    )
    assert done.returncode == 0, done.stderr
    header = (out / "runs.csv").read_text().splitlines()[0].split(",")
    assert "controller.solve_ms_median" in header and "controller.solve_failures" in header

"""The gain-scheduled LQR path tracker (controllers/lqr.py)."""

import numpy as np
import pytest
from tt_mujoco.controllers import ControllerSetup, build_controller, reduced_model

from tt_mujoco import run
from tt_mujoco.reference.paths import circle
from tt_mujoco.sim import Scenario, build, simulate
from tt_mujoco.vehicle.linearize import jacobians
from tt_mujoco.vehicle.params import Params


def _controller(n: int):
    params = Params(eta=-1.0 / 7.0).with_trailers(n)
    setup = ControllerSetup(params=params, model=reduced_model(params), path=circle())
    controller = build_controller("lqr", setup)
    controller.reset()
    return controller


@pytest.mark.parametrize("n", [1, 2, 3])
@pytest.mark.parametrize("kappa", [-1.0, 0.0, 0.5, 1.0])
@pytest.mark.parametrize("v", [0.2, 0.8, 1.5])
def test_the_scheduled_gain_stabilises_the_linearised_kinematics(n, kappa, v):
    # The Riccati gain must make A - b K Hurwitz on every arc the schedule stores.
    ctrl = _controller(n)
    K = ctrl.gain(kappa, v)
    phis = [steady(kappa) for steady in ctrl._steady]
    A, B = jacobians((0.0, 0.0, *phis), (v, kappa * v), kappa, ctrl.lengths, ctrl.etas)
    closed = A - B[:, 1:2] @ K[None, :]
    assert np.linalg.eigvals(closed).real.max() < 0


def test_one_riccati_solution_serves_every_step_of_an_arc():
    ctrl = _controller(1)
    first = ctrl.gain(1.0, 0.8)
    assert ctrl.gain(1.0 + 0.004, 0.8 + 0.009) is first  # within the grid's half steps
    assert len(ctrl._gain_table) == 1


@pytest.mark.parametrize(("traj", "plant"), [("s_curve", "mujoco"), ("s_curve", "reduced")])
def test_it_tracks_the_s_curve_within_3_mm(traj, plant):
    # Measured: cross-track rms 0.5 / 0.6 mm, max 2.1 / 2.9 mm (MuJoCo / reduced).
    result = simulate(Scenario(controller="lqr", traj=traj, plant=plant, disturbance="none"))
    assert result.status == "ok"
    assert result.metrics["cross_track_rms"] < 3e-3
    assert result.metrics["cross_track_max"] < 6e-3


def test_reversing_is_refused_before_the_run(tmp_path, capsys):
    with pytest.raises(ValueError, match="driving forward only"):
        build(Scenario(controller="lqr", reverse=True))
    out = tmp_path / "r"
    argv = ["--controller", "lqr", "--reverse", "--no-video", "--no-plots", "--out", str(out)]
    assert run.main(argv) == 2
    assert not out.exists()

"""The benchmarks' own machinery on a short run: the physics floor they time a loop against is
MuJoCo's C rollout of the inputs the loop gave ``mj_step``, which must replay the run exactly."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from tt_mujoco.sim import Scenario, build

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
bench_closed_loop = pytest.importorskip("bench_closed_loop")


@pytest.mark.parametrize("noise", [None, 20.0], ids=["clean", "noisy"])
def test_the_rollout_of_the_recorded_inputs_replays_the_run(noise):
    scenario = Scenario(traj="s_curve", duration=0.3, noise_snr_db=noise)
    with bench_closed_loop.python_loop():
        _, steps, inputs, initial, final, plant, status = bench_closed_loop.closed_loop(
            scenario, record=True
        )
    assert status == "ok"
    assert len(inputs) == steps * build(scenario).substeps  # one row per physics step
    _, replayed = bench_closed_loop.replay(plant, inputs, initial)
    np.testing.assert_array_equal(replayed, final)


def test_the_parts_of_a_python_step_add_up_to_less_than_the_step():
    parts = bench_closed_loop.parts(Scenario(traj="s_curve", duration=0.3))
    halves = parts["sense (total)"] + parts["law"] + parts["actuate (total)"]
    assert 0.0 < parts["  mj_step"] < parts["actuate (total)"]
    assert 0.0 < halves <= parts["whole control step"]

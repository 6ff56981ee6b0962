"""The compiled episode (tt_mujoco.sim.compiled) against the Python loop: the same numbers bit
for bit, the same stops worded the same way, and the Python loop wherever it cannot run."""

from __future__ import annotations

import numpy as np
import pytest

from tt_mujoco.sim import Scenario, build, compiled, simulate


@pytest.fixture(autouse=True)
def compile_now(monkeypatch):
    """Compile in the test process instead of in the background."""
    monkeypatch.setenv("TT_MUJOCO_COMPILE_NOW", "1")


CASES = [
    dict(traj="s_curve", duration=4.0),
    dict(traj="s_curve", duration=4.0, noise_snr_db=20.0, seed=5),
    dict(traj="circle", plant="reduced", noise_snr_db=20.0, duration=4.0),
    dict(traj="cycloid", duration=3.0),
    dict(traj="cycloid", plant="reduced", target="static"),
    dict(traj="circle", target="static", disturbance="none", duration=3.0),
    dict(traj="s_curve", gains="paper_6_2", disturbance_limit="none", start="paper", duration=3.0),
    dict(traj="s_curve", eta="paper"),  # jackknifes at 1.142 s
    dict(traj="s_curve", eta="paper", plant="reduced"),  # and here at 1.095 s
    dict(traj="cycloid", controller="pid", noise_snr_db=20.0),
    dict(traj="cycloid", controller="fbl", plant="reduced"),
    dict(traj="s_curve", controller="pid", target="static", duration=3.0),
    dict(traj="circle", controller="fbl", noise_snr_db=15.0, duration=3.0),
]


def _both(monkeypatch, scenario):
    monkeypatch.setenv("TT_MUJOCO_COMPILED", "0")
    python = simulate(scenario)
    monkeypatch.setenv("TT_MUJOCO_COMPILED", "1")
    return python, simulate(scenario)


@pytest.mark.parametrize("case", CASES, ids=lambda c: "-".join(str(v) for v in c.values()))
def test_compiled_loop_equals_python_loop_bit_for_bit(monkeypatch, case):
    scenario = Scenario(**case)
    assert compiled.unsupported(build(scenario), build(scenario).new_controller()) is None
    python, fast = _both(monkeypatch, scenario)
    assert set(python.timeseries) == set(fast.timeseries)
    for name, column in python.timeseries.items():
        assert np.array_equal(column, fast.timeseries[name], equal_nan=True), name
    assert (python.status, python.message) == (fast.status, fast.message)


def test_checkpoint_rows_are_the_same(monkeypatch, tmp_path):
    scenario = Scenario(traj="circle", duration=3.0, noise_snr_db=25.0)
    texts = []
    for flag in ("0", "1"):
        monkeypatch.setenv("TT_MUJOCO_COMPILED", flag)
        path = tmp_path / f"partial{flag}.csv"
        simulate(scenario, checkpoint=path)
        texts.append(path.read_text())
    assert texts[0] == texts[1] and len(texts[0].splitlines()) == 3002


@pytest.mark.parametrize(
    ("changes", "reason"),
    [
        (dict(faults=["dropout:t=1"]), "faults or feedback"),
        (dict(path_feedback={}), "faults or feedback"),
        (dict(eta_schedule=True), "faults or feedback"),
        (dict(duration=1.0), "fewer than 2000 steps"),
        (dict(trailers=2), "a train"),
        (dict(disturbance="wrench"), "the wrench disturbance"),
        (dict(reverse=True), "this target"),
    ],
)
def test_the_python_loop_runs_what_has_no_compiled_form(changes, reason):
    built = build(Scenario(**{"traj": "circle", "duration": 3.0, **changes}))
    assert compiled.unsupported(built, built.new_controller()) == reason


def test_switched_off_by_the_environment(monkeypatch):
    monkeypatch.setenv("TT_MUJOCO_COMPILED", "0")
    built = build(Scenario(traj="circle", duration=3.0))
    assert compiled.unsupported(built, built.new_controller()) == "TT_MUJOCO_COMPILED=0"


def test_first_use_compiles_in_the_background_and_runs_the_python_loop(monkeypatch, tmp_path):
    monkeypatch.setenv("TT_MUJOCO_COMPILE_NOW", "0")
    monkeypatch.setenv("TT_MUJOCO_CACHE", str(tmp_path))
    monkeypatch.setattr(compiled, "_KERNEL", None)
    started = []
    monkeypatch.setattr(compiled, "_compile_in_background", lambda: started.append(1))
    built = build(Scenario(traj="circle", duration=3.0))
    reason = compiled.unsupported(built, built.new_controller())
    assert reason == "being compiled in the background (first use)" and started == [1]


def test_a_user_controller_runs_the_python_loop():
    from tt_mujoco.controllers.pid import PidController

    class Mine(PidController):
        pass

    built = build(Scenario(traj="circle", duration=3.0))
    controller = Mine.from_setup(built.controller_setup)
    assert compiled.unsupported(built, controller) == "a controller other than the built-in laws"

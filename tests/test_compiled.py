"""The compiled episode (tt_mujoco.sim.loop.compiled) against the Python loop: the same numbers bit
for bit, the same stops worded the same way, and the Python loop wherever it cannot run."""

from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np
import pytest
from tt_mujoco.controllers import CONTROLLERS

from tt_mujoco.reference.paths import PATHS
from tt_mujoco.sim import Scenario, build, simulate
from tt_mujoco.sim.loop import cache_key, compiled
from tt_mujoco.sim.loop.stepper import Stepper
from tt_mujoco.sim.parts.disturbances import DISTURBANCES
from tt_mujoco.sim.simulate import run_episode


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
    dict(traj="s_curve", disturbance="wrench", duration=3.0),
    dict(traj="s_curve", disturbance="wrench", trailers=2, noise_snr_db=20.0, duration=3.0),
    # trains of any N, on both plants; trailer 2 with eta = 2.5 jackknifes at hitch 2
    dict(traj="s_curve", trailers=3, disturbance="none", duration=3.0),
    dict(traj="s_curve", trailers=2, noise_snr_db=20.0, seed=2, duration=3.0),
    dict(traj="circle", trailers=3, plant="reduced", duration=3.0),
    dict(traj="s_curve", trailers=2, train=[{"eta": 2.5}], duration=3.0),
    dict(traj="s_curve", trailers=2, train=[{"eta": 2.5}], plant="reduced", duration=3.0),
    # the path schedule: gains that follow each axle, an actuated MuJoCo axle, the law's model
    # on the gains in force and the disturbance on the nominal's; a 3-trailer train that
    # jackknifes at hitch 3, and a plain-number law whose model keeps the nominal gains
    dict(traj="s_curve", eta="path", duration=4.0),
    dict(traj="s_curve", eta="path", plant="reduced", noise_snr_db=20.0, duration=3.0),
    dict(traj="cycloid", eta="path", trailers=3, disturbance="none", duration=3.0),
    dict(traj="circle", eta="path", trailers=2, plant="reduced", duration=3.0),
    dict(traj="s_curve", eta="path", trailers=3, disturbance="none"),
    dict(traj="s_curve", eta="path", controller="examples/kanayama.py:kanayama_law", duration=3.0),
    # the curvature schedule: a linkage whose ratio follows the target's curvature
    dict(traj="cycloid", eta="scheduled", duration=3.0),
    dict(traj="s_curve", eta="scheduled", trailers=3, plant="reduced", duration=3.0),
    dict(traj="circle", eta="scheduled", trailers=2, noise_snr_db=20.0, duration=3.0),
    # path feedback on omega_d, with either target, a train and the path schedule
    dict(traj="s_curve", path_feedback={}, duration=4.0),
    dict(traj="cycloid", path_feedback={"k_y": 9.0}, target="static", plant="reduced"),
    dict(traj="s_curve", path_feedback={}, eta="path", trailers=2, noise_snr_db=20.0),
    # backing up: the reverse target, with the hitch cascade (the default) or path feedback
    dict(traj="s_curve", reverse=True, duration=4.0),
    dict(traj="cycloid", reverse=True, trailers=2, plant="reduced", noise_snr_db=20.0),
    dict(traj="circle", reverse=True, trailers=3, disturbance="none", duration=4.0),
    dict(traj="s_curve", reverse=True, target="static", controller="pid", duration=3.0),
    dict(traj="s_curve", reverse=True, eta="paper", path_feedback={}, duration=3.0),
    # sensor dropouts (from the first step, and overlapping) and actuator faults
    dict(traj="s_curve", faults=["dropout:t=1,duration=0.3", "actuator:t=1.2,wheel=left"]),
    dict(
        traj="cycloid",
        plant="reduced",
        noise_snr_db=20.0,
        faults=["dropout:t=0,duration=0.05", "dropout:t=0.02,duration=0.2", "actuator:t=0.5"],
    ),
    dict(
        traj="s_curve",
        trailers=2,
        controller="examples/kanayama.py:kanayama_law",
        faults=["dropout:t=2,duration=0.5", "actuator:t=2,scale=0.5,wheel=right"],
        duration=4.0,
    ),
    # payload steps on the MuJoCo plant: at a time, at places (forward and backing up)
    dict(traj="s_curve", faults=["payload:t=1,factor=2", "payload:s=2.5,factor=0.5"]),
    dict(traj="s_curve", reverse=True, faults=["payload:s=3,factor=2"], duration=5.0),
    dict(traj="circle", trailers=3, faults=["payload:s=1,trailer=3,factor=3"], duration=4.0),
    # DC motors between the command and the wheels
    dict(traj="s_curve", actuator="dc_motor", duration=4.0),
    dict(traj="cycloid", actuator="dc_motor", plant="reduced", trailers=2, noise_snr_db=20.0),
    # wind: steady, gusty with noise (the gusts drawn after the noise), on top of the wrench
    # disturbance, and on a path-scheduled train
    dict(traj="circle", wind="6:90", duration=3.0),
    dict(traj="s_curve", wind="8:45:3", noise_snr_db=20.0, seed=3, duration=3.0),
    dict(traj="s_curve", wind="5:180:2", disturbance="wrench", trailers=2, duration=3.0),
    dict(traj="cycloid", wind="4:270:1", eta="path", trailers=3, disturbance="none"),
    # a sensor delay: the law and the outer loops read the readings of its steps ago, the
    # disturbance and the schedule the plant as it is; with noise and a dropout, a train,
    # backing up with the hitch cascade, path feedback and a plain-number law
    dict(traj="s_curve", sensor_delay=0.01, duration=3.0),
    dict(
        traj="circle",
        sensor_delay=0.005,
        noise_snr_db=20.0,
        faults=["dropout:t=1,duration=0.2"],
        plant="reduced",
        duration=3.0,
    ),
    dict(traj="s_curve", sensor_delay=0.004, trailers=2, eta="path", duration=3.0),
    dict(traj="s_curve", sensor_delay=0.003, reverse=True, trailers=2, duration=3.0),
    dict(traj="cycloid", sensor_delay=0.002, path_feedback={}, disturbance="wrench"),
    dict(
        traj="s_curve",
        sensor_delay=0.005,
        controller="examples/kanayama.py:kanayama_law",
        noise_snr_db=20.0,
        duration=3.0,
    ),
    # friction patches: bands along the path and rectangles, overlapping (the first counts),
    # with a train and backing up
    dict(traj="s_curve", ground=["band:0.5:1.5:0.1", "rect:-1:-1:1:3:0.3"], duration=3.0),
    dict(traj="circle", ground=["rect:0:0:2:2:0.2"], trailers=2, noise_snr_db=20.0),
    dict(traj="s_curve", ground=["band:2:3:0.05"], reverse=True, duration=4.0),
    # payload steps on the reduced plant: its constants change between the step's log and its
    # advance (at a time, at places; a train with a schedule whose gains the change keeps)
    dict(traj="s_curve", plant="reduced", faults=["payload:t=1,factor=2"], duration=3.0),
    dict(
        traj="circle",
        plant="reduced",
        trailers=3,
        eta="path",
        faults=["payload:s=1,trailer=2,factor=3", "payload:t=2,trailer=3,factor=0.5"],
        duration=3.0,
    ),
    dict(traj="s_curve", plant="reduced", reverse=True, faults=["payload:s=3,factor=2"]),
    # a path without closed form and a user's disturbance, which the kernel calls back: the
    # path for the target, for a plain-number law's pose, path feedback and the path schedule,
    # for the static target and friction bands along it; the disturbance matched on a train,
    # and as a wrench
    dict(traj="examples/user_parts.py:slalom", duration=3.0),
    dict(
        traj="examples/user_parts.py:slalom",
        controller="examples/kanayama.py:kanayama_law",
        path_feedback={},
        eta="path",
        duration=3.0,
    ),
    dict(
        traj="examples/user_parts.py:slalom",
        target="static",
        ground=["band:1:2:0.2"],
        duration=3.0,
    ),
    dict(
        traj="s_curve",
        disturbance_model="examples/user_parts.py:headwind_gusts",
        trailers=2,
        duration=3.0,
    ),
    dict(
        traj="s_curve",
        disturbance="wrench",
        disturbance_model="examples/user_parts.py:headwind_gusts",
        duration=3.0,
    ),
    # a controller class, whose compute the kernel calls back at every step: alone, with the
    # path schedule and noise (it is told of every change of the gains), on the reduced plant
    # with a dropout and a sensor delay
    dict(traj="s_curve", controller="examples/kanayama.py:KanayamaTracker", duration=3.0),
    dict(
        traj="s_curve",
        controller="examples/kanayama.py:KanayamaTracker",
        eta="path",
        noise_snr_db=20.0,
        duration=3.0,
    ),
    dict(
        traj="circle",
        controller="examples/kanayama.py:KanayamaTracker",
        plant="reduced",
        faults=["dropout:t=1,duration=0.3"],
        sensor_delay=0.004,
        duration=3.0,
    ),
]

# Every registered controller, path and disturbance, so that a new one joins the matrix by
# being registered.
CASES += [dict(traj="s_curve", controller=name, duration=2.0) for name in CONTROLLERS]
CASES += [dict(traj=name, duration=2.0) for name in PATHS]
CASES += [dict(traj="s_curve", disturbance_model=name, duration=2.0) for name in DISTURBANCES]


def _both(monkeypatch, scenario):
    """The scenario's result from the Python loop, then from the compiled one (checked to have
    run: it may hand an episode back to the Python loop)."""
    ran = []

    def run_compiled(*args, **kwargs):
        ran.append(outcome := run(*args, **kwargs))
        return outcome

    run = compiled.run_compiled
    monkeypatch.setattr(compiled, "run_compiled", run_compiled)
    monkeypatch.setenv("TT_MUJOCO_COMPILED", "0")
    python = simulate(scenario)
    monkeypatch.setenv("TT_MUJOCO_COMPILED", "1")
    fast = simulate(scenario)
    assert len(ran) == 1 and ran[0] is not None
    return python, fast


@pytest.mark.parametrize("case", CASES, ids=lambda c: "-".join(str(v) for v in c.values()))
def test_compiled_loop_equals_python_loop_bit_for_bit(monkeypatch, case):
    scenario = Scenario(**case)
    assert compiled.unsupported(build(scenario), build(scenario).new_controller()) is None
    python, fast = _both(monkeypatch, scenario)
    assert set(python.timeseries) == set(fast.timeseries)
    for name, column in python.timeseries.items():
        assert np.array_equal(column, fast.timeseries[name], equal_nan=True), name
    assert (python.status, python.message) == (fast.status, fast.message)
    assert python.metrics.get("ground") == fast.metrics.get("ground")  # the patches' report


def test_records_of_equal_keys_have_equal_numba_types(monkeypatch):
    """A process finds the machine code of its chunk loop by machine_code.entry_key of the
    records, not by numba's typing: scenarios whose records have equal keys must have equal
    types (else an entry would run on records of other types)."""
    from tt_mujoco.sim.loop import _entry_compile, machine_code

    seen = []
    entry_key = machine_code.entry_key

    def spied(name, args):
        if name == "run_chunk":
            typed = tuple(_entry_compile._typed(compiled.kernel(), r) for r in args)
            seen.append((entry_key(name, args), typed))
        return entry_key(name, args)

    monkeypatch.setattr(machine_code, "entry_key", spied)
    options = [
        dict(seed=1, noise_snr_db=20.0),
        dict(seed=2, noise_snr_db=20.0),
        dict(),
        dict(plant="reduced"),
        dict(trailers=3, disturbance="none"),
        dict(eta="path", trailers=2),
        dict(controller="examples/kanayama.py:kanayama_law"),
        dict(wind="6:90", ground=["rect:0:0:2:2:0.2"], sensor_delay=0.003),
    ]
    for extra in options:
        assert simulate(Scenario(traj="s_curve", duration=2.0, **extra)).status == "ok"
    assert len(seen) == len(options)
    types_of = {}
    for key, types in seen:
        assert types_of.setdefault(key, types) == types
    # and the key tells apart no more than the types do (each new key costs a compile)
    assert len(types_of) == len({types for _, types in seen}) and seen[0][0] == seen[1][0]


def test_a_payload_step_leaves_the_cache_as_its_manifest_lists():
    # The reduced plant's payload step calls a second compiled entry point
    # (advance_after_payload), which a warm-up does not compile. Its first compile adds files to
    # the cache folder; unlisted, the next process found the folder differing from its manifest
    # and set the whole cache aside (Python loop, and a new background compile).
    faults = ["payload:t=1,factor=2"]
    scenario = Scenario(traj="s_curve", plant="reduced", faults=faults, duration=3.0)
    assert simulate(scenario).status == "ok"
    assert compiled._cached()


@pytest.mark.parametrize("plant", ["mujoco", "reduced"])
def test_a_csv_spline_path_runs_compiled_bit_for_bit(monkeypatch, tmp_path, plant):
    # An ellipse of waypoints: a spline path, compiled like the closed-form ones (its curvature
    # for the target, its pose for a plain-number law).
    a = np.linspace(0.0, 1.5 * np.pi, 40)
    rows = "\n".join(f"{2.0 * np.cos(t):.6f},{1.2 * np.sin(t):.6f}" for t in a)
    path = tmp_path / "ellipse.csv"
    path.write_text("x,y\n" + rows + "\n")
    for controller in ("ismc_sta", "examples/kanayama.py:kanayama_law"):
        scenario = Scenario(traj=str(path), plant=plant, controller=controller, duration=3.0)
        built = build(scenario)
        assert compiled.unsupported(built, built.new_controller()) is None
        python, fast = _both(monkeypatch, scenario)
        for name, column in python.timeseries.items():
            assert np.array_equal(column, fast.timeseries[name], equal_nan=True), name
        assert (python.status, python.message) == (
            fast.status,
            fast.message,
        ) and fast.status == "ok"


def test_checkpoint_rows_are_the_same(monkeypatch, tmp_path):
    from tt_mujoco.sim.loop.checkpoint import read_checkpoint

    scenario = Scenario(traj="circle", duration=3.0, noise_snr_db=25.0)
    rows = []
    for flag in ("0", "1"):
        monkeypatch.setenv("TT_MUJOCO_COMPILED", flag)
        path = tmp_path / f"partial{flag}.arrows"
        simulate(scenario, checkpoint=path)
        rows.append(read_checkpoint(path))
    assert list(rows[0]) == list(rows[1]) and len(rows[0]["t"]) == 3001
    for name, column in rows[0].items():
        assert np.array_equal(column, rows[1][name], equal_nan=True), name


@pytest.mark.parametrize(
    ("changes", "reason"),
    [
        (dict(duration=1.0), "the run has 1000 control steps, fewer than the 2000"),
    ],
)
def test_the_python_loop_runs_what_has_no_compiled_form(changes, reason):
    scenario = Scenario(**{"traj": "circle", "duration": 3.0, **changes})
    built = build(scenario)
    assert compiled.unsupported(built, built.new_controller()).startswith(reason)
    # the run says so, once, in its notes (the command line prints them, metrics.json keeps them)
    notes = simulate(scenario).notes
    assert len(notes) == 1 and notes[0].startswith("the Python loop ran") and reason in notes[0]


def test_a_single_short_run_in_a_new_process_takes_the_faster_python_loop(monkeypatch):
    # without machine code in the cache, loading the compiled loop through numba costs what
    # the Python loop takes for its first COLD_MIN_STEPS steps: a process's first episode
    # shorter than that runs in Python, its next ones compiled, and a long one compiled at once
    monkeypatch.delenv("TT_MUJOCO_COMPILE_NOW", raising=False)
    monkeypatch.setattr(compiled, "_KERNEL", None)
    monkeypatch.setattr(compiled, "_EPISODES", 0)
    monkeypatch.setattr(compiled, "_machine_code_pays", lambda: False)
    short = build(Scenario(traj="circle", duration=13.0))
    why = compiled.loading_pays(short)
    assert why is not None and "13000 control steps" in why and "next episode" in why
    assert compiled.loading_pays(short) is None  # the process's second episode
    monkeypatch.setattr(compiled, "_EPISODES", 0)
    assert compiled.loading_pays(build(Scenario(traj="circle", duration=30.0))) is None
    monkeypatch.setattr(compiled, "_EPISODES", 0)
    monkeypatch.setenv("TT_MUJOCO_COMPILE_NOW", "1")  # the tests and benchmarks ask for it
    assert compiled.loading_pays(short) is None
    # machine code loads in milliseconds: a short first episode runs compiled, but for a
    # user's plain-number law whose machine code the cache lacks (numba compiles it)
    from tt_mujoco.sim.loop import compiled_law

    monkeypatch.delenv("TT_MUJOCO_COMPILE_NOW")
    monkeypatch.setattr(compiled, "_machine_code_pays", lambda: True)
    plain = "examples/kanayama.py:kanayama_law"
    for law, cached, pays in [
        ("ismc_sta", False, True),
        (plain, True, True),
        (plain, False, False),
    ]:
        monkeypatch.setattr(compiled_law, "has_machine_law", lambda cls, cached=cached: cached)
        monkeypatch.setattr(compiled, "_EPISODES", 0)
        built = build(Scenario(traj="circle", duration=13.0, controller=law))
        assert (compiled.loading_pays(built) is None) is pays, (law, cached)


def test_switched_off_by_the_environment(monkeypatch):
    monkeypatch.setenv("TT_MUJOCO_COMPILED", "0")
    built = build(Scenario(traj="circle", duration=3.0))
    assert compiled.unsupported(built, built.new_controller()).startswith("TT_MUJOCO_COMPILED=0")


def test_first_use_compiles_in_the_background_and_runs_the_python_loop(monkeypatch, tmp_path):
    monkeypatch.setenv("TT_MUJOCO_COMPILE_NOW", "0")
    monkeypatch.setenv("TT_MUJOCO_CACHE", str(tmp_path))
    monkeypatch.setattr(compiled, "_KERNEL", None)
    started = []
    monkeypatch.setattr(compiled, "_compile_in_background", lambda: started.append(1))
    monkeypatch.setattr(compiled, "_ASKED", False)
    at_exit = []
    monkeypatch.setattr("atexit.register", at_exit.append)
    built = build(Scenario(traj="circle", duration=3.0))
    assert compiled.unsupported(built, built.new_controller()) is None  # a query: no compile
    assert started == []
    # the first episode leaves the machine to the run: the compile starts as the process exits
    assert (
        compiled.not_ready() is not None
        and started == []
        and at_exit == [compiled._compile_at_exit]
    )
    at_exit[0]()
    assert started == [1]
    # a process that runs a second episode starts it then, and registers nothing more
    started.clear()
    assert compiled.not_ready() is not None and started == [1] and len(at_exit) == 1


def test_the_compile_asked_at_exit_is_skipped_once_the_kernel_is_there(monkeypatch, tmp_path):
    monkeypatch.setenv("TT_MUJOCO_COMPILE_NOW", "0")
    monkeypatch.setattr(compiled, "_KERNEL", None)
    _fake_cache(monkeypatch, tmp_path)  # filled meanwhile, by another process
    started = []
    monkeypatch.setattr(compiled, "_compile_in_background", lambda: started.append(1))
    compiled._compile_at_exit()
    assert started == []


def test_a_subclass_of_a_built_in_law_runs_its_compute_called_back(monkeypatch):
    from tt_mujoco.controllers.pid import PidController

    from tt_mujoco.sim.loop.law import PYTHON
    from tt_mujoco.sim.loop.stepper import Stepper

    class Mine(PidController):  # may change what it runs: its Python compute is the law
        pass

    built = build(Scenario(traj="circle", duration=3.0))
    controller = Mine.from_setup(built.controller_setup)
    assert compiled.unsupported(built, controller) is None
    stepper = Stepper(built)
    stepper.reset(np.random.default_rng(0))
    kernel = compiled.kernel()
    _, _, law, _, _ = stepper.begin(controller, None, kernel=kernel)
    assert law.kind == PYTHON and isinstance(law.user, kernel.PythonLawCallback)
    assert stepper.hooks[0] is law.user  # held while the kernel calls it
    # an agent's records name it by address
    _, _, law, _, _ = stepper.begin(controller, None, kernel, by_address=True)
    assert law.user == kernel.address_of(stepper.hooks[0])


FAILING = """
import sys
from tt_mujoco.controllers import Controller

class Fails(Controller):
    def compute(self, t, m, r):
        self.log("v_seen", m.v)
        if t >= 2.5:
            BODY
        return 0.3 + 0.01 * r.v_d - 0.05 * m.omega, 0.3 - 0.01 * r.v_d + 0.05 * m.omega
"""


@pytest.mark.parametrize(
    "body",
    ["raise ZeroDivisionError('gain')", "return None", "return float('nan'), 0.0", "sys.exit(0)"],
)
def test_a_controller_class_that_fails_stops_both_loops_alike(monkeypatch, tmp_path, body):
    # What the compute raises cannot leave the kernel's C callback: it stops the kernel, and
    # the kernel's caller raises it, at the same step and with the same rows as CPython's.
    path = tmp_path / "fails.py"
    path.write_text(FAILING.replace("BODY", body))
    scenario = Scenario(traj="circle", controller=f"{path}:Fails", duration=3.0)
    python, fast = _both(monkeypatch, scenario)
    assert python.status != "ok" and "t=2.500 s" in python.message
    assert (python.status, python.message) == (fast.status, fast.message)
    assert set(python.timeseries) == set(fast.timeseries)
    assert len(fast.timeseries["t"]) == 2500
    for name, column in python.timeseries.items():
        assert np.array_equal(column, fast.timeseries[name], equal_nan=True), name


BREAKING = """
import math

from tt_mujoco.reference.paths import ArcsPath


class BreaksCurvature(ArcsPath):  # users' path classes: no closed form for the kernel
    def curvature_and_rate(self, s):
        if s > 1.5:
            raise ValueError(f"no curvature at s={s}")
        return super().curvature_and_rate(s)


class BreaksPose(ArcsPath):
    def pose_at(self, s):
        if s > 1.5:
            raise ValueError(f"no pose at s={s}")
        return super().pose_at(s)


def arcs(cls):
    R = 1.5
    return cls("s_curve", (0.0, 0.0, 0.0), [(math.pi * R, 1 / R), (math.pi * R, -1 / R)])


def breaks_curvature():
    return arcs(BreaksCurvature)


def breaks_pose():
    return arcs(BreaksPose)


def breaks_at_2_5(t):
    if t >= 2.5:
        raise ValueError("no gust")
    return -1.0, 0.0
"""


@pytest.mark.parametrize(
    "hook",
    [
        dict(traj="{parts}:breaks_curvature"),  # the target's curvature, in the first half
        dict(traj="{parts}:breaks_pose", controller="examples/kanayama.py:kanayama_law"),
        dict(traj="{parts}:breaks_pose", eta="path"),  # the schedule's, after the row's log
        dict(disturbance_model="{parts}:breaks_at_2_5"),  # before the row's log
        dict(disturbance_model="{parts}:breaks_at_2_5", disturbance="wrench", trailers=2),
    ],
    ids=["curvature", "pose-law", "pose-schedule", "matched", "wrench"],
)
def test_a_hook_that_fails_stops_both_loops_alike(monkeypatch, tmp_path, hook):
    # A path or disturbance the kernel calls back that raises stops the step where CPython's
    # stops: the same rows kept, the same plant state handed back, the same error.
    parts = tmp_path / "breaking.py"
    parts.write_text(BREAKING)
    options = {k: v.format(parts=parts) if isinstance(v, str) else v for k, v in hook.items()}
    scenario = Scenario(**{"traj": "s_curve", "duration": 3.0, **options})
    outcomes = []
    for route in ("0", "1"):
        monkeypatch.setenv("TT_MUJOCO_COMPILED", route)
        built = build(scenario)
        stepper = Stepper(built)
        stepper.reset(np.random.default_rng(built.scenario.seed))
        controller = built.new_controller()
        controller.reset()
        try:
            status, message = run_episode(stepper, controller)
        except Exception as err:  # a path's failure is raised as it is
            status, message = type(err).__name__, str(err)
        data = stepper.plant.data  # the MuJoCo plant where it stopped
        state = np.concatenate([data.qpos, data.qvel, data.ctrl, data.qfrc_applied])
        outcomes.append((status, message, stepper.timeseries(), stepper.k, state))
    (status, message, rows, k, state), fast = outcomes
    assert status != "ok" and (status, message, k) == (*fast[:2], fast[3])
    assert 1000 < len(rows["t"]) < 3001 and rows.keys() == fast[2].keys()
    for name, column in rows.items():
        assert np.array_equal(column, fast[2][name], equal_nan=True), name
    assert np.array_equal(state, fast[4])


def test_an_interrupt_inside_a_called_back_compute_ends_the_run_as_it_does_in_python(
    monkeypatch, tmp_path
):
    # a KeyboardInterrupt the compute raises itself is its failure (tt_mujoco.guard); a real
    # Ctrl-C (SIGINT) arriving while it runs ends the run as an interrupt: alike on both loops
    path = tmp_path / "stops.py"
    path.write_text(FAILING.replace("BODY", "raise KeyboardInterrupt"))
    scenario = Scenario(traj="circle", controller=f"{path}:Fails", duration=3.0)
    outcomes = []
    for route in ("0", "1"):
        monkeypatch.setenv("TT_MUJOCO_COMPILED", route)
        run = simulate(scenario)
        outcomes.append((run.status, run.message, len(run.timeseries["t"])))
    assert outcomes[0] == outcomes[1] and outcomes[0][0] == "failed"
    assert "KeyboardInterrupt" in outcomes[0][1]
    real = tmp_path / "interrupted.py"
    real.write_text(
        FAILING.replace("BODY", "import os, signal; os.kill(os.getpid(), signal.SIGINT)")
    )
    for route in ("0", "1"):
        monkeypatch.setenv("TT_MUJOCO_COMPILED", route)
        with pytest.raises(KeyboardInterrupt):
            simulate(Scenario(traj="circle", controller=f"{real}:Fails", duration=3.0))


def test_a_python_law_is_given_the_reference_records_leading_fields():
    import inspect

    from tt_mujoco.controllers import Reference

    from tt_mujoco.sim.loop import records
    from tt_mujoco.sim.loop.python_law import GIVEN_REFERENCE_FIELDS as TARGET_FIELDS

    given = tuple(inspect.signature(Reference).parameters)
    assert records.REFERENCE_FIELDS[: len(TARGET_FIELDS)] == TARGET_FIELDS == given[:-1]


def _fake_cache(monkeypatch, tmp_path):
    """A cache folder laid out as the kernel leaves it, with a manifest."""
    import hashlib

    monkeypatch.setenv("TT_MUJOCO_CACHE", str(tmp_path))
    cache = compiled._cache_dir()
    sub = cache / f"{cache.name}_{hashlib.sha1(str(cache.resolve()).encode()).hexdigest()}"
    sub.mkdir(parents=True)
    (cache / "_kernel.py").write_text("# the kernel's copy\n")
    (sub / "_kernel.run_chunk-1.py311.nbi").write_bytes(b"index" * 100)
    (sub / "_kernel.run_chunk-1.py311.1.nbc").write_bytes(b"code" * 1000)
    compiled._write_manifest()
    return cache, sub


def test_a_whole_cache_is_ready_without_compiling(monkeypatch, tmp_path):
    monkeypatch.setenv("TT_MUJOCO_COMPILE_NOW", "0")
    monkeypatch.setattr(compiled, "_KERNEL", None)
    _fake_cache(monkeypatch, tmp_path)
    started = []
    monkeypatch.setattr(compiled, "_compile_in_background", lambda: started.append(1))
    assert compiled.not_ready() is None and started == []


@pytest.mark.parametrize("damage", ["truncate", "garbage_manifest", "moved"])
def test_a_damaged_cache_is_set_aside_and_the_run_takes_the_python_loop(
    monkeypatch, tmp_path, capsys, damage
):
    # A truncated file would make numba compile in the foreground (seconds), a garbage
    # manifest must not crash: either way the folder is moved aside with a one-line note,
    # a fresh compile starts in the background, and this run takes the Python loop.
    import shutil

    monkeypatch.setenv("TT_MUJOCO_COMPILE_NOW", "0")
    monkeypatch.setattr(compiled, "_KERNEL", None)
    cache, sub = _fake_cache(monkeypatch, tmp_path / "a")
    if damage == "truncate":
        code = next(sub.glob("*.nbc"))
        code.write_bytes(code.read_bytes()[:100])
    elif damage == "garbage_manifest":
        (cache / compiled.MANIFEST).write_text("{not json")
    else:  # the whole cache root copied elsewhere: numba would not find its subfolder
        shutil.copytree(tmp_path / "a", tmp_path / "b")
        monkeypatch.setenv("TT_MUJOCO_CACHE", str(tmp_path / "b"))
        cache = compiled._cache_dir()
    started = []
    monkeypatch.setattr(compiled, "_compile_in_background", lambda: started.append(1))
    monkeypatch.setattr(compiled, "_ASKED", True)  # a second episode: the compile starts now
    why = compiled.not_ready()
    assert why is not None and started == [1]
    assert why.startswith("the compiled-code cache could not be loaded") and str(cache) in why
    assert capsys.readouterr().err == ""  # told once, in the run's notes (run_episode)
    assert not cache.exists() and list(cache.parent.glob(f"{cache.name}.damaged-*"))


def test_a_cache_a_background_compile_is_writing_is_not_set_aside(monkeypatch, tmp_path, capsys):
    # The background compile writes the manifest after each signature it compiles, so a run
    # that starts in between sees more files than the manifest lists. It must take the Python
    # loop and leave the folder to the compile, not move it aside as damaged (which stranded
    # the compile's lock there and started a second compile).
    monkeypatch.setenv("TT_MUJOCO_COMPILE_NOW", "0")
    monkeypatch.setattr(compiled, "_KERNEL", None)
    cache, sub = _fake_cache(monkeypatch, tmp_path)
    (sub / "_kernel.run_chunk-1.py311.2.nbc").write_bytes(b"more")  # a second signature
    (cache / compiled.COMPILE_LOCK).touch()
    started = []
    monkeypatch.setattr(compiled, "_compile_in_background", lambda: started.append(1))
    monkeypatch.setattr(compiled, "_ASKED", True)
    assert "could not be loaded" not in compiled.not_ready()
    assert cache.exists() and not list(cache.parent.glob(f"{cache.name}.damaged-*"))
    # a lock older than the stale age is a compile that died: the folder is judged again
    old = time.time() - compiled.COMPILE_LOCK_STALE_S - 1
    os.utime(cache / compiled.COMPILE_LOCK, (old, old))
    assert compiled.not_ready() is not None
    assert not cache.exists() and list(cache.parent.glob(f"{cache.name}.damaged-*"))


@pytest.mark.parametrize("damage", ["hash", "symbols"])
def test_machine_code_that_fails_to_load_leaves_the_episode_to_the_python_loop(
    monkeypatch, tmp_path, damage
):
    """An entry whose object differs from its description is never loaded (garbage object
    code can crash the process that loads it); one that loads but lacks its symbols is
    refused: either way the cache is set aside and the Python loop runs, the same numbers."""
    import hashlib
    import json

    from tt_mujoco.sim.loop import machine_code

    monkeypatch.setenv("TT_MUJOCO_CACHE", str(tmp_path))
    scenario = Scenario(traj="circle", duration=3.0, noise_snr_db=25.0)
    monkeypatch.setenv("TT_MUJOCO_COMPILED", "0")
    python = simulate(scenario)
    monkeypatch.setenv("TT_MUJOCO_COMPILED", "1")
    entry_key = machine_code.entry_key
    llvm, _ = machine_code._llvm()  # an object of one function: loads, lacks them
    machine = llvm.Target.from_default_triple().create_target_machine()
    obj = machine.emit_object(llvm.parse_assembly("define i32 @f() { ret i32 1 }"))
    sha = hashlib.sha256(obj if damage == "symbols" else b"other").hexdigest()
    meta = {"wrapper": "entry", "env": "env", "ints": 1, "floats": 1, "sha256": sha}

    def damaged(name, args):
        key = entry_key(name, args)
        folder = compiled._cache_dir() / machine_code.MACHINE_DIR
        folder.mkdir(parents=True, exist_ok=True)
        (folder / f"{key}.o").write_bytes(obj)
        (folder / f"{key}.json").write_text(json.dumps(meta))
        return key

    monkeypatch.setattr(machine_code, "entry_key", damaged)
    monkeypatch.setattr(machine_code, "_LOADED", {})
    cache = compiled._cache_dir()
    result = simulate(scenario)
    why = {"hash": "differs from its description", "symbols": "does not load"}[damage]
    assert len(result.notes) == 1 and why in result.notes[0], result.notes
    assert not cache.exists() and list(cache.parent.glob(f"{cache.name}.damaged-*"))
    for name, column in python.timeseries.items():
        assert np.array_equal(column, result.timeseries[name], equal_nan=True), name


def test_the_cache_key_lists_the_sources_the_kernel_compiles():
    # What the kernel registers (kernel_sources.SHARED and STEP, discovered) and the functions
    # it gives a form of its own (COMPILED_FORMS) are what the key hashes.
    import inspect

    from tt_mujoco.sim.loop import kernel_sources

    files = kernel_sources.source_files()
    shared = (
        *kernel_sources.SHARED,
        *kernel_sources.STEP,
        *kernel_sources.COMPILED_FORMS,
        *kernel_sources.RECORDS,
    )
    for fn in shared:
        assert inspect.getsourcefile(fn) in files
    assert len(files) == len(set(files))
    modules = sorted({fn.__module__ for fn in shared})
    assert [inspect.getsourcefile(__import__(m, fromlist=["_"])) for m in modules] == files


def _states_after_both_loops(monkeypatch, scenario, state_of) -> list:
    """``state_of(stepper, controller)`` after the episode on the Python loop, then compiled."""
    from tt_mujoco.sim.loop.stepper import Stepper
    from tt_mujoco.sim.simulate import run_episode

    built = build(scenario)
    assert compiled.unsupported(built, built.new_controller()) is None
    states = []
    for flag in ("0", "1"):
        monkeypatch.setenv("TT_MUJOCO_COMPILED", flag)
        stepper = Stepper(built)
        stepper.reset(np.random.default_rng(0))
        controller = built.new_controller()
        controller.reset()
        assert run_episode(stepper, controller)[0] == "ok"
        states.append(state_of(stepper, controller))
    return states


@pytest.mark.parametrize(
    ("plant", "eta"), [("mujoco", "path"), ("reduced", "path"), ("mujoco", "scheduled")]
)
def test_a_schedule_leaves_the_same_state_on_both_loops(monkeypatch, plant, eta):
    # After a compiled episode the steering record stands where the Python loop leaves it: the
    # gains in force, how many changes, each axle's arc length; and the time series reads the
    # gain in force at each sample alike.
    def state_of(stepper, controller):
        steering = stepper.records.plant.steering
        return (
            stepper.plant_etas,
            int(steering.updates[0]),
            np.asarray(steering.arcs).tolist(),
            stepper.timeseries()["eq_violation"].tolist(),
        )

    scenario = Scenario(traj="cycloid", eta=eta, trailers=2, plant=plant, duration=3.0)
    states = _states_after_both_loops(monkeypatch, scenario, state_of)
    assert states[0] == states[1]
    assert states[0][1] > 10  # the gains did change along the cycloid


def test_a_background_compile_that_fails_is_told_once_and_not_retried(monkeypatch, tmp_path):
    # the compile's program records what failed beside the cache, and the lock is released;
    # a later run says why in its notes and starts no new compile for the same sources
    import subprocess
    import sys

    cache = tmp_path / "cache"
    cache.mkdir()
    lock = cache / compiled.COMPILE_LOCK
    lock.touch()
    sabotage = "import tt_mujoco.sim.loop.compiled as c\nc.warm_up = lambda: 1 / 0\n"
    done = subprocess.run(
        [sys.executable, "-c", sabotage + compiled.compile_script(lock)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode != 0 and "ZeroDivisionError" in done.stderr
    assert not lock.exists()
    assert (cache / compiled.COMPILE_FAILED).read_text() == "ZeroDivisionError: division by zero\n"
    monkeypatch.setattr(compiled, "_cache_dir", lambda: cache)
    monkeypatch.delenv("TT_MUJOCO_COMPILE_NOW", raising=False)
    monkeypatch.setattr(compiled, "_KERNEL", None)
    started = []
    monkeypatch.setattr(compiled, "_compile_in_background", lambda: started.append(1))
    monkeypatch.setattr(compiled, "_ASKED", True)
    why = compiled.not_ready()
    assert why.startswith("the background compile of the compiled loop failed (ZeroDivisionError")
    assert str(cache / compiled.COMPILE_LOG) in why and started == []


def test_a_run_the_python_loop_takes_sooner_judges_no_cache_during_the_run(monkeypatch, tmp_path):
    # a single short run neither keys nor hashes the cache while it runs (that cost it a
    # tenth of its loop): the compile it asks for judges the cache as the process exits
    monkeypatch.delenv("TT_MUJOCO_COMPILE_NOW", raising=False)
    monkeypatch.setattr(compiled, "_KERNEL", None)
    monkeypatch.setattr(compiled, "_EPISODES", 0)
    monkeypatch.setattr(compiled, "_machine_code_pays", lambda: False)
    asked, judged = [], []
    monkeypatch.setattr(compiled, "_ask_for_compile", lambda: asked.append(1))
    monkeypatch.setattr(compiled, "_cached", lambda: judged.append(1) or False)
    run = simulate(Scenario(traj="circle", duration=3.0))
    assert "sooner" in run.notes[0] and asked == [1] and judged == []
    # at exit: a compile that failed for these sources is not tried again
    started = []
    monkeypatch.setattr(compiled, "_compile_in_background", lambda: started.append(1))
    monkeypatch.setattr(compiled, "_cache_dir", lambda: tmp_path)
    (tmp_path / compiled.COMPILE_FAILED).write_text("ZeroDivisionError: x\n")
    compiled._compile_at_exit()
    assert started == [] and judged == []
    (tmp_path / compiled.COMPILE_FAILED).unlink()
    compiled._compile_at_exit()
    assert started == [1] and judged == [1]


def test_the_digest_is_found_by_the_sources_stamp_without_reading_the_sources(
    monkeypatch, tmp_path
):
    """A process that exits judges the cache by its folder, keyed by source_digest: worked
    out once per version of the files, then found by their stamp (sizes and times)."""
    stamps = tmp_path / "stamps"
    cache_key.digest_by_stamp.cache_clear()
    first = cache_key.digest_by_stamp(stamps)
    assert first == cache_key.source_digest()
    assert (stamps / cache_key.sources_stamp()).read_text().strip() == first

    def unread():
        raise AssertionError("the sources were read again")

    monkeypatch.setattr(cache_key, "source_digest", unread)
    cache_key.digest_by_stamp.cache_clear()
    assert cache_key.digest_by_stamp(stamps) == first
    (stamps / cache_key.sources_stamp()).write_text("not a digest\n")  # damaged: worked out again
    monkeypatch.setattr(cache_key, "source_digest", lambda: "0123456789abcdef")
    cache_key.digest_by_stamp.cache_clear()
    assert cache_key.digest_by_stamp(stamps) == "0123456789abcdef"
    cache_key.digest_by_stamp.cache_clear()


def test_the_sources_stamp_changes_with_a_file_of_the_package():
    import tt_mujoco.viz

    path = Path(tt_mujoco.viz.__file__)
    before = path.stat()
    stamp = cache_key.sources_stamp.__wrapped__()
    try:
        os.utime(path, ns=(before.st_atime_ns, before.st_mtime_ns + 1_000_000))
        assert cache_key.sources_stamp.__wrapped__() != stamp
    finally:
        os.utime(path, ns=(before.st_atime_ns, before.st_mtime_ns))
    assert cache_key.sources_stamp.__wrapped__() == stamp


def test_a_new_process_runs_the_machine_code_without_numba():
    """Where the cache holds the chunk loop's machine code (and a plain-number law's), a new
    process runs its first episode compiled without importing numba, with the numbers of the
    process that compiled it."""
    import subprocess
    import sys

    law = str(Path(__file__).resolve().parents[1] / "examples" / "kanayama.py") + ":kanayama_law"
    specs = ("ismc_sta", law)
    here = [simulate(Scenario(traj="circle", duration=3.0, controller=s)) for s in specs]
    script = (
        "import sys\n"
        "from tt_mujoco.sim import Scenario, simulate\n"
        f"for spec in {specs!r}:\n"
        "    run = simulate(Scenario(traj='circle', duration=3.0, controller=spec))\n"
        "    print(run.notes, repr(run.timeseries['T_r'][-1]))\n"
        "print('numba' in sys.modules)\n"
    )
    env = {k: v for k, v in os.environ.items() if k != "TT_MUJOCO_COMPILE_NOW"}
    done = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, env=env, timeout=300
    )
    assert done.returncode == 0, done.stderr
    *runs, imported = done.stdout.splitlines()
    assert imported == "False"
    for line, run in zip(runs, here, strict=True):
        assert line == f"[] {run.timeseries['T_r'][-1]!r}"

"""Faults: runs keep working, report the fault, and lose nothing.

Each fault runs a few seconds on the MuJoCo plant against a baseline without it; the margins
are set well inside the measured ratios quoted in each test (measured with these scenarios).
"""

import json
import math
import os

import numpy as np
import pytest

from tt_mujoco import outputs, run
from tt_mujoco.sim import Scenario, build, simulate
from tt_mujoco.sim.parts import faults

# S-curve, 4 s: the ramp (0-2 s) and 2 s of cruising on the first arc, paper disturbance on.
S_CURVE = {"traj": "s_curve", "duration": 4.0}


@pytest.fixture(scope="module")
def baseline():
    return simulate(Scenario(**S_CURVE))


def same_window(result, reference, fault):
    """Errors of ``reference`` over the window ``result`` reports for ``fault``."""
    t_last = float(result.timeseries["t"][-1])
    t_end = min(t_last, fault["t_end"] + faults.RECOVERY_S)
    return faults.window_errors(
        reference.timeseries, reference.reference_polyline, fault["t"], t_end
    )


# --- same seed, same numbers ---------------------------------------------------------------------
def test_same_seed_gives_identical_outputs(tmp_path):
    common = ["--duration", "3", "--noise-snr", "20", "--no-video", "--no-plots", "--quiet"]
    outs = {}
    for name, seed in (("a", "5"), ("b", "5"), ("c", "6")):
        outs[name] = tmp_path / name
        assert run.main([*common, "--seed", seed, "--out", str(outs[name])]) == 0

    def metrics(name):
        doc = json.loads((outs[name] / "metrics.json").read_text())
        doc.pop("wall_time_s")
        # which loop ran (a process's first short run takes the Python loop, the next the
        # compiled one: the same numbers) is said in the notes, not in the numbers
        doc.pop("notes")
        return doc

    def series(name):
        return (outs[name] / "timeseries.parquet").read_bytes()

    assert metrics("a") == metrics("b")
    assert series("a") == series("b")
    # The seed does reach the numbers (the noise), so the equality above is not vacuous.
    assert series("a") != series("c")
    assert metrics("a")["rmse_v"] != metrics("c")["rmse_v"]


# --- low friction --------------------------------------------------------------------------------
def test_low_friction_reports_slip():
    # Circle, 4 s, paper disturbance. At mu = 0.3 the tractor wheels can push only about
    # 0.6 m/s^2 and the S-curve (same ramp) spins them up into a jackknife at 4.0 s, so the
    # circle is the case that completes and shows the slip.
    circle = {"traj": "circle", "duration": 4.0}
    base = simulate(Scenario(**circle))
    icy = simulate(Scenario(**circle, friction=0.3))
    assert icy.status == "ok"  # the run completes
    # Measured: longitudinal slip 7.49 m/s at mu = 0.3 vs 0.056 at mu = 1 (133x); lateral
    # 0.557 vs 0.00135 m/s (413x); max lateral error 0.158 m vs 2.2e-4 m (732x).
    b, m = base.metrics, icy.metrics
    assert m["slip_longitudinal_max"] > 20 * b["slip_longitudinal_max"]
    assert m["slip_longitudinal_max"] > 1.0
    assert m["slip_lateral_max"] > 100 * b["slip_lateral_max"]
    assert m["max_lateral"] > 50 * b["max_lateral"]


# --- payload step --------------------------------------------------------------------------------
def test_payload_step_half_way_raises_the_errors_after_it():
    # Cycloid (speed changes all along, so mass matters), no disturbance: the only mismatch
    # between plant and nominal model after the step is the payload.
    plain = Scenario(traj="cycloid", disturbance="none")
    base = simulate(plain)
    half = round(float(base.timeseries["t"][-1]) / 2, 3)
    loaded = simulate(Scenario(traj="cycloid", disturbance="none", faults=[f"payload:t={half}"]))
    assert loaded.status == "ok"
    (report,) = loaded.metrics["faults"]
    assert report["kind"] == "payload" and report["factor"] == 1.5 and report["reached"]
    before = same_window(loaded, base, report)
    after = report["window"]
    # Measured over [2.356, 4.712] s: max|e_v| 4.16e-5 vs 1.85e-6 m/s (22x), max|e_omega|
    # 1.35e-4 vs 8.3e-6 rad/s (16x). Small in absolute terms: +3 kg on the trailer body is
    # about +2 % of the effective mass (the wheels' spin inertia is 25 kg each, docs/model.md
    # Section 4).
    assert after["max_abs_v"] > 8 * before["max_abs_v"]
    assert after["max_abs_omega"] > 8 * before["max_abs_omega"]
    # Before the step both runs are the same run.
    first = base.timeseries["t"] < half - 1e-9
    assert np.array_equal(base.timeseries["v"][first], loaded.timeseries["v"][first])


def test_payload_step_on_the_reduced_plant():
    kw = {"traj": "cycloid", "disturbance": "none", "plant": "reduced", "duration": 2.0}
    base = simulate(Scenario(**kw))
    loaded = simulate(Scenario(**kw, faults=[{"kind": "payload", "t": 1.0, "factor": 1.5}]))
    (report,) = loaded.metrics["faults"]
    before = same_window(loaded, base, report)
    # Measured: max|e_v| over [1, 2] s 1.66e-4 vs 3.5e-6 m/s (48x).
    assert report["window"]["max_abs_v"] > 10 * before["max_abs_v"]


@pytest.mark.parametrize("plant", ["mujoco", "reduced"])
def test_a_payload_on_trailer_2_of_a_train_loads_that_trailer(plant):
    kw = {"traj": "circle", "disturbance": "none", "plant": plant, "duration": 1.0, "trailers": 2}
    base = simulate(Scenario(**kw))
    loaded = simulate(Scenario(**kw, faults=["payload:t=0.5,factor=2,trailer=2"]))
    (report,) = loaded.metrics["faults"]
    assert report["trailer"] == 2 and report["factor"] == 2.0
    after = loaded.timeseries["t"] >= 0.5
    assert not np.array_equal(base.timeseries["v"][after], loaded.timeseries["v"][after])
    first = ~after
    assert np.array_equal(base.timeseries["v"][first], loaded.timeseries["v"][first])


def test_unloading_trailer_2_is_the_payload_below_one_and_a_missing_trailer_is_refused():
    kw = {"traj": "circle", "disturbance": "none", "plant": "reduced", "duration": 0.5}
    assert simulate(Scenario(**kw, trailers=2, faults=["payload:t=0.2,factor=0.5,trailer=2"])).ok
    with pytest.raises(ValueError, match="trailer=2 is not allowed: the train has 1 trailer"):
        build(Scenario(**kw, faults=["payload:t=0.2,trailer=2"]))
    with pytest.raises(ValueError, match=r"trailer='1\.5' is not allowed"):
        build(Scenario(**kw, faults=["payload:t=0.2,trailer=1.5"]))


# --- sensor dropout ------------------------------------------------------------------------------
def test_sensor_dropout_holds_the_last_value_and_shows_in_the_errors(baseline):
    dropped = simulate(Scenario(**S_CURVE, faults=[{"kind": "dropout", "t": 2.0}]))
    assert dropped.status == "ok"
    (report,) = dropped.metrics["faults"]
    assert report["held_steps"] == 100  # 100 ms at 1 kHz
    ts = dropped.timeseries
    held = (ts["t"] >= 2.0 - 1e-9) & (ts["t"] < 2.1 - 1e-9)
    last = np.flatnonzero(ts["t"] < 2.0 - 1e-9)[-1]
    assert held.sum() == 100
    assert np.all(ts["v_meas"][held] == ts["v_meas"][last])
    assert np.all(ts["omega_meas"][held] == ts["omega_meas"][last])
    assert np.ptp(ts["v"][held]) > 0  # while the true speed moves on
    before = same_window(dropped, baseline, report)
    # Measured over [2, 3.1] s: max|e_omega| 2.15e-2 vs 2.28e-3 rad/s (9.4x), max|e_v|
    # 1.25e-3 vs 2.6e-4 m/s (4.8x).
    assert report["window"]["max_abs_omega"] > 4 * before["max_abs_omega"]
    assert report["window"]["max_abs_v"] > 2.5 * before["max_abs_v"]


# --- actuator failure ----------------------------------------------------------------------------
@pytest.mark.parametrize("wheel", ["both", "right"])
def test_actuator_at_30_percent_for_one_second(baseline, wheel):
    spec = {"kind": "actuator", "t": 1.5, "duration": 1.0, "scale": 0.3, "wheel": wheel}
    weak = simulate(Scenario(**S_CURVE, faults=[spec]))
    assert weak.status == "ok"  # the run completes
    (report,) = weak.metrics["faults"]
    ts = weak.timeseries
    on = (ts["t"] >= 1.5 - 1e-9) & (ts["t"] < 2.5 - 1e-9)
    assert on.sum() == 1000
    asked_r = np.clip(ts["T_r_cmd"], -15, 15)
    assert np.allclose(ts["T_r"][on], 0.3 * asked_r[on], rtol=0, atol=1e-12)
    assert np.array_equal(ts["T_r"][~on], asked_r[~on])
    if wheel == "right":
        assert np.array_equal(ts["T_l"], np.clip(ts["T_l_cmd"], -15, 15))
    before = same_window(weak, baseline, report)
    # Measured over [1.5, 3.5] s: max|e_v| 1.30 (both) / 1.33 (right) m/s vs 2.9e-4; the
    # matched disturbance needs about 4.6 N m a wheel, and 30 % of 15 N m is 4.5 N m.
    assert report["window"]["max_abs_v"] > 1000 * before["max_abs_v"]
    assert report["window"]["max_abs_v"] > 0.5
    assert report["torque_shortfall_max"] == pytest.approx(10.5)  # 70 % of the 15 N m limit


# --- body wrench beyond traction -----------------------------------------------------------------
def test_body_wrench_beyond_traction_stops_reported_and_written(baseline, tmp_path):
    out = tmp_path / "wrench"
    argv = ["--duration", "4", "--disturbance-mode", "wrench", "--no-video", "--no-plots"]
    code = run.main([*argv, "--quiet", "--out", str(out)])
    assert code == 3  # the run ends, reported as a jackknife, not a crash
    doc = json.loads((out / "metrics.json").read_text())
    assert doc["status"] == "jackknife" and "jackknife at t=" in doc["message"]
    # Measured: stops at t = 1.05 s; longitudinal slip 18.9 vs 0.056 m/s with the matched
    # disturbance (340x), lateral slip 8.5 vs 0.0014 m/s: the tyres cannot carry ~465 N.
    assert doc["slip_longitudinal_max"] > 100 * baseline.metrics["slip_longitudinal_max"]
    assert doc["slip_lateral_max"] > 1000 * baseline.metrics["slip_lateral_max"]
    ts = outputs.read_timeseries(out / "timeseries.parquet")
    assert len(ts["t"]) == doc["steps"] > 500  # everything up to the stop is kept


# --- atomic outputs ------------------------------------------------------------------------------
def test_interrupted_output_leaves_no_metrics(tmp_path, monkeypatch, capsys):
    from tt_mujoco.viz import plots

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(plots, "run_pngs", interrupted)
    out = tmp_path / "run"
    code = run.main(["--duration", "1", "--no-video", "--quiet", "--out", str(out)])
    assert code == run.EXIT_INTERRUPTED
    assert "metrics.json was not written" in capsys.readouterr().err
    names = sorted(p.name for p in out.iterdir())
    # complete files only, no temporaries
    assert names == ["config.toml", "reference_path.parquet", "timeseries.parquet"]
    ts = outputs.read_timeseries(out / "timeseries.parquet")
    assert len(ts["t"]) == 1001 and ts["t"][-1] == 1.0


def test_exception_inside_write_outputs_after_the_csv(tmp_path, monkeypatch):
    from tt_mujoco.viz import plots

    def broken(*args, **kwargs):
        raise RuntimeError("disk on fire")

    monkeypatch.setattr(plots, "run_pngs", broken)
    result = simulate(Scenario(duration=0.5))
    with pytest.raises(RuntimeError, match="disk on fire"):
        run.write_outputs(result, tmp_path, {"video": False, "plots": True, "quiet": True})
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "reference_path.parquet",
        "timeseries.parquet",
    ]


def test_atomic_write_never_leaves_a_partial_file(tmp_path, monkeypatch):
    target = tmp_path / "metrics.json"

    def failing_replace(src, dst):
        raise OSError("rename failed")

    monkeypatch.setattr(os, "replace", failing_replace)
    with pytest.raises(OSError):
        outputs.atomic_write(target, "{}" * 1000)
    assert list(tmp_path.iterdir()) == []


def test_interrupted_simulation_removes_its_folder(tmp_path, monkeypatch, capsys):
    from tt_mujoco import sim

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(sim, "simulate", interrupted)
    out = tmp_path / "run"
    code = run.main(["--duration", "1", "--no-video", "--quiet", "--out", str(out)])
    assert code == run.EXIT_INTERRUPTED
    assert "nothing was written" in capsys.readouterr().err
    assert not out.exists()


def test_fault_specs_parse_and_refuse():
    f = faults.parse_fault("actuator:t=2,scale=0.5,wheel=left")
    assert f == faults.Fault("actuator", 2.0, duration=1.0, scale=0.5, wheel="left")
    assert faults.parse_fault(f.to_dict()) == f
    assert math.isinf(faults.parse_fault({"kind": "payload", "t": 0}).duration)
    with pytest.raises(ValueError, match=r"scale='1\.5'"):
        faults.parse_fault("actuator:t=1,scale=1.5")
    with pytest.raises(ValueError, match="'oops' is not key=value"):
        faults.parse_fault("dropout:t=1,oops")
    for lost in ("dropout:t=1,,duration=0.2", "dropout:t=1,", "dropout:,t=1"):
        with pytest.raises(ValueError, match="an empty item between commas"):
            faults.parse_fault(lost)  # a value lost, not skipped


# --- a payload placed along the path -------------------------------------------------------------
@pytest.mark.parametrize("plant", ["mujoco", "reduced"])
def test_a_payload_at_an_arc_length_acts_where_the_reference_reaches_it(plant):
    kw = {"traj": "circle", "disturbance": "none", "plant": plant, "duration": 2.0}
    placed = simulate(Scenario(**kw, faults=["payload:s=0.3,factor=2"]))
    (report,) = placed.metrics["faults"]
    assert report["s"] == 0.3 and "t" not in report and report["reached"]
    ts = placed.timeseries
    # It acted at the first control step whose reference arc length had reached 0.3 m.
    k = int(np.argmax(ts["s"] >= 0.3))
    assert report["t_acted"] == pytest.approx(ts["t"][k], abs=1e-12)
    # The same payload at that time gives the same run, bit for bit.
    timed = simulate(Scenario(**kw, faults=[f"payload:t={report['t_acted']!r},factor=2"]))
    for name in ("x", "y", "v", "omega", "phi"):
        np.testing.assert_array_equal(ts[name], timed.timeseries[name])


def test_a_payload_placed_backing_up_acts_as_the_arc_length_falls():
    kw = {"traj": "circle", "disturbance": "none", "plant": "reduced", "duration": 2.0}
    run = simulate(Scenario(**kw, reverse=True, faults=["payload:s=0.5,factor=0.5"]))
    (report,) = run.metrics["faults"]
    s = run.timeseries["s"]
    assert s[0] > 0.5 > s[-1]  # driven from the run's end of the path towards its start
    k = int(np.argmax(s <= 0.5))
    assert report["reached"] and report["t_acted"] == pytest.approx(run.timeseries["t"][k])


def test_a_placed_payload_not_reached_and_bad_places_are_reported():
    kw = {"traj": "circle", "disturbance": "none", "plant": "reduced", "duration": 0.5}
    run = simulate(Scenario(**kw, faults=["payload:s=5"]))
    assert run.metrics["faults"][0]["reached"] is False
    assert run.metrics["faults"][0]["t_acted"] is None
    with pytest.raises(ValueError, match="not both"):
        faults.parse_fault("payload:t=1,s=2")
    with pytest.raises(ValueError, match=r"the start time t \(s\) or the arc length s \(m\)"):
        faults.parse_fault("payload:factor=2")
    with pytest.raises(ValueError, match="option 's' is not allowed"):
        faults.parse_fault("dropout:s=2")
    with pytest.raises(ValueError, match=r"s='-1' is not allowed"):
        faults.parse_fault("payload:s=-1")
    with pytest.raises(ValueError, match=r"s=99.0 m is beyond the end of the path"):
        build(Scenario(**kw, faults=["payload:s=99"]))
    f = faults.parse_fault("payload:s=2.5,trailer=1")
    assert f.to_dict() == {"kind": "payload", "s": 2.5, "factor": 1.5, "trailer": 1}
    assert faults.parse_fault(f.to_dict()) == f

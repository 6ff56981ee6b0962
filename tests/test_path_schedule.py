"""The path schedule eta_k(s): its geometry, its kinematic ideal, and runs with ``--eta path``."""

from __future__ import annotations

import importlib.util
import json
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.special import fresnel

from tt_mujoco import outputs, run
from tt_mujoco.reference.path_base import ReferencePath
from tt_mujoco.reference.targets import make_target
from tt_mujoco.sim import Scenario, build, simulate
from tt_mujoco.sweep import BadSpecError
from tt_mujoco.sweep.options import convert
from tt_mujoco.vehicle.params import train_same_path_etas
from tt_mujoco.vehicle.path_schedule import (
    PathSchedule,
    axle_chain,
    nearest_arc_length,
    path_schedule,
)
from tt_mujoco.vehicle.reduced import phi_rate_of
from tt_mujoco.vehicle.rolling import constant_steering, drive_along_path, schedule_steering
from tt_mujoco.vehicle.steering import exact_train_same_path_etas

LINKS = (0.3, 0.4)
PLANTS = ("mujoco", "reduced")


class Clothoid(ReferencePath):
    """kappa(s) = rate * s from s = 0, in closed form (Fresnel integrals)."""

    def __init__(self, rate: float = 0.5, length: float = 2.5):
        super().__init__("clothoid", length)
        self.rate = rate
        self.scale = math.sqrt(math.pi / rate)

    def _pose(self, s):
        sine, cosine = fresnel(np.asarray(s) / self.scale)
        return self.scale * cosine, self.scale * sine, 0.5 * self.rate * np.asarray(s) ** 2

    def _pose_at(self, s):
        x, y, heading = self._pose(s)
        return float(x), float(y), float(heading)

    def _curvature(self, s):
        return self.rate * np.asarray(s)

    def _curvature_rate(self, s):
        return np.full_like(np.asarray(s, dtype=float), self.rate)

    def curvature_and_rate(self, s):
        return self.rate * s, self.rate


def _paths():
    return {
        "circle": make_target("circle").path,
        "cycloid": make_target("cycloid").path,
        "clothoid": Clothoid(),
    }


def _worst(result, n):
    return [float(np.nanmax(np.abs(result[f"offset_{k}"]))) for k in range(1, n + 1)]


def _rms(result, n):
    return [float(np.sqrt(np.nanmean(result[f"offset_{k}"] ** 2))) for k in range(1, n + 1)]


def _shortfall(schedule, k):
    """An upper bound on the off-tracking the bounded gain can cause: the steering it could not
    give, integrated along the axle's path (|d offset / ds| <= |delta beta|)."""
    axle = schedule.axles[k]
    missing = np.abs(axle["beta"] - axle["eta"] * axle["phi"])
    return float(np.sum(0.5 * (missing[1:] + missing[:-1]) * np.diff(axle["s"])))


@pytest.mark.parametrize("n", [1, 2, 3])
@pytest.mark.parametrize("name", ["circle", "cycloid", "clothoid"])
def test_kinematic_ideal_puts_every_axle_on_the_path(name, n):
    # A tractor driven exactly along the path from rest, trailers straight behind it: the
    # schedule keeps every axle on the path, the lead-in and the curvature changes included.
    # Measured 2.5e-7 m at worst (circle), the RK4 step (2 mm) and the table's cubic
    # interpolation; the bound is 1e-6 m. On the clothoid, trailers 2 and 3 meet one point on
    # their lead-in where phi_k passes through zero while beta_k is -0.08 / -0.28 deg: no gain
    # gives that, and the bound there is the steering the gain could not give (12 um for
    # trailer 3, within its bound of 30 um).
    path = _paths()[name]
    lengths = [LINKS] * n
    schedule = path_schedule(path, lengths)
    result = drive_along_path(path, lengths, schedule_steering(schedule))
    for k, worst in enumerate(_worst(result, n)):
        assert worst < 1e-6 + _shortfall(schedule, k)
    feasible = [k for k in range(n) if schedule.axles[k]["exact"].all()]
    assert feasible == (list(range(n)) if name != "clothoid" else [0])
    plain = drive_along_path(path, lengths, constant_steering(train_same_path_etas(lengths)))
    if name == "clothoid":
        assert min(_worst(plain, n)) > 1e-3  # the same-path limit gains, for scale
    else:
        # the README and docs/model.md Section 13 quote these: 2.5e-7 m at worst, against
        # 13-78 mm with the same-path limit gains
        assert max(_worst(result, n)) < 2.6e-7
        assert 13e-3 < min(_worst(plain, n)) and max(_worst(plain, n)) < 78.3e-3


@pytest.mark.parametrize("n", [1, 2, 3])
def test_s_curve_exact_up_to_the_junction_and_four_times_better_than_same_path(n):
    # At the junction of the S (s = 3 pi / 2 m) the tractor's curvature steps from +2/3 to
    # -2/3 1/m; the axles then need |beta / phi| > 3 for a stretch around the inflection
    # (phi passes through zero while beta does not) and the bounded gain leaves them off the
    # path (8.7 / 16.0 / 20.8 mm at worst; 9.8 / 20.8 / 30.2 mm with the table's gain alone,
    # not the blend of PathSchedule.gain), after which they converge back on the second arc.
    path = make_target("s_curve").path
    lengths = [LINKS] * n
    schedule = path_schedule(path, lengths)
    result = drive_along_path(path, lengths, schedule_steering(schedule))
    junction = 1.5 * math.pi
    before = result["s"] < junction
    for k in range(1, n + 1):
        offset = result[f"offset_{k}"]
        assert np.nanmax(np.abs(offset[before])) < 1e-6
        # converging back on the second arc: at the path's end 7e-6 (trailer 1) to 1.6e-3
        # (trailer 3) of the worst
        assert abs(offset[-1]) < 0.01 * np.nanmax(np.abs(offset))
    clipped = ~schedule.axles[0]["exact"]
    assert clipped.any() and np.all(schedule.s_tractor[clipped] > junction)
    # docs/model.md Section 13 quotes these
    expected_worst = [8.70e-3, 16.03e-3, 20.76e-3][:n]
    assert _worst(result, n) == pytest.approx(expected_worst, abs=5e-5)
    plain = drive_along_path(path, lengths, constant_steering(train_same_path_etas(lengths)))
    assert _worst(plain, n) == pytest.approx([52.78e-3, 102.44e-3, 134.91e-3][:n], abs=5e-5)
    for scheduled, limit in (
        (_worst(result, n), _worst(plain, n)),
        (_rms(result, n), _rms(plain, n)),
    ):
        assert all(4.0 * a < b for a, b in zip(scheduled, limit, strict=True)), (scheduled, limit)


@pytest.mark.parametrize("n", [1, 2, 3])
def test_steady_arc_gains_equal_the_exact_same_path_gains(n):
    # An independent construction (vehicle/steering.py: circles about the turn centre) gives the
    # same gains once every axle is on the circle.
    path = make_target("circle").path
    lengths = [LINKS] * n
    schedule = path_schedule(path, lengths)
    steady = schedule.s_tractor > 3.0
    expected = exact_train_same_path_etas(1.0, lengths)
    for axle, eta in zip(schedule.axles, expected, strict=True):
        assert np.max(np.abs(axle["eta"][steady] - eta)) < 1e-9
        assert axle["exact"].all()
        assert axle["eta"].max() == pytest.approx(0.428, abs=1e-3)  # the lead-in (docs)


def test_axles_lie_on_the_path_at_their_link_lengths():
    path = make_target("cycloid").path
    lengths = [LINKS, (0.5, 0.3)]
    s = np.linspace(0.0, path.length, 200)
    fx, fy, fth = path.pose(s)
    for axle, (L, L0) in zip(axle_chain(path, s, lengths), lengths, strict=True):
        x, y, tangent = path.pose(axle["s"])
        np.testing.assert_allclose(x, axle["x"], atol=1e-12)
        np.testing.assert_allclose(y, axle["y"], atol=1e-12)
        ox, oy = fx - L * np.cos(fth), fy - L * np.sin(fth)
        np.testing.assert_allclose(np.hypot(ox - x, oy - y), L0, atol=1e-12)
        np.testing.assert_allclose(np.arctan2(oy - y, ox - x), axle["theta"], atol=1e-12)
        np.testing.assert_allclose(axle["beta"], tangent - axle["theta"], atol=1e-12)
        assert np.all(axle["s"] < s)  # behind the unit ahead
        s, fx, fy, fth = axle["s"], x, y, axle["theta"]


def test_lookup_interpolates_the_table_and_holds_its_ends():
    path = make_target("cycloid").path
    schedule = path_schedule(path, [LINKS])
    axle = schedule.axles[0]
    for i in (0, 17, axle["s"].size // 2, axle["s"].size - 1):
        assert schedule.eta(0, float(axle["s"][i])) == pytest.approx(axle["eta"][i], abs=1e-12)
    assert schedule.eta(0, -50.0) == axle["eta"][0]
    assert schedule.eta(0, 1e3) == axle["eta"][-1]
    x, y, _ = path.pose(2.0)
    assert nearest_arc_length(path, 1.9, x + 0.01 * math.cos(0.3), y) == pytest.approx(
        2.0, abs=0.02
    )


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"eta_max": 0.0}, "eta_max=0.0"),
        ({"eta_max": math.inf}, "eta_max=inf"),
        ({"spacing": -1.0}, "spacing=-1.0"),
    ],
)
def test_bad_schedule_options_are_refused(kwargs, match):
    with pytest.raises(ValueError, match=match):
        path_schedule(make_target("circle").path, [LINKS], **kwargs)


def test_a_path_too_tight_for_the_axle_is_refused_before_the_run():
    with pytest.raises(ValueError, match="trailer 1's axle"):
        build(Scenario(traj="circle", path_options={"R": 0.05}, eta_schedule="path"))


def test_scenario_names_the_allowed_schedules():
    with pytest.raises(ValueError, match=r"eta_schedule='kappa' is not allowed.*'path'"):
        Scenario(eta_schedule="kappa").validate()
    assert Scenario(eta_schedule=True).eta_schedule_kind == "curvature"
    assert Scenario(eta_schedule="path").eta_schedule_kind == "path"
    assert Scenario().eta_schedule_kind is None
    assert isinstance(
        build(Scenario(traj="circle", eta_schedule="path")).path_schedule, PathSchedule
    )


def _offtracks(metrics, n):
    return _stats(metrics, n, "max")


def _stats(metrics, n, stat):
    keys = [f"trailer_offtrack_{stat}"] + [f"trailer_{k}_offtrack_{stat}" for k in range(2, n + 1)]
    return [metrics[key] for key in keys]


@pytest.mark.parametrize(
    ("plant", "traj", "n"),
    [
        *((plant, traj, n) for plant in PLANTS for traj in ("circle", "cycloid") for n in (1, 2)),
        *((plant, traj, 3) for plant in PLANTS for traj in ("circle", "cycloid")),
    ],
)
def test_runs_keep_every_trailer_within_five_millimetres(plant, traj, n):
    # Issue "same path", must-show 1, from rest, no disturbance: measured at worst 4.1 mm
    # (MuJoCo, cycloid, trailer 3); the same-path limit gains leave 13-78 mm here.
    result = simulate(
        Scenario(plant=plant, traj=traj, trailers=n, disturbance="none", eta_schedule="path")
    )
    assert result.status == "ok"
    assert max(_offtracks(result.metrics, n)) < 5e-3


def test_on_the_cycloids_slipping_start_the_feedback_follows_the_tractors_track():
    # docs/model.md Section 13: the cycloid's timed start accelerates four bodies on the
    # tractor's two driven wheels, which slip by more than 1 m/s (0.005 m/s with one trailer)
    # and shake the tractor off the reference path. The table's steering alone (gain 0) keeps
    # the trailers on the reference path, 8 to 9 mm off the tractor's track; the feedback to
    # that track brings them to 4.0 / 4.0 / 4.1 mm. The slipping start is chaotic to the last
    # bit of the arithmetic, so machines differ: the one that recorded the study gave 7.7 /
    # 7.8 / 8.9 mm and slips of 1.16 m/s, another (the same versions of Python, MuJoCo and
    # numba; no AVX-512) 7.6 / 7.9 / 9.0 mm and 1.11 m/s; both 4.0 / 4.0 / 4.1 mm with the
    # feedback. The bounds hold the claim, not one machine's last digit: gain 0 leaves every
    # trailer 7.5-9.5 mm off, the feedback brings every one under 4.5 mm.
    slips = [
        simulate(Scenario(traj="cycloid", trailers=n, disturbance="none", eta="path")).metrics[
            "slip_longitudinal_max"
        ]
        for n in (1, 3)
    ]
    assert slips[0] < 0.05 and slips[1] > 1.0
    worst = {}
    for gain in (0.0, 10.0):
        scenario = Scenario(
            traj="cycloid", trailers=3, disturbance="none", eta="path", driven_path_gain=gain
        )
        worst[gain] = [1e3 * x for x in _offtracks(simulate(scenario).metrics, 3)]
    assert all(7.5 < mm < 9.5 for mm in worst[0.0]), worst
    assert all(mm < 4.5 for mm in worst[10.0]), worst


@pytest.mark.parametrize("plant", PLANTS)
def test_a_user_csv_path_without_an_inflection_keeps_three_trailers_on_it(plant, tmp_path):
    # Must-show 1's user path: the parabola y = 0.3 x^2 (its curvature falls from 0.6 1/m, no
    # inflection) from 16 waypoints. Measured 0.61 mm at worst (MuJoCo, trailer 3), against
    # 17-35 mm with the same-path limit gains.
    x = np.linspace(0.0, 3.0, 16)
    csv = tmp_path / "bend.csv"
    csv.write_text("x,y\n" + "".join(f"{a!r},{0.3 * a * a!r}\n" for a in x.tolist()))
    common = dict(traj=str(csv), plant=plant, trailers=3, disturbance="none")
    result = simulate(Scenario(eta="path", **common))
    assert result.status == "ok"
    assert max(_offtracks(result.metrics, 3)) < 5e-3
    limit = simulate(Scenario(eta="same_path", **common))
    assert min(_offtracks(limit.metrics, 3)) > 15e-3


@pytest.mark.parametrize("plant", ["mujoco", "reduced"])
def test_the_paper_disturbance_keeps_the_bound_for_one_trailer(plant):
    result = simulate(Scenario(plant=plant, traj="cycloid", eta_schedule="path"))
    assert result.status == "ok"
    assert result.metrics["trailer_offtrack_max"] < 5e-3  # measured 1.5 mm (MuJoCo)


def test_cli_eta_path_reaches_the_scenario_and_replays(tmp_path):
    out = tmp_path / "run"
    # no disturbance: the schedule steers towards the path the tractor drove, which the paper's
    # disturbance shakes (the gain then moves by about 1e-3 around the steady one)
    argv = ["--traj", "circle", "--plant", "reduced", "--duration", "4", "--eta", "path"]
    argv += ["--no-disturbance"]
    assert run.main([*argv, "--no-video", "--no-plots", "--quiet", "--out", str(out)]) == 0
    doc = json.loads((out / "metrics.json").read_text())
    assert doc["config"]["scenario"]["eta_schedule"] == "path"
    assert doc["config"]["scenario"]["eta"] == "same_path"  # the constant gain it replaces
    assert doc["trailer_offtrack_max"] < 5e-3
    ts = outputs.read_timeseries(out / "timeseries.parquet")
    # the plant's gain on the steady arc is the exact same-path gain of kappa = 1, not -1/7
    assert ts["beta"][-1] / ts["phi"][-1] == pytest.approx(
        exact_train_same_path_etas(1.0, [LINKS])[0], abs=1e-4
    )
    again = tmp_path / "again"
    assert run.main(["--config", str(out / "config.toml"), "--out", str(again)]) == 0
    assert (again / "timeseries.parquet").read_bytes() == (out / "timeseries.parquet").read_bytes()


def test_sweeps_take_the_schedule_by_name():
    assert convert("eta_schedule", "path") == "path"
    assert convert("eta_schedule", "Curvature") == "curvature"
    assert convert("eta_schedule", "true", typed=False) is True  # command-line text
    assert convert("eta_schedule", True) is True
    with pytest.raises(BadSpecError, match="text where true or false is wanted"):
        convert("eta_schedule", "true")  # a sweep file's string, not its boolean
    with pytest.raises(BadSpecError, match=r"eta_schedule='kappa'.*'curvature', 'path'"):
        convert("eta_schedule", "kappa")


@pytest.mark.parametrize(("n", "disturbance"), [(1, "none"), (3, "none"), (1, "matched")])
def test_s_curve_closed_loop_is_four_times_better_than_same_path_on_the_reduced_plant(
    n, disturbance
):
    # Must-show 1's S-curve, reduced plant: measured 8.5, 8.3 / 7.3 and 8.1 / 7.4 / 6.6 mm max
    # and 1.4, 1.5 / 1.5 and 1.7 / 1.7 / 1.7 mm rms (N = 1 / 2 / 3), 7-25x below the same-path
    # limit gains' 59.7 / 109.8 / 142.4 mm and 12.8 / 29.6 / 43.2 mm; with the paper's
    # disturbance one trailer at 9.8 / 1.8 mm against 59.0 / 12.8 mm.
    common = dict(plant="reduced", traj="s_curve", trailers=n, disturbance=disturbance)
    scheduled = simulate(Scenario(eta="path", **common))
    limit = simulate(Scenario(eta="same_path", **common))
    assert scheduled.status == limit.status == "ok"
    for stat in ("max", "rms"):
        keys = ["trailer_offtrack"] + [f"trailer_{k}_offtrack" for k in range(2, n + 1)]
        for key in keys:
            ratio = limit.metrics[f"{key}_{stat}"] / scheduled.metrics[f"{key}_{stat}"]
            assert ratio > 4.0, (key, stat, ratio)


@pytest.mark.parametrize("disturbance", ["none", "matched"])
def test_s_curve_in_contact_physics_is_four_times_better_with_one_trailer(disturbance):
    # What docs/model.md Section 13 reports: with the axles steered by an actuator of bounded
    # slew rate, and the controllers' model taking the gains the axles can follow, one trailer
    # completes the S-curve at 8.1 mm max and 1.6 mm rms (8.5 / 1.7 mm with the paper's
    # disturbance) against the same-path limit gains' 59.7 / 12.8 mm: more than the issue's 4x,
    # both ways. (An unbounded actuator passed the table's gain flip on as a steering step:
    # 10.5 / 2.4 mm, and 21.6 mm max with the disturbance.)
    common = dict(plant="mujoco", traj="s_curve", disturbance=disturbance)
    one = simulate(Scenario(eta="path", **common)).metrics
    limit = simulate(Scenario(eta="same_path", **common)).metrics
    assert one["status"] == limit["status"] == "ok"
    for stat in ("max", "rms"):
        key = f"trailer_offtrack_{stat}"
        assert limit[key] / one[key] > 4.0, (stat, limit[key], one[key])
    figures = [round(1e3 * one[f"trailer_offtrack_{stat}"], 1) for stat in ("max", "rms")]
    assert figures == {"none": [8.1, 1.6], "matched": [8.5, 1.7]}[disturbance]
    unbounded = simulate(Scenario(eta="path", params={"axle_slew_rate": 1e6}, **common)).metrics
    figures = [round(1e3 * unbounded[f"trailer_offtrack_{stat}"], 1) for stat in ("max", "rms")]
    assert figures == {"none": [10.5, 2.4], "matched": [21.6, 4.1]}[disturbance]


@pytest.mark.parametrize("n", [2, 3])
def test_s_curve_in_contact_physics_is_four_times_better_with_a_train(n):
    # Must-show 1 for trains in contact physics (docs/model.md Section 13): every trailer's
    # max and rms off-tracking at least 4x below the same-path limit gains'. Measured 8.4 / 9.2
    # mm max for two trailers and 9.1 / 7.8 / 7.5 mm for three, against 59.7 / 109.7 and
    # 59.6 / 109.7 / 142.2 mm. With the controllers' model taking the scheduled gains whole
    # (up to |eta| = 3, more than the axles' actuators can follow as the hitch swings through
    # the inflection), both trains jackknifed after t = 7 s. (With the table's gain looked up by
    # arc length alone, a hitch still at 5.4 deg where the table's crosses zero met the other
    # side's gain and jackknifed at 7.2 s.)
    common = dict(plant="mujoco", traj="s_curve", disturbance="none", trailers=n)
    path = simulate(Scenario(eta="path", **common)).metrics
    limit = simulate(Scenario(eta="same_path", **common)).metrics
    assert path["status"] == limit["status"] == "ok"
    for stat in ("max", "rms"):
        ours, theirs = _stats(path, n, stat), _stats(limit, n, stat)
        assert all(b / a > 4.0 for a, b in zip(ours, theirs, strict=True)), (stat, ours, theirs)
    unfollowed = simulate(Scenario(eta="path", params={"axle_slew_rate": 1e6}, **common))
    assert unfollowed.metrics["status"] == "jackknife"


def test_the_gain_is_the_table_on_the_schedule_and_the_path_steering_off_it():
    schedule = path_schedule(make_target("s_curve").path, [LINKS])
    axle = schedule.axles[0]
    i = int(np.argmax(np.abs(axle["phi"])))
    s, phi, beta = float(axle["s"][i]), float(axle["phi"][i]), float(axle["beta"][i])
    assert schedule.gain(0, s, phi) == pytest.approx(schedule.eta(0, s), abs=1e-9)
    # a hitch 2.5x off its schedule still gets nearly the path's steering
    assert schedule.gain(0, s, 2.5 * phi) * 2.5 * phi == pytest.approx(beta, rel=0.01)
    # through zero the steering is continuous, and the gain there the table's
    assert schedule.gain(0, s, 1e-6) == pytest.approx(schedule.eta(0, s), abs=1e-4)
    steer = [schedule.gain(0, s, q) * q for q in np.linspace(-0.02, 0.02, 401)]
    assert np.max(np.abs(np.diff(steer))) < 2e-4


def test_the_nominal_model_follows_the_scheduled_gains():
    # ISMC-STA's model takes the plant's gains (Controller.steering_changed): on the reduced
    # plant a 3-trailer train then stays on the path (0.1 mm at worst; with the scenario's
    # constant eta in the model, 5.6 mm)
    result = simulate(
        Scenario(plant="reduced", traj="cycloid", trailers=3, disturbance="none", eta="path")
    )
    assert max(_offtracks(result.metrics, 3)) < 0.5e-3


@pytest.mark.parametrize(
    ("path", "plant", "n", "disturbance", "steering", "torque_limit"),
    [
        ("cycloid", "reduced", 2, "none", "path", None),
        ("circle", "mujoco", 1, "none", "path", None),
        ("circle", "reduced", 1, "none", "same_path", None),
        # the contact-physics S-curve rows are a chaotic transient (Section 13)
        ("s_curve", "mujoco", 2, "none", "path", None),
        ("s_curve", "mujoco", 3, "matched", "path", None),
        # bounded below 15 N m, two trailers complete the S-curve and the cycloid falls behind
        ("s_curve", "mujoco", 2, "none", "path", 3.0),
        ("cycloid", "mujoco", 3, "none", "path", 3.0),
    ],
)
def test_the_study_table_is_what_its_command_prints(
    path, plant, n, disturbance, steering, torque_limit
):
    docs = Path(__file__).parents[1] / "docs"
    spec = importlib.util.spec_from_file_location("study", docs / "path_schedule_study.py")
    study = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(study)
    line = "| " + " | ".join(study.row(path, plant, n, disturbance, steering, torque_limit)) + " |"
    assert line in (docs / "path_schedule_study.md").read_text()


@pytest.mark.parametrize(
    ("path", "plant", "n", "disturbance", "steering"),
    [
        ("circle", "reduced", 2, "none", "path"),
        ("s_curve", "mujoco", 1, "matched", "same_path"),
        ("cycloid", "reduced", 3, "none", "plain"),
    ],
)
def test_the_reverse_study_table_is_what_its_command_prints(path, plant, n, disturbance, steering):
    docs = Path(__file__).parents[1] / "docs"
    spec = importlib.util.spec_from_file_location("study", docs / "path_schedule_study.py")
    study = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(study)
    cells = study.row(path, plant, n, disturbance, steering, reverse=True)
    assert "| " + " | ".join(cells) + " |" in (docs / "path_schedule_study.md").read_text()


def test_s_curve_gain_swings_from_the_linkage_to_both_bounds_within_a_short_travel():
    # docs/model.md Section 13: at the S-curve's junction the ideal schedule's gain leaves its
    # steady -1/7 and swings to -3 and +3 within 0.3 m of the axle's travel (measured 0.25 m).
    axle = path_schedule(make_target("s_curve").path, [LINKS]).axles[0]
    s, eta = axle["s"], axle["eta"]
    lowest, highest = np.argmin(eta), np.argmax(eta)
    leaves = s[np.flatnonzero(np.abs(eta[:lowest] + 1.0 / 7.0) < 0.01)[-1]]
    lowest, highest = s[lowest], s[highest]
    assert eta.min() == -3.0 and eta.max() == 3.0
    assert leaves < lowest < highest < leaves + 0.3


def test_at_the_s_curve_inflection_the_gain_flips_and_then_exceeds_one():
    # docs/model.md Section 13, what is left at the inflection. (i) Where the schedule's hitch
    # crosses zero the table's gain jumps from -3 to +3 within one entry, and a hitch lagging at
    # 4.5 deg gets part of it through the blend: -2.63 before, -0.79 after; the axle's target
    # moves from -11.85 to -3.56 deg within 2 mm of travel.
    schedule = path_schedule(make_target("s_curve").path, [LINKS])
    axle = schedule.axles[0]
    s, eta = axle["s"], axle["eta"]
    i = int(np.flatnonzero(np.diff(np.sign(eta)) > 0)[-1])
    assert (eta[i], eta[i + 1]) == (-3.0, 3.0)
    assert s[i + 1] - s[i] < 2.1e-3
    phi = math.radians(4.5)
    before, after = schedule.gain(0, s[i], phi), schedule.gain(0, s[i + 1], phi)
    assert (round(before, 2), round(after, 2)) == (-2.63, -0.79)
    steer = [round(math.degrees(gain * phi), 2) for gain in (before, after)]
    assert steer == [-11.85, -3.56]
    # (ii) after the crossing the table asks eta > 1 over 0.147 m of the axle's travel, where the
    # forward hitch is unstable: phi_dot ~ (eta - 1) v phi / L0, 4 1/s at eta = 3, v = 0.8 m/s
    above = s[eta > 1.0]
    assert round(above.max() - above.min(), 3) == 0.147
    L, L0 = LINKS
    h = 1e-7
    slope = (phi_rate_of(h, 3.0, L, L0)[0] - phi_rate_of(-h, 3.0, L, L0)[0]) / (2 * h)
    assert 0.8 * slope == pytest.approx((3.0 - 1.0) * 0.8 / L0, rel=1e-6)
    assert round(0.8 * slope, 6) == 4.0

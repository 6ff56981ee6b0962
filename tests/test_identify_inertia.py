"""Masses and inertias fitted to a log with torques (tt_mujoco.identify_inertia): from logs the
project makes with other masses than its defaults, 60 s at 1 kHz on the weave whose speed
swings between 0.4 and 1.0 m/s every metre (examples/weave_surge.csv), with 20 dB of noise on
every sensor (v, omega, the hitch angles; the torques are the commands as sent); a payload put
on mid-log found; what a log cannot tell apart said; bad requests exit 2."""

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from tt_mujoco import identify
from tt_mujoco.identify_inertia import fit_inertia
from tt_mujoco.sim import Scenario, simulate
from tt_mujoco.vehicle_log import LogError, noisy

WEAVE = str(Path(__file__).resolve().parents[1] / "examples" / "weave_surge.csv")
#: The vehicle the logs are made with: not the project's defaults (Mf 9, Mr 6, Ird 0.02).
TRUTH = {"Mf": 10.0, "Mr": 8.0, "Ird": 0.03}
SENSORS = ("v", "omega", "phi", "phi_2")


def _log(plant: str, **kw) -> tuple[dict, object]:
    scenario = Scenario(
        traj=WEAVE, plant=plant, disturbance="none", duration=60, params=TRUTH, **kw
    )
    return dict(simulate(scenario).timeseries), scenario.plant_params()


def _noisy(ts: dict, db: float, seed: int) -> dict:
    """20 dB: each sensor's noise a tenth of its rms (seeded)."""
    rng = np.random.default_rng(seed)
    out = dict(ts)
    for name in SENSORS:
        if name in ts:
            out[name] = noisy(ts[name], db, rng)
    return out


def _fit(ts: dict, guess, fit=("Mr",), payload=None):
    phis = np.column_stack([ts[n] for n in ("phi", "phi_2") if n in ts])
    torques = (ts["T_r"], ts["T_l"])
    return fit_inertia(ts["t"], ts["v"], ts["omega"], phis, torques, guess, fit, payload)


@pytest.fixture(scope="module")
def mujoco_log():
    return _log("mujoco")


def test_a_clean_reduced_log_gives_every_trailer_s_mass_back():
    """The reduced plant is the fit's own model: two trailers' masses from 25 % off come back
    within 0.3 % (measured 0.05 % and 0.19 %: the 10 ms grid's integration)."""
    ts, p = _log("reduced", trailers=2, train=[{"Mr": 5.0, "Ird": 0.025, "L": 0.35, "L0": 0.45}])
    guess = p.replace(Mr=6.0, train=(dataclasses.replace(p.train[0], Mr=6.0),))
    fit = _fit(ts, guess)
    assert fit.names == ("Mr_1", "Mr_2")
    np.testing.assert_allclose(fit.estimates, [8.0, 5.0], rtol=3e-3)
    assert fit.params.train[0].Mr == fit.estimates[1]


def test_the_mujoco_train_s_second_trailer_comes_out_heavy():
    """Not fitted yet (docs/identify.md): from a clean log of the MuJoCo plant's two-trailer
    train, the first trailer's mass comes back within 0.43 % but the second's 6.3 % heavy
    (measured), beyond its interval; the reduced plant's comes back within 0.19 %. The next
    test gives the cause (the wheels' spin inertia); this one keeps the figures quoted true."""
    ts, p = _log("mujoco", trailers=2, train=[{"Mr": 5.0, "Ird": 0.025, "L": 0.35, "L0": 0.45}])
    guess = p.replace(Mr=6.0, train=(dataclasses.replace(p.train[0], Mr=6.0),))
    fit = _fit(ts, guess)
    error = fit.estimates / [8.0, 5.0] - 1.0
    assert abs(error[0]) < 0.005
    assert 0.05 < error[1] < 0.075 and error[1] * 5.0 > fit.half_widths[1]


def test_the_second_trailer_comes_back_on_wheels_of_a_tenth_of_the_spin_inertia():
    """Why the second trailer comes out heavy: each axle's wheels spin with an inertia worth
    2 Iw / r^2 = 50 kg of mass at the paper's Iw = 0.01 kg m^2 and r = 0.02 m, ten times the
    bed's 5 kg, so a mismatch of 0.6 % in how the contact plant spins them (against the rolling
    model's v / r) reads as 6.3 % of Mr. With wheels of a tenth of that inertia (5 kg worth per
    axle), both trailers' masses come back within 1 % (measured 0.03 % and 0.38 %)."""
    scenario = Scenario(
        traj=WEAVE,
        plant="mujoco",
        disturbance="none",
        duration=60,
        params={**TRUTH, "Iw": 0.001},
        trailers=2,
        train=[{"Mr": 5.0, "Ird": 0.025, "L": 0.35, "L0": 0.45}],
    )
    ts, p = dict(simulate(scenario).timeseries), scenario.plant_params()
    assert 2 * p.Iw / p.r**2 == pytest.approx(5.0)
    guess = p.replace(Mr=6.0, train=(dataclasses.replace(p.train[0], Mr=6.0),))
    fit = _fit(ts, guess)
    np.testing.assert_allclose(fit.estimates, [8.0, 5.0], rtol=0.01)


@pytest.mark.parametrize("seed", [0, 1])
def test_a_noisy_mujoco_log_holds_the_trailer_s_mass_in_its_interval(mujoco_log, seed):
    """20 dB on every sensor, MuJoCo's contact plant: the 95 % interval holds the truth, and
    is narrower than 2.5 % either way (measured half widths 1.5-2.3 %; how often the estimate
    lands within 2 %: benchmarks/identify_coverage.py)."""
    ts, p = mujoco_log
    fit = _fit(_noisy(ts, 20.0, seed), p.replace(Mr=6.0))
    (estimate,), (half,) = fit.estimates, fit.half_widths
    assert abs(estimate - 8.0) <= half < 0.025 * 8.0


def test_a_clean_mujoco_log_says_what_it_cannot_tell_apart(mujoco_log):
    """The tractor's and the trailer's masses and the wheels' spin inertia all move with the
    speed: a log of one path does not tell them apart, and says so."""
    ts, p = mujoco_log
    fit = _fit(ts, p, ("Mf", "Iw", "Mr"))
    pairs = {frozenset((a, b)) for a, b, _ in fit.confounded()}
    assert frozenset(("Mf", "Mr")) in pairs
    assert fit.report()["not_told_apart"]


def test_a_payload_put_on_mid_log_is_found():
    """A payload of half the bed's mass (4 kg) from t = 21.3 s in a 20 dB log: its mass within
    5 % and its time within 0.5 s (measured 3.92 kg at 20.9 s; clean: 4.06 kg at 21.33 s)."""
    ts, p = _log("mujoco", faults="payload:t=21.3")
    fit = _fit(_noisy(ts, 20.0, 0), p.replace(Mr=6.0), payload=1)
    load = fit.payload
    assert load.found and load.trailer == 1
    assert abs(load.mass - 4.0) < 0.05 * 4.0
    assert abs(load.time - 21.3) < 0.5
    assert load.time_interval[0] <= 21.3 <= load.time_interval[1]
    assert abs(fit.estimates[0] - 8.0) < 0.02 * 8.0  # the bed's own mass, before it


def test_a_payload_on_no_trailer_of_the_train_is_refused(mujoco_log):
    ts, p = mujoco_log
    with pytest.raises(LogError, match="--payload 2 is not allowed"):
        _fit(ts, p, payload=2)


def test_a_name_that_is_no_mass_is_refused(mujoco_log):
    ts, p = mujoco_log
    with pytest.raises(LogError, match="'L' is not a mass or inertia"):
        _fit(ts, p, ("L",))


def test_the_command_fits_a_run_s_trailer_mass_and_the_fit_drives_again(tmp_path, capsys):
    from tt_mujoco import run

    log = tmp_path / "log"
    argv = ["--traj", WEAVE, "--plant", "mujoco", "--no-disturbance", "--param", "Mr=8"]
    common = ["--duration", "60", "--no-video", "--no-plots", "--quiet"]
    assert run.main([*argv, *common, "--out", str(log)]) == 0
    out = tmp_path / "fit"
    assert identify.main([str(log), "--fit", "Mr", "--out", str(out)]) == 0
    report = json.loads((out / "identify.json").read_text())
    mr = report["inertia"]["estimates"]["Mr"]
    assert abs(mr["value"] - 8.0) < 0.01 * 8.0 and mr["ci95"][0] <= 8.0 <= mr["ci95"][1]
    assert "Mr = 8.0" in (out / "identified.toml").read_text()
    again = tmp_path / "again"
    assert run.main(["--config", str(out / "identified.toml"), *common[2:], "--duration", "1",
                     "--out", str(again)]) == 0  # fmt: skip
    assert json.loads((again / "metrics.json").read_text())["status"] == "ok"


@pytest.mark.parametrize(
    ("argv", "said"),
    [
        (["--fit", "Mr", "--columns", "T_r=torque_right"], "no column 'torque_right' (for T_r)"),
        (["--payload", "0"], "--payload 0 is not allowed"),
        (["--payload", "2"], "--payload 2 is not allowed"),
        (["--fit", "Mr,Mr"], "'Mr' is given twice"),
        (["--fit", "Mr", "--columns", "T_l=T_bad"], "column 'T_bad' row 5 is nan"),
        (["--fit", "Mr", "--config", "missing.toml"], "missing.toml"),
    ],
)
def test_a_bad_request_is_exit_2_with_nothing_written(tmp_path, capsys, argv, said):
    log = tmp_path / "log.csv"
    t = np.linspace(0, 6, 601)
    columns = {"t": t, "v": 0.5 + 0 * t, "omega": 0.1 + 0 * t, "phi": 0.05 + 0 * t}
    columns.update(T_r=0.1 + 0 * t, T_l=0.1 + 0 * t, T_bad=0.1 + 0 * t)
    columns["T_bad"][3] = np.nan
    np.savetxt(log, np.column_stack(list(columns.values())), delimiter=",",
               header=",".join(columns), comments="")  # fmt: skip
    out = tmp_path / "fit"
    assert identify.main([str(log), *argv, "--out", str(out)]) == 2
    assert said in capsys.readouterr().err
    assert not out.exists()


def _flat_log(path, torque_scale=0.0):
    """20 s at constant speed and turn: nothing accelerates."""
    t = np.linspace(0, 20, 2001)
    columns = {"t": t, "v": 0.5 + 0 * t, "omega": 0.1 + 0 * t, "phi": 0.05 + 0 * t}
    columns.update(T_r=torque_scale + 0 * t, T_l=torque_scale + 0 * t)
    np.savetxt(path, np.column_stack(list(columns.values())), delimiter=",",
               header=",".join(columns), comments="")  # fmt: skip
    return path


def test_a_log_that_does_not_excite_a_mass_says_so_and_keeps_it(tmp_path, capsys):
    log = _flat_log(tmp_path / "flat.csv")
    out = tmp_path / "fit"
    assert identify.main([str(log), "--fit", "Mr", "--out", str(out)]) == 0
    assert json.loads((out / "identify.json").read_text())["inertia"]["not_told"] == ["Mr"]
    assert "Mr = 6.0" in (out / "identified.toml").read_text()  # the given vehicle's
    assert "not told by this log" in capsys.readouterr().out


def test_torques_in_the_wrong_units_are_exit_2(tmp_path, capsys):
    """Torques of 1000 N m at every row (a log in N mm): the model runs away at once."""
    log = _flat_log(tmp_path / "kilo.csv", torque_scale=1000.0)
    out = tmp_path / "fit"
    assert identify.main([str(log), "--fit", "Mr", "--out", str(out)]) == 2
    assert "are the torques the wheels' in N m" in capsys.readouterr().err
    assert not out.exists()

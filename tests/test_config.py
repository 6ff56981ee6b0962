"""Scenario files: options from TOML, command line over file, and exact repeats from a run's
own config.toml."""

import json
import tomllib
from types import SimpleNamespace

import pytest
import tomli_w

from tt_mujoco import config, run
from tt_mujoco.cliargs import BadInputError

SCENARIO_TOML = """
traj = "circle"
controller = "pid"
duration = 1.5
noise-snr = 20        # hyphenated keys are accepted too
seed = 3
video = false
plots = false
quiet = true

[params]
Mr = 7.0
Ird = 0.025

[[faults]]
kind = "dropout"
t = 0.5
duration = 0.05
"""


def without_wall_time(doc: dict) -> dict:
    return {k: v for k, v in doc.items() if k != "wall_time_s"}


def test_run_writes_its_config_and_repeats_exactly_from_it(tmp_path):
    scenario = tmp_path / "scenario.toml"
    scenario.write_text(SCENARIO_TOML)
    first, second = tmp_path / "first", tmp_path / "second"
    # The command line overrides the file: fbl instead of pid, and one more parameter.
    code = run.main(
        ["--config", str(scenario), "--controller", "fbl", "--param", "Mf=9.5", "--out", str(first)]
    )
    assert code == 0
    doc = json.loads((first / "metrics.json").read_text())
    used = doc["config"]["scenario"]
    assert used["controller"] == "fbl"
    assert used["traj"] == "circle" and used["duration"] == 1.5 and used["seed"] == 3
    assert used["noise_snr_db"] == 20.0
    assert used["params"] == {"Mr": 7.0, "Ird": 0.025, "Mf": 9.5}
    assert used["faults"] == [{"kind": "dropout", "t": 0.5, "duration": 0.05}]
    assert doc["faults"][0]["held_steps"] == 50  # 0.05 s at 1 kHz

    written = tomllib.loads((first / "config.toml").read_text())
    assert written["controller"] == "fbl"
    assert written["params"] == {"Mr": 7.0, "Ird": 0.025, "Mf": 9.5}
    assert "out" not in written and "quiet" not in written and "viewer" not in written

    assert run.main(["--config", str(first / "config.toml"), "--out", str(second), "--quiet"]) == 0
    assert (first / "timeseries.parquet").read_bytes() == (
        second / "timeseries.parquet"
    ).read_bytes()
    again = json.loads((second / "metrics.json").read_text())
    assert without_wall_time(again) == without_wall_time(doc)
    assert (second / "config.toml").read_text() == (first / "config.toml").read_text()


def parse(argv):
    """The values a command line stands for: the scenario's and the outputs', by name."""
    invocation = run._parse(argv)
    values = SimpleNamespace(**invocation.scenario.to_dict(), **invocation.outputs)
    return values, values.params, values.faults


def test_command_line_overrides_file_key_by_key(tmp_path):
    path = tmp_path / "c.toml"
    path.write_text(SCENARIO_TOML)
    args, params, faults = parse(["--config", str(path)])
    assert (args.traj, args.controller, args.duration, args.noise_snr_db) == (
        "circle",
        "pid",
        1.5,
        20,
    )
    assert not args.video and not args.plots and args.quiet
    assert params == {"Mr": 7.0, "Ird": 0.025}
    assert faults == [{"kind": "dropout", "t": 0.5, "duration": 0.05}]

    args, params, faults = parse(
        [
            "--config",
            str(path),
            "--duration",
            "2",
            "--video",
            "--no-quiet",
            "--param",
            "Mr=8",
            "--fault",
            "actuator:t=1,wheel=left",
        ]
    )
    assert args.duration == 2.0 and args.video and not args.quiet
    assert args.traj == "circle"  # untouched keys still come from the file
    assert params == {"Mr": 8.0, "Ird": 0.025}  # per key
    # --fault replaces the file's list (an override, not an addition).
    assert faults == [
        {"kind": "actuator", "t": 1.0, "duration": 1.0, "scale": 0.3, "wheel": "left"}
    ]


def test_no_disturbance_flag_overrides_file_mode(tmp_path):
    path = tmp_path / "c.toml"
    path.write_text('disturbance = "wrench"\n')
    assert parse(["--config", str(path)])[0].disturbance == "wrench"
    assert parse(["--config", str(path), "--no-disturbance"])[0].disturbance == "none"
    assert parse([])[0].disturbance == "matched"


def test_relative_csv_path_is_relative_to_the_file(tmp_path, monkeypatch):
    folder = tmp_path / "scenarios"
    folder.mkdir()
    (folder / "lane.csv").write_text("x,y\n0,0\n1,0\n2,0.2\n3,0.6\n4,1.2\n")
    (folder / "lane.toml").write_text('traj = "lane.csv"\n')
    monkeypatch.chdir(tmp_path)  # not the file's folder
    args, _, _ = parse(["--config", "scenarios/lane.toml"])
    assert args.traj == str(folder / "lane.csv")


def test_resolved_options_round_trip_through_toml(tmp_path):
    argv = [
        "--traj",
        "cycloid",
        "--gains",
        '{"k1_v": 12.5}',
        "--control-dt",
        "0.002",
        "--phi0",
        "-3.25",
        "--param",
        "Mw=3.5",
        "--fault",
        "payload:t=1,factor=1.25",
        "--no-plots",
        "--eta",
        "path",
        "--trailers",
        "2",
        "--no-hitch-feedback",
    ]
    invocation = run._parse(argv)
    path = tmp_path / config.CONFIG_FILE
    path.write_text(config.dump_config(invocation.file_form()))
    assert path.read_text().startswith("# Resolved options")
    again = run._parse(["--config", str(path)])
    assert again.scenario == invocation.scenario
    assert again.outputs == invocation.outputs
    s = again.scenario
    assert s.gains == {"k1_v": 12.5} and s.control_dt == 0.002
    assert (s.eta, s.eta_schedule, s.phi0_deg) == ("same_path", "path", -3.25)
    assert s.hitch_feedback is None and s.trailers == 2
    assert s.params == {"Mw": 3.5}
    assert s.faults == [{"kind": "payload", "t": 1.0, "factor": 1.25, "trailer": 1}]


def test_unknown_fault_key_in_file_names_it(tmp_path):
    path = tmp_path / "c.toml"
    path.write_text('[[faults]]\nkind = "payload"\nt = 1.0\nmass = 3.0\n')
    with pytest.raises(ValueError, match="option 'mass' is not allowed"):
        parse(["--config", str(path)])


@pytest.mark.parametrize("flag", ["reverse", "path_feedback", "video", "plots", "quiet"])
@pytest.mark.parametrize("value", [True, False])
def test_a_flags_negative_key_means_what_it_says(tmp_path, flag, value):
    # ``no_video = true`` is --no-video: the option off (it once turned it on, or left it on).
    path = tmp_path / "c.toml"
    path.write_text(f"no_{flag} = {str(value).lower()}\n")
    assert _on(parse(["--config", str(path)])[0], flag) is (not value)
    path.write_text(f"{flag} = {str(value).lower()}\n")
    assert _on(parse(["--config", str(path)])[0], flag) is value
    path.write_text(f"{flag} = true\nno_{flag} = true\n")
    with pytest.raises(ValueError, match="name the same option"):
        parse(["--config", str(path)])


def _on(values, flag: str) -> bool:
    value = getattr(values, flag)
    return value if isinstance(value, bool) else value is not None  # a table on, or None off


#: A value given on the command line for each option that declares what it needs (a new
#: declaration fails the test below until it has one here).
NEEDING = {
    "disturbance_model": ["--disturbance-model", "rolling"],
    "disturbance_limit": ["--disturbance-limit", "5"],
    "hitch_feedback": ["--no-hitch-feedback"],
    "camera": ["--camera", "overview"],
    "fps": ["--fps", "10"],
    "live_realtime": ["--no-live-realtime"],
}
#: Command-line spellings of a value of each option another one needs.
NEEDED = {
    "disturbance": {"none": ["--no-disturbance"], "wrench": ["--disturbance-mode", "wrench"]},
    "reverse": {False: ["--no-reverse"]},
    "video": {False: ["--no-video"]},
    "live": {0: ["--live", "0"]},
}


def _needing_cases():
    for opt in run.RUN_SCHEMA.options:  # the scenario's options and the command's outputs
        if opt.needs is None:
            continue
        other, acts = opt.needs
        for value, spelt in NEEDED[other].items():
            if not acts(value):
                yield pytest.param(opt.name, spelt, id=f"{opt.name}-{other}={value}")


@pytest.mark.parametrize(("name", "spelt"), list(_needing_cases()))
def test_a_command_line_giving_an_option_that_does_nothing_with_another_is_refused(
    tmp_path, capsys, name, spelt
):
    """``--no-disturbance --disturbance-model x`` ran no disturbance and dropped the model in
    silence: one command line that gives both is refused naming both; a command line that
    changes a file's option is an override, and runs."""
    argv = [*NEEDING[name], *spelt]
    with pytest.raises(BadInputError, match="under which it does nothing") as caught:
        run._parse(argv)
    other = run.RUN_SCHEMA[name].needs[0]
    assert NEEDING[name][0].replace("--no-", "--") in str(caught.value).replace("--no-", "--")
    assert run.RUN_SCHEMA[other].cli_flags[0] in str(caught.value).replace("--no-", "--")
    # the option in a file, the other on the command line: an override, taken
    file_form = run._parse(NEEDING[name]).file_form()
    if name in file_form:  # a live view's pacing is the command's, never a file's
        (tmp_path / "f.toml").write_text(tomli_w.dumps({name: file_form[name]}))
        run._parse(["--config", str(tmp_path / "f.toml"), *spelt])

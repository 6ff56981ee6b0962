"""Bad input to ``python -m tt_mujoco.run``: one clear message naming the offending value,
exit code 2, no traceback, and no output folder or file left behind."""

import subprocess
import sys

import pytest

from tt_mujoco import run

GOOD_CSV = "x,y\n0,0\n1,0\n2,0.2\n3,0.6\n4,1.2\n"


@pytest.fixture
def workdir(tmp_path, monkeypatch):
    """Run in an empty folder, so a default output folder (renders/...) would show up."""
    monkeypatch.chdir(tmp_path)
    return tmp_path


def write(path, text):
    path.write_text(text)
    return str(path)


def write_bytes(path, data):
    path.write_bytes(data)
    return str(path)


def csv_cases(d):
    """(argv, expected text) for each bad CSV the issue lists."""
    nan = write(d / "nan.csv", "x,y\n0,0\n1,0\nnan,0.5\n3,1\n")
    inf = write(d / "inf.csv", "x,y\n0,0\n1,0\n2,inf\n3,1\n")
    # Waypoints on a circle of radius 0.2 m (kappa = 5 1/m; the not-a-knot spline fit peaks at
    # 6.022 1/m), over the 2 1/m the vehicle can follow.
    tight = write(d / "tight.csv", "x,y\n0.2,0\n0.1414,0.1414\n0,0.2\n-0.1414,0.1414\n-0.2,0\n")
    return {
        "csv missing": (["--traj", str(d / "nope.csv")], "nope.csv"),
        "csv empty": (["--traj", write(d / "empty.csv", "")], "empty.csv"),
        "csv no header": (["--traj", write(d / "hdr.csv", "a,b\n0,0\n1,0\n2,1\n3,1\n")], "'a,b'"),
        "csv numbers only": (
            ["--traj", write(d / "num.csv", "0,0\n1,0\n2,1\n3,1\n4,2\n")],
            "'0,0'",
        ),
        "csv 3 points": (["--traj", write(d / "three.csv", "x,y\n0,0\n1,0\n2,1\n")], "3 waypoints"),
        "csv nan": (["--traj", nan], "x=nan at line 4"),
        "csv inf": (["--traj", inf], "y=inf at line 4"),
        "csv repeated": (
            ["--traj", write(d / "rep.csv", "x,y\n0,0\n1,0\n1,0\n3,1\n4,1\n")],
            "line 3 and line 4 repeat the point (x=1, y=0)",
        ),
        "csv curvature": (["--traj", tight], "tight.csv: curvature kappa=6.022 1/m"),
        "csv 10 km long": (
            ["--traj", write(d / "long.csv", "x,y\n0,0\n3000,0\n6000,0\n10000,0\n")],
            "12502 s",
        ),
        "csv 1e12 m spacing": (
            ["--traj", write(d / "huge.csv", "x,y\n0,0\n1e12,0\n2e12,0\n3e12,0\n")],
            "huge.csv",
        ),
        "csv speed 1e-320": (
            [
                "--traj",
                write(d / "slow.csv", "x,y,v\n0,0,1e-320\n1,0,1e-320\n2,0,1e-320\n3,0,1e-320\n"),
            ],
            "slow.csv",
        ),
        "csv speed 30": (
            ["--traj", write(d / "fast.csv", "x,y,v\n0,0,30\n1,0,30\n2,0,30\n3,0,30\n")],
            "v=30.0 at line 2",
        ),
        "csv latin-1": (
            [
                "--traj",
                write_bytes(d / "l1.csv", "x,y\n0,0\n1,0\n2,0\n3,0 # caf\xe9\n".encode("latin-1")),
            ],
            "l1.csv' is not UTF-8",
        ),
        "csv too many rows": (
            [
                "--traj",
                write(d / "many.csv", "x,y\n" + "".join(f"{i * 0.01},0\n" for i in range(100_002))),
            ],
            "more than 100000 waypoints",
        ),
    }


OPTION_CASES = {
    "unknown path": (["--traj", "figure9"], "'figure9'"),
    "unknown controller": (["--controller", "lqg"], "'lqg'"),
    "unknown target": (["--target", "dynamc"], "'dynamc'"),
    "unknown plant": (["--plant", "bullet"], "'bullet'"),
    "unknown eta": (["--eta", "banana"], "'banana'"),
    "unknown disturbance mode": (["--disturbance-mode", "gusty"], "'gusty'"),
    "unknown option": (["--frobnicate", "3"], "--frobnicate"),
    "unknown gains preset": (["--gains", "paper_9_9"], "paper_9_9"),
    "gains bad json": (["--gains", '{"k1_v": }'], "not valid JSON"),
    "negative mass": (["--param", "Mf=-1"], "Mf=-1.0"),
    "zero length": (["--param", "L0=0"], "L0=0.0"),
    "infinite inertia": (["--param", "Ird=inf"], "Ird=inf"),
    "nan parameter": (["--param", "Mr=nan"], "Mr=nan"),
    "unknown parameter": (["--param", "Mfoo=1"], "'Mfoo' is not allowed (did you mean 'Mf'?)"),
    "parameter not a number": (["--param", "Mf=heavy"], "'heavy'"),
    "zero param scale": (["--param-scale", "0"], "'0'"),
    "negative friction": (["--friction", "-0.3"], "'-0.3'"),
    "non-finite friction": (["--friction", "inf"], "'inf'"),
    "articulation at the singularity": (["--eta", "paper", "--phi0", "30"], "phi0=30.0"),
    "articulation beyond the singularity": (["--eta", "paper", "--phi0", "-45"], "phi0=-45.0"),
    "articulation past the jackknife stop": (["--eta", "-3", "--phi0", "29"], "phi0=29.0"),
    "articulation nan": (["--phi0", "nan"], "'nan'"),
    "zero duration": (["--duration", "0"], "'0'"),
    "negative duration": (["--duration", "-5"], "'-5'"),
    "duration too long": (["--duration", "601"], "--duration: '601' is not allowed"),
    "timestep too large": (["--timestep", "0.05"], "--timestep: '0.05' is not allowed"),
    "timestep too small": (["--timestep", "1e-7"], "--timestep: '1e-7' is not allowed"),
    "zero timestep": (["--timestep", "0"], "'0'"),
    "control period not a multiple": (["--control-dt", "0.0015"], "control_dt=0.0015"),
    "control period too long": (["--control-dt", "0.1"], "--control-dt: '0.1' is not allowed"),
    "snr not a number": (["--noise-snr", "loud"], "'loud'"),
    "snr infinite": (["--noise-snr", "inf"], "'inf'"),
    "negative seed": (["--seed", "-1"], "'-1'"),
    "unknown fault": (["--fault", "explode:t=1"], "'explode'"),
    "fault bad value": (["--fault", "dropout:t=1,duration=-1"], "duration='-1'"),
    "fault unknown option": (["--fault", "actuator:t=1,gain=2"], "'gain'"),
    "fault without time": (["--fault", "payload:factor=2"], "start time t"),
    "fault after the end": (["--duration", "2", "--fault", "payload:t=100"], "t=100.0"),
    "fault bad wheel": (["--fault", "actuator:t=1,wheel=front"], "'front'"),
    "viewer on the reduced plant": (["--plant", "reduced", "--viewer"], "'reduced'"),
    # Issue 12: each of these once crashed, ran wild or named the wrong value.
    "timestep names itself": (["--timestep", "0.5"], "--timestep: '0.5' is not allowed"),
    "eta too large": (["--eta", "1e308"], "eta=1e+308"),
    "duration below one control period": (["--duration", "1e-300"], "duration=1e-300"),
    "duration of a tenth of a step": (["--duration", "0.0001"], "duration=0.0001"),
    "steps beyond the cap": (["--timestep", "1e-5", "--duration", "600"], "timestep=1e-05"),
    "a mass MuJoCo refuses": (["--param", "Mw=0.0005"], "Mw=0.0005"),
    "a radius MuJoCo refuses": (["--param", "r=1e-9"], "r=1e-09"),
    "repeated fault key": (["--fault", "dropout:t=1,t=2"], "'t' is given twice"),
    "300-character traj": (["--traj", "a" * 300 + ".csv"], "File name too long"),
    "300-character config": (["--config", "c" * 300 + ".toml"], "File name too long"),
    "reduced plant with a wrench": (
        ["--plant", "reduced", "--disturbance-mode", "wrench"],
        "'wrench'",
    ),
}


def config_cases(d):
    def cfg(name, text):
        return ["--config", write(d / name, text)]

    return {
        "config missing": (["--config", str(d / "absent.toml")], "absent.toml"),
        "config unknown key": (cfg("k.toml", 'trajectory = "circle"\n'), "'trajectory'"),
        "config unknown key hint": (cfg("h.toml", 'controler = "pid"\n'), "'controller'"),
        "config unknown param": (cfg("p.toml", "[params]\nMtruck = 3.0\n"), "'Mtruck'"),
        "config out not allowed": (cfg("o.toml", 'out = "x"\n'), "'out' is not allowed"),
        "config bad param": (cfg("bp.toml", "[params]\nMf = -2.0\n"), "bp.toml': params: Mf=-2.0"),
        "config bad value": (cfg("c.toml", 'controller = "lqg"\n'), "'lqg'"),
        "config wrong type": (cfg("t.toml", 'duration = "long"\n'), "'long'"),
        "config flag not bool": (cfg("f.toml", 'video = "maybe"\n'), "'maybe'"),
        "config not toml": (cfg("bad.toml", "traj = \n"), "bad.toml"),
        "config param not a number": (cfg("pn.toml", '[params]\nMf = "x"\n'), "Mf='x'"),
        "config bad fault": (
            cfg("fa.toml", '[[faults]]\nkind = "dropout"\nt = -2.0\n'),
            "fa.toml': faults: fault dropout: t=-2.0",
        ),
        "config nan snr": (cfg("n.toml", "noise_snr = nan\n"), "nan"),
        "config nested too deeply": (cfg("deep.toml", "a = " + "[" * 2000 + "]" * 2000), "deep"),
        "config huge value not echoed": (
            cfg("big.toml", 'traj = "' + "x" * 100_000 + '"\n'),
            "characters)",
        ),
        "config gains named with the file": (cfg("g.toml", "[gains]\nk9 = 1\n"), "g.toml' [gains]"),
        "config the same option twice": (
            cfg("d.toml", "noise-snr = 20\nnoise_snr = 30\n"),
            "same option",
        ),
    }


def assert_refused(argv, expected, workdir, capsys):
    out = workdir / "out"
    code = run.main([*argv, "--out", str(out), "--quiet", "--no-video", "--no-plots"])
    captured = capsys.readouterr()
    assert code == 2, captured
    assert expected in captured.err, captured.err
    assert captured.err.startswith("error: ")
    assert len(captured.err.strip().splitlines()) == 1  # one message
    assert "Traceback" not in captured.err
    assert not out.exists()  # nothing half-written
    assert not (workdir / "renders").exists()


@pytest.mark.parametrize("case", sorted(OPTION_CASES))
def test_bad_option_is_refused(case, workdir, capsys):
    argv, expected = OPTION_CASES[case]
    assert_refused(argv, expected, workdir, capsys)


CSV_NAMES = (
    "csv missing",
    "csv empty",
    "csv no header",
    "csv numbers only",
    "csv 3 points",
    "csv nan",
    "csv inf",
    "csv repeated",
    "csv curvature",
    "csv 10 km long",
    "csv 1e12 m spacing",
    "csv speed 1e-320",
    "csv speed 30",
    "csv latin-1",
    "csv too many rows",
)
CONFIG_NAMES = (
    "config missing",
    "config unknown key",
    "config unknown key hint",
    "config unknown param",
    "config out not allowed",
    "config bad param",
    "config bad value",
    "config wrong type",
    "config flag not bool",
    "config not toml",
    "config param not a number",
    "config bad fault",
    "config nan snr",
    "config nested too deeply",
    "config huge value not echoed",
    "config gains named with the file",
    "config the same option twice",
)


@pytest.mark.parametrize("case", CSV_NAMES)
def test_bad_csv_is_refused(case, workdir, capsys):
    argv, expected = csv_cases(workdir)[case]
    assert_refused(argv, expected, workdir, capsys)


@pytest.mark.parametrize("case", CONFIG_NAMES)
def test_bad_config_is_refused(case, workdir, capsys):
    argv, expected = config_cases(workdir)[case]
    assert_refused(argv, expected, workdir, capsys)


def test_case_lists_are_complete(workdir):
    assert set(CSV_NAMES) == set(csv_cases(workdir))
    assert set(CONFIG_NAMES) == set(config_cases(workdir))


def test_output_folder_that_cannot_be_written(workdir, capsys):
    blocker = workdir / "a_file"
    blocker.write_text("not a folder")
    out = blocker / "run"
    code = run.main(["--out", str(out), "--quiet", "--no-video", "--no-plots"])
    err = capsys.readouterr().err
    assert code == 2
    assert str(out) in err and "cannot be written" in err
    assert "Traceback" not in err
    assert blocker.read_text() == "not a folder"
    assert not (workdir / "renders").exists()


def test_existing_output_folder_is_never_overwritten(workdir, capsys):
    out = workdir / "previous"
    out.mkdir()
    (out / "metrics.json").write_text("{}")
    code = run.main(["--out", str(out), "--quiet", "--no-video", "--no-plots", "--duration", "1"])
    err = capsys.readouterr().err
    assert code == 2
    assert str(out) in err and "never overwritten" in err
    assert [p.name for p in out.iterdir()] == ["metrics.json"]
    assert (out / "metrics.json").read_text() == "{}"


@pytest.mark.parametrize(
    ("argv", "expected"),
    [
        (["--noise-snr", "abc"], "'abc'"),
        (["--traj", "missing.csv"], "missing.csv"),
        (["--config", "missing.toml"], "missing.toml"),
    ],
)
def test_cli_process_prints_one_line_and_exits_2(argv, expected, workdir):
    """The real entry point, in a child process: exit status 2 and no traceback."""
    proc = subprocess.run(
        [sys.executable, "-m", "tt_mujoco.run", *argv, "--quiet", "--no-video"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 2, proc.stderr
    assert expected in proc.stderr
    assert "Traceback" not in proc.stderr
    assert proc.stderr.count("\n") == 1
    assert list(workdir.iterdir()) == []

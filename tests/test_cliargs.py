"""One error style for every CLI: exit code 2, one line, a "did you mean" hint for misspellings."""

import subprocess
import sys
from pathlib import Path

import pytest

from tt_mujoco.cliargs import BadInputError, Parser

CASES = [
    (["tt_mujoco.run", "--controler", "pid"], "did you mean --controller?"),
    (["tt_mujoco.run", "--target", "dynamc"], "did you mean 'dynamic'?"),
    (["tt_mujoco.sweep", "noise_snrr=20", "--dry-run"], "did you mean 'noise_snr"),
    (["tt_mujoco.sweep", "--wokers", "2", "duration=1"], "did you mean --workers?"),
    (["tt_mujoco.paper", "--wokers", "2"], "did you mean --workers?"),
    (["tt_mujoco.run", "--gains", '{"k1_v": 1, "k1_v": 2}'], "the key 'k1_v' is given twice"),
    (
        ["tt_mujoco.run", "--seed", "-1"],
        "--seed: '-1' is not allowed: it must be an integer in [0, 2**63 - 1]",
    ),
    # a value that names no folder (the current one, to Path) and a number argparse took for
    # an option it did not know ("expected one argument")
    (["tt_mujoco.run", "--out", ""], "argument --out: '' is not allowed: give a file or folder"),
    (["tt_mujoco.run", "--noise-snr-db", "-inf"], "'-inf' is not allowed: it must be a finite"),
]


@pytest.mark.parametrize(("argv", "hint"), CASES, ids=[" ".join(c[0]) for c in CASES])
def test_misspelt_options_get_a_hint_and_exit_2(tmp_path, argv, hint):
    proc = subprocess.run(
        [sys.executable, "-m", *argv], capture_output=True, text=True, timeout=120, cwd=tmp_path
    )
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and hint in lines[0] and "Traceback" not in proc.stderr
    assert list(tmp_path.iterdir()) == []  # nothing written


@pytest.mark.parametrize(
    "argv",
    [
        ["--no-disturbance", "--disturbance-mode", "wrench"],  # a const flag and its option
        ["--video", "--no-video"],  # a switch both ways
        ["--duration", "1", "--duration", "2"],  # a value twice
        ["--plant", "reduced", "--plant", "mujoco"],
    ],
)
def test_one_command_line_setting_an_option_twice_is_refused(argv):
    # the last one won in silence (a wrench ran under --no-disturbance); now both are named
    from tt_mujoco import run
    from tt_mujoco.cliargs import BadInputError

    with pytest.raises(BadInputError, match=r"both set .* give one of them") as info:
        run.options_from_argv(argv)
    assert argv[0] in str(info.value) and argv[-1] in str(info.value)


def test_the_same_value_twice_is_no_conflict():
    from tt_mujoco import run

    given = run.options_from_argv(["--seed", "3", "--seed", "3", "--no-disturbance"])
    assert given["seed"] == 3 and given["disturbance"] == "none"


def test_a_duration_that_is_not_whole_control_periods_is_refused():
    # --duration 1.04 --control-dt 0.05 ran 1.05 s and said nothing
    from tt_mujoco.sim import Scenario

    with pytest.raises(ValueError, match=r"duration=1.04 is not allowed: .* would last 1.05 s"):
        Scenario(duration=1.04, control_dt=0.05).validate()
    Scenario(duration=0.3, control_dt=0.01).validate()  # 30 periods, whatever the rounding


def _table_options():
    from tt_mujoco.sim.scenario import SCHEMA

    return [opt for opt in SCHEMA.options if opt.form == "table" and opt.cli]


@pytest.mark.parametrize("opt", _table_options(), ids=lambda opt: opt.cli_flags[0])
def test_a_table_option_setting_one_name_twice_is_refused(opt):
    # every NAME=VALUE option of the schema (--param, --path-option, ...): the last one won
    # in silence; the same value again stays no conflict
    from tt_mujoco import run
    from tt_mujoco.cliargs import BadInputError

    flag = opt.cli_flags[0]
    with pytest.raises((BadInputError, ValueError), match=r"both set 'x'.*give it once") as info:
        run.options_from_argv([flag, "x=1", flag, "x=2"])
    assert f"{flag} x=1.0" in str(info.value) and f"{flag} x=2.0" in str(info.value)


@pytest.mark.parametrize(
    "argv",
    [
        ["tt_mujoco.render", "no_such_run"],
        ["tt_mujoco.identify", "no_such_log.csv"],
        ["tt_mujoco.excite", "--fit", "L,L"],
        ["tt_mujoco.bag", "no_such_run"],
        ["tt_mujoco.compare", "no_such_run"],
        ["tt_mujoco.run", "--trailers", "0"],
    ],
    ids=lambda argv: argv[0],
)
def test_every_command_says_its_errors_alike(tmp_path, argv):
    # one style whichever check refuses: argparse's, the command guard's or the command's own
    proc = subprocess.run(
        [sys.executable, "-m", *argv], capture_output=True, text=True, timeout=120, cwd=tmp_path
    )
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2 and len(lines) == 1 and lines[0].startswith("error: "), lines


def test_every_command_s_numbers_are_read_as_the_option_schema_reads_them():
    """Every command's parser is a Parser (tests/test_commands.py), whose ``type=int`` and
    ``type=float`` options, in groups too, read numbers as the option schema does: ASCII only
    (Python's ``int("６４")`` is 64), a whole float as an integer (``seed = 3.0`` in TOML)."""
    from tt_mujoco.cliargs import BadInputError, Parser

    parser = Parser()
    parser.add_argument("--n", type=int)
    parser.add_mutually_exclusive_group().add_argument("--x", type=float)
    parser.add_argument_group("g").add_argument("--m", type=int)
    got = parser.parse_args(["--n", "2.0", "--x", "1_0.5", "--m", "1_000"])
    assert (got.n, got.x, got.m) == (2, 10.5, 1000)
    for argv, said in (
        (["--n", "６４"], "'６４' is not an integer"),
        (["--m", "2.5"], "'2.5' is not an integer"),
        (["--x", "１.5"], "'１.5' is not a number"),
    ):
        with pytest.raises(BadInputError, match=said):
            parser.parse_args(argv)


def test_every_command_s_paths_name_something_and_its_negative_numbers_are_values():
    """Every command's parser is a Parser: a ``type=Path`` option refuses a name that is
    empty or blank (``Path("")`` is the current folder), and a value that is a negative number
    in any spelling (``-1e3``, ``-inf``) is the option's value, not an unknown option."""
    import math
    from pathlib import Path

    from tt_mujoco.cliargs import BadInputError, Parser

    parser = Parser()
    parser.add_argument("--out", type=Path)
    parser.add_argument_group("g").add_argument("--x", type=float)
    for text in ("", "  "):
        with pytest.raises(BadInputError, match=r"argument --out: '\s*' is not allowed: give a"):
            parser.parse_args(["--out", text])
    assert parser.parse_args(["--out", "a b"]).out == Path("a b")
    for text, value in (("-1e3", -1000.0), ("-2.5E-1", -0.25), ("-5", -5.0), ("-.5", -0.5)):
        assert parser.parse_args(["--x", text]).x == value
    assert parser.parse_args(["--x", "-inf"]).x == -math.inf
    assert math.isnan(parser.parse_args(["--x", "-NaN"]).x)
    with pytest.raises(BadInputError, match="unrecognized arguments: -q"):
        parser.parse_args(["-q"])  # an option-like word that is no number stays one


@pytest.mark.parametrize("name", ["a\nb", "a\tb", "out\x1b[31m", "x\x7f"])
def test_a_path_with_a_control_character_is_refused(name):
    # Before: --out 'a\x01b' made a folder a shell lists as 'ab'
    parser = Parser(prog="t")
    parser.add_argument("--out", type=Path)
    with pytest.raises(BadInputError, match="control characters"):
        parser.parse_args(["--out", name])

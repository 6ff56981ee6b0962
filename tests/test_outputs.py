"""The output module: folder names and claims, atomic and never-overwriting writes, JSON."""

import json
import math
import os

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tt_mujoco import outputs, validate
from tt_mujoco.sim.loop.checkpoint import read_checkpoint
from tt_mujoco.sim.loop.stepper import CHECKPOINT_COLUMNS


def test_output_folders_never_overwrite(tmp_path):
    base = tmp_path / "renders" / "paper"
    assert outputs.free_name(base) == base
    base.mkdir(parents=True)
    assert outputs.free_name(base) == base.with_name("paper-2")
    base.with_name("paper-2").mkdir()
    assert outputs.free_name(base) == base.with_name("paper-3")
    (base / "x.txt").write_text("x")
    with pytest.raises(ValueError, match="not an empty folder"):
        outputs.claim_folder(base, base)
    empty = tmp_path / "empty"
    empty.mkdir()
    assert outputs.claim_folder(empty, base) == (empty, False)
    made, created = outputs.claim_folder(None, base)
    assert made == base.with_name("paper-3") and created and made.is_dir()


def test_a_symlink_is_never_an_output_folder(tmp_path):
    (tmp_path / "real").mkdir()
    (tmp_path / "link").symlink_to(tmp_path / "real")
    with pytest.raises(ValueError, match="link"):
        outputs.claim_folder(tmp_path / "link", tmp_path / "x")


def test_publish_new_never_replaces(tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    a.write_text("new")
    b.write_text("old")
    with pytest.raises(FileExistsError):
        outputs.publish_new(a, b)
    assert b.read_text() == "old" and a.exists()
    c = tmp_path / "c"
    outputs.publish_new(a, c)
    assert c.read_text() == "new" and not a.exists()


def test_atomic_write_leaves_no_temporary_file(tmp_path, monkeypatch):
    outputs.atomic_write(tmp_path / "f.txt", "hello")
    assert [p.name for p in tmp_path.iterdir()] == ["f.txt"]

    def failing_replace(src, dst):
        raise OSError("rename failed")

    monkeypatch.setattr(os, "replace", failing_replace)
    with pytest.raises(OSError):
        outputs.atomic_write(tmp_path / "g.txt", "x")
    assert [p.name for p in tmp_path.iterdir()] == ["f.txt"]


def test_strict_json_and_timeseries_round_trip(tmp_path):
    outputs.write_json(tmp_path / "m.json", {"a": math.nan, "b": np.float64(2.5)}, strict=True)
    assert json.loads((tmp_path / "m.json").read_text()) == {"a": None, "b": 2.5}
    ts = {"t": np.array([0.0, 0.1]), "x": np.array([1.0 / 3.0, -2e-300])}
    (tmp_path / "ts.csv").write_text(outputs.timeseries_csv(ts, ("t", "x")))
    back = outputs.read_timeseries(tmp_path / "ts.csv")
    assert np.array_equal(back["x"], ts["x"]) and np.array_equal(back["t"], ts["t"])


def test_validate_refuses_a_used_folder_before_running(tmp_path, capsys):
    (tmp_path / "report.md").write_text("mine")
    assert validate.main(["--out", str(tmp_path)]) == 2
    assert "not an empty folder" in capsys.readouterr().err
    assert (tmp_path / "report.md").read_text() == "mine"


def test_two_runs_into_one_folder_never_lose_or_mix_outputs(tmp_path):
    # Both start at once into the same (new, or existing empty) folder, 8 times: exactly one
    # writes, the other is refused with exit code 2 and touches nothing; the folder holds one
    # complete run (its metrics.json names the controller that wrote it).
    import subprocess
    import sys

    base = [sys.executable, "-m", "tt_mujoco.run", "--duration", "0.3", "--quiet"]
    base += ["--no-video", "--no-plots", "--plant", "reduced"]
    for i in range(8):
        out = tmp_path / f"shared-{i}"
        if i % 2:
            out.mkdir()  # an existing empty folder: the check-then-create race
        procs = [
            subprocess.Popen([*base, "--controller", c, "--out", str(out)], stderr=subprocess.PIPE)
            for c in ("ismc_sta", "pid")
        ]
        codes = sorted(p.wait(timeout=120) for p in procs)
        errors = [p.stderr.read().decode() for p in procs]
        assert codes == [0, 2], errors
        assert any("another run" in e or "not an empty folder" in e for e in errors)
        names = sorted(p.name for p in out.iterdir())
        assert names == [
            "config.toml",
            "metrics.json",
            "reference_path.parquet",
            "timeseries.parquet",
        ]
        doc = json.loads((out / "metrics.json").read_text())
        config = (out / "config.toml").read_text()
        assert f'controller = "{doc["config"]["controller"]["name"]}"' in config


def test_a_full_disk_is_one_message_and_the_written_files_stay_complete(tmp_path, capsys):
    import errno

    from tt_mujoco import run

    real = outputs.atomic_write

    def full_disk(path, data):
        if path.name == "metrics.json":
            raise OSError(errno.ENOSPC, "No space left on device", str(path))
        return real(path, data)

    out = tmp_path / "run"
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(outputs, "atomic_write", full_disk)
        argv = ["--duration", "0.5", "--plant", "reduced", "--no-video", "--no-plots"]
        code = run.main([*argv, "--quiet", "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and "No space left on device" in err and "Traceback" not in err
    kept = ["config.toml", "reference_path.parquet", "timeseries.parquet"]
    assert sorted(p.name for p in out.iterdir()) == kept
    assert len(outputs.read_timeseries(out / "timeseries.parquet")["t"]) == 501


@pytest.mark.parametrize("full_after", [0, 2])
def test_a_disk_that_fills_during_the_run_is_one_message_and_keeps_the_rows_that_fit(
    tmp_path, capsys, full_after
):
    # the rows' background writer raised at the end and the command took it for a bug of its
    # own (exit 70); a disk full before the first block leaves nothing behind
    import errno

    from tt_mujoco import run
    from tt_mujoco.sim.loop import checkpoint

    real = checkpoint.Checkpoint.append
    calls = []

    def fills(self, *parts):
        calls.append(1)
        if len(calls) > full_after:
            raise OSError(errno.ENOSPC, "No space left on device")
        return real(self, *parts)

    out = tmp_path / "run"
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(checkpoint.Checkpoint, "append", fills)
        argv = ["--duration", "30", "--plant", "reduced", "--no-video", "--no-plots"]
        code = run.main([*argv, "--quiet", "--out", str(out)])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and "No space left on device" in err, err
    if full_after == 0:
        assert "none reached it; nothing was written" in err and not out.exists()
    else:
        rows = checkpoint.read_checkpoint(out / "timeseries.partial.arrows")
        assert f"the {len(rows['t'])} rows that reached it are kept" in err
        assert len(rows["t"]) > 0 and not (out / "metrics.json").exists()


def test_a_killed_run_keeps_the_rows_it_computed(tmp_path):
    # A long run streams its rows to timeseries.partial.arrows block by block; SIGKILL it part
    # way and the folder keeps those rows, labelled by the claim file as incomplete.
    import signal
    import subprocess
    import sys
    import time

    out = tmp_path / "long"
    cmd = [sys.executable, "-m", "tt_mujoco.run", "--plant", "reduced", "--duration", "600"]
    cmd += ["--traj", "circle", "--no-video", "--no-plots", "--quiet", "--out", str(out)]
    # The Python loop (a few seconds a block), so the run is still going when it is killed.
    proc = subprocess.Popen(cmd, env={**os.environ, "TT_MUJOCO_COMPILED": "0"})
    partial = out / "timeseries.partial.arrows"
    # Stepper.run's chunk: 1 % of the run's 600000 steps, the progress report's stride
    rows_per_block = 6000
    block = rows_per_block * len(CHECKPOINT_COLUMNS) * 8  # bytes of one block's values
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        if partial.exists() and partial.stat().st_size > 3 * block:
            break
        time.sleep(0.2)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert (out / outputs.CLAIM_FILE).exists()  # labelled: not a finished run
    rows = read_checkpoint(partial)
    assert list(rows) == list(CHECKPOINT_COLUMNS)
    t = rows["t"]
    assert len(t) >= 3 * rows_per_block and len(t) % rows_per_block == 0
    assert np.all(np.diff(t) > 0)
    np.testing.assert_array_equal(t, np.arange(len(t)) * 0.001)
    assert not (out / "metrics.json").exists()


def _stop_a_long_run_with_sigterm(out):
    """Start a long run in ``out``, send SIGTERM part way into a block, check what it kept and
    said, and return the kept rows' times."""
    import signal
    import subprocess
    import sys
    import time

    cmd = [sys.executable, "-m", "tt_mujoco.run", "--plant", "reduced", "--duration", "600"]
    cmd += ["--traj", "circle", "--no-video", "--no-plots", "--quiet", "--out", str(out)]
    env = {**os.environ, "TT_MUJOCO_COMPILED": "0"}
    proc = subprocess.Popen(cmd, env=env, stderr=subprocess.PIPE, text=True)
    partial = out / "timeseries.partial.arrows"
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and not (partial.exists() and partial.stat().st_size > 1e6):
        time.sleep(0.1)
    time.sleep(0.3)  # part way into the next block
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert str(partial) in err and "Traceback" not in err
    rows = read_checkpoint(partial)
    t = rows["t"]
    assert len(t) >= 6000  # a starved machine may compute no row between a block and the signal
    assert f"the {len(t)} rows computed" in err and f"t={t[-1]:.3f} s" in err
    assert (out / outputs.CLAIM_FILE).exists() and not (out / "metrics.json").exists()
    return t


def test_sigterm_keeps_every_row_computed_and_says_where(tmp_path):
    # A batch system stops a job with SIGTERM: the run ends with exit 130 and keeps every row it
    # computed (the rows since the last block included), and the message names the file.
    # Python runs the handler between bytecodes, so a signal that arrives while a block is
    # being written is handled just after it, at a block boundary, where there is no
    # unfinished block to keep (so is one that a loaded machine let compute no row since the
    # block); another run then stops elsewhere. A run that dropped its unfinished block would
    # end on a boundary every time and fail them all.
    ends = []
    for attempt in range(3):
        t = _stop_a_long_run_with_sigterm(tmp_path / f"long{attempt}")
        ends.append(len(t))
        if len(t) % 6000 != 0:  # Stepper.run's chunk here: 1 % of the run
            break
    assert any(n % 6000 != 0 for n in ends), ends  # the unfinished block is kept too


def test_pandas_reads_a_runs_time_series_as_the_simulation_made_it(tmp_path):
    # The run's timeseries.parquet is read by pandas (and polars where installed) directly,
    # with the same float64 numbers the simulation produced and the units in its metadata.
    import pyarrow.parquet as pq

    from tt_mujoco import run
    from tt_mujoco.sim import COLUMNS, Scenario, simulate

    pd = pytest.importorskip("pandas")
    argv = ["--plant", "reduced", "--traj", "circle", "--duration", "1", "--seed", "3"]
    out = tmp_path / "run"
    assert (
        run.main(
            [
                *argv,
                "--noise-snr-db",
                "20",
                "--no-video",
                "--no-plots",
                "--quiet",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    ts = simulate(
        Scenario(plant="reduced", traj="circle", duration=1.0, seed=3, noise_snr_db=20.0)
    ).timeseries
    frame = pd.read_parquet(out / "timeseries.parquet")
    assert list(frame.columns) == list(COLUMNS)
    for name in COLUMNS:
        np.testing.assert_array_equal(frame[name].to_numpy(), ts[name])
    schema = pq.read_schema(out / "timeseries.parquet")
    assert schema.field("v").metadata[b"unit"] == b"m/s"
    assert schema.field("T_r").metadata[b"unit"] == b"N m"
    try:
        import polars as pl
    except ImportError:
        return
    np.testing.assert_array_equal(
        pl.read_parquet(out / "timeseries.parquet")["x"].to_numpy(), ts["x"]
    )


def test_an_out_name_that_is_not_utf8_is_refused_before_the_run(tmp_path, capsys):
    from tt_mujoco import run

    out = tmp_path / "bad\udcffname"  # a byte 0xff from the command line
    argv = ["--plant", "reduced", "--duration", "0.2", "--no-video", "--no-plots", "--quiet"]
    assert run.main([*argv, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "not UTF-8" in err and "Traceback" not in err and err.count("\n") == 1
    assert list(tmp_path.iterdir()) == []


def test_a_dangling_symlink_as_out_is_named_as_a_link(tmp_path, capsys):
    from tt_mujoco import run

    link = tmp_path / "link"
    link.symlink_to(tmp_path / "missing")
    argv = ["--plant", "reduced", "--duration", "0.2", "--no-video", "--no-plots", "--quiet"]
    assert run.main([*argv, "--out", str(link)]) == 2
    err = capsys.readouterr().err
    assert "is a symbolic link" in err and "which does not exist" in err
    assert not (tmp_path / "missing").exists()


def test_an_integer_beyond_a_float_is_neither_read_nor_written():
    # what the strict reader refuses, the writer never writes: a metric's 10**400 is None
    from tt_mujoco.outputs import json_safe, parse_strict_json

    with pytest.raises(ValueError, match="beyond a float"):
        parse_strict_json('{"m": 1' + "0" * 400 + "}")
    assert parse_strict_json('{"m": 12345678901234567890}') == {"m": 12345678901234567890}
    assert json_safe({"m": 10**400, "n": -(10**400), "k": 3}) == {"m": None, "n": None, "k": 3}


#: Every command that makes an output folder, with arguments that would run it (short).
FOLDER_COMMANDS = {
    "tt_mujoco.run": ["--plant", "reduced", "--duration", "0.2", "--no-video", "--quiet"],
    "tt_mujoco.sweep.cli": ["duration=0.2", "plant=reduced", "--no-figures", "--quiet"],
    "tt_mujoco.validate": [],
    "tt_mujoco.model": [],
    "tt_mujoco.compare": ["{run}", "{other}"],
    "tt_mujoco.identify": ["{run}"],
    "tt_mujoco.excite": [],
    "tt_mujoco.paper.cli": [],
}


def test_every_command_that_makes_a_folder_is_listed_here():
    from pathlib import Path

    package = Path(outputs.__file__).parent
    makers = {
        "tt_mujoco." + str(p.relative_to(package.parent).with_suffix("")).replace("/", ".")[10:]
        for p in package.rglob("*.py")
        if "claim_folder(" in p.read_text() or "prepare_out(" in p.read_text()
    }
    makers -= {"tt_mujoco.folders", "tt_mujoco.outputs", "tt_mujoco.sweep.execute"}  # the makers
    assert makers | {"tt_mujoco.sweep.cli"} == set(FOLDER_COMMANDS), makers


@pytest.fixture(scope="module")
def finished_run(tmp_path_factory):
    import shutil

    from tt_mujoco import run

    folder = tmp_path_factory.mktemp("finished") / "run"
    assert run.main([*FOLDER_COMMANDS["tt_mujoco.run"], "--no-plots", "--out", str(folder)]) == 0
    shutil.copytree(folder, folder.parent / "other")  # a second run to compare it with
    return folder


def _argv(command: str, finished_run) -> list[str]:
    return [
        a.format(run=finished_run, other=finished_run.parent / "other")
        for a in FOLDER_COMMANDS[command]
    ]


@pytest.mark.parametrize("command", list(FOLDER_COMMANDS))
@pytest.mark.parametrize("where", ["inside a finished run", "a dangling link"])
def test_no_command_writes_inside_a_finished_run_or_through_a_link(
    finished_run, tmp_path, capsys, command, where
):
    import importlib

    before = sorted(p.name for p in finished_run.iterdir())
    if where == "a dangling link":
        out = tmp_path / "link"
        out.symlink_to(tmp_path / "missing")
    else:
        out = finished_run / "inner"
    code = importlib.import_module(command).main([*_argv(command, finished_run), "--out", str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1, err
    said = ("is a symbolic link",) if where == "a dangling link" else ("lies inside", "is inside")
    assert any(words in err[0] for words in said), err
    assert sorted(p.name for p in finished_run.iterdir()) == before
    assert not (tmp_path / "missing").exists()


#: Commands whose writes a 1 KiB file size limit does not reach soon: the paper's suite runs
#: for 40 s before it writes (the same guard says what the file system refused), and an
#: identification's files fit in the limit.
LATE_WRITERS = ("tt_mujoco.paper.cli", "tt_mujoco.identify")


@pytest.mark.parametrize("command", [c for c in FOLDER_COMMANDS if c not in LATE_WRITERS])
def test_every_command_whose_writes_the_file_system_refuses_says_so_in_one_line(
    finished_run, tmp_path, command
):
    """A full disk, a quota, a file size limit (here: RLIMIT_FSIZE, EFBIG): one line naming
    what was refused, exit code 2, and no folder left that holds nothing but its claim."""
    import resource
    import subprocess
    import sys

    def limited():
        resource.setrlimit(resource.RLIMIT_FSIZE, (1024, 1024))

    out = tmp_path / "out"
    module = command.removesuffix(".cli")
    env = {**os.environ, "TT_MUJOCO_COMPILED": "0"}  # no compile of the loop to write
    proc = subprocess.run(
        [sys.executable, "-m", module, *_argv(command, finished_run), "--out", str(out)],
        preexec_fn=limited,
        capture_output=True,
        text=True,
        timeout=300,
        cwd=tmp_path,
        env=env,
    )
    err = proc.stderr.strip().splitlines()
    assert proc.returncode == 2 and len(err) == 1, proc.stderr
    assert "File too large" in err[0] and "Traceback" not in proc.stderr, err
    assert not out.exists() or {p.name for p in out.iterdir()} - {outputs.CLAIM_FILE}


@pytest.mark.parametrize("kind", ["fifo", "device", "folder"])
def test_a_file_read_back_is_a_regular_file_or_refused_before_it_is_opened(tmp_path, kind):
    """A FIFO waits for a writer and /dev/zero never ends: every reader of a file read back
    (TOML, strict JSON, a sweep's journal) goes through read_regular, which refuses them."""
    from tt_mujoco.sweep.options import BadSpecError
    from tt_mujoco.sweep.tables import read_journal

    path = {"fifo": tmp_path / "f.toml", "device": "/dev/zero", "folder": tmp_path}[kind]
    if kind == "fifo":
        os.mkfifo(path)
    said = "it is a folder" if kind == "folder" else "it is not a regular file"
    with pytest.raises(ValueError, match=f"cannot be read: {said}"):
        outputs.read_toml(path, "a file")
    with pytest.raises(ValueError, match=f"cannot be read: {said}"):
        outputs.read_strict_json(path)
    with pytest.raises(BadSpecError, match=f"cannot be read: {said}"):
        read_journal(path)
    with pytest.raises(FileNotFoundError):
        outputs.read_regular(tmp_path / "missing", "missing")


def test_a_text_file_saved_with_a_byte_order_mark_reads_as_without(tmp_path):
    """Windows editors start UTF-8 files with U+FEFF: every text reader (TOML, strict JSON;
    the CSV readers already did) drops it."""
    toml, doc = tmp_path / "a.toml", tmp_path / "a.json"
    toml.write_bytes(b"\xef\xbb\xbfduration = 1.0\n")
    doc.write_bytes(b'\xef\xbb\xbf{"status": "ok"}\n')
    assert outputs.read_toml(toml, "a file") == {"duration": 1.0}
    assert outputs.read_strict_json(doc) == {"status": "ok"}


def test_a_csv_row_with_fewer_values_is_named_by_its_line(tmp_path):
    """NumPy's own message advised its ``usecols``, which no command has."""
    path = tmp_path / "log.csv"
    path.write_text("t,v,omega\n0,1,0\n0.1,1,0\n0.2,1\n0.3,1,0\n")
    with pytest.raises(
        ValueError, match=r"log.csv: row 4 has 2 values where the rows before have 3$"
    ):
        outputs.read_timeseries(path)


_JSON_ISH = st.one_of(
    st.text(max_size=60),
    st.recursive(
        st.one_of(st.none(), st.booleans(), st.integers(), st.floats(), st.text(max_size=5)),
        lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=3), inner),
        max_leaves=8,
    ).map(lambda doc: json.dumps(doc, allow_nan=True)),
)


@settings(max_examples=300, deadline=None)
@given(text=_JSON_ISH)
def test_the_strict_json_reader_takes_strict_json_or_refuses_it_in_words(text):
    """Every text: a document whose numbers are all finite, or a ValueError (never another
    exception, never NaN or an infinity taken)."""
    from tt_mujoco.outputs import parse_strict_json

    try:
        doc = parse_strict_json(text)
    except ValueError as err:
        assert str(err)
        return
    assert json.loads(json.dumps(doc, allow_nan=False)) == doc


@settings(max_examples=200, deadline=None)
@given(content=st.binary(max_size=200))
def test_the_toml_reader_takes_toml_or_refuses_it_naming_the_file(tmp_path_factory, content):
    path = tmp_path_factory.mktemp("toml") / "f.toml"
    path.write_bytes(content)
    try:
        outputs.read_toml(path, "a file")
    except ValueError as err:
        assert str(path) in str(err), err

"""One guard for what is read back (tt_mujoco/runfolder.py): every file of a finished run's
folder x every kind of damage, generated from what the module declares (its metrics fields,
its columns, the files a run keeps), read by read_run and by every command that reads run
folders. A damaged file is exit 2, one line naming the file (and the field, column or row),
with nothing written anywhere; damage a run may carry (a missing reference path or kept world)
is read as before."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest
from documents import key_paths, nested, parent_of
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tt_mujoco import bag, compare, render, run, runfolder
from tt_mujoco.analysis.metric_names import METRIC_UNITS
from tt_mujoco.outputs import CLAIM_FILE, REFERENCE_FILE, read_timeseries, write_timeseries
from tt_mujoco.world.builtin import KEPT_WORLD

#: The commands that read run folders, each with the arguments that make it write a new file.
COMMANDS = {
    "render": lambda folder, good, out: render.main(
        [str(folder), "--out", str(out / "v.mp4"), "--no-progress", "--width", "64"]
    ),
    "bag": lambda folder, good, out: bag.main([str(folder), "--out", str(out / "b.mcap")]),
    "compare": lambda folder, good, out: compare.main(
        [str(good), str(folder), "--out", str(out / "cmp")]
    ),
}


@pytest.fixture(scope="module")
def finished(tmp_path_factory) -> dict[str, Path]:
    """Two finished runs in a world (a reduced-plant maneuver), one kept as Parquet, one as
    CSV."""
    base = tmp_path_factory.mktemp("runs")
    runs = {}
    for fmt in ("parquet", "csv"):
        folder = base / fmt
        argv = ["--world", "loading_bay", "--traj", "plan", "--reverse", "--plant", "reduced"]
        argv += ["--duration", "3", "--timeseries-format", fmt, "--out", str(folder)]
        assert run.main([*argv, "--no-video", "--no-plots", "--quiet"]) in (0, 3)
        runs[fmt] = folder
    return runs


def _metrics(folder: Path) -> dict:
    return json.loads((folder / runfolder.METRICS_FILE).read_text())


def _put(doc: dict, path: str, value) -> None:
    keys = path.split(".")
    for key in keys[:-1]:
        doc = doc.setdefault(key, {})
    doc[keys[-1]] = value


def _wrong_values(field: runfolder.MetricsField) -> list:
    """Values of JSON types the field does not allow."""
    candidates = [["a", "list"], "text", 7, -3, 1.5, True, None, {"a": 1}]
    return [v for v in candidates if field.why_not(v)][:3]


def _edit_metrics(path: str, value, says: str | None = None):
    def edit(folder: Path) -> str:
        doc = _metrics(folder)
        _put(doc, path, value)
        (folder / runfolder.METRICS_FILE).write_text(json.dumps(doc))
        return says or path

    return edit


def _metrics_text(text: str, says: str):
    def edit(folder: Path) -> str:
        (folder / runfolder.METRICS_FILE).write_bytes(text.encode("latin-1"))
        return says

    return edit


def _series_edit(change, says: str):
    def edit(folder: Path) -> str:
        ts = read_timeseries(folder / "timeseries.parquet")
        change(ts)
        (folder / "timeseries.parquet").unlink()
        write_timeseries(folder / "timeseries.parquet", ts, list(ts))
        return says

    return edit


def _file_damage(name: str, how: str):
    def edit(folder: Path) -> str:
        file = folder / name
        data = file.read_bytes()
        if how == "missing":
            file.unlink()
        elif how == "empty":
            file.write_bytes(b"")
        elif how == "truncated":
            file.write_bytes(data[: len(data) // 2])
        elif how == "not UTF-8":
            file.write_bytes(b"\xff\xfe\x80" + data)
        elif how == "a device":  # endless bytes: never to be read
            file.unlink()
            file.symlink_to("/dev/zero")
        elif how == "a folder":
            file.unlink()
            file.mkdir()
        return name

    return edit


def _nan_at(column: str, row: int):
    def change(ts):
        ts[column][row] = np.nan

    return change


def _drop(column: str):
    def change(ts):
        del ts[column]

    return change


def _as_text(column: str):
    def edit(folder: Path) -> str:
        import pyarrow as pa
        import pyarrow.parquet as pq

        file = folder / "timeseries.parquet"
        table = pq.read_table(file)
        j = table.column_names.index(column)
        text = pa.array([repr(v) for v in table.column(j).to_pylist()])
        pq.write_table(table.set_column(j, column, text), file)
        return f"column {column!r} holds string, not numbers"

    return edit


def _claimed(folder: Path) -> str:
    """A writer's claim left beside complete outputs (a run killed while it drew its video)."""
    (folder / CLAIM_FILE).write_text("claimed by process 1\n")
    return f"{CLAIM_FILE} is there"


def _backwards(ts):
    ts["t"][5] = ts["t"][3]


def _cases() -> dict[str, tuple]:
    """name -> (damage, format the damage applies to)."""
    cases = {}
    for field in runfolder.METRICS_FIELDS:
        for value in _wrong_values(field):
            cases[f"metrics {field.path}={json.dumps(value)}"] = (
                _edit_metrics(field.path, value),
                "parquet",
            )
    for name in METRIC_UNITS:  # every built-in metric: a number or null, never text
        cases[f"metrics {name}=text"] = (_edit_metrics(name, "abc"), "parquet")
    cases["metrics NaN"] = (_metrics_text('{"config": {}, "rmse_v": NaN}', "NaN"), "parquet")
    cases["metrics 1e400"] = (_metrics_text('{"config": {}, "rmse_v": 1e400}', "beyond"), "parquet")
    cases["metrics huge int"] = (
        _metrics_text('{"config": {}, "steps": ' + "9" * 5000 + "}", "strict JSON"),
        "parquet",
    )
    cases["metrics key twice"] = (_metrics_text('{"config": {}, "config": {}}', "twice"), "parquet")
    cases["metrics a list"] = (_metrics_text("[1, 2]", "not a run's metrics"), "parquet")
    cases["metrics no config"] = (_metrics_text('{"status": "ok"}', "no config"), "parquet")
    cases["metrics deep"] = (_metrics_text("[" * 100000 + "]" * 100000, "strict JSON"), "parquet")
    cases["plant_params extra key"] = (
        _edit_metrics("config.plant_params.wheelbase", 1.0, "['wheelbase'] are not Params fields"),
        "parquet",
    )
    cases["plant_params L=-1"] = (
        _edit_metrics("config.plant_params.L", -1.0, "plant_params: L=-1.0"),
        "parquet",
    )
    cases["plant_params L edited"] = (
        _edit_metrics("config.plant_params.L", 0.5, "are not the vehicle"),
        "parquet",
    )
    cases["plant_params L huge"] = (
        _edit_metrics(
            "config.plant_params.L", 10**30, "it must be a finite number in [0.001, 100] m"
        ),
        "parquet",
    )
    cases["steps beyond rows"] = (_edit_metrics("steps", 10**7, "the file is cut"), "parquet")
    for how in ("missing", "empty", "truncated", "not UTF-8", "a device", "a folder"):
        cases[f"metrics.json {how}"] = (_file_damage("metrics.json", how), "parquet")
        cases[f"timeseries.parquet {how}"] = (_file_damage("timeseries.parquet", how), "parquet")
        cases[f"timeseries.csv {how}"] = (_file_damage("timeseries.csv", how), "csv")
        if how != "missing":  # without it the run's reference point is drawn
            cases[f"{REFERENCE_FILE} {how}"] = (_file_damage(REFERENCE_FILE, how), "parquet")
            cases[f"{KEPT_WORLD} {how}"] = (_file_damage(KEPT_WORLD, how), "parquet")
    for column in runfolder.read_columns(1):
        cases[f"no column {column}"] = (_series_edit(_drop(column), column), "parquet")
    for column in runfolder.STATE_COLUMNS:
        cases[f"NaN in {column}"] = (_series_edit(_nan_at(column, 7), column), "parquet")
    for column in runfolder.STATE_COLUMNS:  # numbers spelt as text are not numbers
        cases[f"text in {column}"] = (_as_text(column), "parquet")
    cases["time backwards"] = (_series_edit(_backwards, "time must increase"), "parquet")
    cases["a writer's claim"] = (_claimed, "parquet")
    return cases


CASES = _cases()
#: Damage a finished run may carry: read as before.
ACCEPTED = {
    f"{REFERENCE_FILE} missing": _file_damage(REFERENCE_FILE, "missing"),
    f"{KEPT_WORLD} missing": _file_damage(KEPT_WORLD, "missing"),
    "an extra metric": _edit_metrics("my_metric", {"a": [1, None, "x"]}),
}


def _damaged(finished, tmp_path, damage, fmt) -> tuple[Path, str]:
    folder = tmp_path / "run"
    shutil.copytree(finished[fmt], folder)
    return folder, damage(folder)


def test_the_matrix_covers_every_declared_field_column_and_file():
    names = " ".join(CASES)
    assert all(f.path in names for f in runfolder.METRICS_FIELDS)
    assert all(f"no column {c}" in CASES for c in runfolder.read_columns(1))
    for file in (
        "metrics.json",
        "timeseries.parquet",
        "timeseries.csv",
        REFERENCE_FILE,
        KEPT_WORLD,
    ):
        assert f"{file} truncated" in CASES
    assert len(CASES) >= 80, len(CASES)


@pytest.mark.parametrize("name", list(CASES))
def test_a_damaged_run_folder_is_refused_naming_what(finished, tmp_path, name):
    damage, fmt = CASES[name]
    folder, says = _damaged(finished, tmp_path, damage, fmt)
    with pytest.raises(runfolder.RunFolderError) as err:
        runfolder.read_run(folder)
    message = str(err.value)
    assert says in message and len(message.splitlines()) == 1, message


@pytest.mark.parametrize("name", list(ACCEPTED))
def test_what_a_run_may_lack_is_read_as_before(finished, tmp_path, name):
    folder, _ = _damaged(finished, tmp_path, ACCEPTED[name], "parquet")
    kept = runfolder.read_run(finished["parquet"])
    again = runfolder.read_run(folder)
    assert again.world == kept.world
    np.testing.assert_array_equal(again.timeseries["x"], kept.timeseries["x"])


# Every command x a sample of every kind of damage (each kind's first case): exit 2, one line,
# nothing written anywhere, the run folder unchanged.
_KINDS = {}
for _name in CASES:
    _KINDS.setdefault(_name.split(" ")[0] + " " + _name.split(" ")[-1][:4], _name)


@pytest.mark.parametrize("command", list(COMMANDS))
@pytest.mark.parametrize("name", sorted(set(_KINDS.values())))
def test_every_command_refuses_a_damaged_run_in_one_line(finished, tmp_path, capsys, command, name):
    damage, fmt = CASES[name]
    folder, says = _damaged(finished, tmp_path, damage, fmt)
    before = _snapshot(folder)
    out = tmp_path / "out"
    out.mkdir()
    code = COMMANDS[command](folder, finished["parquet"], out)
    err = capsys.readouterr().err
    assert code == 2, err
    assert len(err.strip().splitlines()) == 1 and says in err, err
    assert "np." not in err, err  # a value as the user reads it, not NumPy's repr
    assert not list(out.iterdir())
    assert _snapshot(folder) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out", "run"]


def _snapshot(folder: Path) -> dict:
    """A run folder's files by name: their bytes, a link's target, a folder's mark (a link to
    a device is never read)."""
    return {
        p: ("link", str(p.readlink()))
        if p.is_symlink()
        else "folder"
        if p.is_dir()
        else p.read_bytes()
        for p in folder.iterdir()
    }


@pytest.mark.parametrize("command", list(COMMANDS))
def test_no_command_writes_inside_a_run_folder(finished, tmp_path, capsys, command):
    folder = tmp_path / "run"
    shutil.copytree(finished["parquet"], folder)
    before = sorted(p.name for p in folder.iterdir())
    code = COMMANDS[command](folder, finished["csv"], folder / "sub")
    assert code == 2 and "inside the run folder" in capsys.readouterr().err
    assert sorted(p.name for p in folder.iterdir()) == before


def test_defaults_are_beside_the_run(tmp_path):
    assert runfolder.default_out(tmp_path / "r", "follow", ".mp4") == tmp_path / "r.follow.mp4"
    assert runfolder.default_out(Path("."), "ros2", ".mcap").parent == Path.cwd().parent


def test_a_reader_is_the_only_one_that_opens_a_run_folder():
    """No command module reads metrics.json or a run's time series itself."""
    root = Path(runfolder.__file__).parent
    for module in ("render.py", "bag.py", "compare.py"):
        text = (root / module).read_text()
        assert "read_timeseries" not in text and "json.load" not in text, module


# --- property-based: any metrics.json, any journal line -------------------------------------

_JSON = nested(
    st.none()
    | st.booleans()
    | st.integers(-(10**30), 10**30)
    | st.floats(allow_nan=False, allow_infinity=False)
    | st.text(max_size=8)
)


@settings(
    max_examples=150,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
@given(data=st.data())
def test_any_edit_of_metrics_json_is_read_or_refused_in_one_line(finished, tmp_path_factory, data):
    """Any JSON value put anywhere in a run's metrics.json (or the file replaced by any text):
    read_run reads it or raises RunFolderError, in one line; nothing else."""
    folder = tmp_path_factory.mktemp("edited") / "run"
    shutil.copytree(finished["parquet"], folder)
    doc = _metrics(folder)
    if data.draw(st.booleans()):
        path = data.draw(st.sampled_from(list(key_paths(doc, depth=3))))
        parent_of(doc, path)[path[-1]] = data.draw(_JSON)
        (folder / runfolder.METRICS_FILE).write_text(json.dumps(doc))
    else:
        raw = data.draw(st.binary(max_size=200))
        (folder / runfolder.METRICS_FILE).write_bytes(raw)
    try:
        runfolder.read_run(folder)
    except runfolder.RunFolderError as err:
        assert len(str(err).splitlines()) == 1


@settings(max_examples=300, deadline=None)
@given(
    lines=st.lists(
        st.binary(max_size=120) | _JSON.map(lambda v: json.dumps(v).encode()), max_size=5
    )
)
def test_any_journal_is_read_or_refused_in_one_line(tmp_path_factory, lines):
    from tt_mujoco.sweep.options import BadSpecError
    from tt_mujoco.sweep.tables import read_journal

    path = tmp_path_factory.mktemp("journal") / "journal.jsonl"
    path.write_bytes(b"\n".join(lines))
    try:
        done = read_journal(path)
    except BadSpecError as err:
        assert len(str(err).splitlines()) == 1
    else:
        assert all(isinstance(k, str) and isinstance(r, dict) for k, r in done.items())


@pytest.mark.parametrize("command", list(COMMANDS))
def test_every_command_refuses_a_run_folder_name_the_file_system_refuses(
    finished, tmp_path, capsys, command
):
    """A name too long for the file system: one line, exit 2 (compare's was a bug of ours)."""
    out = tmp_path / "out"
    out.mkdir()
    code = COMMANDS[command](tmp_path / ("a" * 300), finished["parquet"], out)
    err = capsys.readouterr().err
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert "File name too long" in err and not list(out.iterdir())

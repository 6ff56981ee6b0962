"""A sweep's journal read back (tt_mujoco/sweep/tables.py read_journal): every declared field
of a record x every way to break it, generated from JOURNAL_FIELDS. Only a last line cut by a
kill is dropped (that run runs again); any other damage is exit 2 naming the line and the
field, with the sweep folder left as it was."""

from __future__ import annotations

import json
import shutil

import pytest

from tt_mujoco.sweep import cli
from tt_mujoco.sweep.options import JOURNAL, BadSpecError
from tt_mujoco.sweep.tables import JOURNAL_FIELDS, read_journal

RECORD = {
    "run_id": "65ae4bd6d11276c0",
    "index": 0,
    "status": "ok",
    "message": "completed 0.500 s",
    "error": "",
    "metrics": {"rmse_v": 0.04, "offtrack_follower": "trailer", "trailer_rmse_lateral": None},
    "config": {"plant": "reduced", "seed": 0},
    "run_wall_s": 0.2,
}


def _line(record) -> bytes:
    return (json.dumps(record) + "\n").encode()


def _broken_records() -> dict[str, tuple[bytes, str]]:
    """name -> (a journal's bytes, what the refusal names)."""
    cases = {}
    for field in JOURNAL_FIELDS:
        for value in (["a"], "text", -3, 1.5, True, None, {"a": 1}):
            if field.why_not(value):
                record = {**RECORD, field.path: value}
                cases[f"{field.path}={json.dumps(value)}"] = (_line(record), field.path)
        if field.required:
            record = {k: v for k, v in RECORD.items() if k != field.path}
            cases[f"no {field.path}"] = (_line(record), field.path)
    for table in ("metrics", "config"):
        for value in ([1, 2], {"a": 1}):
            record = {**RECORD, table: {**RECORD[table], "bad": value}}
            cases[f"{table}.bad={json.dumps(value)}"] = (_line(record), f"{table}.bad")
    good = _line(RECORD)
    cases["NaN"] = (good.replace(b"0.04", b"NaN"), "NaN")
    cases["1e400"] = (good.replace(b"0.04", b"1e400"), "beyond a float")
    cases["key twice"] = (good.replace(b'"index": 0', b'"index": 0, "index": 1'), "twice")
    cases["not UTF-8"] = (b"\xff\xfe" + good, "not UTF-8")
    cases["a list"] = (b"[1, 2]\n", "not a run's record")
    cases["cut, then more"] = (good[:40] + b"\n" + good, "line 1")
    cases["deep"] = (b"[" * 100000 + b"]" * 100000 + b"\n", "nested too deeply")
    return cases


CASES = _broken_records()


def test_every_declared_field_is_broken_in_the_matrix():
    assert all(any(f.path in name for name in CASES) for f in JOURNAL_FIELDS)
    assert len(CASES) >= 30, len(CASES)


@pytest.mark.parametrize("name", list(CASES))
def test_a_damaged_journal_line_is_refused_naming_it(tmp_path, name):
    data, says = CASES[name]
    path = tmp_path / JOURNAL
    path.write_bytes(_line({**RECORD, "run_id": "first"}) + data)
    with pytest.raises(BadSpecError) as err:
        read_journal(path)
    message = str(err.value)
    assert says in message and "line" in message and len(message.splitlines()) == 1, message


def test_a_last_line_cut_by_a_kill_is_dropped_and_the_rest_kept(tmp_path):
    path = tmp_path / JOURNAL
    good = _line(RECORD)
    path.write_bytes(_line({**RECORD, "run_id": "first"}) + good[:50])
    assert list(read_journal(path)) == ["first"]
    path.write_bytes(_line({**RECORD, "run_id": "first"}) + good[:-1])  # whole, no newline
    assert list(read_journal(path)) == ["first", RECORD["run_id"]]
    assert read_journal(tmp_path / "none.jsonl") == {}


@pytest.fixture(scope="module")
def finished_sweep(tmp_path_factory):
    out = tmp_path_factory.mktemp("sweep") / "s"
    argv = ["plant=reduced", "duration=0.3", "seed=0,1", "--workers", "1", "--quiet"]
    assert cli.main([*argv, "--no-figures", "--out", str(out)]) == 0
    return out


@pytest.mark.parametrize("name", ["status=-3", "NaN"])
def test_resuming_a_damaged_sweep_is_exit_2_leaving_the_folder_as_it_was(
    finished_sweep, tmp_path, capsys, name
):
    out = tmp_path / "s"
    shutil.copytree(finished_sweep, out)
    data, says = CASES[name]
    (out / JOURNAL).write_bytes((out / JOURNAL).read_bytes() + data)
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    assert cli.main(["--resume", "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert says in err and len(err.strip().splitlines()) == 1, err
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before


def test_resuming_with_a_saved_spec_that_is_not_utf8_is_exit_2(finished_sweep, tmp_path, capsys):
    out = tmp_path / "s"
    shutil.copytree(finished_sweep, out)
    (out / "sweep.toml").write_bytes((out / "sweep.toml").read_bytes() + b"\xff")
    assert cli.main(["--resume", "--out", str(out), "--quiet"]) == 2
    assert "not UTF-8" in capsys.readouterr().err

"""``python -m tt_mujoco.compare``: the table, the figures, and what it refuses."""

import json

import pytest

from tt_mujoco import compare, run


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    base = tmp_path_factory.mktemp("runs")
    folders = []
    for controller, traj in (("ismc_sta", "circle"), ("pid", "circle"), ("fbl", "s_curve")):
        out = base / f"{controller}-{traj}"
        argv = ["--plant", "reduced", "--traj", traj, "--duration", "2", "--controller", controller]
        assert run.main([*argv, "--no-video", "--no-plots", "--quiet", "--out", str(out)]) == 0
        folders.append(out)
    return folders


def test_compare_writes_the_table_and_figures(runs, tmp_path, capsys):
    out = tmp_path / "cmp"
    assert compare.main([str(runs[0]), str(runs[1]), "--out", str(out)]) == 0
    assert sorted(p.name for p in out.iterdir()) == [
        "compare.json",
        "compare.md",
        "errors.png",
        "paths.png",
        "signals.png",
    ]
    doc = json.loads((out / "compare.json").read_text())
    rows = {r["metric"]: r for r in doc["rows"]}
    first = json.loads((runs[0] / "metrics.json").read_text())
    second = json.loads((runs[1] / "metrics.json").read_text())
    assert rows["rmse_v"]["values"] == [first["rmse_v"], second["rmse_v"]]
    assert rows["rmse_v"]["ratios"][1] == pytest.approx(second["rmse_v"] / first["rmse_v"])
    assert "| rmse_v |" in (out / "compare.md").read_text()


def test_compare_refuses_runs_on_different_paths_unless_asked(runs, tmp_path, capsys):
    out = tmp_path / "cmp"
    assert compare.main([str(runs[0]), str(runs[2]), "--out", str(out)]) == 2
    assert "different paths" in capsys.readouterr().err and not out.exists()
    args = [str(runs[0]), str(runs[2]), "--allow-different-paths", "--out", str(out)]
    assert compare.main(args) == 0


def test_compare_refuses_a_folder_that_is_not_a_run(runs, tmp_path, capsys):
    assert compare.main([str(runs[0]), str(tmp_path), "--out", str(tmp_path / "x")]) == 2
    assert "not a finished run" in capsys.readouterr().err


def test_a_broken_copy_of_the_path_is_refused_before_an_output_folder(tmp_path, capsys):
    from tt_mujoco.outputs import REFERENCE_FILE

    argv = ["--plant", "reduced", "--duration", "0.5", "--no-video", "--no-plots", "--quiet"]
    for name in ("a", "b"):
        assert run.main([*argv, "--out", str(tmp_path / name)]) == 0
    (tmp_path / "a" / REFERENCE_FILE).write_text("garbage")
    out = tmp_path / "cmp"
    assert compare.main([str(tmp_path / "a"), str(tmp_path / "b"), "--out", str(out)]) == 2
    assert REFERENCE_FILE in capsys.readouterr().err
    assert not out.exists()


def test_every_run_is_one_column_whatever_its_folder_is_called(runs, tmp_path, capsys):
    """Copies of one run in folders of one name (``a/run``, ``b/run``) are told apart by
    their paths; a folder given twice, in any spelling, is refused."""
    import shutil

    copies = [tmp_path / "a" / "run", tmp_path / "b" / "run", tmp_path / "b" / "c" / "run"]
    for copy in copies:
        shutil.copytree(runs[0], copy)
    out = tmp_path / "cmp"
    assert compare.main([*map(str, copies), "--out", str(out)]) == 0
    labels = json.loads((out / "compare.json").read_text())["labels"]
    assert len(set(labels)) == 3, labels
    assert [label.split(" (")[0] for label in labels] == ["a/run", "b/run", "c/run"]
    capsys.readouterr()
    for twice in (
        [runs[0], runs[0]],
        [runs[0], runs[1], runs[0].parent / ".." / runs[0].parent.name / runs[0].name],
    ):
        assert compare.main([*map(str, twice), "--out", str(tmp_path / "twice")]) == 2
        assert "is given twice" in capsys.readouterr().err
        assert not (tmp_path / "twice").exists()

"""The paper-reproduction suite and its report builder (tt_mujoco.paper), on a reduced set."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from tt_mujoco import paper
from tt_mujoco.paper import (
    CELLS,
    PLANTS,
    SUITE_SEED,
    TABLE_RUNS,
    RunSpec,
    build_report,
    curvature_split,
    execute,
    main,
    run_suite,
    suite,
)
from tt_mujoco.reference.targets import make_target
from tt_mujoco.sim import Scenario

#: docs/model.md Section 10, transcribed independently of paper.py: (table, case) -> {metric:
#: value}.
SPEC_10 = {
    (1, "Nominal"): {"rmse_v": 0.0147, "rmse_omega": 0.0224, "rmse_lateral": 0.0368},
    (1, "+20 %"): {"rmse_v": 0.0157, "rmse_omega": 0.0284, "rmse_lateral": 0.0352},
    (1, "-20 %"): {"rmse_v": 0.0146, "rmse_omega": 0.0216, "rmse_lateral": 0.0397},
    (2, "20 dB Gaussian noise"): {"rmse_v": 0.0165, "rmse_omega": 0.0269, "rmse_lateral": 0.0484},
    (3, "PID"): {"rmse_v": 0.3273, "rmse_omega": 0.2544, "max_abs_v": 0.6669},
    (3, "FBL"): {"rmse_v": 0.5247, "rmse_omega": 0.2699, "max_abs_omega": 0.5155},
    (3, "ISMC-STA"): {"max_abs_v": 0.0971, "max_abs_omega": 0.0659},
    (4, "Dynamic"): {"rmse_position": 0.0091, "rmse_omega": 0.0514, "max_position": 0.0174},
    (4, "Static"): {"rmse_position": 0.0261, "rmse_v": 0.0131, "max_position": 0.0488},
    (5, "Dynamic"): {"rmse_position": 0.0111, "rmse_v": 0.0131, "rmse_omega": 0.0223},
    (5, "Static"): {"rmse_position": 0.0115, "rmse_omega": 0.0151, "max_position": 0.0174},
}


def test_cells_are_the_papers_tables():
    counts = {t: sum(c.table == t for c in CELLS) for t in range(1, 6)}
    assert counts == {1: 9, 2: 6, 3: 12, 4: 8, 5: 8}
    by_key = {(c.table, c.case, c.metric): c.paper for c in CELLS}
    for (table, case), values in SPEC_10.items():
        for metric, value in values.items():
            assert by_key[(table, case, metric)] == value
    assert all(c.run in TABLE_RUNS for c in CELLS)


def test_full_suite_definition():
    specs = suite()
    keys = [s.key for s in specs]
    assert len(keys) == len(set(keys))
    runs = {s.key: s.scenario for s in specs}
    for cell in CELLS:
        for plant in PLANTS:
            assert f"{cell.run}@{plant}" in runs
    for spec in specs:
        spec.scenario.validate()
        assert spec.scenario.seed == SUITE_SEED
    for base in TABLE_RUNS:
        sc = runs[f"{base}@mujoco"]
        assert sc.eta == "same_path" and sc.disturbance == "matched"
        assert sc.plant == "mujoco" and runs[f"{base}@reduced"].plant == "reduced"
    assert runs["cycloid_plus20@reduced"].param_scale == 1.2
    assert runs["cycloid_minus20@reduced"].param_scale == 0.8
    assert runs["cycloid_noise@reduced"].noise_snr_db == 20.0
    assert runs["cycloid_nominal@reduced"].gains == "paper_6_1"
    assert runs["cycloid_ismc_6_2@reduced"].gains == "paper_6_2"
    assert runs["cycloid_pid@reduced"].controller == "pid"
    assert runs["s_curve_static@mujoco"].target == "static"
    assert runs["s_curve_static@mujoco"].duration == 10.0  # the paper's stated 10 s
    # The isolation runs the causes read exist (friction 3 for every slipping cycloid run).
    for base in TABLE_RUNS:
        if base.startswith("cycloid"):
            assert runs[f"{base}~mu3@mujoco"].friction == 3.0
    assert runs["cycloid_nominal~nodist@reduced"].disturbance == "none"
    assert runs["steer:circle:scheduled eta(kappa)@mujoco"].eta_schedule
    assert runs["steer:circle:paper eta = 3, reverse@mujoco"].reverse
    assert runs["fb:cycloid:on@mujoco"].path_feedback == {}
    assert runs["fb:cycloid:off@mujoco"].path_feedback is None


def _synthetic_records():
    """Every table run with the paper's numbers, except two cells made 3x too large."""
    records = {}
    for base in TABLE_RUNS:
        for plant in PLANTS:
            metrics = {c.metric: c.paper for c in CELLS if c.run == base}
            metrics["slip_longitudinal_max"] = 0.0
            records[f"{base}@{plant}"] = {
                "status": "ok",
                "metrics": dict(metrics),
                "scenario": Scenario(plant=plant, **TABLE_RUNS[base]).to_dict(),
                "group": "table",
                "info": {},
            }
    # Cell 1: MuJoCo 3x too large with the wheels slipping, and an isolating friction-3 run
    # back at the paper's value: cause C1 must claim it.
    mj = records["cycloid_nominal@mujoco"]["metrics"]
    mj["rmse_v"] = 3 * 0.0147
    mj["slip_longitudinal_max"] = 0.9
    records["cycloid_nominal~mu3@mujoco"] = {
        "status": "ok",
        "metrics": {"rmse_v": 0.0147},
        "scenario": {},
        "group": "isolation",
        "info": {},
    }
    # Cell 2: the reduced circle's e_v 3x too large and no isolation run: unexplained.
    records["circle_dynamic@reduced"]["metrics"]["rmse_v"] = 3 * 0.0131
    return records


def test_report_builder_flags_and_explains(tmp_path):
    out = tmp_path / "report"
    report = build_report(_synthetic_records(), out, {"runs": 1}, figures=False)
    text = report.read_text()
    for title in paper.TABLE_TITLES.values():
        assert f"### {title}" in text
    # Every cell is a row with the paper's value and three value columns.
    data = json.loads((out / "report.json").read_text())
    assert len(data["cells"]) == len(CELLS) == 43
    row_lines = [ln for ln in text.splitlines() if ln.startswith("| Nominal | e_v RMSE")]
    assert row_lines and row_lines[0].count("|") == 7
    assert "| Nominal | e_v RMSE (m/s) | 0.0147 | 0.0147 | 0.0441 | MuJoCo x3: C1 |" in text
    assert "### C1." in text
    assert "### Not explained" in text
    assert "Table 5 Dynamic, e_v RMSE (m/s), reduced" in text
    assert data["unexplained"] == [
        {"table": 5, "case": "Dynamic", "metric": "rmse_v", "plant": "reduced"}
    ]
    assert data["causes"]["C1"]["cells"][0] == {
        "table": 1,
        "case": "Nominal",
        "metric": "rmse_v",
        "plant": "mujoco",
    }
    # The unflagged rows carry no cause; nothing in the report is NaN text.
    assert "nan" not in text.lower().replace("nan (", "")
    assert (out / "summary.md").read_text().startswith("## The paper's results")


def test_run_suite_runs_identical_scenarios_once():
    calls = []

    def runner(key, scenario, keep):
        calls.append(key)
        return {"key": key, "status": "ok", "metrics": {"x": 1.0}}

    sc = Scenario(plant="reduced", duration=0.1)
    specs = [RunSpec("a", "table", sc), RunSpec("b", "steering", Scenario(**sc.to_dict()))]
    records = run_suite(specs, workers=1, progress=False, runner=runner)
    assert calls == ["a"]
    assert records["b"]["same_as"] == "a" and records["b"]["group"] == "steering"
    with pytest.raises(ValueError, match="workers"):
        run_suite(specs, workers=0, progress=False, runner=runner)


def test_quick_suite_end_to_end(tmp_path):
    # Four 0.5 s runs in two spawned worker processes (~5 s), then the whole report.
    specs = suite(quick=True)
    records = run_suite(specs, workers=2, progress=False)
    assert all(r["status"] == "ok" for r in records.values())
    out = tmp_path / "quick"
    report = build_report(records, out, {"runs": len(specs), "workers": 2})
    text = report.read_text()
    assert (out / "fig_ratios.png").stat().st_size > 10_000
    assert "not run" in text  # the cells whose runs are not in the quick set
    data = json.loads((out / "report.json").read_text())
    nominal = next(c for c in data["cells"] if c["run"] == "cycloid_nominal")
    for plant in PLANTS:
        assert nominal[plant]["status"] == "ok"
        assert math.isfinite(nominal[plant]["value"])
    # Determinism: the same scenario in this process gives the same numbers as the worker.
    spec = next(s for s in specs if s.key == "cycloid_nominal@reduced")
    again = execute(spec.key, spec.scenario)
    assert again["metrics"]["rmse_v"] == records[spec.key]["metrics"]["rmse_v"]
    assert again["metrics"]["rmse_lateral"] == records[spec.key]["metrics"]["rmse_lateral"]
    # The run configurations are in the report.
    assert "`cycloid_nominal@mujoco`" in text and "paper_6_1" in text


def test_main_rejects_bad_input(tmp_path, capsys):
    assert main(["--workers", "0"]) == 2
    full = tmp_path / "full"
    full.mkdir()
    (full / "f").write_text("x")
    assert main(["--out", str(full)]) == 2
    assert "not an empty folder" in capsys.readouterr().err


def test_curvature_split_is_exact_on_a_constructed_run():
    # P on the unit circle (kappa_d = 1) at v = 0.8 m/s, turning at omega = 0.9 rad/s while
    # the target asked for 0.85: e_omega / v = 0.0625 and (omega_d - v kappa_d) / v = 0.0625.
    path, _, _ = make_target("circle")
    t = np.linspace(0.0, 2.0, 201)
    angle = 0.8 * t
    ts = {
        "t": t,
        "x": np.cos(angle),
        "y": np.sin(angle),
        "v": np.full_like(t, 0.8),
        "omega": np.full_like(t, 0.9),
        "omega_d": np.full_like(t, 0.85),
    }
    split = curvature_split(ts, path, path.dense())
    assert split["rms_e_omega_over_v"] == pytest.approx(0.0625, rel=1e-12)
    assert split["rms_mismatch"] == pytest.approx(0.0625, rel=1e-9)
    assert split["rms_total"] == pytest.approx(0.9 / 0.8 - 1.0, rel=1e-9)
    assert split["heading_drift_e_omega_end"] == pytest.approx(0.05 * 2.0, rel=1e-12)
    assert split["heading_drift_mismatch_max"] == pytest.approx(0.05 * 2.0, rel=1e-9)
    assert split["samples"] == 201


def test_steady_mask_windows_on_the_s_curve():
    path, _, _ = make_target("s_curve")
    half = path.length / 2  # the curvature step
    s = np.linspace(0.0, path.length, 2001)
    forward = paper.steady_mask(path, s, reverse=False, spacing=0.7)
    # Forward: the trailer settles 2 m after the tractor's start or the step plus the 0.7 m
    # spacing, and stops being steady as soon as the tractor passes the step.
    expected = ((s >= 2.7) & (s < half)) | (s >= half + 2.7)
    # The step is located on a 1 mm grid: samples within 2 mm of a window's edge may go
    # either way.
    edges = np.array([2.7, half, half + 2.7, path.length - 2.0, half + 0.7, half - 2.0, 0.7])
    clear = np.min(np.abs(s[:, None] - edges[None, :]), axis=1) > 2e-3
    assert np.array_equal(forward[clear], expected[clear])
    # Reversing from the end: P0 leads 0.7 m ahead (lower s) and must stay on the path.
    reverse = paper.steady_mask(path, s[::-1], reverse=True, spacing=0.7)[::-1]
    expected_rev = ((s <= path.length - 2.0) & (s > half + 0.7)) | (s <= half - 2.0)
    expected_rev &= s >= 0.7
    assert np.array_equal(reverse[clear], expected_rev[clear])


def test_table_3_gains_the_baselines_and_the_docs_quote_the_suite():
    from tt_mujoco.paper.markdown import baselines_markdown
    from tt_mujoco.paper.suite import PLANTS, TABLE_3_CONTROLLERS
    from tt_mujoco.sim import simulate

    specs = {s.key: s for s in paper.suite()}
    assert list(TABLE_3_CONTROLLERS) == ["ISMC-STA", "PID", "FBL", "Stanley", "LQR", "NMPC"]
    for run in TABLE_3_CONTROLLERS.values():
        for plant in PLANTS:
            assert f"{run}@{plant}" in specs
    # Re-run the LQR's reduced-plant run: its halves of docs/paper.md's row are the suite's.
    key = "cycloid_lqr@reduced"
    records = {key: {"status": "ok", "metrics": simulate(specs[key].scenario).metrics}}
    ours = next(line for line in baselines_markdown(records) if line.startswith("| LQR |"))
    page = (Path(__file__).resolve().parents[1] / "docs" / "paper.md").read_text()
    quoted = next(line for line in page.splitlines() if line.startswith("| LQR | 0."))
    halves = [cell.split(" / ")[0] for cell in quoted.strip("|").split("|")[1:]]
    assert [cell.split(" / ")[0] for cell in ours.strip("|").split("|")[1:]] == halves


def test_the_robustness_study_runs_in_the_suite_and_its_table_reads_the_records():
    from tt_mujoco.paper import robustness

    specs = {s.key: s for s in paper.suite()}
    keys = [k for k in specs if specs[k].group == "robustness"]
    n_cases = len(robustness.cases("cycloid"))
    assert len(keys) == len(robustness.PATHS) * n_cases * len(robustness.CONTROLLERS) == 96
    grade = next(c for c in robustness.cases("s_curve") if c.startswith("grade"))
    spec = specs[robustness.run_key("s_curve", grade, "ISMC-STA")]
    assert spec.scenario.terrain == "slope:20.9:0" and spec.scenario.plant == "mujoco"
    key = robustness.run_key("cycloid", "no disturbance", "PID")
    failed = robustness.run_key("cycloid", "no disturbance", "FBL")
    records = {
        key: {"status": "ok", "metrics": {"cross_track_rms": 0.0123}},
        failed: {"status": "jackknife", "metrics": {"sim_time_s": 1.51}},
    }
    table = "\n".join(robustness.robustness_markdown(records))
    assert "| no disturbance | not run | 12.3 | jackknife at 1.51 s | not run |" in table


def test_docs_paper_quotes_the_suites_robustness_table():
    from tt_mujoco.paper import robustness
    from tt_mujoco.sim import simulate

    key = robustness.run_key("cycloid", "no disturbance", "LQR")
    spec = {s.key: s for s in paper.suite()}[key]
    records = {key: {"status": "ok", "metrics": simulate(spec.scenario).metrics}}
    ours = next(
        line for line in robustness.robustness_markdown(records) if line.startswith("| no dist")
    )
    lqr = list(robustness.CONTROLLERS).index("LQR")
    cell = ours.strip("|").split("|")[1 + lqr].strip()
    page = (Path(__file__).resolve().parents[1] / "docs" / "paper.md").read_text()
    cycloid = page.split("cycloid:\n", 1)[1].split("s_curve:\n", 1)[0]
    quoted = next(line for line in cycloid.splitlines() if line.startswith("| no dist"))
    assert quoted.strip("|").split("|")[1 + lqr].strip() == cell


def test_docs_paper_is_the_suites_summary_as_written_by_its_command():
    from tt_mujoco.paper.cli import docs_page

    page = docs_page(
        "## The results\n\ntext\n\n### Table 1\n\n| a |\n", "python -m x --docs-page p"
    )
    assert page == (
        "# The results\n\ntext\n\n## Table 1\n\n| a |\n\nWritten by `python -m x --docs-page p`.\n"
    )
    docs = (Path(__file__).resolve().parents[1] / "docs" / "paper.md").read_text()
    assert docs.startswith("# The paper's results in contact physics\n")
    assert docs.endswith("Written by `python -m tt_mujoco.paper --docs-page docs/paper.md`.\n")


def test_a_docs_page_in_a_missing_folder_is_refused_before_the_suite(tmp_path, capsys):
    from tt_mujoco.paper.cli import main

    code = main(["--docs-page", str(tmp_path / "nope" / "paper.md"), "--out", str(tmp_path / "o")])
    assert code == 2
    assert "its folder does not exist" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize(
    ("page", "says"),
    [
        ("run/metrics.json", "it must end in .md"),  # it replaced a finished run's record
        ("run/page.md", "is inside the run folder"),
        ("folder.md", "it is a folder"),  # it was exit 70 after the whole suite
        ("nowhere/page.md", "its folder does not exist"),
    ],
)
def test_a_docs_page_that_would_harm_a_run_or_cannot_be_written_is_refused_first(
    tmp_path, monkeypatch, capsys, page, says
):
    from tt_mujoco import run
    from tt_mujoco.paper import cli

    argv = ["--plant", "reduced", "--duration", "0.2", "--no-video", "--no-plots", "--quiet"]
    assert run.main([*argv, "--out", str(tmp_path / "run")]) == 0
    (tmp_path / "folder.md").mkdir()
    record = (tmp_path / "run" / "metrics.json").read_bytes()
    monkeypatch.setattr(cli, "run_suite", lambda *a, **k: pytest.fail("the suite ran"))
    out = tmp_path / "paper"
    code = cli.main(["--quick", "--docs-page", str(tmp_path / page), "--out", str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and says in err[0], err
    assert not out.exists() and (tmp_path / "run" / "metrics.json").read_bytes() == record

"""Sweeps: specification, seeds, executors (process pool and Dask) and resume after a kill."""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tt_mujoco import sweep
from tt_mujoco.sweep import BadSpecError, parse_spec
from tt_mujoco.vehicle.params import Params

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "sweep_example.toml"

# The executor tests' sweep: 8 short MuJoCo runs with noise. With phi0 = 25 deg the paper's
# eta = 3 jackknifes within 1 s (a failure row) and the stable same_path design finishes (ok);
# the slow ok runs come last so that a kill after the first rows leaves work to resume.
ITEMS = ["duration=1.0", "phi0_deg=25", "noise_snr_db=20", "eta=paper,same_path"]
REPEATS = 4
N_RUNS = 2 * REPEATS


def _table(path: Path) -> list[dict]:
    """runs.csv without the columns that measure the machine's load."""
    return [
        {k: v for k, v in row.items() if k not in sweep.WALL_COLUMNS}
        for row in sweep.read_table(path)
    ]


@pytest.fixture(scope="module")
def reference(tmp_path_factory) -> Path:
    """The sweep run uninterrupted through the local process pool (2 workers)."""
    spec = parse_spec(ITEMS, repeats=REPEATS, seed=7)
    out = tmp_path_factory.mktemp("pool") / "sweep"
    result = sweep.run_sweep(spec, out, workers=2)
    assert result.reused == 0
    return out


# --- specification -------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "toml",
    [
        "[options]\nduration = {lin = [0.1, 1, 2.5]}\n",
        "[options]\nduration = {lin = [0.1, 1, true]}\n",
        "[options]\nseed = {range = [0, 3, 0.5]}\n",
    ],
)
def test_a_generators_integer_is_an_integer_not_cut_to_one(tmp_path, toml):
    # 2.5 points made 2, and true made 1, in silence
    path = tmp_path / "sweep.toml"
    path.write_text(toml)
    with pytest.raises(BadSpecError, match="is not an integer"):
        parse_spec([], config=path)
    with pytest.raises(BadSpecError, match="is not an integer"):
        sweep.parse_item("duration=lin:0.1:1:2.5")
    assert len(sweep.expand(parse_spec(["duration=lin:0.1:1:3"]))) == 3


def test_values_lists_generators_and_toml_agree():
    assert sweep.parse_item("gain.k1_v=5,10,20").values == (5.0, 10.0, 20.0)
    assert sweep.parse_item("scale.Mr=lin:0.8:1.2:5").values == (0.8, 0.9, 1.0, 1.1, 1.2)
    assert sweep.parse_item("gain.k1_v=log:1:100:3").values == (1.0, 10.0, 100.0)
    assert sweep.parse_item("seed=range:0:10:3").values == (0, 3, 6, 9)
    assert sweep.parse_item("noise_snr_db=none,20").values == (None, 20.0)
    assert sweep.parse_item("eta=same_path,paper,-0.2").values == ("same_path", "paper", -0.2)
    # A fault spec keeps its commas: one value.
    assert sweep.parse_item("faults=payload:t=2,factor=1.5").values == ("payload:t=2,factor=1.5",)

    from_file = sweep.expand(parse_spec(config=EXAMPLE))
    from_cli = sweep.expand(
        parse_spec(
            [
                "traj=s_curve",
                "controller=ismc_sta",
                "duration=10",
                "disturbance=matched",
                "noise_snr_db=20,30",
                "gain.k1_v=5,10,20",
                "scale.Mr=lin:0.8:1.2:3",
            ],
            seed=1,
            repeats=4,
        )
    )
    assert len(from_file) == 72
    assert [r["run_id"] for r in from_file] == [r["run_id"] for r in from_cli]


@pytest.mark.parametrize(
    ("items", "kwargs", "message"),
    [
        (["foo=1"], {}, "option 'foo' is not allowed"),
        (["scale.L=1.1"], {}, "option 'scale.L' is not allowed"),
        (["controller=lqg"], {}, "controller='lqg' is not allowed"),
        (["duration=-1"], {}, "duration='-1' is not allowed"),
        (["gain.k1_v=5,x"], {}, "gain.k1_v='x' is not allowed"),
        (["gain.kp_v=2"], {}, "'kp_v' (value 2.0) is not a gain of ismc_sta"),
        (["scale.Mr=uniform:0.8:1.2"], {}, "give --samples N"),
        (["scale.Mr=uniform:1.2:0.8"], {"samples": 3}, "needs A < B"),
        (["gain.k1_v=5,5"], {}, "lists a value twice"),
        (["seed=1,2"], {"repeats": 2}, "would run identical copies"),
        (["traj=missing.csv"], {}, "missing.csv"),
        (["eta=paper", "phi0_deg=40"], {}, "phi0=40.0 deg is not allowed"),
        (["faults=payload:t=20", "duration=3"], {}, "after the end of the run"),
        (["scale.Mx=1.1"], {}, "scale.Mx"),
        (["Mr"], {}, "write OPTION=VALUES"),
        (["gain.k1_v=5", "gain.k1_v=10"], {}, "'gain.k1_v=5' and 'gain.k1_v=10' both give"),
    ],
)
def test_bad_specs_raise_one_clear_error(items, kwargs, message):
    with pytest.raises(BadSpecError) as info:
        sweep.expand(parse_spec(items, **kwargs))
    assert message in str(info.value)


def test_cli_bad_spec_is_exit_2_with_one_line(tmp_path, capsys):
    assert sweep.main(["gain.k1_v=-3", "--out", str(tmp_path / "s")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "k1_v=-3.0 is not allowed" in err
    assert not (tmp_path / "s").exists()  # nothing made for a bad spec
    (tmp_path / "used").mkdir()
    (tmp_path / "used" / "x").write_text("")
    assert sweep.main(["duration=1", "--out", str(tmp_path / "used")]) == 2
    assert "pass --resume" in capsys.readouterr().err
    # a flag that only changes a resume is refused without one, not ignored
    for flag in ("--extend", "--retry-errors"):
        assert sweep.main(["duration=1", flag, "--out", str(tmp_path / "x")]) == 2
        assert f"{flag} is not allowed without --resume" in capsys.readouterr().err
        assert not (tmp_path / "x").exists()
    # --resume names a sweep to continue: a folder without one (a typo) is refused, not begun
    (tmp_path / "empty").mkdir()
    for name, state in (("typo", "does not exist"), ("empty", "is empty")):
        assert sweep.main(["duration=1", "--resume", "--out", str(tmp_path / name)]) == 2
        assert f"{state}: there is no sweep to resume" in capsys.readouterr().err
    assert not (tmp_path / "typo").exists() and not any((tmp_path / "empty").iterdir())
    # --workers and --scheduler both say who runs the runs: one of them, not the last
    argv = ["duration=1", "--workers", "2", "--scheduler", "local", "--out", str(tmp_path / "w")]
    assert sweep.main(argv) == 2
    assert "--workers 2 is not allowed with --scheduler 'local'" in capsys.readouterr().err
    assert not (tmp_path / "w").exists()


def test_scales_gains_and_timestep_reach_the_scenario():
    defaults = Params()
    scenario = sweep.build_scenario(
        {"scale.Mr": 1.2, "scale.Ird": 0.5, "param.L0": 0.5, "gain.k1_v": 12.0, "timestep": 0.002}
    )
    # scale.* is a plant-only mismatch; param.* changes vehicle and nominal model alike.
    assert scenario.params == {"L0": 0.5}
    assert scenario.plant_scale == {"Mr": 1.2, "Ird": 0.5}
    plant, nominal = scenario.plant_params(), scenario.nominal_params()
    assert plant.Mr == pytest.approx(defaults.Mr * 1.2) and nominal.Mr == defaults.Mr
    assert plant.Ird == pytest.approx(defaults.Ird * 0.5) and nominal.Ird == defaults.Ird
    assert plant.L0 == nominal.L0 == 0.5
    assert scenario.gains == {"k1_v": 12.0}
    assert scenario.control_dt == 0.002  # the control period follows the timestep
    assert sweep.build_scenario({"gains": "paper_6_2", "gain.eps": 0.1}).gains == {
        "eps": 0.1,
        "preset": "paper_6_2",
    }
    # Boolean and optional-dict Scenario fields: on/off switches and single entries.
    feedback = []
    for item in ("path_feedback=on", "path_feedback.k_y=2", "path_feedback=off"):
        axis = sweep.parse_item(item)
        feedback.append(sweep.build_scenario({axis.name: axis.values[0]}).path_feedback)
    assert feedback == [{}, {"k_y": 2.0}, None]
    assert sweep.parse_item("reverse=true,false").values == (True, False)
    with pytest.raises(BadSpecError, match="reverse='maybe' is not allowed"):
        sweep.parse_item("reverse=maybe")


# --- seeds -------------------------------------------------------------------------------------
def test_grid_seeds_are_common_random_numbers_and_follow_the_sweep_seed():
    runs = sweep.expand(parse_spec(["gain.k1_v=5,10,20"], repeats=3, seed=5))
    seeds = [
        [r["options"]["seed"] for r in runs if r["options"]["gain.k1_v"] == k] for k in (5, 10, 20)
    ]
    # Repeat j has the same noise at every grid point (paired comparison of the gains)...
    assert seeds[0] == seeds[1] == seeds[2]
    assert len(set(seeds[0])) == 3  # ...and a different one per repeat
    other = sweep.expand(parse_spec(["gain.k1_v=5,10,20"], repeats=3, seed=6))
    assert not set(seeds[0]) & {r["options"]["seed"] for r in other}


def test_random_samples_are_stable_when_the_sweep_grows():
    items = ["scale.Mr=uniform:0.8:1.2", "gain.k1_v=loguniform:2:50", "eta=paper,same_path"]
    small = sweep.expand(parse_spec(items, samples=5, seed=3))
    large = sweep.expand(parse_spec(items, samples=9, seed=3))
    assert [r["run_id"] for r in large[:5]] == [r["run_id"] for r in small]
    for run in large:
        assert 0.8 <= run["options"]["scale.Mr"] < 1.2
        assert 2.0 <= run["options"]["gain.k1_v"] < 50.0
    assert len({r["options"]["seed"] for r in large}) == 9


def test_a_crashing_run_is_a_row_with_its_error():
    result = sweep.run_one({"controller": "nope", "duration": 0.1})
    assert result["status"] == "error"
    assert result["error"].startswith("ValueError: controller='nope' is not allowed")
    assert result["metrics"] == {}


def test_a_seed_whose_start_has_no_plan_is_a_row_not_the_sweep_s_end(monkeypatch, tmp_path):
    """A planned run's start is drawn by its seed, and a start the planner finds no path from
    is that run's outcome (status "no_plan", the planner's message), whichever seed it is: the
    configuration is checked with the next seed, never refused for the first one's start (it
    was refused, exit 2, when the first seed's start had no plan, and a row "error" when a
    later one's had none). A sweep whose every run has no plan ends as every failed one does,
    exit 3 (the forward dead end: every start faces the corridor's end)."""
    import importlib

    from tt_mujoco.sweep.runs import validate_runs
    from tt_mujoco.world.plan import PlanError

    build_module = importlib.import_module("tt_mujoco.sim.build")  # the module, not build()
    real = build_module.planned

    def none_for_seed_0(world, p, seed, reverse, deadline=None):
        if seed == 0:
            raise PlanError("no path (the test's) from seed 0's start")
        return real(world, p, seed, reverse, deadline)

    monkeypatch.setattr(build_module, "planned", none_for_seed_0)
    options = {"world": "loading_bay", "traj": "plan", "reverse": True, "plant": "reduced"}
    runs = [{"index": i, "options": {**options, "seed": i}} for i in (0, 1)]
    validate_runs(runs)  # seed 0 has no plan: checked with seed 1
    row = sweep.run_one({**options, "seed": 0, "duration": 0.5})
    assert row["status"] == "no_plan" and row["error"] == "" and row["metrics"] == {}
    assert row["message"] == "no path (the test's) from seed 0's start"
    assert sweep.run_one({**options, "seed": 1, "duration": 0.5})["status"] == "ok"
    monkeypatch.undo()
    monkeypatch.chdir(tmp_path)
    dead_end = str(Path(__file__).resolve().parents[1] / "examples" / "worlds" / "dead_end.toml")
    items = [f"world={dead_end}", "traj=plan", "reverse=false", "plant=reduced", "seed=0,1"]
    assert sweep.main([*items, "--quiet", "--no-figures", "--out", "forward"]) == 3
    rows = _table(tmp_path / "forward" / "runs.csv")
    assert [row["status"] for row in rows] == ["no_plan", "no_plan"]
    assert all(row["message"].startswith("no path to world 'dead_end'") for row in rows)


def test_a_seed_whose_plan_has_a_cusp_is_a_row_where_faults_are_asked():
    """Faults are timed within one run, so a start whose plan has a cusp cannot take them: in
    a sweep over seeds that is the run's outcome (status "start_refused"), whichever seed drew
    it, never the whole sweep refused because the first seed did (loading bay, one trailer:
    seed 9's plan has a cusp, seed 0's none)."""
    from tt_mujoco.sweep.runs import validate_runs

    options = {
        "world": "loading_bay",
        "traj": "plan",
        "reverse": True,
        "plant": "reduced",
        "faults": "dropout:t=0.2,duration=0.1",
    }
    validate_runs(
        [{"index": i, "options": {**options, "seed": seed}} for i, seed in enumerate((9, 0))]
    )
    row = sweep.run_one({**options, "seed": 9, "duration": 0.5})
    assert row["status"] == "start_refused" and row["error"] == ""
    assert "cusp" in row["message"] and "faults=" in row["message"]
    assert sweep.run_one({**options, "seed": 0, "duration": 0.5})["status"] == "ok"


def test_nested_metrics_become_flat_columns():
    # The per-fault report is a list of dicts in metrics.json: one column per entry here.
    result = sweep.run_one({"duration": 0.4, "faults": "payload:t=0.1;dropout:t=0.2"})
    assert result["status"] == "ok"
    m = result["metrics"]
    assert m["faults.0.kind"] == "payload" and m["faults.1.kind"] == "dropout"
    assert m["faults.1.window.rmse_v"] >= 0.0
    assert not any(isinstance(v, dict | list) for v in m.values())


# --- executors and resume ----------------------------------------------------------------------
def test_pool_sweep_writes_table_summary_and_figures(reference):
    rows = sweep.read_table(reference / "runs.csv")
    assert len(rows) == N_RUNS and [int(r["index"]) for r in rows] == list(range(N_RUNS))
    assert [r["status"] for r in rows] == ["jackknife"] * REPEATS + ["ok"] * REPEATS
    assert all("jackknife at t=" in r["message"] for r in rows[:REPEATS])
    # The full configuration and every metric are columns.
    for column in ("eta_value", "gain.k1_v", "seed", "phi0_deg", "rmse_lateral", "steps"):
        assert column in rows[0]
    assert len({r["seed"] for r in rows}) == REPEATS  # paired across the two eta values
    summary = json.loads((reference / "summary.json").read_text())
    assert summary["failed"] == REPEATS and summary["by_status"] == {"jackknife": 4, "ok": 4}
    assert summary["metrics"]["rmse_lateral"]["n"] == REPEATS
    for name in ("summary.csv", "histograms.png", "scatter.png", "sweep.toml"):
        assert (reference / name).stat().st_size > 0


def test_dask_local_cluster_gives_the_same_table(reference, tmp_path):
    pytest.importorskip("distributed")
    spec = parse_spec(ITEMS, repeats=REPEATS, seed=7)
    out = tmp_path / "dask"
    sweep.run_sweep(spec, out, workers=2, scheduler="local", figures=False)
    assert _table(out / "runs.csv") == _table(reference / "runs.csv")


def test_killed_sweep_resumes_to_the_uninterrupted_table(reference, tmp_path):
    out = tmp_path / "killed"
    cmd = [sys.executable, "-m", "tt_mujoco.sweep", *ITEMS, "--repeats", str(REPEATS)]
    cmd += ["--seed", "7", "--workers", "1", "--quiet", "--no-figures", "--out", str(out)]
    # A session of its own, so that the kill takes the pool's worker processes with it.
    proc = subprocess.Popen(cmd, start_new_session=True, stdout=subprocess.PIPE, text=True)
    journal = out / sweep.JOURNAL
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and proc.poll() is None:
        if journal.exists() and journal.read_text().count("\n") >= 2:
            break
        time.sleep(0.01)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.communicate()
    finished = sweep.read_journal(journal)
    assert 2 <= len(finished) < N_RUNS, "the sweep must be killed part way for this test"
    assert not (out / sweep.TABLE).exists()  # the final table only appears at the end

    # Resume from the folder alone: its saved spec, only the runs not in the journal.
    done = subprocess.run(
        [sys.executable, "-m", "tt_mujoco.sweep", "--resume", "--out", str(out), "--quiet"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    assert f"{N_RUNS} runs ({len(finished)} reused)" in done.stdout
    ids = [json.loads(line)["run_id"] for line in journal.read_text().splitlines()]
    assert len(ids) == len(set(ids)) == N_RUNS  # nothing redone, nothing lost
    assert _table(out / "runs.csv") == _table(reference / "runs.csv")


def test_an_edited_input_file_is_not_reused_and_a_changed_spec_is_refused(tmp_path, monkeypatch):
    # A resumed sweep reuses a run only if its options *and* the files it reads are the same.
    monkeypatch.chdir(tmp_path)
    csv = tmp_path / "p.csv"
    csv.write_text("x,y\n0,0\n1,0\n2,0.1\n3,0.3\n")
    spec = sweep.parse_spec(["traj=p.csv", "duration=0.5", "plant=reduced"], None, 0, 1, None)
    first = sweep.expand(spec)[0]
    assert first["options"]["traj"] == str(csv.resolve())  # made absolute
    csv.write_text("x,y\n0,0\n1,0\n2,0.2\n3,0.6\n")
    assert sweep.expand(spec)[0]["run_id"] != first["run_id"]
    out = tmp_path / "sw"
    sweep.run_sweep(spec, out, workers=1, figures=False)
    other = sweep.parse_spec(["traj=p.csv", "duration=0.5,0.6", "plant=reduced"], None, 0, 1, None)
    with pytest.raises(sweep.BadSpecError, match="another specification"):
        sweep.run_sweep(other, out, workers=1, figures=False, resume=True)
    extended = sweep.run_sweep(
        other, out, workers=1, figures=False, resume=sweep.Resume(extend=True)
    )
    assert extended.reused == 1 and len(extended.rows) == 2


def test_symlinked_sweep_files_are_refused(tmp_path):
    spec = sweep.parse_spec(["duration=0.2", "plant=reduced"], None, 0, 1, None)
    out = tmp_path / "sw"
    out.mkdir()
    victim = tmp_path / "victim.txt"
    victim.write_text("keep me")
    (out / ".lock").symlink_to(victim)
    (out / sweep.JOURNAL).symlink_to(tmp_path / "elsewhere.jsonl")
    with pytest.raises(sweep.BadSpecError, match="symlink"):
        sweep.run_sweep(spec, out, workers=1, figures=False, resume=True)
    assert victim.read_text() == "keep me" and not (tmp_path / "elsewhere.jsonl").exists()


def _descendants(pid: int) -> set[int]:
    """Live descendants of ``pid`` (Linux /proc)."""
    children: dict[int, list[int]] = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        children.setdefault(int(fields[1]), []).append(int(stat.parent.name))
    out, todo = set(), [pid]
    while todo:
        for child in children.get(todo.pop(), []):
            out.add(child)
            todo.append(child)
    return out


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs Linux /proc")
def test_workers_end_with_a_killed_sweep(tmp_path):
    # Kill only the sweep process (not its group): its pool's workers, the forkserver's
    # children, must not go on computing runs nobody will collect.
    cmd = [sys.executable, "-m", "tt_mujoco.sweep", "traj=circle", "duration=120"]
    cmd += [
        "seed=1,2,3,4",
        "--workers",
        "2",
        "--quiet",
        "--no-figures",
        "--out",
        str(tmp_path / "s"),
    ]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 60
    workers: set[int] = set()
    while time.monotonic() < deadline and len(workers) < 3:  # forkserver and 2 workers
        time.sleep(0.2)
        workers = _descendants(proc.pid)
    assert len(workers) >= 3
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    deadline = time.monotonic() + 10
    alive = workers
    while alive and time.monotonic() < deadline:
        time.sleep(0.2)
        alive = {p for p in workers if Path(f"/proc/{p}").exists() and "Z" not in _state(p)}
    assert not alive


def _state(pid: int) -> str:
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return "Z"


def test_summaries_are_grouped_by_the_categorical_options_that_vary(tmp_path):
    # ISMC-STA and PID pooled give a median between their two clusters; grouped, each keeps its
    # own (the summary's groups, the CSV's group column).
    spec = sweep.parse_spec(
        ["controller=ismc_sta,pid", "plant=reduced", "duration=3", "noise_snr_db=20,30"],
        None,
        0,
        2,
        None,
    )
    result = sweep.run_sweep(spec, tmp_path / "g", workers=1, figures=True)
    groups = result.summary["groups"]
    assert result.summary["group_by"] == ["controller"]
    ismc = groups["controller=ismc_sta"]["metrics"]["rmse_v"]
    pid = groups["controller=pid"]["metrics"]["rmse_v"]
    assert ismc["n"] == pid["n"] == 4
    assert ismc["max"] < pid["min"]  # two populations
    pooled = result.summary["metrics"]["rmse_v"]["p50"]
    assert ismc["max"] < pooled < pid["min"]  # the pooled median describes neither
    text = (tmp_path / "g" / "summary.csv").read_text()
    assert text.startswith("group,metric,") and "controller=pid,rmse_v," in text


def test_workers_are_capped_at_the_runs_and_warned_above_the_cores(capsys):
    from tt_mujoco.sweep import execute

    assert execute._worker_count(1000, 3, None) == 3
    assert "more than this machine's" in capsys.readouterr().err
    assert execute._worker_count(1, 3, None) == 1
    assert capsys.readouterr().err == ""


@pytest.fixture
def silent_scheduler(monkeypatch):
    """The address of a peer on loopback that takes the connection and says nothing."""
    import socket

    from tt_mujoco import executor

    pytest.importorskip("distributed")
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(1)
    monkeypatch.setattr(executor, "CONNECT_TIMEOUT_S", 2.0)
    yield f"tcp://127.0.0.1:{server.getsockname()[1]}"
    server.close()


def test_a_scheduler_that_accepts_and_never_answers_is_given_up_at_the_deadline(
    silent_scheduler,
):
    import time

    from tt_mujoco import executor

    start = time.monotonic()
    with pytest.raises(executor.ExecutorError, match="cannot connect to a Dask scheduler"):
        executor.Executors(1, silent_scheduler).open()
    assert time.monotonic() - start < 10


@pytest.mark.parametrize("width", [4.0, 12.0])
def test_the_sweep_figures_label_units_and_keep_their_titles_inside(reference, monkeypatch, width):
    # the histograms' axes had no units, and a long title was clipped at the figure's sides
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from tt_mujoco.analysis.metrics import metric_unit
    from tt_mujoco.sweep import tables

    made = []
    monkeypatch.setattr(tables, "save_figure", lambda fig, path, dpi: made.append(fig) or path)
    real_figure = Figure

    def narrow(*args, figsize=None, **kwargs):  # every figure as narrow or wide as asked
        return real_figure(*args, figsize=(width, figsize[1]), **kwargs)

    monkeypatch.setattr("matplotlib.figure.Figure", narrow)
    rows = sweep.read_table(reference / "runs.csv")
    tables.plot_summary(rows, parse_spec(ITEMS, repeats=REPEATS, seed=7), reference)
    assert len(made) == 2
    for fig in made:
        canvas = FigureCanvasAgg(fig)
        canvas.draw()
        renderer = canvas.get_renderer()
        title = fig._suptitle.get_window_extent(renderer)
        assert 0 <= title.x0 and title.x1 <= fig.bbox.width, fig._suptitle.get_text()
        for ax in fig.axes:
            if not ax.get_visible() or ax.get_xlabel() == "":
                continue
            for label in (ax.get_xlabel(), ax.get_ylabel()):
                name = label.split(" [")[0]
                if metric_unit(name):
                    assert label == f"{name} [{metric_unit(name)}]"


@pytest.mark.parametrize(
    "resume, named",
    [("yes", "resume='yes'"), (1, "resume=1"), (None, "resume=None")],
)
def test_a_resume_that_is_not_one_is_refused_before_any_run(tmp_path, resume, named):
    spec = sweep.parse_spec(["duration=0.2", "plant=reduced"], None, 0, 1, None)
    with pytest.raises(sweep.BadSpecError, match=re.escape(named)):
        sweep.run_sweep(spec, tmp_path / "sw", workers=1, figures=False, resume=resume)
    assert not (tmp_path / "sw").exists()


@pytest.mark.parametrize("field", ["retry_errors", "extend"])
def test_a_resume_s_switches_are_booleans(field):
    with pytest.raises(sweep.BadSpecError, match=rf"Resume\({field}='no'\)"):
        sweep.Resume(**{field: "no"})


def test_a_sweep_its_scheduler_refuses_leaves_nothing_that_blocks_the_retry(
    tmp_path, silent_scheduler
):
    """The issue's case: journal.jsonl and sweep.toml stayed, and the same command again was
    refused ('already exists and is not empty'). A resumed sweep's files stay as they were."""
    from tt_mujoco.sweep import cli

    out = tmp_path / "sweep"
    argv = ["duration=0.2", "plant=reduced", "--scheduler", silent_scheduler, "--out", str(out)]
    for _ in range(2):  # the retry meets the same refusal, not a folder in its way
        assert cli.main([*argv, "--quiet", "--no-figures"]) == 2
        assert not out.exists()


@pytest.mark.parametrize("key", ["seed", "repeats", "samples"])
def test_a_sweep_file_s_numbers_are_typed(tmp_path, key):
    """A TOML file gives numbers with their type, so [sweep] repeats = "3" is a mistake named,
    as an option's text is in [options] (schema_values.check_typed)."""
    spec = tmp_path / "sweep.toml"
    spec.write_text(f'[sweep]\n{key} = "3"\n[options]\nplant = "reduced"\n')
    with pytest.raises(BadSpecError, match=rf"\[sweep\] {key}='3' is not allowed: it is text"):
        sweep.load_spec(spec)


def test_a_resume_after_its_spec_file_was_edited_is_refused_unless_extending(tmp_path, capsys):
    """An edited sweep.toml is a changed sweep: its finished runs came from what it held."""
    from tt_mujoco.sweep import cli

    out = tmp_path / "sw"
    argv = ["--out", str(out), "--workers", "1", "--quiet", "--no-figures"]
    assert cli.main([*argv, "plant=reduced", "duration=0.3,0.4"]) == 0
    spec = out / sweep.SPEC_FILE
    spec.write_text(spec.read_text().replace("0.4", "0.5"))
    capsys.readouterr()
    assert cli.main([*argv, "--resume"]) == 2
    assert f"its {sweep.SPEC_FILE} was edited" in capsys.readouterr().err
    assert cli.main([*argv, "--resume", "--extend"]) == 0
    assert "2 runs (1 reused)" in capsys.readouterr().out
    assert cli.main([*argv, "--resume"]) == 0  # the extension wrote what it ran


def test_a_table_that_cannot_be_written_is_one_line_and_the_runs_kept(tmp_path, capsys):
    from tt_mujoco.sweep import cli

    out = tmp_path / "sw"
    argv = ["--out", str(out), "--workers", "1", "--quiet", "--no-figures", "--resume"]
    assert cli.main([*argv[:-1], "plant=reduced", "duration=0.3"]) == 0
    (out / sweep.TABLE).unlink()
    (out / sweep.TABLE).mkdir()  # a folder where the table goes
    capsys.readouterr()
    assert cli.main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and f"{out / sweep.TABLE}: Is a directory" in err, err
    assert "--resume --out" in err and len(sweep.read_journal(out / sweep.JOURNAL)) == 1

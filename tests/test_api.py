"""The Python API (tt_mujoco.api): the same numbers as the other routes, and its helpers."""

import subprocess
import sys

import numpy as np
import pytest

import tt_mujoco
from tt_mujoco.sim import Scenario
from tt_mujoco.sim import simulate as sim_simulate


def test_the_api_gives_the_numbers_of_the_simulation_loop():
    scenario = tt_mujoco.Scenario(traj="circle", plant="reduced", duration=1.0, seed=3)
    run = tt_mujoco.simulate(scenario)
    direct = sim_simulate(scenario)
    assert run.status == "ok"
    for name, column in direct.timeseries.items():
        np.testing.assert_array_equal(run.timeseries[name], column)
    assert run.metrics["rmse_v"] == direct.metrics["rmse_v"]


def test_to_pandas_carries_every_column_and_its_unit():
    pd = pytest.importorskip("pandas")
    run = tt_mujoco.simulate(Scenario(traj="circle", plant="reduced", duration=0.5))
    frame = run.to_pandas()
    assert isinstance(frame, pd.DataFrame)
    assert set(frame.columns) == set(run.timeseries)
    assert len(frame) == len(run.timeseries["t"])
    assert frame.attrs["units"]["t"] == "s" and frame.attrs["units"]["phi"] == "rad"
    np.testing.assert_array_equal(frame["x"].to_numpy(), run.timeseries["x"])


def test_plot_writes_the_four_figures(tmp_path):
    run = tt_mujoco.simulate(Scenario(traj="circle", plant="reduced", duration=0.5))
    made = run.plot(tmp_path)
    assert len(made) == 4 and all(p.exists() and p.stat().st_size > 0 for p in made)
    # a folder that does not exist yet is made, as a user expects; a file is refused
    again = run.plot(tmp_path / "new" / "figures")
    assert [p.name for p in again] == [p.name for p in made] and all(p.exists() for p in again)
    (tmp_path / "a_file").write_text("")
    with pytest.raises(ValueError, match=r"a_file.*is a file, not a folder"):
        run.plot(tmp_path / "a_file")
    # figures there already are never overwritten (a second call replaced them in silence)
    before = {p.name: p.read_bytes() for p in made}
    with pytest.raises(ValueError, match=r"holds path\.png already"):
        run.plot(tmp_path)
    assert {p.name: p.read_bytes() for p in made} == before


@pytest.mark.parametrize("reverse", [False, True])
def test_plot_draws_the_figures_the_command_line_writes(tmp_path, reverse):
    """The same run's figures on both routes, byte for byte: backing up, the errors figure
    measures the run as its metrics do (the trailer leading), on the API's route too."""
    from tt_mujoco import run as run_cli

    argv = ["--plant", "reduced", "--duration", "1", "--seed", "4", "--no-video", "--quiet"]
    argv += ["--reverse"] if reverse else []
    assert run_cli.main([*argv, "--out", str(tmp_path / "cli")]) == 0
    run = tt_mujoco.simulate(Scenario(plant="reduced", duration=1.0, seed=4, reverse=reverse))
    for made in run.plot(tmp_path / "api"):
        assert made.read_bytes() == (tmp_path / "cli" / made.name).read_bytes(), made.name


def test_plot_never_writes_inside_a_finished_run(tmp_path):
    from tt_mujoco import run as run_cli

    folder = tmp_path / "finished"
    argv = ["--plant", "reduced", "--duration", "0.2", "--no-video", "--no-plots", "--quiet"]
    assert run_cli.main([*argv, "--out", str(folder)]) == 0
    run = tt_mujoco.simulate(Scenario(traj="circle", plant="reduced", duration=0.5))
    with pytest.raises(ValueError, match="lies inside"):
        run.plot(folder / "figures")
    assert not (folder / "figures").exists()


def test_a_progress_that_is_not_callable_is_named():
    with pytest.raises(TypeError, match=r"progress=3 is not allowed"):
        tt_mujoco.simulate(Scenario(plant="reduced", duration=0.2), progress=3)


def _raise(err):
    raise err


@pytest.mark.parametrize(
    ("make", "said"),
    [
        (lambda: lambda done, total: 1 / 0, "ZeroDivisionError: division by zero"),
        (lambda: lambda done: None, "TypeError"),  # the wrong signature
        (lambda: lambda done, total: _raise(SystemExit(0)), "it called sys.exit(0)"),
        (lambda: lambda done, total: _raise(GeneratorExit()), "GeneratorExit"),
    ],
    ids=["raises", "signature", "SystemExit", "GeneratorExit"],
)
def test_a_progress_that_fails_is_the_run_s_failure_with_its_rows_kept(make, said):
    """The caller's progress is user code like any hook: its failure (a BaseException too)
    stops the run as "failed", naming it, with the rows computed, and never escapes."""
    from tt_mujoco.sim import simulate

    result = simulate(Scenario(plant="reduced", duration=0.5), progress=make())
    assert result.status == "failed"
    assert result.message.startswith("progress failed at t=") and said in result.message
    assert len(result.timeseries["t"]) == 501 and result.details.strip()


@pytest.mark.parametrize("wrong", ["s_curve", {"traj": "s_curve"}, None])
def test_simulate_names_what_it_takes(wrong):
    # simulate("s_curve") was an AttributeError about 'validate' from deep inside
    with pytest.raises(TypeError, match=r"scenario=.* is not allowed: simulate takes a"):
        tt_mujoco.simulate(wrong)


def test_load_scenario_reads_a_toml_file_as_the_command_line_does(tmp_path):
    file = tmp_path / "s.toml"
    file.write_text('traj = "circle"\nplant = "reduced"\nduration = 1.5\n')
    scenario = tt_mujoco.load_scenario(file, "--seed", "7")
    assert (scenario.traj, scenario.plant, scenario.duration, scenario.seed) == (
        "circle",
        "reduced",
        1.5,
        7,
    )
    with pytest.raises(ValueError, match="dynamc"):
        tt_mujoco.load_scenario(file, "--target", "dynamc")


def test_importing_the_package_loads_no_simulation():
    code = "import sys, tt_mujoco; print('mujoco' in sys.modules)"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.stdout.strip() == "False"


def test_a_constructor_that_does_not_return_is_refused_at_the_time_limit(tmp_path):
    """The Python API's set-up is bounded by the scenario's time limit as the command's is."""
    (tmp_path / "hangs.py").write_text(
        "from tt_mujoco.controllers import Controller\n\n"
        "class C(Controller):\n    def __init__(self, setup, gains=None):\n"
        "        super().__init__(setup, gains)\n        while True:\n            pass\n\n"
        "    def compute(self, t, m, r):\n        return 0.0, 0.0\n"
    )
    scenario = Scenario(
        controller=f"{tmp_path / 'hangs.py'}:C", plant="reduced", duration=1.0, time_limit_s=0.5
    )
    with pytest.raises(ValueError, match=r"passed its time limit of 0.5 s .*hangs.py, line 6"):
        tt_mujoco.simulate(scenario)


def test_a_path_object_names_a_file_as_its_text():
    # Before: Scenario(traj=Path("my.csv")) was refused ("it must be a non-empty string"),
    # and a world as a Path failed inside the check (AttributeError: no strip)
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    csv, world = (
        root / "examples" / "weave_surge.csv",
        root / "examples" / "worlds" / "dead_end.toml",
    )
    common = {"plant": "reduced", "duration": 0.3}
    as_path = tt_mujoco.simulate(Scenario(traj=csv, **common))
    as_text = tt_mujoco.simulate(Scenario(traj=str(csv), **common))
    assert as_path.metrics["rmse_v"] == as_text.metrics["rmse_v"]
    assert as_path.scenario.traj == str(csv)
    planned = tt_mujoco.simulate(Scenario(world=world, traj="plan", reverse=True, **common))
    assert planned.scenario.world == str(world) and planned.status == "ok"

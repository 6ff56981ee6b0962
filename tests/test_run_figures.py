"""tt_mujoco.viz.run_figures: the run's figures drawn by a worker forked ahead of them are the
figures plot_run draws, byte for byte, and the run's own process never imports matplotlib."""

from __future__ import annotations

import subprocess
import sys

import pytest

from tt_mujoco import sim
from tt_mujoco.analysis.metrics import run_error_signals
from tt_mujoco.viz import FIGURES, plots
from tt_mujoco.viz.run_figures import GROUPS, RunFigures


@pytest.fixture(scope="module")
def result():
    return sim.simulate(sim.Scenario(duration=1.0, trailers=2))


def test_the_groups_hold_every_figure_once():
    drawn = [name for group in GROUPS for name in group]
    assert sorted(drawn) == sorted(FIGURES) and len(drawn) == len(set(drawn))


@pytest.mark.parametrize("forked", [True, False])
def test_the_workers_figures_are_plot_runs(result, tmp_path, forked):
    figures = RunFigures(forked=forked)
    params = result.scenario.plant_params()
    figures.draw(result.timeseries, result.reference_polyline, params)
    pngs = figures.result()
    written = plots.plot_run(result.timeseries, result.reference_polyline, tmp_path, params)
    assert list(pngs) == list(FIGURES) == [path.name for path in written]
    for path in written:
        assert pngs[path.name] == path.read_bytes(), path.name


def test_a_figure_that_fails_in_the_worker_is_raised_here(result):
    figures = RunFigures(forked=True)
    bad = dict(result.timeseries)
    del bad["T_l"]
    figures.draw(bad, result.reference_polyline)
    with pytest.raises(ValueError, match="no column 'T_l'"):
        figures.result()


def test_the_run_process_never_imports_matplotlib(tmp_path):
    out = tmp_path / "run"
    code = (
        "import sys\n"
        "from tt_mujoco import run\n"
        f"argv = ['--duration', '1', '--no-video', '--quiet', '--out', {str(out)!r}]\n"
        "assert run.main(argv) == 0\n"
        "print(sorted(m for m in sys.modules if m.split('.')[0] == 'matplotlib'))\n"
    )
    shown = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=300
    )
    assert shown.stdout.strip().splitlines()[-1] == "[]"
    assert sorted(p.name for p in out.glob("*.png")) == sorted(FIGURES)


@pytest.mark.parametrize("reverse", [False, True])
def test_the_errors_figure_of_the_runs_own_signals_is_the_one_measured_again(reverse):
    """The run hands its figures the error signals its metrics measured (the worker no longer
    projects the run again): the same figure as measuring them in the worker, byte for byte."""
    result = sim.simulate(sim.Scenario(duration=1.0, reverse=reverse))
    ts, reference = result.timeseries, result.reference_polyline
    signals = run_error_signals(ts, reference, reverse)
    names = ("errors.png",)
    handed = plots.run_pngs(ts, reference, names=names, errors=signals, reverse=reverse)
    measured = plots.run_pngs(ts, reference, names=names, reverse=reverse)
    assert handed == measured
    assert plots.tracking_errors(ts, reference, reverse)["lateral"] == pytest.approx(
        signals["lateral"], abs=0.0, nan_ok=True
    )

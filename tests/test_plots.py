"""Run figures: the PNGs are written, valid and not blank, and the error signals they plot
(lateral distances to a polyline, off-tracking) are right."""

from __future__ import annotations

import math

import numpy as np
import pytest
from matplotlib import _pylab_helpers
from PIL import Image

from tt_mujoco.analysis import metrics
from tt_mujoco.vehicle.params import Params
from tt_mujoco.viz import plots
from tt_mujoco.viz.demo import open_loop_timeseries

OFFSET = 0.02  # m: the test reference runs this far to the right of the tractor's path


@pytest.fixture(scope="module")
def run():
    """A 3 s open-loop run and a reference path OFFSET to the right of the tractor's."""
    ts, tractor_path = open_loop_timeseries(duration=3.0, dt=0.01)
    theta = ts["theta"]
    right = np.column_stack([np.sin(theta), -np.cos(theta)])
    return ts, tractor_path + OFFSET * right


def check_png(path, size):
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with Image.open(path) as im:
        assert im.size == size
        pixels = np.asarray(im.convert("RGB"), dtype=float)
    # A white page with a few axes has std ~30-60 grey levels (measured 35-60 here); a blank
    # figure is exactly 0. 5 catches empty figures without depending on the curves' shapes.
    assert pixels.std() > 5.0
    return pixels


def test_plot_run_writes_valid_figures(run, tmp_path):
    ts, reference = run
    managers = _pylab_helpers.Gcf.get_num_fig_managers()
    written = plots.plot_run(ts, reference, tmp_path / "figs", Params())
    assert [p.name for p in written] == list(plots.FIGURES)
    # figsize (inches) x DPI 120
    sizes = {"path.png": (840, 720), "errors.png": (960, 1080), "torques.png": (960, 600)}
    sizes["articulation.png"] = (960, 480)
    for path in written:
        check_png(path, sizes[path.name])
    # No temporary files left, and no pyplot figure managers created (no global state).
    assert sorted(p.name for p in (tmp_path / "figs").iterdir()) == sorted(plots.FIGURES)
    assert _pylab_helpers.Gcf.get_num_fig_managers() == managers


def test_plot_run_replaces_its_own_files(run, tmp_path):
    ts, reference = run
    first = plots.plot_run(ts, reference, tmp_path)
    before = {p.name: p.read_bytes() for p in first}
    slower = dict(ts, v=ts["v"] * 0.5)
    second = plots.plot_run(slower, reference, tmp_path)
    assert [p.name for p in second] == list(plots.FIGURES)
    assert second[1].read_bytes() != before["errors.png"]
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(plots.FIGURES)


def test_plot_comparison_writes_one_figure(run, tmp_path):
    ts, reference = run
    runs = {"exact": ts, "slow": dict(ts, v=ts["v"] - 0.05), "fast": dict(ts, v=ts["v"] + 0.05)}
    out = plots.plot_comparison(runs, tmp_path / "cmp" / "errors.png", reference)
    check_png(out, (960, int(round((2.6 * 3 + 0.6) * 120))))
    without_path = plots.plot_comparison(runs, tmp_path / "cmp2.png")
    check_png(without_path, (960, int(round((2.6 * 2 + 0.6) * 120))))


def test_bad_inputs_raise_value_error(run, tmp_path):
    ts, reference = run
    broken = dict(ts)
    del broken["T_l_cmd"]
    with pytest.raises(ValueError, match="'T_l_cmd'"):
        plots.plot_run(broken, reference, tmp_path)
    with pytest.raises(ValueError, match="reference_polyline"):
        plots.plot_run(ts, reference[:, :1], tmp_path)
    with pytest.raises(ValueError, match="runs"):
        plots.plot_comparison({}, tmp_path / "x.png")
    with pytest.raises(ValueError, match=r"\.png"):
        plots.plot_comparison({"a": ts}, tmp_path / "x.pdf")


def test_tracking_errors_of_the_offset_reference(run):
    ts, reference = run
    err = plots.tracking_errors(ts, reference)
    np.testing.assert_array_equal(err["e_v"], ts["v"] - ts["v_d"])
    # P is OFFSET to the left of a parallel curve (radius of curvature >= 1.5 m here, so the
    # polyline of the offset curve is within ~1e-7 m of it): measured 2e-7.
    np.testing.assert_allclose(err["lateral"], OFFSET, atol=1e-6)
    # The trailer starts L + L0 = 0.7 m behind P: no off-tracking until it passes P's start.
    offtrack = err["trailer_offtrack"]
    assert np.isnan(offtrack[0]) and np.isfinite(offtrack[-1])
    # Same-path steering keeps P0 within a few cm of the tractor's path (measured max 2.3 cm).
    assert np.nanmax(np.abs(offtrack)) < 0.05


def test_plotted_errors_are_the_metrics(run):
    ts, reference = run
    err = plots.tracking_errors(ts, reference)
    m = metrics.compute_metrics(ts, reference, torque_limit=15.0)
    # Same functions underneath: equal to rounding.
    assert math.sqrt(np.mean(err["lateral"] ** 2)) == pytest.approx(m["rmse_lateral"], rel=1e-12)
    trailer_lateral = err["trailer_lateral"][np.isfinite(err["trailer_lateral"])]
    assert len(trailer_lateral) == m["trailer_lateral_samples"]
    trailer = math.sqrt(np.mean(trailer_lateral**2))
    assert trailer == pytest.approx(m["trailer_rmse_lateral"], rel=1e-12)
    offtrack = err["trailer_offtrack"][np.isfinite(err["trailer_offtrack"])]
    assert math.sqrt(np.mean(offtrack**2)) == pytest.approx(m["trailer_offtrack_rms"], rel=1e-12)


def test_a_diverged_run_is_plotted_up_to_where_it_stopped(run, tmp_path):
    ts, reference = run
    diverged = {name: col.copy() for name, col in ts.items()}
    for name, col in diverged.items():
        if name != "t":
            col[200:] = np.nan  # the loop stopped at t = 2 s
    err = plots.tracking_errors(diverged, reference)
    assert np.all(np.isfinite(err["lateral"][:200])) and np.all(np.isnan(err["lateral"][200:]))
    np.testing.assert_array_equal(
        err["lateral"][:200], plots.tracking_errors(ts, reference)["lateral"][:200]
    )
    assert len(plots.plot_run(diverged, reference, tmp_path)) == len(plots.FIGURES)

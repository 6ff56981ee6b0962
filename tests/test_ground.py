"""Friction patches (tt_mujoco/sim/parts/ground.py): where they are, what they do, on every
route."""

import subprocess
import sys

import numpy as np
import pytest
from tt_mujoco.controllers import Controller

from tt_mujoco import run
from tt_mujoco.reference.paths import circle
from tt_mujoco.sim import Scenario, build, simulate
from tt_mujoco.sim.parts.ground import GroundPatches, Patch, parse_patch


class Push(Controller):
    """1 N m on both wheels from rest: more than the ice transmits."""

    name = "push"

    def compute(self, t, measurement, reference):
        return 1.0, 1.0


def test_parse_patch_reads_back_its_spec():
    band = parse_patch("band:2:3.5:0.1")
    assert band == Patch("band", (2.0, 3.5), 0.1) and parse_patch(band.spec()) == band
    rect = parse_patch("rect:-1:0:1:2:0.3")
    assert rect.contains(0.0, 1.0, float("nan")) and not rect.contains(0.0, 2.5, 0.0)


@pytest.mark.parametrize(
    ("text", "named"),
    [("band:3:2:0.1", "3.0 to 2.0"), ("band:1:2:0", "friction 0.0"), ("disc:1:2:0.1", "'disc"),
     ("rect:0:0:1:0.1", "'rect:0:0:1:0.1'"), ("band:1:x:0.1", "'band:1:x:0.1'")],
)  # fmt: skip
def test_a_bad_patch_is_refused_naming_it(text, named):
    with pytest.raises(ValueError, match="is not allowed") as err:
        parse_patch(text)
    assert named in str(err.value)


def test_a_band_is_found_by_the_arc_length_of_the_nearest_path_point():
    path = circle()  # the unit circle from (1, 0), counter-clockwise
    ground = GroundPatches([parse_patch("band:1:2:0.1")], path, base_mu=1.0)
    # points just outside the circle at arc lengths 0.5, 1.5 and 2.5 m
    points = [(1.02 * np.cos(s), 1.02 * np.sin(s)) for s in (0.5, 1.5, 2.5)]
    mus, mask = ground.frictions(points)
    assert mus == [1.0, 0.1, 1.0] and mask == 1


def test_ice_lets_the_driven_wheels_spin():
    # Pushed with 1 N m a wheel from rest: the tyres hold on the default friction 1, and spin
    # on ice (mu 0.05) under the tractor.
    kw = {"controller": f"{__file__}:Push", "traj": "circle", "start": "paper"}
    kw |= {"disturbance": "none", "duration": 0.3}
    dry = simulate(Scenario(**kw)).timeseries
    ice = simulate(Scenario(ground=["rect:0:-1:2:1:0.05"], **kw))
    spin = np.abs(ice.timeseries["slip_left"]).max()
    # measured: 2 mm/s on dry ground, 0.52 m/s on ice after 0.3 s
    assert np.abs(dry["slip_left"]).max() < 0.01 and spin > 0.2
    (report,) = ice.metrics["ground"]
    assert report["time_s"] == pytest.approx(0.3, abs=0.002)
    assert report["slip_longitudinal_max"] == pytest.approx(spin)


def test_the_report_counts_the_time_on_a_band():
    result = simulate(Scenario(traj="s_curve", disturbance="none", ground=["band:2:3:0.1"]))
    (report,) = result.metrics["ground"]
    # 1 m of path at 0.8 m/s, plus the 0.7 m from the tractor's wheels to the trailer's
    assert report["time_s"] == pytest.approx((1.0 + 0.7) / 0.8, rel=0.05)


def test_patches_are_refused_on_the_reduced_plant_and_a_bad_one_on_the_cli(tmp_path, capsys):
    with pytest.raises(ValueError, match="rolls without slip"):
        build(Scenario(plant="reduced", ground=["band:1:2:0.1"]))
    out = tmp_path / "r"
    assert (
        run.main(["--ground", "band:2:1:0.1", "--no-video", "--no-plots", "--out", str(out)]) == 2
    )
    assert "'band:2:1:0.1'" in capsys.readouterr().err and not out.exists()
    sweep = tmp_path / "s"
    args = ["traj=circle", "duration=0.3", "ground=band:0:1:0.2", "--repeats", "1"]
    done = subprocess.run(
        [sys.executable, "-m", "tt_mujoco.sweep", *args, "--out", str(sweep)], capture_output=True
    )
    assert done.returncode == 0, done.stderr
    assert "band:0:1:0.2" in (sweep / "runs.csv").read_text()

"""tt_mujoco.excite_inertia (``python -m tt_mujoco.excite --fit Mr,...``): the run to log so
that a fit of the masses and inertias tells them, written with its path."""

from __future__ import annotations

import numpy as np
import pytest

from tt_mujoco import excite, run
from tt_mujoco.excite_inertia import MEAN_SPEED, SURGES, rank_inertial, surge_rows
from tt_mujoco.sim import Scenario


def test_a_candidate_path_swings_its_speed_and_weaves_as_said():
    weave, _, swing, _ = SURGES[-1]
    rows = surge_rows(SURGES[-1], 12.0)
    x, y, v = rows.T
    assert x[0] == 0.0 and x[-1] == pytest.approx(12.0) and np.all(np.diff(x) > 0)
    assert np.max(np.abs(y)) == pytest.approx(weave, rel=1e-3)
    assert np.min(v) == pytest.approx(MEAN_SPEED - swing, abs=1e-3)
    assert np.max(v) == pytest.approx(MEAN_SPEED + swing, abs=1e-3)


def test_a_swinging_weave_tells_the_mass_better_than_a_gentle_straight():
    """The prediction ranks what a log can tell: on a straight with a small swing the mass's
    95 % half width is several times the weave's with a larger one (measured 22 % and 3 % at
    20 dB over 20 s; here over 10 s)."""
    gentle = (0.0, 1.0, 0.15, 2.0)
    swinging = (0.4, 6.0, 0.3, 1.0)
    ranked = rank_inertial(Scenario(), ("Mr",), 20.0, 10.0, candidates=(gentle, swinging))
    assert [c.surge for c in ranked] == [swinging, gentle]
    best, worst = ranked
    assert best.names == ("Mr",) and np.all(np.isfinite(best.half_widths))
    assert best.worst * 3 < worst.worst
    assert best.values[0] == pytest.approx(Scenario().plant_params().Mr, rel=0.1)


def test_the_command_writes_a_run_every_command_takes(tmp_path, capsys):
    out = tmp_path / "ex"
    assert excite.main(["--fit", "Mr", "--duration", "10", "--out", str(out)]) == 0
    assert sorted(p.name for p in out.iterdir()) == [
        "excitation.md",
        "excitation.toml",
        "excitation_path.csv",
    ]
    assert "best: " in capsys.readouterr().out
    logged = tmp_path / "logged"
    argv = ["--config", str(out / "excitation.toml"), "--plant", "reduced", "--no-video"]
    assert run.main([*argv, "--no-plots", "--quiet", "--out", str(logged)]) == 0
    assert (logged / "metrics.json").is_file()


@pytest.mark.parametrize(
    ("argv", "said"),
    [
        (["--fit", "L,Mr"], "in two excitations"),
        (["--fit", "Mr", "--snr-db", "0"], "--snr-db 0.0 is not allowed"),
        (["--fit", "Mr", "--duration", "1"], "--duration 1.0 is not allowed"),
        (["--fit", "Mass"], "--fit 'Mass' is not allowed"),
    ],
)
def test_a_bad_request_is_exit_2_with_nothing_written(tmp_path, capsys, argv, said):
    assert excite.main([*argv, "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and said in err[0], err
    assert not (tmp_path / "o").exists()

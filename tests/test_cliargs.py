"""One error style for every CLI: exit code 2, one line, a "did you mean" hint for misspellings."""

import subprocess
import sys

import pytest

CASES = [
    (["tt_mujoco.run", "--controler", "pid"], "did you mean --controller?"),
    (["tt_mujoco.run", "--target", "dynamc"], "did you mean 'dynamic'?"),
    (["tt_mujoco.sweep", "noise_snrr=20", "--dry-run"], "did you mean 'noise_snr"),
    (["tt_mujoco.sweep", "--wokers", "2", "duration=1"], "did you mean --workers?"),
    (["tt_mujoco.paper", "--wokers", "2"], "did you mean --workers?"),
    (["tt_mujoco.run", "--seed", "-1"], "--seed: '-1' is not allowed: it must be an integer >= 0"),
]


@pytest.mark.parametrize(("argv", "hint"), CASES, ids=[" ".join(c[0]) for c in CASES])
def test_misspelt_options_get_a_hint_and_exit_2(tmp_path, argv, hint):
    proc = subprocess.run(
        [sys.executable, "-m", *argv], capture_output=True, text=True, timeout=120, cwd=tmp_path
    )
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and hint in lines[0] and "Traceback" not in proc.stderr
    assert list(tmp_path.iterdir()) == []  # nothing written

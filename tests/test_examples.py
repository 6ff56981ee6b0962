"""The scenario files the repository ships run as a user first runs them: to the end, with
their own seed and with others (an example that holds for one seed only teaches nothing).

The files are found, not listed: a scenario file added to ``examples/`` is covered by this test.
A sweep file (a ``[sweep]`` table) is the sweep tests' (tests/test_sweep.py).
"""

import tomllib
from pathlib import Path

import pytest

import tt_mujoco

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
SCENARIO_FILES = sorted(
    path for path in EXAMPLES.glob("*.toml") if "sweep" not in tomllib.loads(path.read_text())
)
#: Seeds tried beside the file's own: a jackknife on any of them fails the example.
OTHER_SEEDS = (0, 1, 2, 3, 8)


def test_the_examples_folder_has_scenario_files():
    assert SCENARIO_FILES, "examples/ ships a scenario file (docs/scenarios.md shows one)"


@pytest.mark.parametrize("path", SCENARIO_FILES, ids=lambda p: p.name)
def test_a_shipped_scenario_file_runs_to_its_end(path):
    own = tt_mujoco.load_scenario(path)
    for seed in (None, *OTHER_SEEDS):
        scenario = own if seed is None else tt_mujoco.load_scenario(path, "--seed", str(seed))
        run = tt_mujoco.simulate(scenario)
        assert run.status == "ok", (path.name, scenario.seed, run.result.message)

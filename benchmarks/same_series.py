"""The time series of a set of scenarios here and at another commit, compared column by column.

    python benchmarks/same_series.py REF

A restructuring of the step must leave every number as it was, to the last bit. This checks
``REF`` out into a temporary git worktree, runs each scenario of :data:`SCENARIOS` there and
here (a fresh process each side, the kernel compiled in the foreground), and prints per
scenario ``same`` or the columns that differ. Exit code 1 when any differs.

The package maps the repository's ``controllers/`` folder onto ``tt_mujoco.controllers``
(``pyproject.toml``'s package directories); the worktree gets the same mapping as a link, so
that its ``tt_mujoco`` imports its own controllers, not this checkout's.
"""

from __future__ import annotations

import argparse
import os
import pickle
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
#: What is compared: the parts of the step, each on at least one scenario.
SCENARIOS = [
    dict(traj="s_curve"),
    dict(traj="cycloid", plant="reduced", noise_snr_db=20.0, seed=3),
    dict(traj="s_curve", disturbance="wrench", trailers=2, duration=4.0),
    dict(
        traj="circle",
        trailers=3,
        plant="reduced",
        faults=["payload:t=1,factor=2", "actuator:t=1.2,wheel=left", "dropout:t=1,duration=0.3"],
        duration=4.0,
    ),
    dict(traj="s_curve", reverse=True, duration=4.0),
    dict(traj="s_curve", eta="path", controller="examples/kanayama.py:kanayama_law", duration=3.0),
    dict(traj="s_curve", disturbance_model="examples/user_parts.py:headwind_gusts", duration=3.0),
    dict(traj="s_curve", path_feedback={}, duration=4.0),
    dict(traj="cycloid", path_feedback={"k_y": 9.0}, target="static", plant="reduced"),
    dict(traj="s_curve", reverse=True, eta="paper", path_feedback={}, duration=3.0),
    dict(traj="cycloid", reverse=True, trailers=2, plant="reduced", noise_snr_db=20.0),
    dict(traj="s_curve", eta="scheduled", trailers=3, plant="reduced", duration=3.0),
    dict(traj="s_curve", reverse=True, target="static", controller="pid", duration=3.0),
    dict(traj="s_curve", sensor_delay=0.01, wind="8:90:2", duration=3.0),
    dict(traj="cycloid", controller="fbl", gains='{"k_v": 6.0}', trailers=2, duration=3.0),
    dict(traj="s_curve", controller="smc", plant="reduced", noise_snr_db=30.0, duration=3.0),
    dict(traj="s_curve", controller="pid", faults=["actuator:t=1,wheel=left"], duration=3.0),
]
RUN = """
import pickle, sys
import tt_mujoco, tt_mujoco.controllers
from tt_mujoco.sim import Scenario, simulate
for module in (tt_mujoco, tt_mujoco.controllers):  # this checkout's package, not another's
    assert module.__file__.startswith(sys.argv[3]), (module.__file__, sys.argv[3])
out = [dict(simulate(Scenario(**case)).timeseries) for case in pickle.load(open(sys.argv[1], "rb"))]
pickle.dump(out, open(sys.argv[2], "wb"))
"""


def series(checkout: Path, tmp: Path, name: str) -> list[dict]:
    """Every scenario's time series, run by the package of ``checkout`` in a new process."""
    cases, out = tmp / "cases.pkl", tmp / f"{name}.pkl"
    cases.write_bytes(pickle.dumps(SCENARIOS))
    env = {**os.environ, "PYTHONPATH": str(checkout), "TT_MUJOCO_COMPILE_NOW": "1"}
    # run from the checkout: its package first on the path, its examples for the scenarios
    argv = [sys.executable, "-c", RUN, str(cases), str(out), str(checkout)]
    subprocess.run(argv, cwd=checkout, env=env, check=True)
    return pickle.loads(out.read_bytes())


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("ref", help="the commit to compare with (a hash, a branch, HEAD~3, ...)")
    args = p.parse_args()
    with tempfile.TemporaryDirectory() as name:
        tmp = Path(name)
        tree = tmp / "ref"
        subprocess.run(
            ["git", "worktree", "add", "-q", "--detach", str(tree), args.ref], cwd=ROOT, check=True
        )
        try:
            (tree / "tt_mujoco" / "controllers").symlink_to(tree / "controllers")
            before, after = series(tree, tmp, "before"), series(ROOT, tmp, "after")
        finally:
            subprocess.run(
                ["git", "worktree", "remove", "--force", str(tree)], cwd=ROOT, check=True
            )
    differing = 0
    for case, old, new in zip(SCENARIOS, before, after, strict=True):
        columns = sorted(set(old) | set(new))
        changed = [
            c
            for c in columns
            if c not in old or c not in new or not np.array_equal(old[c], new[c], equal_nan=True)
        ]
        differing += bool(changed)
        shown = ", ".join(f"{k}={v}" for k, v in case.items())
        print(f"{'same' if not changed else 'DIFFERS: ' + ', '.join(changed)}  ({shown})")
    print(f"{len(SCENARIOS) - differing} of {len(SCENARIOS)} scenarios the same as at {args.ref}")
    return 1 if differing else 0


if __name__ == "__main__":
    sys.exit(main())

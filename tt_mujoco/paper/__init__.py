"""``python -m tt_mujoco.paper``: the paper's Tables 1-5 on both plants, side by side, and beyond.

Runs every scenario behind Tables 1-5 of Wen, Chen and Zhou (Axioms 2026, 15, 598;
docs/model.md Section 10) on the reduced model and on MuJoCo, plus

- **isolation runs** for every cell where our number and the paper's differ by more than a
  factor of two (a cause is only claimed together with a run that isolates it);
- the **static vs dynamic target analysis** of the paper's eqs. (37)-(39), measured: along each
  run the curvature error ``omega / v - kappa_d`` is split exactly into the yaw-tracking part
  ``e_omega / v`` and the target's mismatch part ``omega_d / v - kappa_d``
  (:func:`curvature_split`);
- a **passive-steering study** (:mod:`tt_mujoco.vehicle.steering`): trailer off-tracking for eta =
0,
  the paper's eta = 3 (forward and reversing), eta = -3, the same-path gains and the
  curvature-scheduled eta;
- a **path-feedback study** (:mod:`tt_mujoco.reference.feedback`): the outer lateral/heading loop
on all
  three paths under the paper's disturbances and 20 dB noise.

The runs go to the project's process pool (:mod:`tt_mujoco.executor`, ``--workers``, default
2) with a progress bar; identical scenarios run once. The report (``report.md``, ``report.json``,
``summary.md`` for docs/paper.md, figures) goes to ``renders/paper``, or to the first free
``renders/paper-N`` if that exists (never overwritten), or to ``--out DIR`` (new or empty).

All runs use seed :data:`SUITE_SEED` and the same-path steering preset (the paper's eta = 3
jackknifes driving forward, docs/model.md Section 3; the steering study shows it)."""

from tt_mujoco.paper.causes import CAUSES
from tt_mujoco.paper.cli import main
from tt_mujoco.paper.execute import curvature_split, execute, run_suite, steady_mask
from tt_mujoco.paper.report import build_report
from tt_mujoco.paper.suite import (
    CELLS,
    PLANTS,
    SUITE_SEED,
    TABLE_RUNS,
    TABLE_TITLES,
    Cell,
    RunSpec,
    suite,
)

__all__ = [
    "CAUSES",
    "CELLS",
    "PLANTS",
    "SUITE_SEED",
    "TABLE_RUNS",
    "TABLE_TITLES",
    "Cell",
    "RunSpec",
    "build_report",
    "curvature_split",
    "execute",
    "main",
    "run_suite",
    "steady_mask",
    "suite",
]

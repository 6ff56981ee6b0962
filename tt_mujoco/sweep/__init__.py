"""``python -m tt_mujoco.sweep``: Monte Carlo runs and parameter sweeps, laptop to cluster.

A sweep is a set of *options* (the fields of :class:`tt_mujoco.sim.Scenario`, controller gains
``gain.<name>``, mass and inertia factors ``scale.<field>`` and absolute parameter overrides
``param.<field>``), each fixed or varied:

- **grid** (the default): the Cartesian product of every option's list of values, each point
  run ``repeats`` times;
- **random** (``samples=N``): N runs, each option drawn from its list (uniformly) or from a
  distribution (``uniform``, ``loguniform``, ``normal``).

Seeds. Every run's ``seed`` (the measurement-noise seed of :class:`~tt_mujoco.sim.Scenario`) comes
from the sweep seed through :class:`numpy.random.SeedSequence` with spawn key ``(0, k)``: ``k`` is
the repeat number in a grid (so every grid point sees the same noise realisations: common random
numbers, which makes comparisons between gains paired) and the sample number in random mode,
whose option values come from spawn key ``(1, k)``. A run is thus a pure function of its
configuration, and the table does not depend on the executor, the worker count or the order in
which runs finish. Giving ``seed`` as an option sets the runs' seeds directly instead.

Each run is keyed by ``run_id``, a hash of its configuration. Finished runs are appended to
``journal.jsonl`` (one JSON line each, flushed at once), so an interrupted sweep resumes with
``--resume`` without redoing them; a run whose configuration is unchanged is reused even when
the sweep grew (more values, more samples). At the end the sorted table ``runs.csv`` (one row per
run: its full configuration and every metric), ``summary.csv`` / ``summary.json`` (percentiles of
each metric over the runs that finished ``ok``, failure counts) and the figures
``histograms.png`` and ``scatter.png`` are written, each atomically.

Runs execute through a :mod:`concurrent.futures` executor: local worker processes
(``--workers N``), or Dask distributed (the ``dask`` extra) with ``--scheduler ADDRESS`` or
``--scheduler local`` for a ``LocalCluster``. A run that diverges, jackknifes or raises is a row
with its status and error, never lost. Exit codes: 0 the sweep finished (whatever its runs did),
2 bad sweep specification (one message), 130 interrupted (resumable)."""

from tt_mujoco.sweep.cli import main
from tt_mujoco.sweep.execute import Resume, SweepResult, run_sweep
from tt_mujoco.sweep.options import (
    JOURNAL,
    KEY_METRICS,
    MAX_RUNS,
    RESULT_COLUMNS,
    SPEC_FILE,
    TABLE,
    WALL_COLUMNS,
    BadSpecError,
)
from tt_mujoco.sweep.runs import build_scenario, expand, run_one
from tt_mujoco.sweep.spec import Axis, SweepSpec, load_spec, parse_item, parse_spec
from tt_mujoco.sweep.tables import plot_summary, read_journal, read_table, summarize

__all__ = [
    "JOURNAL",
    "KEY_METRICS",
    "MAX_RUNS",
    "RESULT_COLUMNS",
    "SPEC_FILE",
    "TABLE",
    "WALL_COLUMNS",
    "Axis",
    "BadSpecError",
    "Resume",
    "SweepResult",
    "SweepSpec",
    "build_scenario",
    "expand",
    "load_spec",
    "main",
    "parse_item",
    "parse_spec",
    "plot_summary",
    "read_journal",
    "read_table",
    "run_one",
    "run_sweep",
    "summarize",
]

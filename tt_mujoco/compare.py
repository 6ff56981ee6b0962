"""``python -m tt_mujoco.compare RUN_DIR RUN_DIR ...``: finished runs side by side.

Reads each run's ``metrics.json`` and time series and writes into a new folder:

- ``compare.md``: every numeric metric of the runs side by side, with each run's ratio to the
  first run (the reference) - the table docs/compare.md shows;
- ``compare.json``: the same numbers (strict JSON);
- ``paths.png``: the tractor's (solid) and trailer's (dashed) tracks over the reference path;
- ``errors.png``: e_v, e_omega and the lateral error over time, one colour per run;
- ``signals.png``: wheel torques and articulation over time.

Runs on different paths are refused (their errors do not compare) unless
``--allow-different-paths``. Exit codes: 0 written, 2 bad input.
"""

from __future__ import annotations

import contextlib
import glob
import math
import sys
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from tt_mujoco import guard
from tt_mujoco.cliargs import BadInputError, Parser
from tt_mujoco.defaults import EXIT_BAD_INPUT, EXIT_OK
from tt_mujoco.outputs import (
    OutputError,
    atomic_write,
    claim_folder,
    release_folder,
    remove_if_empty,
    save_figure,
    write_json,
)
from tt_mujoco.runfolder import FinishedRun, check_out, read_run
from tt_mujoco.viz.plots import DPI, plot_comparison

__all__ = ["Run", "load_run", "main", "metrics_table"]

DEFAULT_OUT = Path("renders") / "compare"


class Run:
    """A finished run as compare shows it: its label, metrics, configuration and time series."""

    def __init__(self, run: FinishedRun):
        self.folder = run.folder
        self.metrics = run.metrics
        self.config = run.config
        self.timeseries = run.timeseries
        self.reference = run.reference
        scenario = run.scenario
        self.path = str(scenario.get("traj", "?"))
        self.parts = [str(scenario.get("controller", "?")), str(scenario.get("plant", "?"))]
        self.label = self.named(1)

    def named(self, depth: int) -> str:
        """The label with the folder's last ``depth`` path parts."""
        name = "/".join(self.folder.absolute().parts[-depth:])
        return f"{name} ({', '.join(self.parts)})"


def _distinct(runs: list[Run]) -> None:
    """Refuse a folder given twice; label runs that a folder's name does not tell apart (two
    seeds of one scenario in ``a/run`` and ``b/run``) by as much of their paths as tells them
    apart: every table column and every figure's legend entry is one run."""
    seen = {}
    for run in runs:
        key = run.folder.resolve()
        if key in seen:
            again = "" if run.folder == seen[key] else f" (as {str(seen[key])!r} before)"
            raise BadInputError(
                f"RUN_DIR {str(run.folder)!r} is given twice{again}: give each run once"
            )
        seen[key] = run.folder
    depth = 1
    while len({r.label for r in runs}) < len(runs) and depth < 64:
        depth += 1
        shared = [r for r in runs if sum(o.label == r.label for o in runs) > 1]
        for run in shared:
            run.label = run.named(depth)


def load_run(folder: Path) -> Run:
    """Read a run folder through :func:`tt_mujoco.runfolder.read_run`; RunFolderError (a
    BadInputError) naming what is missing or broken."""
    return Run(read_run(folder))


def _numeric(value) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)


def metrics_table(runs: list[Run]) -> tuple[list[str], list[dict]]:
    """The metrics every run has as numbers, in the first run's order, and per metric the runs'
    values and their ratios to the first run (None where the first is 0)."""
    skip = {"wall_time_s", "sample_period_s"}
    names = [k for k, v in runs[0].metrics.items() if _numeric(v) and k not in skip]
    names = [k for k in names if all(_numeric(r.metrics.get(k)) for r in runs)]
    rows = []
    for name in names:
        values = [float(r.metrics[name]) for r in runs]
        ratios = [v / values[0] if values[0] else None for v in values]
        rows.append({"metric": name, "values": values, "ratios": ratios})
    return names, rows


def _markdown(runs: list[Run], rows: list[dict]) -> str:
    head = "| metric | " + " | ".join(r.label for r in runs) + " |"
    lines = [
        f"# {len(runs)} runs compared",
        "",
        f"Made by `python -m tt_mujoco.compare {' '.join(str(r.folder) for r in runs)}`. "
        f"Ratios are to the first run, {runs[0].label}.",
        "",
        head,
        "|" + "---|" * (len(runs) + 1),
    ]
    for row in rows:
        cells = []
        for value, ratio in zip(row["values"], row["ratios"], strict=True):
            cell = f"{value:.4g}"
            if ratio is not None and cells:
                cell += f" (x{ratio:.3g})"
            cells.append(cell)
        lines.append(f"| {row['metric']} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def _paths_figure(runs: list[Run], reference) -> Figure:
    fig = Figure(figsize=(7, 6), layout="constrained")
    ax = fig.add_subplot()
    if reference is not None:
        ax.plot(reference[:, 0], reference[:, 1], color="0.6", lw=3, label="reference path")
    for i, run in enumerate(runs):
        ts, color = run.timeseries, f"C{i % 10}"
        ax.plot(ts["x"], ts["y"], color=color, lw=1.3, label=f"{run.label}: tractor P")
        ax.plot(ts["x0"], ts["y0"], "--", color=color, lw=1.0, label="trailer P0")
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, loc="best")
    fig.suptitle("Tracks")
    return fig


def _signals_figure(runs: list[Run]) -> Figure:
    fig = Figure(figsize=(8, 7), layout="constrained")
    axes = fig.subplots(3, 1, sharex=True)
    for i, run in enumerate(runs):
        ts, color = run.timeseries, f"C{i % 10}"
        axes[0].plot(ts["t"], ts["T_r"], color=color, lw=1.0, label=run.label)
        axes[1].plot(ts["t"], ts["T_l"], color=color, lw=1.0)
        axes[2].plot(ts["t"], np.degrees(ts["phi"]), color=color, lw=1.0)
    for ax, ylabel in zip(axes, ("T_r (N m)", "T_l (N m)", "phi (deg)"), strict=True):
        ax.set_ylabel(ylabel)
        ax.grid(True, alpha=0.3)
    axes[0].legend(fontsize=8)
    axes[-1].set_xlabel("t (s)")
    fig.suptitle("Wheel torques and articulation")
    return fig


def compare(folders: list[Path], out: Path | None, allow_different_paths: bool) -> Path:
    """Write the comparison of ``folders`` into a new folder; returns it."""
    runs = [load_run(f) for f in folders]
    _distinct(runs)
    paths = sorted({r.path for r in runs})
    if len(paths) > 1 and not allow_different_paths:
        raise BadInputError(
            f"the runs follow different paths ({', '.join(paths)}): their errors do not compare; "
            "pass --allow-different-paths to compare them anyway"
        )
    _, rows = metrics_table(runs)
    reference = runs[0].reference
    if out is not None:
        check_out(out / "compare.md")
    folder, created = claim_folder(out, DEFAULT_OUT)
    try:
        _write_comparison(folder, runs, rows, reference)
    except BaseException as err:  # a full disk, an interrupt: no half comparison left behind
        for name in WRITTEN:
            with contextlib.suppress(OSError):
                (folder / name).unlink()
        if created:
            remove_if_empty(folder)
        else:
            release_folder(folder)
        if isinstance(err, OSError) and not err.filename:  # a figure's writer names nothing
            raise OSError(err.errno, err.strerror, str(folder)) from err
        raise
    release_folder(folder)
    return folder


#: The files a comparison writes.
WRITTEN = ("compare.md", "compare.json", "paths.png", "errors.png", "signals.png")


def _write_comparison(folder: Path, runs: list[Run], rows: list[dict], reference) -> None:
    atomic_write(folder / "compare.md", _markdown(runs, rows))
    write_json(
        folder / "compare.json",
        {"runs": [str(r.folder) for r in runs], "labels": [r.label for r in runs], "rows": rows},
        strict=True,
    )
    save_figure(_paths_figure(runs, reference), folder / "paths.png", DPI)
    plot_comparison(
        {r.label: r.timeseries for r in runs},
        folder / "errors.png",
        reference_polyline=reference,
        title="Tracking errors",
    )
    save_figure(_signals_figure(runs), folder / "signals.png", DPI)


def _expand(patterns: list[str]) -> list[Path]:
    folders = []
    for pattern in patterns:
        matches = sorted(glob.glob(pattern)) if any(c in pattern for c in "*?[") else [pattern]
        if not matches:
            raise BadInputError(f"{pattern!r} matches no run folder")
        folders += [Path(m) for m in matches]
    return folders


@guard.command
def main(argv: list[str] | None = None) -> int:
    parser = Parser(
        prog="python -m tt_mujoco.compare",
        description="Compare finished runs: a table of every metric with ratios to the first "
        "run, and overlay figures of tracks, errors, torques and articulation.",
    )
    parser.add_argument("runs", nargs="+", metavar="RUN_DIR", help="run folders (or a glob)")
    parser.add_argument(
        "--out", type=Path, default=None, help="a new folder (default: renders/compare[-N])"
    )
    parser.add_argument(
        "--allow-different-paths", action="store_true", help="compare runs on different paths"
    )
    try:
        args = parser.parse_args(argv)
        folders = _expand(args.runs)
        if len(folders) < 2:
            raise BadInputError("give at least two run folders to compare")
        folder = compare(folders, args.out, args.allow_different_paths)
    except (BadInputError, OutputError) as err:
        print(f"error: {err}", file=sys.stderr)
        return EXIT_BAD_INPUT
    print((folder / "compare.md").read_text())
    print(f"wrote {', '.join(WRITTEN)} to {folder}/")
    return EXIT_OK


if __name__ == "__main__":
    guard.end(main())

"""The figure of a planning with no plan: its best candidate, drawn where it was blocked.

A run refused for want of a plan leaves nothing in its output folder, so its figure is written
beside the crash files, in the temporary folder, and the refusal's one line names it.
"""

from __future__ import annotations

import math
import os
import tempfile
import time
from pathlib import Path

from matplotlib.figure import Figure

from tt_mujoco.outputs import save_figure
from tt_mujoco.viz.plots import DPI, TRACTOR_COLOR, draw_world

__all__ = ["plot_best_candidate", "write_best_candidate"]

BLOCKED_COLOR = "tab:red"


def plot_best_candidate(best) -> Figure:
    """The figure of ``best`` (a :class:`tt_mujoco.world.plan.BestCandidate`): the world, the
    start, the candidate's path (solid where clear, dotted beyond), and the train where it was
    blocked, its unit too close in red.

    Parameters
    ----------
    best : tt_mujoco.world.plan.BestCandidate

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.patches import Polygon

    from tt_mujoco.vehicle.footprint import footprints, unit_names
    from tt_mujoco.world.world import rectangle

    fig = Figure(figsize=(7, 6), layout="constrained")
    ax = fig.add_subplot()
    draw_world(ax, best.world, best.params)
    line = best.polyline
    clear = max(1, round(best.reached * (len(line) - 1)) + 1)
    ax.plot(*line[:clear].T, color=TRACTOR_COLOR, lw=1.6, label=f"best candidate ({best.word})")
    ax.plot(*line[clear - 1 :].T, ":", color=TRACTOR_COLOR, lw=1.2, label="its blocked rest")
    x, y, heading = best.start
    ax.plot(x, y, "o", color="k", mfc="white", ms=7, label="start (tractor)")
    ax.annotate(
        "",
        xy=(x + 0.5 * math.cos(heading), y + 0.5 * math.sin(heading)),
        xytext=(x, y),
        arrowprops={"arrowstyle": "->", "color": "k"},
    )
    boxes, names = footprints(best.params), unit_names(best.params.n_trailers)
    for pose, box, name in zip(best.poses, boxes, names, strict=True):
        blocked = name == best.unit
        ax.add_patch(
            Polygon(
                rectangle(*pose, *box),
                closed=True,
                fill=blocked,
                fc=BLOCKED_COLOR if blocked else "none",
                ec=BLOCKED_COLOR if blocked else "0.2",
                alpha=0.6 if blocked else 1.0,
                lw=1.0,
            )
        )
    what = "the world's bounds" if best.obstacle is None else repr(best.obstacle)
    ax.plot([], [], "s", color=BLOCKED_COLOR, alpha=0.6, label=f"{best.unit}, blocked by {what}")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(f"No plan: the best candidate is clear for {math.floor(100 * best.reached)} %")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    return fig


def write_best_candidate(best, folder: Path | None = None) -> Path:
    """Write the figure of ``best`` as a new PNG file in ``folder`` (default: the temporary
    folder) and return its path; the name is made there exclusively, so no file is replaced.

    Parameters
    ----------
    best : tt_mujoco.world.plan.BestCandidate
    folder : Path, optional
    """
    stamp = time.strftime("%Y%m%d-%H%M%S")
    # the name made ours exclusively; the figure is then renamed over that empty file, whole
    handle, name = tempfile.mkstemp(prefix=f"tt_mujoco-no-plan-{stamp}-", suffix=".png", dir=folder)
    os.close(handle)
    return save_figure(plot_best_candidate(best), Path(name), DPI)

"""Figures of a finished run: the kinds of the paper's Figs. 2-8, as PNG files.

Matplotlib through :class:`matplotlib.figure.Figure` objects only (no ``pyplot``, so no global
figure state and no GUI backend; ``savefig`` uses Agg). Every file is written under a temporary
name in its folder and renamed into place, so a reader never sees half a PNG.

A run is a mapping column -> 1-D array with the columns of ``timeseries.csv`` (SI units,
radians); the errors are ``e_v = v - v_d`` and ``e_omega = omega - omega_d`` (paper eq. 37's
tracking errors). Lateral errors are signed distances to a polyline, positive to the left of
its direction of travel (:func:`distance_to_polyline`).
"""

from __future__ import annotations

import io
import math
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from tt_mujoco.analysis import metrics
from tt_mujoco.outputs import save_figure
from tt_mujoco.sim.loop.timeseries import train_columns
from tt_mujoco.vehicle.params import Params
from tt_mujoco.viz import FIGURES

__all__ = [
    "FIGURES",
    "draw_world",
    "plot_comparison",
    "plot_run",
    "run_pngs",
    "tracking_errors",
    "warm_up",
]


DPI = 120
TRACTOR_COLOR = "tab:orange"
TRAILER_COLOR = "tab:blue"
REFERENCE_COLOR = "0.2"


# --- error signals -------------------------------------------------------------------------------
def tracking_errors(
    ts: Mapping, reference_polyline=None, reverse: bool = False
) -> dict[str, np.ndarray]:
    """Error signals of a run, as its metrics measure them.

    Returns
    -------
    dict
        ``e_v``, ``e_omega``; when a reference polyline is given, ``lateral`` (P to the path,
        signed, positive left of the path's direction of travel), ``trailer_lateral`` (P0's
        cross-track where it counts) and ``trailer_offtrack``, those of
        :func:`tt_mujoco.analysis.metrics.run_error_signals` (NaN after the run's finite
        part), whose RMS values are the metrics'; without one, ``trailer_offtrack`` of
        :func:`tt_mujoco.analysis.metrics.follower_offtrack`.
    """
    if reference_polyline is not None:
        signals = metrics.run_error_signals(ts, reference_polyline, reverse)
        names = ("e_v", "e_omega", "lateral", "trailer_lateral", "trailer_offtrack")
        return {name: signals[name] for name in names}
    c = _columns(ts, ("t", "x", "y", "x0", "y0", "v", "v_d", "omega", "omega_d"))
    return {
        "e_v": c["v"] - c["v_d"],
        "e_omega": c["omega"] - c["omega_d"],
        "trailer_offtrack": metrics.follower_offtrack(ts, reverse),
    }


# --- helpers --------------------------------------------------------------------------------------
def _columns(ts: Mapping, names) -> dict[str, np.ndarray]:
    out = {}
    for name in names:
        if name not in ts:
            raise ValueError(f"time series has no column {name!r}; this figure needs {names}")
        out[name] = np.asarray(ts[name], dtype=float)
    n = len(out[names[0]])
    for name, col in out.items():
        if col.ndim != 1 or len(col) != n:
            raise ValueError(
                f"time series column {name!r} has shape {col.shape}: all columns must be 1-D "
                f"with {n} samples"
            )
    if n < 2:
        raise ValueError(f"time series has {n} samples: a figure needs >= 2")
    return out


def _rms(x: np.ndarray) -> float:
    x = x[np.isfinite(x)]
    return float(np.sqrt(np.mean(x**2))) if len(x) else math.nan


def _reference(reference_polyline) -> np.ndarray | None:
    if reference_polyline is None:
        return None
    ref = np.asarray(reference_polyline, dtype=float)
    if ref.ndim != 2 or ref.shape[1] != 2 or len(ref) < 2:
        raise ValueError(
            f"reference_polyline of shape {ref.shape} is not allowed: it must be (M, 2), M >= 2"
        )
    return ref


#: Colours of trailers 2, 3, ... of a train (cycled).
TRAIN_COLORS = ("tab:purple", "tab:cyan", "tab:pink", "tab:olive")


def _train(c: dict) -> list[tuple[int, str]]:
    """``(k, colour)`` of the trailers k >= 2 whose columns ``c`` holds."""
    out, k = [], 2
    while f"x0_{k}" in c:
        out.append((k, TRAIN_COLORS[(k - 2) % len(TRAIN_COLORS)]))
        k += 1
    return out


# --- figures of one run ---------------------------------------------------------------------------
def draw_world(ax, world, params: Params) -> None:
    """Draw a world's obstacles (grey) and its goal (the last trailer's footprint there,
    dashed) into the axes ``ax``, for the train ``params``."""
    from matplotlib.patches import Polygon

    from tt_mujoco.vehicle.footprint import footprints
    from tt_mujoco.world.world import rectangle

    boxes = footprints(params)
    for i, polygon in enumerate(world.polygons(boxes[-1])):
        label = "obstacle" if i == 0 else None
        ax.add_patch(Polygon(polygon, closed=True, fc="0.6", ec="0.3", lw=0.8, label=label))
    goal = world.goal
    if goal is not None:
        heading = np.radians(goal.heading_deg)
        corners = rectangle(goal.x, goal.y, heading, *boxes[-1])
        ax.add_patch(Polygon(corners, closed=True, fill=False, ec="tab:green", ls="--", lw=1.2))
        ax.plot(goal.x, goal.y, "*", color="tab:green", ms=10, label="goal (last axle)")
        length = boxes[-1][1]
        ax.annotate(
            "",
            xy=(goal.x + length * np.cos(heading), goal.y + length * np.sin(heading)),
            xytext=(goal.x, goal.y),
            arrowprops={"arrowstyle": "->", "color": "tab:green"},
        )


def _margins(fig: Figure, rows: int = 1, top: float = 0.45) -> Figure:
    """Margins in inches, set once, for a run's figures (tick labels and an axis label at the
    left and bottom, a title at the ``top``): matplotlib's constrained layout draws a figure
    twice to place them (``docs/performance.md``)."""
    width, height = fig.get_size_inches()
    left, right, bottom, between = 0.85, 0.2, 0.55, 0.2
    axes_height = (height - top - bottom - between * (rows - 1)) / rows
    fig.subplots_adjust(
        left=left / width,
        right=1 - right / width,
        bottom=bottom / height,
        top=1 - top / height,
        hspace=between / axes_height,
    )
    return fig


def _path_figure(c: dict, ref: np.ndarray, world=None, params: Params | None = None) -> Figure:
    fig = Figure(figsize=(7, 6))
    ax = fig.add_subplot()
    if world is not None:
        draw_world(ax, world, Params() if params is None else params)
    ax.plot(ref[:, 0], ref[:, 1], "--", color=REFERENCE_COLOR, lw=1.2, label="reference path")
    ax.plot(c["x"], c["y"], color=TRACTOR_COLOR, lw=1.6, label="tractor P")
    ax.plot(c["x0"], c["y0"], color=TRAILER_COLOR, lw=1.2, label="trailer P0")
    for k, color in _train(c):
        ax.plot(c[f"x0_{k}"], c[f"y0_{k}"], color=color, lw=1.0, label=f"trailer {k} P0_{k}")
    for xs, ys, color in ((c["x"], c["y"], TRACTOR_COLOR), (c["x0"], c["y0"], TRAILER_COLOR)):
        ax.plot(xs[0], ys[0], "o", color=color, ms=7, mfc="white", mew=1.5)
        ax.plot(xs[-1], ys[-1], "s", color=color, ms=6)
    ax.plot([], [], "ko", mfc="white", label="start")
    ax.plot([], [], "ks", label="end")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title("Path: reference, tractor and trailer")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best", fontsize=9)
    return _margins(fig)


def _errors_figure(c: dict, err: dict, reverse: bool = False) -> Figure:
    t = c["t"]
    fig = Figure(figsize=(8, 9))
    axes = fig.subplots(4, 1, sharex=True)
    rows = (
        ("e_v", "e_v (m/s)", "velocity error v - v_d"),
        ("e_omega", "e_omega (rad/s)", "yaw-rate error omega - omega_d"),
        ("lateral", "lateral (m)", "tractor P to the reference path"),
    )
    for ax, (key, ylabel, label) in zip(axes, rows, strict=False):
        ax.plot(
            t, err[key], color=TRACTOR_COLOR, lw=1.2, label=f"{label}, RMS {_rms(err[key]):.4g}"
        )
        ax.axhline(0.0, color="0.5", lw=0.8)
        ax.set_ylabel(ylabel)
    ax = axes[3]
    ax.plot(
        t,
        err["trailer_lateral"],
        color=TRAILER_COLOR,
        lw=1.2,
        label=f"P0 to the reference path, RMS {_rms(err['trailer_lateral']):.4g}",
    )
    ax.plot(
        t,
        err["trailer_offtrack"],
        "--",
        color=TRAILER_COLOR,
        lw=1.2,
        label=f"{OFFTRACK_LABELS[reverse]} (off-tracking, unsigned), "
        f"RMS {_rms(err['trailer_offtrack']):.4g}",
    )
    ax.axhline(0.0, color="0.5", lw=0.8)
    ax.set_ylabel("trailer (m)")
    ax.set_xlabel("t (s)")
    for ax in axes:
        ax.grid(True, alpha=0.3)
        ax.legend(loc="upper right", fontsize=8)
    fig.suptitle("Tracking errors (lateral: positive left of the path)")
    return _margins(fig, rows=4, top=0.5)


#: Who is off-tracked against whose path (metrics.trailer_offtrack): the trailer against the
#: tractor's driving forward, the tractor against the trailer's backing up.
OFFTRACK_LABELS = {False: "P0 to the tractor's path", True: "tractor P to P0's path"}


def _torques_figure(c: dict, limit: float) -> Figure:
    t = c["t"]
    fig = Figure(figsize=(8, 5))
    axes = fig.subplots(2, 1, sharex=True)
    for ax, side, color in ((axes[0], "r", "tab:red"), (axes[1], "l", "tab:green")):
        name = "right" if side == "r" else "left"
        ax.plot(t, c[f"T_{side}"], color=color, lw=1.3, label=f"T_{side} applied")
        ax.plot(t, c[f"T_{side}_cmd"], "--", color="k", lw=1.0, label=f"T_{side} commanded")
        dist = c.get(f"dist_T_{side}")
        if dist is not None and np.any(dist != 0.0):
            # The matched disturbance acts on the wheel beside the motor: with it the net
            # torque explains why the motors push back (both negative under the paper's push).
            ax.plot(t, dist, color="tab:purple", lw=1.0, label="disturbance")
            ax.plot(t, c[f"T_{side}"] + dist, color="0.5", lw=1.0, label="net (applied + dist.)")
        # The saturation lines only when the torques come near them (else they flatten the plot).
        peak = max(np.max(np.abs(c[f"T_{side}"])), np.max(np.abs(c[f"T_{side}_cmd"])))
        if peak >= 0.5 * limit:
            for sign in (1, -1):
                ax.axhline(sign * limit, color="0.4", ls=":", lw=1.0)
        ax.set_ylabel(f"{name} wheel (N m)")
        ax.grid(True, alpha=0.3)
        ax.legend(loc="upper right", fontsize=8)
    axes[1].set_xlabel("t (s)")
    fig.suptitle(f"Wheel torques (saturation +-{limit:g} N m, dotted when approached)")
    return _margins(fig, rows=2, top=0.5)


def _articulation_figure(c: dict, params: Params) -> Figure:
    t = c["t"]
    fig = Figure(figsize=(8, 4))
    ax = fig.add_subplot()
    ax.plot(t, np.degrees(c["phi"]), color=TRACTOR_COLOR, lw=1.4, label="phi = theta - theta0")
    ax.plot(t, np.degrees(c["beta"]), color=TRAILER_COLOR, lw=1.4, label="beta (trailer steer)")
    ax.plot(
        t,
        np.degrees(params.eta * c["phi"]),
        "--",
        color="k",
        lw=1.0,
        label=f"eta * phi (eta = {params.eta:.4g})",
    )
    for k, color in _train(c):
        ax.plot(t, np.degrees(c[f"phi_{k}"]), color=color, lw=1.0, label=f"phi_{k} (trailer {k})")
    # The jackknife singularity |eta phi| = 90 deg (docs/model.md Section 2), once phi gets near it.
    limit = math.degrees(params.phi_singular)
    if math.isfinite(limit) and np.max(np.abs(np.degrees(c["phi"]))) > 0.5 * limit:
        for sign in (1, -1):
            ax.axhline(sign * limit, color="tab:red", ls=":", lw=1.0)
        ax.plot([], [], ":", color="tab:red", label=f"phi singular (+-{limit:.1f} deg)")
    ax.axhline(0.0, color="0.5", lw=0.8)
    ax.set_xlabel("t (s)")
    ax.set_ylabel("angle (deg)")
    ax.set_title("Articulation and passive steering")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    return _margins(fig)


def plot_run(
    ts: Mapping,
    reference_polyline,
    out_dir,
    params: Params | None = None,
    world=None,
    names: Sequence[str] = FIGURES,
    reverse: bool = False,
) -> list[Path]:
    """Write the run's figures (:data:`FIGURES`, or those of them in ``names``) into
    ``out_dir`` (created if missing).

    - ``path.png``: reference path, tractor P and trailer P0, equal axes, start (circle) and
      end (square) markers (paper Figs. 2a, 7a, 8a).
    - ``errors.png``: e_v, e_omega, P's lateral error, P0's lateral error and off-tracking
      (paper Figs. 2-3, 7b-c, 8b-c), each labelled with its RMS.
    - ``torques.png``: applied (solid) and commanded (dashed) T_r, T_l with the saturation, and
      the matched disturbance torque and the net torque when there is a disturbance.
    - ``articulation.png``: phi and beta in degrees, eta * phi dashed.

    Parameters
    ----------
    ts : mapping of str to 1-D arrays
        The run's time series (columns of ``timeseries.csv``).
    reference_polyline : array_like, shape (M, 2)
    out_dir : str or Path
    params : Params, optional
        The run's parameters (torque limit, eta); ``Params()`` if not given.
    world : World, optional
        The run's obstacles and goal (:mod:`tt_mujoco.world`), drawn in ``path.png``.
    names : sequence of str, optional
        The figures to draw (default all of :data:`FIGURES`).
    reverse : bool, optional
        The run backed up (the trailer led): its errors measured as its metrics measure them.

    Returns
    -------
    list of Path
        The files written, in :data:`FIGURES` order.
    """
    figures = _run_figures(ts, reference_polyline, params, world, names, reverse=reverse)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    return [save_figure(make(), out / name, DPI) for name, make in figures.items()]


def run_pngs(
    ts: Mapping,
    reference_polyline,
    params: Params | None = None,
    world=None,
    names: Sequence[str] = FIGURES,
    errors: Mapping | None = None,
    reverse: bool = False,
) -> dict[str, bytes]:
    """The figures :func:`plot_run` writes, as PNG files' bytes by file name (in
    :data:`FIGURES` order): what a worker drawing them hands back
    (:mod:`tt_mujoco.viz.run_figures`). The other arguments are :func:`plot_run`'s.

    Parameters
    ----------
    errors : mapping, optional
        The run's error signals as its metrics measured them
        (:func:`tt_mujoco.analysis.metrics.run_error_signals`); :func:`tracking_errors` of
        ``reference_polyline`` otherwise.
    reverse : bool, optional
        The run backed up (the trailer led): who is off-tracked against whose path.
    """
    pngs = {}
    figures = _run_figures(ts, reference_polyline, params, world, names, errors, reverse)
    for name, make in figures.items():
        buffer = io.BytesIO()
        make().savefig(buffer, format="png", dpi=DPI)
        pngs[name] = buffer.getvalue()
    return pngs


def _run_figures(ts, reference_polyline, params, world, names, errors=None, reverse=False) -> dict:
    """File name -> a function making that figure, for ``names`` in :data:`FIGURES` order;
    the time series checked first."""
    unknown = sorted(set(names) - set(FIGURES))
    if unknown:
        raise ValueError(f"names={unknown!r} is not allowed: the figures are {FIGURES}")
    p = Params() if params is None else params
    ref = _reference(reference_polyline)
    if ref is None:
        raise ValueError("reference_polyline=None is not allowed: plot_run needs the path")
    drawn = ("t", "x", "y", "x0", "y0", "v", "v_d", "omega", "omega_d", "phi", "beta")
    drawn += ("T_r", "T_l", "T_r_cmd", "T_l_cmd")
    c = _columns(ts, drawn)
    c.update(
        _columns(ts, tuple(n for n in ("dist_T_r", "dist_T_l") if n in ts))
        if "dist_T_r" in ts
        else {}
    )
    n_trailers = 1 + sum(1 for name in ts if name.startswith("x0_"))
    c.update(_columns(ts, train_columns(n_trailers)) if n_trailers > 1 else {})
    makers = {
        "path.png": lambda: _path_figure(c, ref, world, p),
        "errors.png": lambda: _errors_figure(
            c, tracking_errors(ts, ref, reverse) if errors is None else errors, reverse
        ),
        "torques.png": lambda: _torques_figure(c, p.torque_limit),
        "articulation.png": lambda: _articulation_figure(c, p),
    }
    return {name: makers[name] for name in FIGURES if name in names}


def warm_up() -> None:
    """Draw a small figure with text into memory: matplotlib loads its fonts and renderer on
    the first draw, which a worker forked ahead of the run's figures does before they come."""
    fig = Figure(figsize=(2, 1.5))
    ax = fig.add_subplot()
    ax.plot([0.0, 1.0], [0.0, 1.0], label="warm")
    ax.set_title("warm up")
    ax.legend(fontsize=8)
    fig.savefig(io.BytesIO(), format="png", dpi=DPI)


def plot_comparison(
    runs: Mapping[str, Mapping],
    out_path,
    reference_polyline=None,
    title: str = "Tracking errors",
) -> Path:
    """Overlay several runs' errors in one figure (paper Figs. 3-6 style).

    Rows: e_v, e_omega and, when ``reference_polyline`` is given, P's lateral error; one
    colour per run, its RMS in the legend.

    Parameters
    ----------
    runs : mapping of label to time series
        At least one run; labels are shown in the legend.
    out_path : str or Path
        The ``.png`` to write (its folder is created if missing).
    reference_polyline : array_like, shape (M, 2), optional
    title : str

    Returns
    -------
    Path
    """
    if not runs:
        raise ValueError("runs={} is not allowed: give at least one labelled time series")
    out = Path(out_path)
    if out.suffix.lower() != ".png":
        raise ValueError(f"out_path={str(out)!r} is not allowed: it must end in .png")
    ref = _reference(reference_polyline)
    rows = [("e_v", "e_v (m/s)"), ("e_omega", "e_omega (rad/s)")]
    if ref is not None:
        rows.append(("lateral", "lateral (m)"))
    fig = Figure(figsize=(8, 2.6 * len(rows) + 0.6), layout="constrained")
    axes = fig.subplots(len(rows), 1, sharex=True, squeeze=False)[:, 0]
    colors = [f"C{i % 10}" for i in range(len(runs))]
    for (label, ts), color in zip(runs.items(), colors, strict=True):
        t = _columns(ts, ("t",))["t"]
        err = tracking_errors(ts, ref)
        for ax, (key, _) in zip(axes, rows, strict=True):
            ax.plot(t, err[key], color=color, lw=1.1, label=f"{label} (RMS {_rms(err[key]):.4g})")
    for ax, (_, ylabel) in zip(axes, rows, strict=True):
        ax.axhline(0.0, color="0.5", lw=0.8)
        ax.set_ylabel(ylabel)
        ax.grid(True, alpha=0.3)
        ax.legend(loc="upper right", fontsize=8)
    axes[-1].set_xlabel("t (s)")
    fig.suptitle(title)
    out.parent.mkdir(parents=True, exist_ok=True)
    return save_figure(fig, out, DPI)

"""The report's figures."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from tt_mujoco.paper.studies import steering_row
from tt_mujoco.paper.suite import FACTOR, PLANT_LABEL, PLANTS, STEERING_VARIANTS, STUDY_PATHS

#: The curvature split's runs, each with its panel's title: ISMC-STA, and FBL with a stiff yaw
#: loop.
CURVATURE_CASES = (
    ("cycloid_nominal", "cycloid, dynamic"),
    ("cycloid_static", "cycloid, static"),
    ("s_curve_dynamic", "S-curve, dynamic"),
    ("s_curve_static", "S-curve, static"),
    ("circle_dynamic", "circle, dynamic"),
    ("circle_static", "circle, static"),
)
STIFF_YAW_CASES = (
    ("stiff_yaw_fbl:s_curve_dynamic", "S-curve, dynamic"),
    ("stiff_yaw_fbl:s_curve_static", "S-curve, static"),
    ("stiff_yaw_fbl:circle_dynamic", "circle, dynamic"),
    ("stiff_yaw_fbl:circle_static", "circle, static"),
)


# --- figures ------------------------------------------------------------------------------------
def draw_figures(records, rows, steering, out: Path) -> list[str]:
    """Draw the report's figures into ``out``; the names of those drawn (a figure whose runs
    are missing is left out)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figures = (
        ("fig_ratios.png", _ratios_figure(plt, rows)),
        (
            "fig_curvature_split.png",
            _split_grid(
                plt,
                records,
                CURVATURE_CASES,
                "Curvature error split (eqs. 37-39), ISMC-STA, MuJoCo",
            ),
        ),
        (
            "fig_curvature_split_stiff_yaw.png",
            _split_grid(
                plt,
                records,
                STIFF_YAW_CASES,
                "Curvature error split, FBL K = diag(8, 50) (e_v ~ 0.5 m/s), MuJoCo",
            ),
        ),
        ("fig_steering.png", _steering_figure(plt, steering) if steering else None),
        ("fig_path_feedback.png", _feedback_figure(plt, records)),
    )
    made = []
    for name, fig in figures:
        if fig is None:
            continue
        fig.tight_layout()
        fig.savefig(out / name, dpi=110)
        plt.close(fig)
        made.append(name)
    return made


def _ratios_figure(plt, rows):
    """Ours / paper for every cell, on both plants, the band of a factor of two shaded."""
    fig, ax = plt.subplots(figsize=(10, 3.6))
    labels = [f"T{r['table']} {r['case']} {r['metric']}" for r in rows]
    x = np.arange(len(rows))
    for dx, plant, marker in ((-0.15, "reduced", "o"), (0.15, "mujoco", "s")):
        y = [r[plant]["ratio"] for r in rows]
        ax.scatter(x + dx, y, marker=marker, s=18, label=PLANT_LABEL[plant])
    ax.axhspan(1 / FACTOR, FACTOR, color="0.9", zorder=0)
    ax.axhline(1.0, color="0.5", lw=0.8)
    ax.set_yscale("log")  # the band [1/2, 2] keeps the axis valid without data
    ax.set_xticks(x, labels, rotation=90, fontsize=6)
    ax.set_ylabel("ours / paper")
    ax.legend(fontsize=8)
    return fig


def _split_grid(plt, records, cases, title):
    """The curvature error split of ``cases`` on MuJoCo, a panel each; None without them."""
    if not any(f"{c}@mujoco" in records and "series" in records[f"{c}@mujoco"] for c, _ in cases):
        return None
    nrow = len(cases) // 2
    fig, axes = plt.subplots(nrow, 2, figsize=(10, 2.4 * nrow), squeeze=False)
    for i, (base, label) in enumerate(cases):
        ax = axes[i // 2][i % 2]
        rec = records.get(f"{base}@mujoco", {})
        s = rec.get("series")
        if s is not None:
            ax.plot(s["t"], s["e_omega_over_v"], lw=0.8, label="e_omega / v")
            ax.plot(s["t"], s["mismatch"], lw=0.8, label="(omega_d - v kappa_d) / v")
            ax.set_ylim(-0.3, 0.3)
        ax.set_title(label, fontsize=9)
        ax.set_xlabel("t (s)", fontsize=8)
        ax.set_ylabel("1/m", fontsize=8)
        ax.tick_params(labelsize=7)
        if i == 0:
            ax.legend(fontsize=7)
    fig.suptitle(title, fontsize=10)
    return fig


def _steering_figure(plt, steering):
    """Off-tracking by steering design, path and plant: over the run and on steady arcs."""
    fig, axes = plt.subplots(2, 2, figsize=(11, 6), sharey="row")
    rows_spec = (("offtrack_rms", "whole run"), ("offtrack_steady_rms", "steady arcs"))
    for i, (field_name, what) in enumerate(rows_spec):
        for ax, plant in zip(axes[i], PLANTS, strict=True):
            for j, name in enumerate(STEERING_VARIANTS):
                vals = []
                for path in STUDY_PATHS:
                    r = steering_row(steering, path, plant, name)
                    ok = r is not None and r["status"] == "ok"
                    value = r.get(field_name) if ok else None
                    vals.append(np.nan if value is None else value)
                ax.bar(np.arange(3) + (j - 3) * 0.11, vals, width=0.11, label=name)
            ax.set_xticks(np.arange(3), STUDY_PATHS)
            if any(p.get_height() > 0 for p in ax.patches):  # log needs a positive bar
                ax.set_yscale("log")
            ax.set_title(f"{PLANT_LABEL[plant]}, {what} (jackknifed runs left out)", fontsize=9)
            ax.set_ylabel("off-track rms (m)")
    axes[0][1].legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.0, 1.0))
    return fig


def _feedback_figure(plt, records):
    """The paths driven with and without the path feedback, and their cross-track errors;
    None without the runs."""
    fb = [
        (case, records.get(f"fb:{case}:off@mujoco"), records.get(f"fb:{case}:on@mujoco"))
        for case in ("cycloid", "s_curve", "circle")
    ]
    if not any(off and on and "series" in off and "series" in on for _, off, on in fb):
        return None
    fig, axes = plt.subplots(2, 3, figsize=(12, 6))
    for j, (case, off, on) in enumerate(fb):
        if not (off and on and "series" in off and "series" in on):
            continue
        ax = axes[0][j]
        ref = np.asarray(on["series"]["reference"])
        ax.plot(ref[:, 0], ref[:, 1], color="0.6", lw=2, label="reference")
        for rec, label in ((off, "no feedback"), (on, "path feedback")):
            s = rec["series"]
            ax.plot(s["x"], s["y"], lw=0.8, label=label)
            axes[1][j].plot(s["t"], 1000 * np.asarray(s["lateral"]), lw=0.8, label=label)
        axes[1][j].set_ylabel("signed cross-track error (mm)")
        ax.set_aspect("equal")
        ax.set_title(f"{case} (MuJoCo, disturbance + 20 dB noise)", fontsize=9)
        axes[1][j].set_xlabel("t (s)")
        if j == 0:
            ax.legend(fontsize=7)
            axes[1][j].legend(fontsize=7)
    return fig

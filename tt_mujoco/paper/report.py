"""Writing the report: report.md, report.json, summary.md and the figures."""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping
from pathlib import Path

from tt_mujoco.outputs import atomic_write, json_safe
from tt_mujoco.paper.causes import CAUSES, explain_cells, unique_cells
from tt_mujoco.paper.figures import draw_figures
from tt_mujoco.paper.markdown import (
    baselines_markdown,
    config_markdown,
    feedback_markdown,
    steering_markdown,
    suite_setup_lines,
    tables_markdown,
)
from tt_mujoco.paper.robustness import robustness_markdown
from tt_mujoco.paper.studies import (
    check_rows,
    curvature_findings,
    curvature_rows,
    feedback_rows,
    steering_ratio,
    steering_row,
    steering_rows,
)
from tt_mujoco.paper.suite import (
    COMMAND,
    FACTOR,
    PLANT_LABEL,
    PLANTS,
    SETTLE_DISTANCE,
    STUDY_PATHS,
    SUITE_SEED,
    V_MIN,
)
from tt_mujoco.paper.values import fmt, metric_of


def _paper_tables(rows, records) -> list[str]:
    """Tables 1-5 (paper, reduced model, MuJoCo), the baselines and the robustness study."""
    return [*tables_markdown(rows), *baselines_markdown(records), *robustness_markdown(records)]


def _causes_section(records, by_cause) -> list[str]:
    """The cells that differ by more than a factor of two, grouped by their causes."""
    md = ["## Where we differ by more than a factor of two, and why", ""]
    for cause in CAUSES:
        cells = by_cause[cause.code]
        if not cells:
            continue
        md += [f"### {cause.code}. {cause.title} ({cause.kind})", ""]
        md.append(cause.describe(unique_cells(cells), records))
        listed = ", ".join(f"T{c.table} {c.case} {c.metric} ({PLANT_LABEL[p]})" for c, p in cells)
        md += ["", f"Explains: {listed}.", ""]
    if by_cause["unexplained"]:
        md += ["### Not explained", ""]
        md += [
            f"- Table {c.table} {c.case}, {c.quantity}, {PLANT_LABEL[p]}: paper {fmt(c.paper)}, "
            f"ours {fmt(metric_of(records, f'{c.run}@{p}', c.metric))}"
            for c, p in by_cause["unexplained"]
        ]
        md.append("")
    return md


def _curvature_section(records, curvature, figs) -> list[str]:
    """The static and the dynamic target's curvature errors split (eqs. 37-39)."""
    md = ["## Static vs dynamic target: eqs. (37)-(39) measured", ""]
    md += [
        "Along each run the curvature error of the driven path, omega/v - kappa_d (kappa_d at "
        "the nearest path point), is split exactly into the yaw-tracking part e_omega/v "
        "(eq. 37) and the target's mismatch (omega_d - v kappa_d)/v (eq. 39; for the dynamic "
        f"target only measurement noise and s drift). RMS over |v| >= {V_MIN} m/s; heading "
        "drifts are the same parts integrated without 1/v (rad).",
        "",
        "| path | target | controller | plant | e_v RMSE | lateral RMSE (m) | RMS e_omega/v "
        "(1/m) | RMS mismatch (1/m) | mismatch share | max drift int e_omega (rad) "
        "| max drift int mismatch (rad) |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in curvature:
        md.append(
            f"| {r['path']} | {r['target']} | {r['controller']} | {PLANT_LABEL[r['plant']]} | "
            f"{fmt(r['rmse_v'])} | {fmt(r['rmse_lateral'])} | "
            f"{fmt(r['rms_e_omega_over_v'])} | {fmt(r['rms_mismatch'])} | "
            f"{fmt(r['mismatch_share'], 2)} | {fmt(r['heading_drift_e_omega_max'], 3)} | "
            f"{fmt(r['heading_drift_mismatch_max'], 3)} |"
        )
    md += ["", *curvature_findings(records), ""]
    for name, caption in (
        ("fig_curvature_split.png", "curvature error split, ISMC-STA, MuJoCo"),
        ("fig_curvature_split_stiff_yaw.png", "curvature error split, FBL diag(8, 50), MuJoCo"),
    ):
        if name in figs:
            md += [f"![{caption}]({name})", ""]
    return md


def _steering_section(steering, figs) -> list[str]:
    """The passive steering study: off-tracking by steering design."""
    md = ["## Passive steering study", ""]
    md += [
        "Trailer off-tracking with each steering design, ISMC-STA (set 6.1), dynamic target, "
        "no disturbance (off-tracking is geometry; the disturbance rows are marked). 'Off-track' "
        "is the follower axle's distance from the leader's path (P0 from P's path forward, P "
        "from P0's path reversing); 'steady arc' only counts samples whose follower has run "
        f"{SETTLE_DISTANCE:g} m on constant curvature (none on the cycloid); 'analytic steady' "
        "is the steady-turn value of `steering.steady_offtrack`; 'trailer to reference' is P0 "
        "to the reference path.",
        "",
        *steering_markdown(steering),
        "",
    ]
    ratio_lines = []
    for path in ("circle", "s_curve", "cycloid"):
        for plant in PLANTS:
            full = steering_ratio(steering, path, plant, "offtrack_rms")
            steady = steering_ratio(steering, path, plant, "offtrack_steady_rms")
            if math.isfinite(full):
                ratio_lines.append(
                    f"- {path}, {PLANT_LABEL[plant]}: plain / same_path off-tracking "
                    f"x{fmt(full, 3)} over the run, x{fmt(steady, 3)} on steady arcs"
                )
    md += ratio_lines
    md += ["", *STEERING_NOTES, ""]
    if "fig_steering.png" in figs:
        md += ["![off-tracking by steering design](fig_steering.png)", ""]
    return md


def _feedback_section(feedback, figs) -> list[str]:
    """Beyond the paper: the outer path feedback."""
    md = ["## Beyond the paper: path feedback", ""]
    md += [
        "The outer path feedback adds v (-k_y e_y - k_psi e_psi) to the dynamic "
        "target's omega_d (k_y = 4 1/m^2, k_psi = 4 1/m, critically damped in arc length). "
        "Paper disturbances on; 20 dB noise unless the case says otherwise. 'Cross-track' "
        "measures P against the path continued along its end tangents (a vehicle that "
        "overshoots the path's end is not counted as lateral error there).",
        "",
        *feedback_markdown(feedback),
        "",
        *FEEDBACK_NOTES,
        "",
    ]
    if "fig_path_feedback.png" in figs:
        md += ["![path feedback](fig_path_feedback.png)", ""]
    return md


def _payload(info, rows, by_cause, checks, studies, figs, records) -> dict:
    """``report.json``: the cells, their causes, the checks, the studies' rows (curvature
    split, steering, feedback), the figures and every run without its series."""
    curvature, steering, feedback = studies
    return {
        "command": info.get("command", COMMAND),
        "suite": info,
        "factor": FACTOR,
        "cells": rows,
        "causes": {
            c.code: {
                "title": c.title,
                "kind": c.kind,
                "cells": [
                    {"table": x.table, "case": x.case, "metric": x.metric, "plant": p}
                    for x, p in by_cause[c.code]
                ],
            }
            for c in CAUSES
        },
        "unexplained": [
            {"table": x.table, "case": x.case, "metric": x.metric, "plant": p}
            for x, p in by_cause["unexplained"]
        ],
        "checks": checks,
        "curvature_split": curvature,
        "steering": steering,
        "feedback": feedback,
        "figures": figs,
        "runs": {k: {kk: vv for kk, vv in r.items() if kk != "series"} for k, r in records.items()},
    }


def build_report(
    records: Mapping[str, dict],
    out_dir: str | os.PathLike,
    suite_info: Mapping | None = None,
    figures: bool = True,
) -> Path:
    """Write ``report.md``, ``report.json``, ``summary.md`` and figures into ``out_dir``.

    Parameters
    ----------
    records : mapping
        Run key -> record, as :func:`run_suite` returns (missing runs are shown as "not run").
    out_dir : path
        Created if needed.
    suite_info : mapping, optional
        Wall time, workers, command, ... (written to the report's header and JSON).
    figures : bool
        Also draw the PNG figures (matplotlib).

    Returns
    -------
    Path
        The ``report.md`` written.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    info = dict(suite_info or {})
    rows, by_cause = explain_cells(records)
    steering = steering_rows(records)
    feedback = feedback_rows(records)
    curvature = curvature_rows(records)
    checks = check_rows(rows, steering, feedback)
    figs = draw_figures(records, rows, steering, out) if figures else []

    md = ["# The paper's Tables 1-5 in contact physics", ""]
    md += [
        f"Made by `{info.get('command', COMMAND)}`: {info.get('runs', len(records))} runs "
        f"({info.get('unique_runs', '?')} distinct), {info.get('workers', '?')} worker(s), "
        f"{fmt(info.get('wall_time_s'), 3)} s. Every number below is in `report.json` with "
        "the full configuration of its run (section *Runs* lists them).",
        "",
        "## Checks",
        "",
    ]
    md += [f"- [{'x' if c['passed'] else ' '}] {c['check']}: {c['detail']}" for c in checks]
    md += ["", "## Setup common to all runs", "", *suite_setup_lines(SUITE_SEED), ""]
    md += ["## Tables 1-5: paper, reduced model, MuJoCo", ""]
    md += [
        f"A cell is flagged when ours / paper is above {FACTOR:g} or below 1/{FACTOR:g}; the "
        "last column gives the ratio and the causes (next section), each backed by runs that "
        "isolate it.",
        "",
    ]
    md += _paper_tables(rows, records)
    if "fig_ratios.png" in figs:
        md += ["![ours / paper for every cell](fig_ratios.png)", ""]

    md += _causes_section(records, by_cause)

    md += _curvature_section(records, curvature, figs)

    md += _steering_section(steering, figs)

    md += _feedback_section(feedback, figs)

    md += ["## Runs", ""]
    md += [
        "Every run with its configuration (seed "
        f"{SUITE_SEED}, timestep and control period 1 ms unless listed under 'other'). Runs "
        "with identical scenarios were simulated once. Full configurations, including the "
        "resolved parameters, are in `report.json`.",
        "",
        *config_markdown(records),
        "",
    ]
    report = out / "report.md"
    atomic_write(report, "\n".join(md) + "\n")

    summary = _summary_markdown(rows, records, steering, feedback, checks, info)
    atomic_write(out / "summary.md", summary)
    payload = _payload(info, rows, by_cause, checks, (curvature, steering, feedback), figs, records)
    atomic_write(
        out / "report.json",
        json.dumps(json_safe(payload), indent=1, sort_keys=False, allow_nan=False),
    )
    return report


STEERING_NOTES = [
    "Notes. (i) The paper's eta = 3 jackknifes driving forward on every path within about "
    "1 s, on both plants (docs/model.md Section 3). Reversing, trailer first, it is stable in the "
    "reduced model and P0 leads on a wider circle (the analytic off-track); in MuJoCo the "
    "reversing S-curve slips at the curvature step and jackknifes unless the friction is "
    "raised (the friction-3 row). With the paper's disturbance as unbounded matched torques "
    "g^-1 Delta, the reversing circle jackknifes on both plants: those torques grow with "
    "1/cos(beta) far past the 15 N m a wheel motor has, and drive the articulation "
    "themselves; bounded at the actuator limit (the default), the same run tracks. (ii) "
    "eta = -3 runs in the reduced model but jackknifes in MuJoCo at the "
    "cycloid's start and after the S-curve's curvature step: the strongly counter-steered "
    "trailer axle asks for more lateral tyre force than the contact gives (lateral slip "
    "column); friction 3 cures the cycloid, not the S-curve. (iii) (L - L0)/(L + L0) = -1/7 "
    "is the exact small-curvature same-path gain and the project's same_path default "
    "(`params.same_path_eta`); the half-difference -(L0 - L)/(2 L0) = -0.125 leaves the analytic "
    "2.9 mm "
    "at R = 1.5 m and 4.8 mm at R = 1 m, "
    "-1/7 leaves 0.27 mm and 0.92 mm, the scheduled exact gain 0 (the measured steady-arc "
    "values agree). (iv) Over a whole S-curve run the off-tracking is dominated by transients "
    "that no steering gain removes: at the curvature step the articulation has to swing from "
    "one steady value to the other (and at the start build up from 0), and P0 cuts across "
    "meanwhile (max off-track about 6 cm for every stable gain). On the steady arcs the "
    "same-path designs win by the analytic factors.",
]


FEEDBACK_NOTES = [
    "Speed tracking is untouched (v_d is not modified) and e_omega rises only by the "
    "correction the yaw loop now follows. The S-curve's residual cross-track error is the "
    "curvature step: the yaw loop needs a few tenths of a second to follow the jump in omega_d "
    "and the feedback then pulls P back. On the S-curve the paper's lateral metric hardly "
    "moves: with noise the speed loop, which has no position feedback, lets P run about 8 cm "
    "ahead of the reference by the end, past the path's last point, and the distance to that "
    "point counts as 'lateral'; the cross-track columns measure against the path's "
    "continuation instead. The same along-track lead, no longer masked by a sideways offset, "
    "is why the position RMSE there rises. Along-track position is not fed back.",
]


def _summary_markdown(rows, records, steering, feedback, checks, info) -> str:
    """The section docs/paper.md carries (one heading level down there): the tables, the
    steering ratios and the path-feedback gains."""
    md = [
        "## The paper's results in contact physics",
        "",
        f"`{info.get('command', COMMAND)}` runs every scenario behind the paper's Tables 1-5 on "
        "the reduced model and on MuJoCo, with isolation runs, a steering study and a path "
        f"feedback study ({info.get('runs', '?')} runs, {fmt(info.get('wall_time_s'), 3)} s "
        f"on {info.get('workers', '?')} worker(s)), and writes `report.md` (with the reason for "
        "every difference beyond a factor of two), `report.json` and figures. All table runs "
        "use the same-path steering gain (the paper's eta = 3 jackknifes forward) and seed "
        f"{SUITE_SEED}. Ratios ours / paper outside [0.5, 2] are flagged, with the causes "
        "(C1 wheel slip, C2 gain set, C3 open-loop position error, C4 static-target mismatch, "
        "C5 yaw reference at t = 0) explained in the report.",
        "",
    ]
    md += _paper_tables(rows, records)
    md += ["### Passive steering: trailer off-tracking (m, rms over the run / on steady arcs)", ""]
    md += [
        "| path | plant | plain eta = 0 | half-difference -0.125 | same_path -1/7 | scheduled "
        "| path schedule | eta = -3 | eta = 3 forward | eta = 3 reverse |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    names = (
        "plain (eta = 0)",
        "half-difference gain (-0.125)",
        "same_path (-1/7)",
        "scheduled eta(kappa)",
        "path schedule eta(s)",
        "eta = -3",
        "paper eta = 3, forward",
        "paper eta = 3, reverse",
    )
    for path in STUDY_PATHS:
        for plant in PLANTS:
            cells = []
            for name in names:
                r = steering_row(steering, path, plant, name)
                if r is None:
                    cells.append("—")
                elif r["status"] == "jackknife":
                    cells.append(f"jackknife {fmt(r['end_time_s'], 2)} s")
                else:
                    cells.append(
                        f"{fmt(r['offtrack_rms'], 2)} / {fmt(r['offtrack_steady_rms'], 2)}"
                    )
            md.append(f"| {path} | {PLANT_LABEL[plant]} | " + " | ".join(cells) + " |")
    md += ["", *BEYOND_THE_TABLES, ""]
    md += ["### Path feedback (paper disturbances, 20 dB noise unless stated)", ""]
    md += feedback_markdown(feedback, ("rmse_lateral", "cross_track_rms", "rmse_v"))
    md += ["", "Checks:", ""]
    md += [f"- [{'x' if c['passed'] else ' '}] {c['check']}: {c['detail']}" for c in checks]
    md += ["", *FULL_REPORT]
    return "\n".join(md) + "\n"


#: What the summary says of the two steering studies beyond the table (their figures are on
#: their own pages, which their scripts write).
BEYOND_THE_TABLES = (
    "`--eta path` (the table's \"path schedule\" column) schedules every trailer's gain along",
    "the path from its geometry, eta_k(s), looked up at the trailer's own arc length: it keeps",
    "every axle of a train on the circle and the cycloid, and where a passive axle cannot follow",
    "(the S-curve's inflection) it is bounded to |eta| <= 3. Per trailer, for trains of one to",
    "three, with and without the paper's disturbance (and where the torque limit binds):",
    "docs/model.md Section 13 and `docs/path_schedule_study.md`.",
    "",
    "`--reverse` backs the train up: the last trailer's axle tracks the path and a cascade on",
    "the hitch angles sets the tractor's yaw rate (`controllers/backing.py`;",
    '`--no-hitch-feedback` leaves the hitches to themselves, as the table\'s "eta = 3 reverse"',
    "column does): docs/model.md Section 14, `docs/backing_study.md` and",
    "`docs/backing_roa.md`.",
)
FULL_REPORT = (
    "The full report, with the exact configuration of every run, the isolation runs behind each",
    "cause, and the curvature-error split of the paper's eq. 37-39 (the e_omega / v part and the",
    "static target's mismatch part, plotted in `fig_curvature_split.png`), is",
    "`renders/paper/report.md`.",
)

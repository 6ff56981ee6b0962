"""Markdown pieces of the report: the tables, the studies' tables, the configurations."""

from __future__ import annotations

import json

from tt_mujoco.outputs import json_safe
from tt_mujoco.paper.studies import row_pair
from tt_mujoco.paper.suite import (
    FEEDBACK_CASES,
    PLANT_LABEL,
    PLANTS,
    STEERING_VARIANTS,
    STUDY_PATHS,
    TABLE_3_CONTROLLERS,
    TABLE_TITLES,
)
from tt_mujoco.paper.values import fmt, metric_of
from tt_mujoco.sim import Scenario


def _cell_text(entry) -> str:
    if entry["status"] in ("not run", "error"):
        return entry["status"]
    text = fmt(entry["value"])
    if entry["status"] != "ok":
        text += f" ({entry['status']})"
    return text


def _why_text(row) -> str:
    parts = []
    for plant in PLANTS:
        e = row[plant]
        if e["flagged"]:
            why = ", ".join(e["causes"]) or "**unexplained**"
            parts.append(f"{PLANT_LABEL[plant]} x{fmt(e['ratio'], 2)}: {why}")
    return "; ".join(parts)


def tables_markdown(rows, with_why: bool = True) -> list[str]:
    out = []
    for table, title in TABLE_TITLES.items():
        out += [f"### {title}", ""]
        head = "| case | quantity | paper | reduced | MuJoCo |"
        sep = "|---|---|---|---|---|"
        if with_why:
            head += " > 2x off: why |"
            sep += "---|"
        out += [head, sep]
        for row in (r for r in rows if r["table"] == table):
            line = (
                f"| {row['case']} | {row['quantity']} | {fmt(row['paper'])} | "
                f"{_cell_text(row['reduced'])} | {_cell_text(row['mujoco'])} |"
            )
            if with_why:
                line += f" {_why_text(row)} |"
            out.append(line)
        out.append("")
    return out


def steering_markdown(steering) -> list[str]:
    out = [
        "| path | steering | plant | status | off-track rms / max (m) | steady-arc rms (m) "
        "| analytic steady (m) | trailer to reference rms / max (m) | max phi (deg) "
        "| max lateral slip (m/s) |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    order = {name: i for i, name in enumerate(STEERING_VARIANTS)}
    for r in sorted(
        steering,
        key=lambda r: (
            STUDY_PATHS.index(r["path"]),
            order.get(r["variant"], len(order)),
            r["label"],
            PLANTS.index(r["plant"]),
        ),
    ):
        name = r["variant"] + (f", {r['label']}" if r["label"] else "")
        status = r["status"]
        if status == "jackknife":
            status = f"jackknife at {fmt(r['end_time_s'], 3)} s"
        out.append(
            f"| {r['path']} | {name} | {PLANT_LABEL[r['plant']]} | {status} | "
            f"{fmt(r['offtrack_rms'])} / {fmt(r['offtrack_max'])} | "
            f"{fmt(r['offtrack_steady_rms'])} | {fmt(r['analytic_steady'])} | "
            f"{fmt(r['trailer_rmse_lateral'])} / {fmt(r['trailer_max_lateral'])} | "
            f"{fmt(r['phi_max_abs_deg'], 3)} | {fmt(r['slip_lateral_max'], 3)} |"
        )
    return out


#: The path-feedback table's columns, metric -> header; each cell reads "off -> on".
FEEDBACK_COLUMNS = {
    "rmse_lateral": "lateral RMSE off -> on (m)",
    "max_lateral": "max lateral off -> on (m)",
    "cross_track_rms": "cross-track RMS off -> on (m)",
    "cross_track_max": "cross-track max off -> on (m)",
    "rmse_v": "e_v RMSE off -> on (m/s)",
    "rmse_omega": "e_omega RMSE off -> on (rad/s)",
    "rmse_position": "position RMSE off -> on (m)",
}


def feedback_markdown(feedback, metrics=tuple(FEEDBACK_COLUMNS)) -> list[str]:
    """The path-feedback study, one row a case and plant with both runs done; ``metrics``
    picks and orders the columns (keys of :data:`FEEDBACK_COLUMNS`)."""
    out = [
        "| case | plant | " + " | ".join(FEEDBACK_COLUMNS[m] for m in metrics) + " |",
        "|---|---|" + "---|" * len(metrics),
    ]
    for case in FEEDBACK_CASES:
        for plant in PLANTS:
            off, on = row_pair(feedback, case, plant)
            if off and on:
                cells = " | ".join(f"{fmt(off[m])} -> {fmt(on[m])}" for m in metrics)
                out.append(f"| {case} | {PLANT_LABEL[plant]} | {cells} |")
    return out


def config_markdown(records) -> list[str]:
    cols = (
        "plant",
        "traj",
        "target",
        "controller",
        "gains",
        "eta",
        "disturbance",
        "noise_snr_db",
        "param_scale",
        "duration",
        "start",
        "friction",
    )
    out = [
        "| run | " + " | ".join(cols) + " | other | status | wall (s) |",
        "|---|" + "---|" * (len(cols) + 3),
    ]
    defaults = Scenario().to_dict()
    for key, rec in records.items():
        sc = rec.get("scenario", {})
        cells = []
        for c in cols:
            value = sc.get(c)
            cells.append(json.dumps(value) if isinstance(value, dict) else _cfg(value))
        other = {
            k: v
            for k, v in sc.items()
            if k not in cols and k not in ("seed",) and v != json_safe(defaults.get(k))
        }
        out.append(
            f"| `{key}` | "
            + " | ".join(cells)
            + f" | {json.dumps(other) if other else ''} | {rec.get('status', 'not run')} | "
            f"{fmt(rec.get('wall_time_s'), 2)} |"
        )
    return out


def _cfg(value) -> str:
    if value is None:
        return "—"
    if isinstance(value, float):
        return fmt(value, 6)
    return str(value)


def suite_setup_lines(seed: int) -> list[str]:
    return [
        "- Paper: Wen, Chen, Zhou, *Axioms* 2026, 15, 598; its Tables 1-5 as in docs/model.md §10.",
        "- Plants: `reduced` = the exact reduced ODE (RK4, pure rolling); `MuJoCo` "
        "= the multibody model with tyre contact (docs/model.md §5). Timestep and control period "
        "1 ms on both.",
        "- Steering: **eta = same_path (-1/7)** in every table run. The paper uses eta = 3, "
        "which jackknifes driving forward within about 1 s (docs/model.md §3; steering study "
        "below), so its tables cannot have been produced with it in the stated convention.",
        "- Disturbance: the paper's Delta1, Delta2 (Section 6.1) as matched wheel torques "
        "(docs/model.md Section 8); noise: Gaussian, 20 dB SNR on measured v and omega; parameter "
        "uncertainty: plant masses and inertias x1.2 / x0.8, nominal model unchanged.",
        "- Cycloid: starts on the path (the paper's pose is 0.30 m off it, docs/paper-notes.md), "
        "dynamic target eq. (34), 3 pi/2 s. S-curve: the paper's 10 s (7.2 m of 9.42 m). "
        "Circle: 10 s.",
        "- Gains: ISMC-STA set 6.1 (lambda = diag(5, 6), eps = 0.005) for Tables 1, 2, 4, 5; "
        "Table 3 uses the comparison set 6.2 for ISMC-STA and the paper's PID and FBL gains.",
        "- 'lateral deviation' = P to the reference path (`rmse_lateral`); 'position error' = P "
        "to the reference point (`rmse_position`).",
        f"- Seed {seed} for every run; the same command gives the same numbers.",
    ]


#: The quantities of Table 3, in its order.
TABLE_3_METRICS = ("rmse_v", "rmse_omega", "max_abs_v", "max_abs_omega")


def baselines_markdown(records) -> list[str]:
    """Table 3 with the six controllers: the paper's three and the baselines, on both plants
    (ours only: the paper has no baseline columns)."""
    out = [
        "### Table 3 with the baselines (cycloid, paper disturbance; ours)",
        "",
        "Each cell is reduced / MuJoCo; Stanley, LQR and NMPC with their default gains "
        "(docs/controllers.md), the others as in Table 3.",
        "",
        "| controller | e_v RMSE (m/s) | e_omega RMSE (rad/s) | max abs e_v (m/s) "
        "| max abs e_omega (rad/s) | cross-track RMSE (m) |",
        "|---|---|---|---|---|---|",
    ]
    for name, run in TABLE_3_CONTROLLERS.items():
        cells = []
        for metric in (*TABLE_3_METRICS, "cross_track_rms"):
            pair = (fmt(metric_of(records, f"{run}@{plant}", metric)) for plant in PLANTS)
            cells.append(" / ".join(pair))
        out.append(f"| {name} | " + " | ".join(cells) + " |")
    return [*out, ""]

"""The studies' rows: curvature-error split, steering gains, path feedback, and the checks."""

from __future__ import annotations

import math

from tt_mujoco.paper.causes import split_of
from tt_mujoco.paper.suite import PLANTS
from tt_mujoco.paper.values import fmt, metric_of


def curvature_rows(records) -> list[dict]:
    """The eq. 37-39 split for the target comparison runs (tables, analysis, stiff-yaw FBL)."""
    cases = [
        ("cycloid", "dynamic", "cycloid_nominal", "ISMC-STA 6.1"),
        ("cycloid", "static", "cycloid_static", "ISMC-STA 6.1"),
        ("s_curve", "dynamic", "s_curve_dynamic", "ISMC-STA 6.1"),
        ("s_curve", "static", "s_curve_static", "ISMC-STA 6.1"),
        ("circle", "dynamic", "circle_dynamic", "ISMC-STA 6.1"),
        ("circle", "static", "circle_static", "ISMC-STA 6.1"),
        ("s_curve", "dynamic", "stiff_yaw_fbl:s_curve_dynamic", "FBL diag(8, 50)"),
        ("s_curve", "static", "stiff_yaw_fbl:s_curve_static", "FBL diag(8, 50)"),
        ("circle", "dynamic", "stiff_yaw_fbl:circle_dynamic", "FBL diag(8, 50)"),
        ("circle", "static", "stiff_yaw_fbl:circle_static", "FBL diag(8, 50)"),
    ]
    rows = []
    for traj, target, base, ctrl in cases:
        for plant in PLANTS:
            key = f"{base}@{plant}"
            if key not in records:
                continue
            split = records[key].get("curvature_split") or {}
            rows.append(
                {
                    "path": traj,
                    "target": target,
                    "controller": ctrl,
                    "plant": plant,
                    "run": key,
                    "rmse_v": metric_of(records, key, "rmse_v"),
                    "rmse_lateral": metric_of(records, key, "rmse_lateral"),
                    **{k: split.get(k) for k in _SPLIT_KEYS},
                }
            )
    return rows


def curvature_findings(records) -> list[str]:
    """What the split table shows, with its numbers (MuJoCo runs)."""

    def lat(key):
        return metric_of(records, f"{key}@mujoco", "rmse_lateral")

    def share(key):
        return split_of(records, f"{key}@mujoco", "mismatch_share")

    def mism(key):
        return split_of(records, f"{key}@mujoco", "rms_mismatch")

    out = ["Findings (MuJoCo; the reduced model agrees):", ""]
    out.append(
        "- With ISMC-STA the speed loop holds e_v near 0.01 m/s, so the static target's "
        "mismatch only acts where v(t) leaves v_ref(t). Circle: it lives in the speed ramps "
        f"(RMS {fmt(mism('circle_static'), 2)} 1/m, share {fmt(share('circle_static'), 2)}) "
        f"and costs lateral RMSE {fmt(lat('circle_static'), 2)} m against "
        f"{fmt(lat('circle_dynamic'), 2)} m for the dynamic target. S-curve: "
        f"{fmt(lat('s_curve_static'), 2)} vs {fmt(lat('s_curve_dynamic'), 2)} m, the "
        "curvature step dominating both. Millimetres either way, below the along-track error "
        "that makes up the position error of Tables 4-5, so both targets give nearly the same "
        "table numbers."
    )
    out.append(
        "- Cycloid: static lateral RMSE "
        f"{fmt(lat('cycloid_static'), 2)} m vs dynamic {fmt(lat('cycloid_nominal'), 2)} m, "
        f"but the mismatch share is only {fmt(share('cycloid_static'), 2)}: the static error "
        "is e_omega / v at the start, where the eq. (32) yaw rate of -0.5 rad/s is a step for a "
        "vehicle whose yaw rate is 0."
    )
    ratios = []
    for traj in ("s_curve", "circle"):
        st, dy = lat(f"stiff_yaw_fbl:{traj}_static"), lat(f"stiff_yaw_fbl:{traj}_dynamic")
        ratios.append(
            f"{traj} {fmt(st, 3)} vs {fmt(dy, 3)} m (mismatch share "
            f"{fmt(share(f'stiff_yaw_fbl:{traj}_static'), 2)})"
        )
    out.append(
        "- With a loose speed loop and a tight yaw loop (FBL K = diag(8, 50), e_v ~ 0.5 m/s) the "
        "mismatch dominates the static target's curvature error and the dynamic target keeps "
        f"the path: lateral RMSE static vs dynamic {'; '.join(ratios)}. The paper's claim "
        "(eqs. 37-39) holds, under a condition its own tables do not show."
    )
    return out


_SPLIT_KEYS = (
    "rms_e_omega_over_v",
    "rms_mismatch",
    "mismatch_share",
    "heading_drift_e_omega_max",
    "heading_drift_mismatch_max",
)


def steering_rows(records) -> list[dict]:
    rows = []
    for key, rec in records.items():
        if rec.get("group") != "steering":
            continue
        off = rec.get("offtrack") or {}
        status = rec.get("status", "not run")
        rows.append(
            {
                "path": rec["info"]["path"],
                "variant": rec["info"]["variant"],
                "label": rec["info"].get("label", ""),
                "plant": key.rsplit("@", 1)[1],
                "run": key,
                "status": status,
                "end_time_s": off.get("end_time_s"),
                "offtrack_rms": off.get("offtrack_rms"),
                "offtrack_max": off.get("offtrack_max"),
                "offtrack_steady_rms": off.get("offtrack_steady_rms"),
                "analytic_steady": off.get("analytic_steady"),
                "trailer_rmse_lateral": metric_of(records, key, "trailer_rmse_lateral"),
                "trailer_max_lateral": metric_of(records, key, "trailer_max_lateral"),
                "phi_max_abs_deg": metric_of(records, key, "phi_max_abs_deg"),
                "slip_lateral_max": metric_of(records, key, "slip_lateral_max"),
            }
        )
    return rows


def steering_row(rows, path: str, plant: str, variant: str) -> dict | None:
    """The steering study's main (unlabelled) row for a path, plant and variant, or None."""
    return next(
        (
            r
            for r in rows
            if r["path"] == path
            and r["plant"] == plant
            and r["variant"] == variant
            and not r["label"]
        ),
        None,
    )


def steering_ratio(rows, path: str, plant: str, field_name: str) -> float:
    def get(variant):
        r = steering_row(rows, path, plant, variant)
        return None if r is None else r.get(field_name)

    plain, same = get("plain (eta = 0)"), get("same_path (-1/7)")
    if plain is None or same is None or not same:
        return math.nan
    return float(plain) / float(same)


def feedback_rows(records) -> list[dict]:
    rows = []
    for key, rec in records.items():
        if rec.get("group") != "feedback":
            continue
        cross = rec.get("cross_track") or {}
        rows.append(
            {
                "case": rec["info"]["case"],
                "feedback": rec["info"]["feedback"],
                "plant": key.rsplit("@", 1)[1],
                "run": key,
                "status": rec.get("status", "not run"),
                **{
                    m: metric_of(records, key, m)
                    for m in (
                        "rmse_lateral",
                        "max_lateral",
                        "rmse_v",
                        "rmse_omega",
                        "rmse_position",
                        "trailer_rmse_lateral",
                    )
                },
                "cross_track_rms": cross.get("rms"),
                "cross_track_max": cross.get("max"),
            }
        )
    return rows


def row_pair(rows, case, plant):
    got = {r["feedback"]: r for r in rows if r["case"] == case and r["plant"] == plant}
    return got.get("off"), got.get("on")


def check_rows(rows_cells, steering, feedback) -> list[dict]:
    """The issue's acceptance points, evaluated on this report's numbers."""
    checks = []
    complete = all(
        r[p]["status"] == "ok" and math.isfinite(r[p]["value"]) for r in rows_cells for p in PLANTS
    )
    checks.append(
        {
            "check": "every cell of Tables 1-5 has paper, reduced and MuJoCo values",
            "passed": complete,
            "detail": f"{len(rows_cells)} cells",
        }
    )
    for path in ("circle", "s_curve"):
        full = steering_ratio(steering, path, "mujoco", "offtrack_rms")
        steady = steering_ratio(steering, path, "mujoco", "offtrack_steady_rms")
        detail = f"whole run x{fmt(full, 3)}, steady arcs x{fmt(steady, 3)}"
        if not full >= 5.0 and steady >= 5.0:
            detail += (
                " (not over the whole run: the transients at the start and at the curvature "
                "step dominate it and no steering gain removes them; see the steering notes)"
            )
        checks.append(
            {
                "check": f"{path}, MuJoCo: plain-trailer / same_path off-tracking >= 5",
                "passed": bool(full >= 5.0),
                "detail": detail,
            }
        )
    for case in ("cycloid, no noise", "cycloid"):
        off, on = row_pair(feedback, case, "mujoco")
        if off and on:
            ok = on["rmse_lateral"] < 0.005 and on["rmse_v"] <= 1.02 * off["rmse_v"]
            detail = (
                f"rmse_lateral {fmt(off['rmse_lateral'])} -> {fmt(on['rmse_lateral'])} m "
                f"(paper 0.0368), rmse_v {fmt(off['rmse_v'])} -> {fmt(on['rmse_v'])} m/s"
            )
        else:
            ok, detail = False, "not run"
        checks.append(
            {
                "check": f"path feedback, {case}, MuJoCo: rmse_lateral < 0.005 m, rmse_v not "
                "raised (<= +2 %)",
                "passed": ok,
                "detail": detail,
            }
        )
    return checks

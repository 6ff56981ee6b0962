"""Why a number differs from the paper's by more than a factor of two: causes C1-C5."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

from tt_mujoco.paper.suite import CELLS, FACTOR, PLANT_LABEL, PLANTS, TABLE_RUNS, Cell
from tt_mujoco.paper.values import fmt, metric_of


# --- the report ---------------------------------------------------------------------------------
def _ratio(ours: float, paper: float) -> float:
    return ours / paper if (math.isfinite(ours) and paper) else math.nan


def _flagged(ratio: float) -> bool:
    return math.isfinite(ratio) and (ratio > FACTOR or ratio < 1.0 / FACTOR)


@dataclass(frozen=True)
class Cause:
    """A reason why a cell differs from the paper, with the runs that isolate it.

    ``applies(cell, plant, records)`` decides whether it explains a flagged cell;
    ``describe(cells, records)`` writes its section (markdown) from the isolation runs.
    """

    code: str
    title: str
    kind: str  # "contact effect", "paper inconsistency" or "model difference"
    applies: Callable
    describe: Callable


def _run_status(records, key) -> str:
    rec = records.get(key)
    return rec.get("status", "not run") if rec else "not run"


def _applies_traction(cell: Cell, plant: str, records) -> bool:
    if plant != "mujoco":
        return False
    iso = f"{cell.run}~mu3@mujoco"
    if iso not in records:
        return False
    mj = metric_of(records, f"{cell.run}@mujoco", cell.metric)
    red = metric_of(records, f"{cell.run}@reduced", cell.metric)
    slip = metric_of(records, f"{cell.run}@mujoco", "slip_longitudinal_max")
    # MuJoCo too high where the reduced model is not, with the wheels slipping.
    return mj > FACTOR * cell.paper and mj > 1.5 * red and slip > 0.1


def _describe_traction(cells, records) -> str:
    lines = [
        "MuJoCo's tyres have a friction limit the reduced model does not: about 88 N of normal "
        "load per tractor wheel (docs/model.md §5). On the cycloid the dynamic target asks for "
        "1.85 m/s^2 at t = 0 while the matched disturbance steps to 4 m/s^2 (Delta1(0) = 3.5 + "
        "0.5) before the controller's integral terms have built up: the wheels spin up "
        "(longitudinal slip in the table) and the error transient is larger and longer. The "
        "isolating runs repeat each scenario in MuJoCo with friction coefficient 3 instead of 1 "
        "(nothing else changed): the MuJoCo numbers then fall onto the reduced model's.",
        "",
        "| run | quantity | paper | MuJoCo (mu = 1) | max slip (m/s) | MuJoCo (mu = 3) | reduced |",
        "|---|---|---|---|---|---|---|",
    ]
    for cell, _ in cells:
        base = f"{cell.run}@mujoco"
        lines.append(
            f"| `{cell.run}` | {cell.quantity} | {fmt(cell.paper)} | "
            f"{fmt(metric_of(records, base, cell.metric))} | "
            f"{fmt(metric_of(records, base, 'slip_longitudinal_max'), 3)} | "
            f"{fmt(metric_of(records, f'{cell.run}~mu3@mujoco', cell.metric))} | "
            f"{fmt(metric_of(records, f'{cell.run}@reduced', cell.metric))} |"
        )
    return "\n".join(lines)


def _applies_gains(cell: Cell, plant: str, records) -> bool:
    iso = f"{cell.run}~gains_6_2@{plant}"
    if iso not in records:
        return False
    ours = _ratio(metric_of(records, f"{cell.run}@{plant}", cell.metric), cell.paper)
    alt = _ratio(metric_of(records, iso, cell.metric), cell.paper)
    # Ours too low, and the 6.2 set brings it at least 1.5 times closer.
    return (
        ours < 1.0 / FACTOR
        and math.isfinite(alt)
        and abs(math.log(alt)) < abs(math.log(ours)) - math.log(1.5)
    )


def _describe_gains(cells, records) -> str:
    ismc_max_v = fmt(metric_of(records, "cycloid_ismc_6_2@reduced", "max_abs_v"))
    lines = [
        "The paper gives two ISMC-STA gain sets: Section 6.1 (lambda = diag(5, 6), "
        'eps = 0.005), which it states for Tables 1-2 and, in Section 6.3 ("controller '
        'settings remain identical to those in the cycloidal trajectory case"), for Tables 4-5; '
        "and the comparison set of Section 6.2 (lambda = diag(5, 0.3), eps = 0.02) for Table 3. "
        "Yet Table 3's ISMC-STA row repeats Table 1's nominal row digit for digit "
        "(0.0147 / 0.0224), and several numbers fit the 6.2 set, not the 6.1 set: Table 3's "
        f"max |e_v| 0.0971 (ours with 6.2: {ismc_max_v}, "
        f"with 6.1: {fmt(metric_of(records, 'cycloid_nominal@reduced', 'max_abs_v'))}), and "
        f"the circle's e_v 0.0131 and max position 0.0174 (ours with 6.2: "
        f"{fmt(metric_of(records, 'circle_dynamic~gains_6_2@reduced', 'rmse_v'))} and "
        f"{fmt(metric_of(records, 'circle_dynamic~gains_6_2@reduced', 'max_position'))}). The "
        "small yaw-channel lambda = 0.3 lets more of the yaw disturbance through, hence the "
        "larger e_omega, and it undoes the resulting heading error 20 times more slowly (C3), "
        "hence the larger lateral and position errors. The isolating runs repeat each scenario "
        "with the 6.2 set, nothing else changed:",
        "",
        "| run | plant | quantity | paper | ours, set 6.1 | ours, set 6.2 |",
        "|---|---|---|---|---|---|",
    ]
    for cell, plant in cells:
        lines.append(
            f"| `{cell.run}` | {PLANT_LABEL[plant]} | {cell.quantity} | {fmt(cell.paper)} | "
            f"{fmt(metric_of(records, f'{cell.run}@{plant}', cell.metric))} | "
            f"{fmt(metric_of(records, f'{cell.run}~gains_6_2@{plant}', cell.metric))} |"
        )
    lines += [
        "",
        "The S-curve is the exception: with the 6.2 set its curvature step costs e_omega "
        f"{fmt(metric_of(records, 's_curve_dynamic~gains_6_2@reduced', 'rmse_omega'))} rad/s and "
        "a position error of "
        f"{fmt(metric_of(records, 's_curve_dynamic~gains_6_2@reduced', 'rmse_position'))} m "
        "(paper: 0.0514 and 0.0091), so Table 4 fits the 6.1 set better. Which set produced "
        "which table cannot be settled from the text.",
    ]
    return "\n".join(lines)


_POSITION_METRICS = ("rmse_lateral", "rmse_position", "max_position")


def _applies_open_loop(cell: Cell, plant: str, records) -> bool:
    ours = metric_of(records, f"{cell.run}@{plant}", cell.metric)
    return cell.metric in _POSITION_METRICS and ours < cell.paper / FACTOR


def split_of(records, key, name):
    rec = records.get(key) or {}
    value = (rec.get("curvature_split") or {}).get(name)
    return math.nan if value is None else float(value)


def _describe_open_loop(cells, records) -> str:
    lines = [
        "Neither target feeds position back (eqs. 32-34). With omega_d = kappa v the heading "
        "error relative to the path is the integral of e_omega (plus the target's mismatch, "
        "zero for the dynamic target), and the lateral deviation is that heading error "
        "integrated once more along the path; the along-track part of the position error is "
        "int e_v dt. Position errors therefore measure the low-frequency content of e_v and "
        "e_omega, not their RMS. ISMC-STA's integral sliding surface S = e + lambda int e "
        "drives int e itself back to zero at the rate lambda once S = 0: with the 6.1 set "
        "(lambda_omega = 6) the heading error that the disturbance step at t = 0 causes is "
        "undone within a second; with the 6.2 set (lambda_omega = 0.3) it lingers for the whole "
        "run and the lateral deviation is an order of magnitude larger (C2; end-of-run heading "
        "errors in the table). The isolating runs switch the disturbance off, nothing else "
        "changed: on the cycloid and the circle the position errors then all but vanish, so "
        "they are the integrated disturbance transient (in MuJoCo plus the start's wheel slip, "
        "C1); on the S-curve they stay, because there they come from the yaw loop's lag at "
        "the curvature step, which is not a disturbance effect (C4 compares the targets). The "
        "paper's "
        "0.0368 m would need a heading error of about 0.013 rad held over the 5 m driven "
        "(e_y ~ delta s, RMS ~ 2.9 delta). The path-feedback study below removes such errors by "
        "closing the loop on position.",
        "",
        "| run | plant | quantity | paper | ours | heading error int e_omega dt: max / end "
        "(rad) | ours, no disturbance | ours, set 6.2 | set 6.2: max / end (rad) |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for cell, plant in cells:
        key = f"{cell.run}@{plant}"
        nodist = _nodist_twin(cell, plant)
        alt = f"{cell.run}~gains_6_2@{plant}"
        lines.append(
            f"| `{cell.run}` | {PLANT_LABEL[plant]} | {cell.quantity} | {fmt(cell.paper)} | "
            f"{fmt(metric_of(records, key, cell.metric))} | {_drift(records, key)} | "
            f"{fmt(metric_of(records, nodist, cell.metric))} | "
            f"{fmt(metric_of(records, alt, cell.metric))} | "
            f"{_drift(records, alt) if alt in records else '—'} |"
        )
    return "\n".join(lines)


def _drift(records, key: str) -> str:
    top = split_of(records, key, "heading_drift_e_omega_max")
    end = split_of(records, key, "heading_drift_e_omega_end")
    return f"{fmt(top, 2)} / {fmt(end, 2)}"


def _nodist_twin(cell: Cell, plant: str) -> str:
    """The no-disturbance isolation run for a cell: its own path's reference scenario."""
    base = {"circle": "circle_dynamic", "s_curve": "s_curve_static"}
    traj = TABLE_RUNS[cell.run]["traj"]
    return f"{base.get(traj, 'cycloid_nominal')}~nodist@{plant}"


def _applies_static(cell: Cell, plant: str, records) -> bool:
    if not cell.run.endswith("_static"):
        return False
    dynamic = cell.run.replace("_static", "_dynamic")
    twin = next((c for c in CELLS if c.run == dynamic and c.metric == cell.metric), None)
    ours = metric_of(records, f"{cell.run}@{plant}", cell.metric)
    return twin is not None and cell.paper > 1.5 * twin.paper and ours < cell.paper / FACTOR


def _describe_static(cells, records) -> str:
    lines = [
        "Eq. (39) splits the static target's curvature error into e_omega / v and the mismatch "
        "(omega_d - v kappa_d) / v. The mismatch needs a speed error: with v = v_ref and "
        "s = s_ref it is zero. Our ISMC-STA rejects the matched disturbance in the v channel "
        "(e_v RMS about 0.01 m/s, as in the paper), so on the S-curve the mismatch is small "
        "and static and dynamic targets give nearly the same errors (split measured in the "
        "analysis section). The paper reports equal speed errors for both targets (0.0137 vs "
        "0.0131 m/s) and yet a three times larger static position error; eq. (39) cannot give "
        "that. The isolating runs make the speed error large on purpose while keeping the yaw "
        "loop tight: FBL with K = diag(8, 50), so e_v ~ Delta1 / 8 ~ 0.5 m/s. Then the static "
        "target's mismatch dominates and its lateral deviation is many times the dynamic "
        "target's, as eqs. (37)-(39) predict:",
        "",
        "| path | plant | target | e_v RMSE | e_omega RMSE | lateral RMSE (m) "
        "| RMS e_omega/v | RMS mismatch (1/m) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for traj in ("s_curve", "circle"):
        for plant in PLANTS:
            for target in ("dynamic", "static"):
                key = f"stiff_yaw_fbl:{traj}_{target}@{plant}"
                lines.append(
                    f"| {traj} | {PLANT_LABEL[plant]} | {target} | "
                    f"{fmt(metric_of(records, key, 'rmse_v'))} | "
                    f"{fmt(metric_of(records, key, 'rmse_omega'))} | "
                    f"{fmt(metric_of(records, key, 'rmse_lateral'))} | "
                    f"{fmt(split_of(records, key, 'rms_e_omega_over_v'))} | "
                    f"{fmt(split_of(records, key, 'rms_mismatch'))} |"
                )
    return "\n".join(lines)


def _applies_static_start(cell: Cell, plant: str, records) -> bool:
    iso = f"{cell.run}~static_target@{plant}"
    ours = _ratio(metric_of(records, f"{cell.run}@{plant}", cell.metric), cell.paper)
    return cell.metric == "max_abs_omega" and iso in records and ours < 1.0 / FACTOR


def _describe_static_start(cells, records) -> str:
    # Both comparison controllers, on the reduced model (MuJoCo adds the start's slip, C1).
    cells = [(c, "reduced") for c in CELLS if c.table == 3 and c.metric == "max_abs_omega"]
    cells = [(c, p) for c, p in cells if c.run != "cycloid_ismc_6_2"]
    lines = [
        "The paper's maximum yaw-rate errors for PID (0.5585) and FBL (0.5155) sit just above "
        "0.5 rad/s, the magnitude of the static cycloid target's constant yaw rate (eq. 32). "
        "Section 6.2 says all controllers track the dynamic target, whose omega_d = kappa v "
        "starts at 0 with the vehicle; then nothing forces a 0.5 rad/s error. A static target "
        "does: it asks for -0.5 rad/s at t = 0 while the vehicle's yaw rate is 0. The isolating "
        "runs swap only the target kind:",
        "",
        "| run | plant | paper max e_omega | ours, dynamic target | ours, static target |",
        "|---|---|---|---|---|",
    ]
    for cell, plant in cells:
        lines.append(
            f"| `{cell.run}` | {PLANT_LABEL[plant]} | {fmt(cell.paper)} | "
            f"{fmt(metric_of(records, f'{cell.run}@{plant}', cell.metric))} | "
            f"{fmt(metric_of(records, f'{cell.run}~static_target@{plant}', cell.metric))} |"
        )
    lines.append(
        "\nSo the paper's Table 3 maxima were most likely taken from a run whose yaw reference "
        "started at 0.5 rad/s (a static target, or a dynamic one started at speed); the RMS "
        "values and max |e_v| fit the dynamic target."
    )
    return "\n".join(lines)


#: Causes in the order they are tried; a flagged cell lists every cause that applies.
CAUSES = (
    Cause("C1", "Wheel slip at the start", "contact effect", _applies_traction, _describe_traction),
    Cause(
        "C2",
        "Which ISMC-STA gain set the paper used",
        "paper inconsistency",
        _applies_gains,
        _describe_gains,
    ),
    Cause(
        "C3",
        "Position errors accumulate open loop from a small yaw residue",
        "model difference",
        _applies_open_loop,
        _describe_open_loop,
    ),
    Cause(
        "C4",
        "The static target's mismatch needs a speed error (eq. 39)",
        "paper inconsistency",
        _applies_static,
        _describe_static,
    ),
    Cause(
        "C5",
        "Table 3's maximum yaw errors fit a 0.5 rad/s initial yaw reference",
        "paper inconsistency",
        _applies_static_start,
        _describe_static_start,
    ),
)


def unique_cells(cells: list) -> list:
    """(cell, plant) pairs without repeats of the same run, metric and plant (Table 2's
    first row is Table 1's nominal row)."""
    seen, out = set(), []
    for cell, plant in cells:
        if (cell.run, cell.metric, plant) not in seen:
            seen.add((cell.run, cell.metric, plant))
            out.append((cell, plant))
    return out


def explain_cells(records) -> tuple[list[dict], dict[str, list]]:
    """Every table cell with values, ratios and, where flagged, the causes that apply.

    Returns
    -------
    rows : list of dict
        One per :data:`CELLS` entry: ``table, case, quantity, metric, paper, run`` and per plant
        ``value``, ``ratio``, ``flagged``, ``causes`` (codes), ``status``.
    by_cause : dict
        Cause code -> list of ``(cell, plant)`` it explains; ``"unexplained"`` -> the rest.
    """
    rows, by_cause = [], {c.code: [] for c in CAUSES}
    by_cause["unexplained"] = []
    for cell in CELLS:
        row = {
            "table": cell.table,
            "case": cell.case,
            "quantity": cell.quantity,
            "metric": cell.metric,
            "paper": cell.paper,
            "run": cell.run,
        }
        for plant in PLANTS:
            key = f"{cell.run}@{plant}"
            value = metric_of(records, key, cell.metric)
            ratio = _ratio(value, cell.paper)
            causes = []
            if _flagged(ratio):
                causes = [c.code for c in CAUSES if c.applies(cell, plant, records)]
                for code in causes:
                    by_cause[code].append((cell, plant))
                if not causes:
                    by_cause["unexplained"].append((cell, plant))
            row[plant] = {
                "value": value,
                "ratio": ratio,
                "flagged": _flagged(ratio),
                "causes": causes,
                "status": _run_status(records, key),
                "run": key,
            }
        rows.append(row)
    return rows, by_cause

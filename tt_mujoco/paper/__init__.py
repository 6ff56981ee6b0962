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

The runs go to a ``concurrent.futures.ProcessPoolExecutor`` (``--workers``, default 2) with a
progress bar; identical scenarios run once. The report (``report.md``, ``report.json``,
``summary.md`` for the README, figures) goes to ``renders/paper``, or to the first free
``renders/paper-N`` if that exists (never overwritten), or to ``--out DIR`` (new or empty).

All runs use seed :data:`SUITE_SEED` and the same-path steering preset (the paper's eta = 3
jackknifes driving forward, docs/model.md Section 3; the steering study shows it).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import os
import sys
import time
from collections.abc import Callable, Iterable, Mapping
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from tt_mujoco.outputs import atomic_write, claim_folder, json_safe
from tt_mujoco.sim import Scenario

__all__ = [
    "CAUSES",
    "CELLS",
    "PLANTS",
    "SUITE_SEED",
    "Cell",
    "RunSpec",
    "build_report",
    "curvature_split",
    "execute",
    "main",
    "run_suite",
    "suite",
]

#: Seed of every run (measurement noise); fixed so that the report is reproducible.
SUITE_SEED = 0
PLANTS = ("reduced", "mujoco")
PLANT_LABEL = {"reduced": "reduced", "mujoco": "MuJoCo"}
#: A cell is flagged when ours / paper is outside [1/FACTOR, FACTOR].
FACTOR = 2.0
#: Speeds below this (m/s) are left out of the curvature split (it divides by v).
V_MIN = 0.1
#: Distance (m) the trailer axle must be past a curvature change (or the start) for its
#: off-tracking to count as steady: the articulation settles over L0 / (1 - eta) = 0.36 m
#: (same-path) to 0.4 m (plain trailer) of travel, so 2 m leaves < 1 % of the transient.
SETTLE_DISTANCE = 2.0
#: Points kept per run for the figures.
SERIES_POINTS = 600
DEFAULT_OUT = Path("renders") / "paper"
COMMAND = "python -m tt_mujoco.paper"

# --- the paper's tables (docs/model.md Section 10; paper Tables 1-5)
# -----------------------------------
#: Scenario of each table row, without the plant. Tables 1-3 on the cycloid (Section 6.1-6.2),
#: Tables 4-5 on the S-curve and the circle (Section 6.3). Gain set "paper_6_1" (Section 6.1)
#: except Table 3's comparison set "paper_6_2"; the S-curve runs the paper's stated 10 s.
TABLE_RUNS: dict[str, dict] = {
    "cycloid_nominal": {"traj": "cycloid", "gains": "paper_6_1"},
    "cycloid_plus20": {"traj": "cycloid", "gains": "paper_6_1", "param_scale": 1.2},
    "cycloid_minus20": {"traj": "cycloid", "gains": "paper_6_1", "param_scale": 0.8},
    "cycloid_noise": {"traj": "cycloid", "gains": "paper_6_1", "noise_snr_db": 20.0},
    "cycloid_ismc_6_2": {"traj": "cycloid", "gains": "paper_6_2"},
    "cycloid_pid": {"traj": "cycloid", "controller": "pid", "gains": "paper_6_2"},
    "cycloid_fbl": {"traj": "cycloid", "controller": "fbl", "gains": "paper_6_2"},
    "s_curve_dynamic": {"traj": "s_curve", "gains": "paper_6_1", "duration": 10.0},
    "s_curve_static": {
        "traj": "s_curve",
        "target": "static",
        "gains": "paper_6_1",
        "duration": 10.0,
    },
    "circle_dynamic": {"traj": "circle", "gains": "paper_6_1"},
    "circle_static": {"traj": "circle", "target": "static", "gains": "paper_6_1"},
}

TABLE_TITLES = {
    1: "Table 1. Tracking performance (RMSE) under parameter uncertainties (cycloid)",
    2: "Table 2. Tracking performance (RMSE) under measurement noise (cycloid)",
    3: "Table 3. Comparison of controllers (cycloid, dynamic target)",
    4: "Table 4. Dynamic vs static target, S-curve (RMSE)",
    5: "Table 5. Dynamic vs static target, unit circle (RMSE)",
}

QUANTITY = {
    "rmse_v": "e_v RMSE (m/s)",
    "rmse_omega": "e_omega RMSE (rad/s)",
    "rmse_lateral": "lateral deviation RMSE (m)",
    "max_abs_v": "max abs e_v (m/s)",
    "max_abs_omega": "max abs e_omega (rad/s)",
    "rmse_position": "position error RMSE (m)",
    "max_position": "max position error (m)",
}


@dataclass(frozen=True)
class Cell:
    """One number of the paper's Tables 1-5 and the run that reproduces it."""

    table: int
    case: str
    metric: str
    paper: float
    run: str  # a key of TABLE_RUNS

    @property
    def quantity(self) -> str:
        return QUANTITY[self.metric]


def _cells() -> tuple[Cell, ...]:
    out = []
    t1 = {"rmse_v": (0.0147, 0.0157, 0.0146), "rmse_omega": (0.0224, 0.0284, 0.0216)}
    t1["rmse_lateral"] = (0.0368, 0.0352, 0.0397)
    for i, (case, run) in enumerate(
        (("Nominal", "cycloid_nominal"), ("+20 %", "cycloid_plus20"), ("-20 %", "cycloid_minus20"))
    ):
        out += [Cell(1, case, m, vals[i], run) for m, vals in t1.items()]
    t2 = {"rmse_v": (0.0147, 0.0165), "rmse_omega": (0.0224, 0.0269)}
    t2["rmse_lateral"] = (0.0368, 0.0484)
    for i, (case, run) in enumerate(
        (("Without noise", "cycloid_nominal"), ("20 dB Gaussian noise", "cycloid_noise"))
    ):
        out += [Cell(2, case, m, vals[i], run) for m, vals in t2.items()]
    t3 = {
        ("ISMC-STA", "cycloid_ismc_6_2"): (0.0147, 0.0224, 0.0971, 0.0659),
        ("PID", "cycloid_pid"): (0.3273, 0.2544, 0.6669, 0.5585),
        ("FBL", "cycloid_fbl"): (0.5247, 0.2699, 0.6172, 0.5155),
    }
    for (case, run), vals in t3.items():
        metrics = ("rmse_v", "rmse_omega", "max_abs_v", "max_abs_omega")
        out += [Cell(3, case, m, v, run) for m, v in zip(metrics, vals, strict=True)]
    t45 = {
        (4, "Dynamic", "s_curve_dynamic"): (0.0091, 0.0137, 0.0514, 0.0174),
        (4, "Static", "s_curve_static"): (0.0261, 0.0131, 0.0969, 0.0488),
        (5, "Dynamic", "circle_dynamic"): (0.0111, 0.0131, 0.0223, 0.0174),
        (5, "Static", "circle_static"): (0.0115, 0.0131, 0.0151, 0.0174),
    }
    for (table, case, run), vals in t45.items():
        metrics = ("rmse_position", "rmse_v", "rmse_omega", "max_position")
        out += [Cell(table, case, m, v, run) for m, v in zip(metrics, vals, strict=True)]
    return tuple(out)


#: Every number of the paper's Tables 1-5 (43 cells).
CELLS = _cells()

#: Variants used by the isolation runs (key suffix "~name").
VARIANTS = {
    "gains_6_2": {"gains": "paper_6_2"},
    "mu3": {"friction": 3.0},
    "nodist": {"disturbance": "none"},
    "static_target": {"target": "static"},
}
# (table run, variant, plants): the isolation runs the causes below read.
_ISOLATION = (
    *((b, "gains_6_2", PLANTS) for b in ("cycloid_nominal", "cycloid_plus20", "cycloid_minus20")),
    *((b, "gains_6_2", PLANTS) for b in ("cycloid_noise", "s_curve_dynamic", "s_curve_static")),
    *((b, "gains_6_2", PLANTS) for b in ("circle_dynamic", "circle_static")),
    *((b, "mu3", ("mujoco",)) for b in TABLE_RUNS if b.startswith("cycloid")),
    *((b, "nodist", PLANTS) for b in ("cycloid_nominal", "circle_dynamic", "s_curve_static")),
    *((b, "static_target", PLANTS) for b in ("cycloid_pid", "cycloid_fbl")),
)
#: FBL with a stiff yaw loop: e_v ~ Delta1 / k_v ~ 0.5 m/s while e_omega stays small, the
#: situation in which eq. (39)'s static mismatch term matters.
STIFF_YAW_GAINS = {"k_v": 8.0, "k_omega": 50.0}

# --- steering and path-feedback studies --------------------------------------------------------
STUDY_PATHS = ("cycloid", "s_curve", "circle")
#: Steering designs of the study (the study runs without the paper's disturbance: off-tracking is
#: geometry, and reversing with eta = 3 the matched disturbance torques alone exceed 15 N m).
STEERING_VARIANTS: dict[str, dict] = {
    "plain (eta = 0)": {"eta": 0.0},
    "paper eta = 3, forward": {"eta": "paper"},
    "paper eta = 3, reverse": {"eta": "paper", "reverse": True},
    "eta = -3": {"eta": -3.0},
    "half-difference gain (-0.125)": {"eta": -0.125},
    "same_path (-1/7)": {"eta": "same_path"},
    "scheduled eta(kappa)": {"eta": "same_path", "eta_schedule": True},
}
STEERING_BASE = {"controller": "ismc_sta", "gains": "paper_6_1", "disturbance": "none"}
#: Extra steering runs: (path, variant, overrides, plants, label).
STEERING_EXTRA = (
    ("circle", "paper eta = 3, reverse", {"disturbance": "matched"}, PLANTS, "with disturbance"),
    ("cycloid", "eta = -3", {"friction": 3.0}, ("mujoco",), "friction 3"),
    ("s_curve", "eta = -3", {"friction": 3.0}, ("mujoco",), "friction 3"),
    ("s_curve", "paper eta = 3, reverse", {"friction": 3.0}, ("mujoco",), "friction 3"),
)
FEEDBACK_CASES: dict[str, dict] = {
    "cycloid": {"traj": "cycloid", "gains": "paper_6_1", "noise_snr_db": 20.0},
    "s_curve": {"traj": "s_curve", "gains": "paper_6_1", "noise_snr_db": 20.0},
    "circle": {"traj": "circle", "gains": "paper_6_1", "noise_snr_db": 20.0},
    "cycloid, no noise": {"traj": "cycloid", "gains": "paper_6_1"},
    "cycloid, gains 6.2": {"traj": "cycloid", "gains": "paper_6_2", "noise_snr_db": 20.0},
    "cycloid, paper start pose": {"traj": "cycloid", "gains": "paper_6_1", "start": "paper"},
}


@dataclass
class RunSpec:
    """One run of the suite: a unique key, the group it reports in, and its scenario."""

    key: str
    group: str
    scenario: Scenario
    keep_series: bool = False
    info: dict = field(default_factory=dict)


def _scenario(plant: str, **kw) -> Scenario:
    base = {"plant": plant, "seed": SUITE_SEED, "eta": "same_path"}
    return Scenario(**{**base, **kw})


def suite(quick: bool = False) -> list[RunSpec]:
    """The runs of the report.

    Parameters
    ----------
    quick : bool
        A reduced set for tests and smoke checks: Table 1's nominal run on both plants, one
        steering and one path-feedback run, each cut to 0.5 s. The report still lists every
        cell of Tables 1-5 (the missing ones as "not run").
    """
    specs: list[RunSpec] = []
    if quick:
        short = {"duration": 0.5}
        for plant in PLANTS:
            sc = _scenario(plant, **{**TABLE_RUNS["cycloid_nominal"], **short})
            specs.append(RunSpec(f"cycloid_nominal@{plant}", "table", sc, True))
        sc = _scenario("reduced", traj="circle", **STEERING_BASE, **short)
        specs.append(
            RunSpec(
                "steer:circle:same_path (-1/7)@reduced",
                "steering",
                sc,
                info={"path": "circle", "variant": "same_path (-1/7)", "label": ""},
            )
        )
        sc = _scenario("reduced", **FEEDBACK_CASES["circle"], path_feedback={}, **short)
        specs.append(
            RunSpec(
                "fb:circle:on@reduced", "feedback", sc, True, {"case": "circle", "feedback": "on"}
            )
        )
        return specs

    for base, kw in TABLE_RUNS.items():
        for plant in PLANTS:
            specs.append(RunSpec(f"{base}@{plant}", "table", _scenario(plant, **kw), True))
    for base, variant, plants in _ISOLATION:
        for plant in plants:
            kw = {**TABLE_RUNS[base], **VARIANTS[variant]}
            specs.append(RunSpec(f"{base}~{variant}@{plant}", "isolation", _scenario(plant, **kw)))
    for traj in ("s_curve", "circle"):
        for target in ("dynamic", "static"):
            for plant in PLANTS:
                kw = {"traj": traj, "target": target, "controller": "fbl"}
                kw["gains"] = dict(STIFF_YAW_GAINS)
                if traj == "s_curve":
                    kw["duration"] = 10.0
                key = f"stiff_yaw_fbl:{traj}_{target}@{plant}"
                specs.append(RunSpec(key, "isolation", _scenario(plant, **kw), True))
    for plant in PLANTS:
        kw = {"traj": "cycloid", "target": "static", "gains": "paper_6_1"}
        specs.append(RunSpec(f"cycloid_static@{plant}", "analysis", _scenario(plant, **kw), True))
    for traj in STUDY_PATHS:
        for name, kw in STEERING_VARIANTS.items():
            for plant in PLANTS:
                sc = _scenario(plant, traj=traj, **STEERING_BASE, **kw)
                info = {"path": traj, "variant": name, "label": ""}
                specs.append(RunSpec(f"steer:{traj}:{name}@{plant}", "steering", sc, info=info))
    for traj, name, over, plants, label in STEERING_EXTRA:
        for plant in plants:
            kw = {**STEERING_BASE, **STEERING_VARIANTS[name], **over}
            info = {"path": traj, "variant": name, "label": label}
            key = f"steer:{traj}:{name}~{label}@{plant}"
            specs.append(RunSpec(key, "steering", _scenario(plant, traj=traj, **kw), info=info))
    for case, kw in FEEDBACK_CASES.items():
        for state in ("off", "on"):
            for plant in PLANTS:
                extra = {"path_feedback": {}} if state == "on" else {}
                sc = _scenario(plant, **kw, **extra)
                info = {"case": case, "feedback": state}
                specs.append(RunSpec(f"fb:{case}:{state}@{plant}", "feedback", sc, True, info))
    return specs


# --- per-run analysis (runs in the worker processes) -------------------------------------------
def curvature_split(ts: Mapping[str, np.ndarray], path, polyline, v_min: float = V_MIN) -> dict:
    """The paper's eqs. (37)-(39) measured along a run.

    With ``kappa_d`` the path curvature at the nearest path point of P, the curvature error of
    the driven path splits exactly into

        omega / v - kappa_d = e_omega / v + (omega_d / v - kappa_d),

    the yaw-tracking part (eq. 37, the only part a dynamic target leaves) and the target's
    mismatch part ((omega_d - v kappa_d) / v, eq. 39's static-target term; for the dynamic
    target it is only what separates the target's own s and measured v from the true ones).
    Samples with |v| < ``v_min`` are left out of the RMS values. The heading drifts are the
    same two parts without the 1/v: ``int (omega - omega_d) dt`` and
    ``int (omega_d - v kappa_d) dt`` (rad), defined at any speed.

    Returns
    -------
    dict
        ``rms_e_omega_over_v``, ``rms_mismatch``, ``rms_total`` (1/m), ``mismatch_share``
        (mismatch's share of the mean square), ``heading_drift_e_omega_max``,
        ``heading_drift_e_omega_end``, ``heading_drift_mismatch_max`` (rad), ``samples``,
        ``v_min``, and the arrays
        ``e_omega_over_v``, ``mismatch`` (NaN where |v| < v_min) under ``"series"``.
    """
    from scipy.integrate import cumulative_trapezoid

    from tt_mujoco.analysis.metrics import signed_lateral_error

    t, v, w, wd = (np.asarray(ts[k], dtype=float) for k in ("t", "v", "omega", "omega_d"))
    n = _finite_length(ts)
    t, v, w, wd = t[:n], v[:n], w[:n], wd[:n]
    out = {"v_min": v_min, "samples": 0}
    nan_keys = ("rms_e_omega_over_v", "rms_mismatch", "rms_total", "mismatch_share")
    out.update(dict.fromkeys(nan_keys, math.nan))
    drift_keys = ("heading_drift_e_omega_max", "heading_drift_e_omega_end")
    out.update(dict.fromkeys((*drift_keys, "heading_drift_mismatch_max"), math.nan))
    if n < 2:
        out["series"] = {"e_omega_over_v": np.full(n, np.nan), "mismatch": np.full(n, np.nan)}
        return out
    xy = np.column_stack([ts["x"][:n], ts["y"][:n]])
    _, s_near = signed_lateral_error(xy, polyline)
    kappa_d = np.asarray(path.curvature(s_near), dtype=float)
    fast = np.abs(v) >= v_min
    safe_v = np.where(fast, v, 1.0)
    e_part = np.where(fast, (w - wd) / safe_v, np.nan)
    m_part = np.where(fast, wd / safe_v - kappa_d, np.nan)
    drift_e = cumulative_trapezoid(w - wd, t, initial=0.0)
    drift_m = cumulative_trapezoid(wd - v * kappa_d, t, initial=0.0)
    out["samples"] = int(fast.sum())
    if fast.any():
        rms_e = float(np.sqrt(np.mean(e_part[fast] ** 2)))
        rms_m = float(np.sqrt(np.mean(m_part[fast] ** 2)))
        total = e_part[fast] + m_part[fast]
        out["rms_e_omega_over_v"], out["rms_mismatch"] = rms_e, rms_m
        out["rms_total"] = float(np.sqrt(np.mean(total**2)))
        denom = rms_e**2 + rms_m**2
        out["mismatch_share"] = rms_m**2 / denom if denom > 0 else math.nan
    out["heading_drift_e_omega_max"] = float(np.max(np.abs(drift_e)))
    out["heading_drift_e_omega_end"] = float(drift_e[-1])
    out["heading_drift_mismatch_max"] = float(np.max(np.abs(drift_m)))
    out["series"] = {"e_omega_over_v": e_part, "mismatch": m_part}
    return out


def _finite_length(ts: Mapping[str, np.ndarray]) -> int:
    cols = ("t", "x", "y", "v", "omega", "omega_d")
    bad = np.zeros(len(ts["t"]), dtype=bool)
    for c in cols:
        bad |= ~np.isfinite(np.asarray(ts[c], dtype=float))
    hits = np.flatnonzero(bad)
    return int(hits[0]) if hits.size else len(bad)


def _steady_mask(path, s_tractor: np.ndarray, reverse: bool, spacing: float) -> np.ndarray:
    """Samples at which the trailer has run on one constant curvature long enough to settle.

    ``s_tractor`` is P's arc length along the path (the target's s, which runs monotonically;
    a projection would jump where a path overlaps itself, as the circle's 1.02 laps do). The
    articulation starts to change when the *leading* axle meets a curvature change and settles
    over :data:`SETTLE_DISTANCE` of the follower's travel, so the window of constant curvature
    needed is ``[s - spacing, s + SETTLE_DISTANCE]`` reversing (P0 leads, ``spacing`` ahead at
    lower s) and ``[s - spacing - SETTLE_DISTANCE, s]`` driving forward (P leads). The run's
    start counts as a change, and the leader must be on the path (not on the straight
    continuation past its end). Paths whose curvature varies continuously have no steady arcs.
    """
    grid = np.arange(0.0, path.length + 1e-3, 1e-3)
    kappa = np.asarray(path.curvature(grid), dtype=float)
    changed = grid[np.flatnonzero(np.abs(np.diff(kappa)) > 1e-9) + 1]
    if changed.size > grid.size // 10:  # e.g. the cycloid: curvature changes everywhere
        return np.zeros(s_tractor.shape, dtype=bool)
    s_tractor = np.asarray(s_tractor, dtype=float)
    if reverse:
        lo, hi = s_tractor - spacing, s_tractor + SETTLE_DISTANCE
        free = (hi <= s_tractor[0]) & (lo >= 0.0)  # the leader stays on the path
    else:
        lo, hi = s_tractor - spacing - SETTLE_DISTANCE, s_tractor
        free = lo >= 0.0
    for c in changed:
        free &= ~((lo <= c) & (c <= hi))
    return free & (s_tractor >= 0.0) & (s_tractor <= path.length)


def _offtrack_summary(ts, path, scenario: Scenario, plant_params) -> dict:
    """Follower off-tracking (full run and steady arcs), jackknife time, analytic steady value."""
    from tt_mujoco.vehicle.steering import follower_offtrack, steady_offtrack

    n = _finite_length(ts)
    columns = {k: np.asarray(ts[k])[:n] for k in ("x", "y", "x0", "y0")}
    off = follower_offtrack(columns, reverse=scenario.reverse)
    have = ~np.isnan(off)
    out = {
        "offtrack_rms": float(np.sqrt(np.mean(off[have] ** 2))) if have.any() else math.nan,
        "offtrack_max": float(np.max(off[have])) if have.any() else math.nan,
        "offtrack_steady_rms": math.nan,
        "steady_samples": 0,
        "analytic_steady": math.nan,
        "end_time_s": float(ts["t"][n - 1]) if n else math.nan,
    }
    if n < 2:
        return out
    s_tractor = np.asarray(ts["s"][:n], dtype=float)
    spacing = plant_params.L + plant_params.L0
    steady = _steady_mask(path, s_tractor, scenario.reverse, spacing) & have
    if steady.any():
        out["offtrack_steady_rms"] = float(np.sqrt(np.mean(off[steady] ** 2)))
        out["steady_samples"] = int(steady.sum())
        if scenario.eta_schedule:
            out["analytic_steady"] = 0.0  # the exact same-path gain, by construction
        else:
            kappa = float(path.curvature(float(s_tractor[np.flatnonzero(steady)[0]])))
            out["analytic_steady"] = abs(steady_offtrack(kappa, plant_params))
    return out


def execute(key: str, scenario: Scenario, keep_series: bool = False) -> dict:
    """Run one scenario and reduce it to a record (metrics, analyses, optional series).

    Runs in a worker process. ``simulate`` never raises for a diverging run; any other
    exception is recorded as status ``"error"`` so that one bad run cannot stop the suite.
    """
    from tt_mujoco.analysis.metrics import signed_lateral_error
    from tt_mujoco.reference.targets import make_target
    from tt_mujoco.sim import simulate

    start = time.perf_counter()
    record = {"key": key, "scenario": json_safe(scenario.to_dict())}
    try:
        result = simulate(scenario)
        ts = result.timeseries
        polyline = result.reference_polyline
        path = make_target(
            scenario.traj, kind=scenario.target, duration=scenario.duration, start=scenario.start
        ).path
        split = curvature_split(ts, path, polyline)
        series_split = split.pop("series")
        n = _finite_length(ts)
        xy = np.column_stack([ts["x"][:n], ts["y"][:n]])
        cross, _ = signed_lateral_error(xy, polyline, extend_ends=True)
        plant_params = scenario.plant_params()
        record.update(
            status=result.status,
            message=result.message,
            metrics=result.metrics,
            config=result.config,
            curvature_split=split,
            offtrack=_offtrack_summary(ts, path, scenario, plant_params),
            cross_track={
                "rms": float(np.sqrt(np.mean(cross**2))) if n else math.nan,
                "max": float(np.max(np.abs(cross))) if n else math.nan,
            },
        )
        if keep_series and n >= 2:
            idx = np.unique(np.linspace(0, n - 1, min(n, SERIES_POINTS)).astype(int))
            lateral, _ = signed_lateral_error(xy[idx], polyline, extend_ends=True)
            cols = ("t", "x", "y", "x0", "y0", "v", "v_d", "omega", "omega_d")
            series = {c: np.asarray(ts[c])[idx] for c in cols}
            series["lateral"] = lateral
            series.update({k: v[idx] for k, v in series_split.items()})
            series["reference"] = polyline[:: max(1, len(polyline) // 400)]
            record["series"] = series
    except Exception as err:  # recorded, not raised: the report shows it
        record.update(status="error", message=f"{type(err).__name__}: {err}", metrics={})
    record["wall_time_s"] = time.perf_counter() - start
    return record


def _scenario_identity(scenario: Scenario) -> str:
    return json.dumps(json_safe(scenario.to_dict()), sort_keys=True)


def run_suite(
    specs: Iterable[RunSpec],
    workers: int = 2,
    progress: bool = True,
    runner: Callable = execute,
) -> dict[str, dict]:
    """Run specs in parallel (identical scenarios once) and return records by key.

    Parameters
    ----------
    specs : iterable of RunSpec
    workers : int
        Worker processes (``concurrent.futures.ProcessPoolExecutor``); 1 runs in this process.
    progress : bool
        Show a tqdm progress bar over the unique runs.
    runner : callable
        ``runner(key, scenario, keep_series) -> record`` (picklable; :func:`execute`).
    """
    specs = list(specs)
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise ValueError(f"workers={workers!r} is not allowed: it must be an integer >= 1")
    unique: dict[str, RunSpec] = {}
    alias: dict[str, str] = {}
    for spec in specs:
        ident = _scenario_identity(spec.scenario)
        if ident in unique:
            alias[spec.key] = unique[ident].key
            unique[ident].keep_series |= spec.keep_series
        else:
            unique[ident] = dataclasses.replace(spec)
            alias[spec.key] = spec.key
    todo = sorted(unique.values(), key=_expected_cost, reverse=True)  # long runs first
    from tqdm import tqdm

    bar = tqdm(total=len(todo), desc="paper suite", unit="run", disable=not progress)
    done: dict[str, dict] = {}
    try:
        if workers == 1:
            for spec in todo:
                done[spec.key] = runner(spec.key, spec.scenario, spec.keep_series)
                bar.update()
        else:
            import multiprocessing

            ctx = multiprocessing.get_context("spawn")  # no state inherited from this process
            with ProcessPoolExecutor(max_workers=workers, mp_context=ctx) as pool:
                futures = {
                    pool.submit(runner, s.key, s.scenario, s.keep_series): s.key for s in todo
                }
                for fut in as_completed(futures):
                    done[futures[fut]] = fut.result()
                    bar.update()
    finally:
        bar.close()
    records = {}
    for spec in specs:
        rec = dict(done[alias[spec.key]])
        rec.update(key=spec.key, group=spec.group, info=spec.info, same_as=alias[spec.key])
        records[spec.key] = rec
    return records


def _expected_cost(spec: RunSpec) -> float:
    sc = spec.scenario
    default = {"cycloid": 4.71, "s_curve": 13.78, "circle": 10.0}.get(sc.traj, 10.0)
    return (sc.duration or default) * (1.3 if sc.plant == "reduced" else 1.0)


# --- the report ---------------------------------------------------------------------------------
def _metric(records, key: str, metric: str) -> float:
    rec = records.get(key)
    if not rec or rec.get("status") == "error":
        return math.nan
    value = rec.get("metrics", {}).get(metric)
    return math.nan if value is None else float(value)


def _fmt(value, digits: int = 4) -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "—"
    if isinstance(value, int | np.integer):
        return str(int(value))
    value = float(value)
    if value == 0.0:
        return "0"
    if abs(value) >= 1e4:
        return f"{value:.{digits - 1}e}"
    return f"{value:.{digits}g}"


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
    mj = _metric(records, f"{cell.run}@mujoco", cell.metric)
    red = _metric(records, f"{cell.run}@reduced", cell.metric)
    slip = _metric(records, f"{cell.run}@mujoco", "slip_longitudinal_max")
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
            f"| `{cell.run}` | {cell.quantity} | {_fmt(cell.paper)} | "
            f"{_fmt(_metric(records, base, cell.metric))} | "
            f"{_fmt(_metric(records, base, 'slip_longitudinal_max'), 3)} | "
            f"{_fmt(_metric(records, f'{cell.run}~mu3@mujoco', cell.metric))} | "
            f"{_fmt(_metric(records, f'{cell.run}@reduced', cell.metric))} |"
        )
    return "\n".join(lines)


def _applies_gains(cell: Cell, plant: str, records) -> bool:
    iso = f"{cell.run}~gains_6_2@{plant}"
    if iso not in records:
        return False
    ours = _ratio(_metric(records, f"{cell.run}@{plant}", cell.metric), cell.paper)
    alt = _ratio(_metric(records, iso, cell.metric), cell.paper)
    # Ours too low, and the 6.2 set brings it at least 1.5 times closer.
    return (
        ours < 1.0 / FACTOR
        and math.isfinite(alt)
        and abs(math.log(alt)) < abs(math.log(ours)) - math.log(1.5)
    )


def _describe_gains(cells, records) -> str:
    ismc_max_v = _fmt(_metric(records, "cycloid_ismc_6_2@reduced", "max_abs_v"))
    lines = [
        "The paper gives two ISMC-STA gain sets: Section 6.1 (lambda = diag(5, 6), "
        'eps = 0.005), which it states for Tables 1-2 and, in Section 6.3 ("controller '
        'settings remain identical to those in the cycloidal trajectory case"), for Tables 4-5; '
        "and the comparison set of Section 6.2 (lambda = diag(5, 0.3), eps = 0.02) for Table 3. "
        "Yet Table 3's ISMC-STA row repeats Table 1's nominal row digit for digit "
        "(0.0147 / 0.0224), and several numbers fit the 6.2 set, not the 6.1 set: Table 3's "
        f"max |e_v| 0.0971 (ours with 6.2: {ismc_max_v}, "
        f"with 6.1: {_fmt(_metric(records, 'cycloid_nominal@reduced', 'max_abs_v'))}), and "
        f"the circle's e_v 0.0131 and max position 0.0174 (ours with 6.2: "
        f"{_fmt(_metric(records, 'circle_dynamic~gains_6_2@reduced', 'rmse_v'))} and "
        f"{_fmt(_metric(records, 'circle_dynamic~gains_6_2@reduced', 'max_position'))}). The "
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
            f"| `{cell.run}` | {PLANT_LABEL[plant]} | {cell.quantity} | {_fmt(cell.paper)} | "
            f"{_fmt(_metric(records, f'{cell.run}@{plant}', cell.metric))} | "
            f"{_fmt(_metric(records, f'{cell.run}~gains_6_2@{plant}', cell.metric))} |"
        )
    lines += [
        "",
        "The S-curve is the exception: with the 6.2 set its curvature step costs e_omega "
        f"{_fmt(_metric(records, 's_curve_dynamic~gains_6_2@reduced', 'rmse_omega'))} rad/s and "
        "a position error of "
        f"{_fmt(_metric(records, 's_curve_dynamic~gains_6_2@reduced', 'rmse_position'))} m "
        "(paper: 0.0514 and 0.0091), so Table 4 fits the 6.1 set better. Which set produced "
        "which table cannot be settled from the text.",
    ]
    return "\n".join(lines)


_POSITION_METRICS = ("rmse_lateral", "rmse_position", "max_position")


def _applies_open_loop(cell: Cell, plant: str, records) -> bool:
    ours = _metric(records, f"{cell.run}@{plant}", cell.metric)
    return cell.metric in _POSITION_METRICS and ours < cell.paper / FACTOR


def _split(records, key, name):
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
            f"| `{cell.run}` | {PLANT_LABEL[plant]} | {cell.quantity} | {_fmt(cell.paper)} | "
            f"{_fmt(_metric(records, key, cell.metric))} | {_drift(records, key)} | "
            f"{_fmt(_metric(records, nodist, cell.metric))} | "
            f"{_fmt(_metric(records, alt, cell.metric))} | "
            f"{_drift(records, alt) if alt in records else '—'} |"
        )
    return "\n".join(lines)


def _drift(records, key: str) -> str:
    top = _split(records, key, "heading_drift_e_omega_max")
    end = _split(records, key, "heading_drift_e_omega_end")
    return f"{_fmt(top, 2)} / {_fmt(end, 2)}"


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
    ours = _metric(records, f"{cell.run}@{plant}", cell.metric)
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
                    f"{_fmt(_metric(records, key, 'rmse_v'))} | "
                    f"{_fmt(_metric(records, key, 'rmse_omega'))} | "
                    f"{_fmt(_metric(records, key, 'rmse_lateral'))} | "
                    f"{_fmt(_split(records, key, 'rms_e_omega_over_v'))} | "
                    f"{_fmt(_split(records, key, 'rms_mismatch'))} |"
                )
    return "\n".join(lines)


def _applies_static_start(cell: Cell, plant: str, records) -> bool:
    iso = f"{cell.run}~static_target@{plant}"
    ours = _ratio(_metric(records, f"{cell.run}@{plant}", cell.metric), cell.paper)
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
            f"| `{cell.run}` | {PLANT_LABEL[plant]} | {_fmt(cell.paper)} | "
            f"{_fmt(_metric(records, f'{cell.run}@{plant}', cell.metric))} | "
            f"{_fmt(_metric(records, f'{cell.run}~static_target@{plant}', cell.metric))} |"
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


def _unique(cells: list) -> list:
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
            value = _metric(records, key, cell.metric)
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


def _cell_text(entry) -> str:
    if entry["status"] in ("not run", "error"):
        return entry["status"]
    text = _fmt(entry["value"])
    if entry["status"] != "ok":
        text += f" ({entry['status']})"
    return text


def _why_text(row) -> str:
    parts = []
    for plant in PLANTS:
        e = row[plant]
        if e["flagged"]:
            why = ", ".join(e["causes"]) or "**unexplained**"
            parts.append(f"{PLANT_LABEL[plant]} x{_fmt(e['ratio'], 2)}: {why}")
    return "; ".join(parts)


def _tables_markdown(rows, with_why: bool = True) -> list[str]:
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
                f"| {row['case']} | {row['quantity']} | {_fmt(row['paper'])} | "
                f"{_cell_text(row['reduced'])} | {_cell_text(row['mujoco'])} |"
            )
            if with_why:
                line += f" {_why_text(row)} |"
            out.append(line)
        out.append("")
    return out


def _curvature_rows(records) -> list[dict]:
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
                    "rmse_v": _metric(records, key, "rmse_v"),
                    "rmse_lateral": _metric(records, key, "rmse_lateral"),
                    **{k: split.get(k) for k in _SPLIT_KEYS},
                }
            )
    return rows


def _curvature_findings(records) -> list[str]:
    """What the split table shows, with its numbers (MuJoCo runs)."""

    def lat(key):
        return _metric(records, f"{key}@mujoco", "rmse_lateral")

    def share(key):
        return _split(records, f"{key}@mujoco", "mismatch_share")

    def mism(key):
        return _split(records, f"{key}@mujoco", "rms_mismatch")

    out = ["Findings (MuJoCo; the reduced model agrees):", ""]
    out.append(
        "- With ISMC-STA the speed loop holds e_v near 0.01 m/s, so the static target's "
        "mismatch only acts where v(t) leaves v_ref(t). Circle: it lives in the speed ramps "
        f"(RMS {_fmt(mism('circle_static'), 2)} 1/m, share {_fmt(share('circle_static'), 2)}) "
        f"and costs lateral RMSE {_fmt(lat('circle_static'), 2)} m against "
        f"{_fmt(lat('circle_dynamic'), 2)} m for the dynamic target. S-curve: "
        f"{_fmt(lat('s_curve_static'), 2)} vs {_fmt(lat('s_curve_dynamic'), 2)} m, the "
        "curvature step dominating both. Millimetres either way, below the along-track error "
        "that makes up the position error of Tables 4-5, so both targets give nearly the same "
        "table numbers."
    )
    out.append(
        "- Cycloid: static lateral RMSE "
        f"{_fmt(lat('cycloid_static'), 2)} m vs dynamic {_fmt(lat('cycloid_nominal'), 2)} m, "
        f"but the mismatch share is only {_fmt(share('cycloid_static'), 2)}: the static error "
        "is e_omega / v at the start, where the eq. (32) yaw rate of -0.5 rad/s is a step for a "
        "vehicle whose yaw rate is 0."
    )
    ratios = []
    for traj in ("s_curve", "circle"):
        st, dy = lat(f"stiff_yaw_fbl:{traj}_static"), lat(f"stiff_yaw_fbl:{traj}_dynamic")
        ratios.append(
            f"{traj} {_fmt(st, 3)} vs {_fmt(dy, 3)} m (mismatch share "
            f"{_fmt(share(f'stiff_yaw_fbl:{traj}_static'), 2)})"
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


def _steering_rows(records) -> list[dict]:
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
                "trailer_rmse_lateral": _metric(records, key, "trailer_rmse_lateral"),
                "trailer_max_lateral": _metric(records, key, "trailer_max_lateral"),
                "phi_max_abs_deg": _metric(records, key, "phi_max_abs_deg"),
                "slip_lateral_max": _metric(records, key, "slip_lateral_max"),
            }
        )
    return rows


def _steering_row(rows, path: str, plant: str, variant: str) -> dict | None:
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


def _steering_ratio(rows, path: str, plant: str, field_name: str) -> float:
    def get(variant):
        r = _steering_row(rows, path, plant, variant)
        return None if r is None else r.get(field_name)

    plain, same = get("plain (eta = 0)"), get("same_path (-1/7)")
    if plain is None or same is None or not same:
        return math.nan
    return float(plain) / float(same)


def _feedback_rows(records) -> list[dict]:
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
                    m: _metric(records, key, m)
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


def _pair(rows, case, plant):
    got = {r["feedback"]: r for r in rows if r["case"] == case and r["plant"] == plant}
    return got.get("off"), got.get("on")


def _checks(rows_cells, steering, feedback) -> list[dict]:
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
        full = _steering_ratio(steering, path, "mujoco", "offtrack_rms")
        steady = _steering_ratio(steering, path, "mujoco", "offtrack_steady_rms")
        detail = f"whole run x{_fmt(full, 3)}, steady arcs x{_fmt(steady, 3)}"
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
        off, on = _pair(feedback, case, "mujoco")
        if off and on:
            ok = on["rmse_lateral"] < 0.005 and on["rmse_v"] <= 1.02 * off["rmse_v"]
            detail = (
                f"rmse_lateral {_fmt(off['rmse_lateral'])} -> {_fmt(on['rmse_lateral'])} m "
                f"(paper 0.0368), rmse_v {_fmt(off['rmse_v'])} -> {_fmt(on['rmse_v'])} m/s"
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


def _steering_markdown(steering) -> list[str]:
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
            status = f"jackknife at {_fmt(r['end_time_s'], 3)} s"
        out.append(
            f"| {r['path']} | {name} | {PLANT_LABEL[r['plant']]} | {status} | "
            f"{_fmt(r['offtrack_rms'])} / {_fmt(r['offtrack_max'])} | "
            f"{_fmt(r['offtrack_steady_rms'])} | {_fmt(r['analytic_steady'])} | "
            f"{_fmt(r['trailer_rmse_lateral'])} / {_fmt(r['trailer_max_lateral'])} | "
            f"{_fmt(r['phi_max_abs_deg'], 3)} | {_fmt(r['slip_lateral_max'], 3)} |"
        )
    return out


def _feedback_markdown(feedback) -> list[str]:
    out = [
        "| case | plant | lateral RMSE off -> on (m) | max lateral off -> on (m) "
        "| cross-track RMS off -> on (m) | cross-track max off -> on (m) "
        "| e_v RMSE off -> on | e_omega RMSE off -> on | position RMSE off -> on (m) |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for case in FEEDBACK_CASES:
        for plant in PLANTS:
            off, on = _pair(feedback, case, plant)
            if not (off and on):
                continue

            def both(m, off=off, on=on):
                return f"{_fmt(off[m])} -> {_fmt(on[m])}"

            out.append(
                f"| {case} | {PLANT_LABEL[plant]} | {both('rmse_lateral')} | "
                f"{both('max_lateral')} | {both('cross_track_rms')} | "
                f"{both('cross_track_max')} | {both('rmse_v')} | "
                f"{both('rmse_omega')} | {both('rmse_position')} |"
            )
    return out


def _config_markdown(records) -> list[str]:
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
            f"{_fmt(rec.get('wall_time_s'), 2)} |"
        )
    return out


def _cfg(value) -> str:
    if value is None:
        return "—"
    if isinstance(value, float):
        return _fmt(value, 6)
    return str(value)


def _suite_setup_lines(seed: int) -> list[str]:
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
    steering = _steering_rows(records)
    feedback = _feedback_rows(records)
    curvature = _curvature_rows(records)
    checks = _checks(rows, steering, feedback)
    figs = _draw_figures(records, rows, steering, out) if figures else []

    md = ["# The paper's Tables 1-5 in contact physics", ""]
    md += [
        f"Made by `{info.get('command', COMMAND)}`: {info.get('runs', len(records))} runs "
        f"({info.get('unique_runs', '?')} distinct), {info.get('workers', '?')} worker(s), "
        f"{_fmt(info.get('wall_time_s'), 3)} s. Every number below is in `report.json` with "
        "the full configuration of its run (section *Runs* lists them).",
        "",
        "## Checks",
        "",
    ]
    md += [f"- [{'x' if c['passed'] else ' '}] {c['check']}: {c['detail']}" for c in checks]
    md += ["", "## Setup common to all runs", "", *_suite_setup_lines(SUITE_SEED), ""]
    md += ["## Tables 1-5: paper, reduced model, MuJoCo", ""]
    md += [
        f"A cell is flagged when ours / paper is above {FACTOR:g} or below 1/{FACTOR:g}; the "
        "last column gives the ratio and the causes (next section), each backed by runs that "
        "isolate it.",
        "",
    ]
    md += _tables_markdown(rows)
    if "fig_ratios.png" in figs:
        md += ["![ours / paper for every cell](fig_ratios.png)", ""]

    md += ["## Where we differ by more than a factor of two, and why", ""]
    for cause in CAUSES:
        cells = by_cause[cause.code]
        if not cells:
            continue
        md += [f"### {cause.code}. {cause.title} ({cause.kind})", ""]
        md.append(cause.describe(_unique(cells), records))
        listed = ", ".join(f"T{c.table} {c.case} {c.metric} ({PLANT_LABEL[p]})" for c, p in cells)
        md += ["", f"Explains: {listed}.", ""]
    if by_cause["unexplained"]:
        md += ["### Not explained", ""]
        md += [
            f"- Table {c.table} {c.case}, {c.quantity}, {PLANT_LABEL[p]}: paper {_fmt(c.paper)}, "
            f"ours {_fmt(_metric(records, f'{c.run}@{p}', c.metric))}"
            for c, p in by_cause["unexplained"]
        ]
        md.append("")

    md += ["## Static vs dynamic target: eqs. (37)-(39) measured", ""]
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
            f"{_fmt(r['rmse_v'])} | {_fmt(r['rmse_lateral'])} | "
            f"{_fmt(r['rms_e_omega_over_v'])} | {_fmt(r['rms_mismatch'])} | "
            f"{_fmt(r['mismatch_share'], 2)} | {_fmt(r['heading_drift_e_omega_max'], 3)} | "
            f"{_fmt(r['heading_drift_mismatch_max'], 3)} |"
        )
    md += ["", *_curvature_findings(records), ""]
    for name, caption in (
        ("fig_curvature_split.png", "curvature error split, ISMC-STA, MuJoCo"),
        ("fig_curvature_split_stiff_yaw.png", "curvature error split, FBL diag(8, 50), MuJoCo"),
    ):
        if name in figs:
            md += [f"![{caption}]({name})", ""]

    md += ["## Passive steering study", ""]
    md += [
        "Trailer off-tracking with each steering design, ISMC-STA (set 6.1), dynamic target, "
        "no disturbance (off-tracking is geometry; the disturbance rows are marked). 'Off-track' "
        "is the follower axle's distance from the leader's path (P0 from P's path forward, P "
        "from P0's path reversing); 'steady arc' only counts samples whose follower has run "
        f"{SETTLE_DISTANCE:g} m on constant curvature (none on the cycloid); 'analytic steady' "
        "is the steady-turn value of `steering.steady_offtrack`; 'trailer to reference' is P0 "
        "to the reference path.",
        "",
        *_steering_markdown(steering),
        "",
    ]
    ratio_lines = []
    for path in ("circle", "s_curve", "cycloid"):
        for plant in PLANTS:
            full = _steering_ratio(steering, path, plant, "offtrack_rms")
            steady = _steering_ratio(steering, path, plant, "offtrack_steady_rms")
            if math.isfinite(full):
                ratio_lines.append(
                    f"- {path}, {PLANT_LABEL[plant]}: plain / same_path off-tracking "
                    f"x{_fmt(full, 3)} over the run, x{_fmt(steady, 3)} on steady arcs"
                )
    md += ratio_lines
    md += ["", *STEERING_NOTES, ""]
    if "fig_steering.png" in figs:
        md += ["![off-tracking by steering design](fig_steering.png)", ""]

    md += ["## Beyond the paper: path feedback", ""]
    md += [
        "The outer path feedback adds v (-k_y e_y - k_psi e_psi) to the dynamic "
        "target's omega_d (k_y = 4 1/m^2, k_psi = 4 1/m, critically damped in arc length). "
        "Paper disturbances on; 20 dB noise unless the case says otherwise. 'Cross-track' "
        "measures P against the path continued along its end tangents (a vehicle that "
        "overshoots the path's end is not counted as lateral error there).",
        "",
        *_feedback_markdown(feedback),
        "",
        *FEEDBACK_NOTES,
        "",
    ]
    if "fig_path_feedback.png" in figs:
        md += ["![path feedback](fig_path_feedback.png)", ""]

    md += ["## Runs", ""]
    md += [
        "Every run with its configuration (seed "
        f"{SUITE_SEED}, timestep and control period 1 ms unless listed under 'other'). Runs "
        "with identical scenarios were simulated once. Full configurations, including the "
        "resolved parameters, are in `report.json`.",
        "",
        *_config_markdown(records),
        "",
    ]
    report = out / "report.md"
    atomic_write(report, "\n".join(md) + "\n")

    summary = _summary_markdown(rows, steering, feedback, checks, info)
    atomic_write(out / "summary.md", summary)
    payload = {
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
    atomic_write(out / "report.json", json.dumps(json_safe(payload), indent=1, sort_keys=False))
    return report


STEERING_NOTES = [
    "Notes. (i) The paper's eta = 3 jackknifes driving forward on every path within about "
    "1 s, on both plants (docs/model.md Section 3). Reversing, trailer first, it is stable in the "
    "reduced model and P0 leads on a wider circle (the analytic off-track); in MuJoCo the "
    "reversing S-curve slips at the curvature step and jackknifes unless the friction is "
    "raised (the friction-3 row), and with the paper's disturbance the reversing circle "
    "saturates the 15 N m wheels (the matched torques grow with 1/cos(beta)) and jackknifes "
    "on both plants. (ii) eta = -3 runs in the reduced model but jackknifes in MuJoCo at the "
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


def _summary_markdown(rows, steering, feedback, checks, info) -> str:
    """The README section: the tables, the steering ratios and the path-feedback gains."""
    md = [
        "## The paper's results in contact physics",
        "",
        f"`{info.get('command', COMMAND)}` runs every scenario behind the paper's Tables 1-5 on "
        "the reduced model and on MuJoCo, with isolation runs, a steering study and a path "
        f"feedback study ({info.get('runs', '?')} runs, {_fmt(info.get('wall_time_s'), 3)} s "
        f"on {info.get('workers', '?')} worker(s)), and writes `report.md` (with the reason for "
        "every difference beyond a factor of two), `report.json` and figures. All table runs "
        "use the same-path steering gain (the paper's eta = 3 jackknifes forward) and seed "
        f"{SUITE_SEED}. Ratios ours / paper outside [0.5, 2] are flagged, with the causes "
        "(C1 wheel slip, C2 gain set, C3 open-loop position error, C4 static-target mismatch, "
        "C5 yaw reference at t = 0) explained in the report.",
        "",
    ]
    md += _tables_markdown(rows)
    md += ["### Passive steering: trailer off-tracking (m, rms over the run / on steady arcs)", ""]
    md += [
        "| path | plant | plain eta = 0 | half-difference -0.125 | same_path -1/7 | scheduled "
        "| eta = -3 | eta = 3 forward | eta = 3 reverse |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    names = (
        "plain (eta = 0)",
        "half-difference gain (-0.125)",
        "same_path (-1/7)",
        "scheduled eta(kappa)",
        "eta = -3",
        "paper eta = 3, forward",
        "paper eta = 3, reverse",
    )
    for path in STUDY_PATHS:
        for plant in PLANTS:
            cells = []
            for name in names:
                r = _steering_row(steering, path, plant, name)
                if r is None:
                    cells.append("—")
                elif r["status"] == "jackknife":
                    cells.append(f"jackknife {_fmt(r['end_time_s'], 2)} s")
                else:
                    cells.append(
                        f"{_fmt(r['offtrack_rms'], 2)} / {_fmt(r['offtrack_steady_rms'], 2)}"
                    )
            md.append(f"| {path} | {PLANT_LABEL[plant]} | " + " | ".join(cells) + " |")
    md += ["", "### Path feedback (paper disturbances, 20 dB noise unless stated)", ""]
    md += [
        "| case | plant | lateral RMSE off -> on (m) | cross-track RMS off -> on (m) "
        "| e_v RMSE off -> on (m/s) |",
        "|---|---|---|---|---|",
    ]
    for case in FEEDBACK_CASES:
        for plant in PLANTS:
            off, on = _pair(feedback, case, plant)
            if off and on:
                md.append(
                    f"| {case} | {PLANT_LABEL[plant]} | {_fmt(off['rmse_lateral'])} -> "
                    f"{_fmt(on['rmse_lateral'])} | {_fmt(off['cross_track_rms'])} -> "
                    f"{_fmt(on['cross_track_rms'])} | {_fmt(off['rmse_v'])} -> "
                    f"{_fmt(on['rmse_v'])} |"
                )
    md += ["", "Checks:", ""]
    md += [f"- [{'x' if c['passed'] else ' '}] {c['check']}: {c['detail']}" for c in checks]
    return "\n".join(md) + "\n"


# --- figures ------------------------------------------------------------------------------------
def _draw_figures(records, rows, steering, out: Path) -> list[str]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    made = []

    def save(fig, name):
        fig.tight_layout()
        fig.savefig(out / name, dpi=110)
        plt.close(fig)
        made.append(name)

    # Ratios ours / paper.
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
    save(fig, "fig_ratios.png")

    def split_grid(cases, name, title):
        if not any(
            f"{c}@mujoco" in records and "series" in records[f"{c}@mujoco"] for c, _ in cases
        ):
            return
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
        save(fig, name)

    split_grid(
        [
            ("cycloid_nominal", "cycloid, dynamic"),
            ("cycloid_static", "cycloid, static"),
            ("s_curve_dynamic", "S-curve, dynamic"),
            ("s_curve_static", "S-curve, static"),
            ("circle_dynamic", "circle, dynamic"),
            ("circle_static", "circle, static"),
        ],
        "fig_curvature_split.png",
        "Curvature error split (eqs. 37-39), ISMC-STA, MuJoCo",
    )
    split_grid(
        [
            ("stiff_yaw_fbl:s_curve_dynamic", "S-curve, dynamic"),
            ("stiff_yaw_fbl:s_curve_static", "S-curve, static"),
            ("stiff_yaw_fbl:circle_dynamic", "circle, dynamic"),
            ("stiff_yaw_fbl:circle_static", "circle, static"),
        ],
        "fig_curvature_split_stiff_yaw.png",
        "Curvature error split, FBL K = diag(8, 50) (e_v ~ 0.5 m/s), MuJoCo",
    )

    if steering:
        fig, axes = plt.subplots(2, 2, figsize=(11, 6), sharey="row")
        rows_spec = (("offtrack_rms", "whole run"), ("offtrack_steady_rms", "steady arcs"))
        for i, (field_name, what) in enumerate(rows_spec):
            for ax, plant in zip(axes[i], PLANTS, strict=True):
                for j, name in enumerate(STEERING_VARIANTS):
                    vals = []
                    for path in STUDY_PATHS:
                        r = _steering_row(steering, path, plant, name)
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
        save(fig, "fig_steering.png")

    fb = [
        (case, records.get(f"fb:{case}:off@mujoco"), records.get(f"fb:{case}:on@mujoco"))
        for case in ("cycloid", "s_curve", "circle")
    ]
    if any(off and on and "series" in off and "series" in on for _, off, on in fb):
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
        save(fig, "fig_path_feedback.png")
    return made


# --- command line -------------------------------------------------------------------------------
class _BadInputError(Exception):
    pass


class _Parser(argparse.ArgumentParser):
    def error(self, message: str):
        raise _BadInputError(message)


def _workers(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"--workers {text!r} is not an integer >= 1") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"--workers {text!r} is not an integer >= 1")
    return value


def build_parser() -> argparse.ArgumentParser:
    p = _Parser(
        prog=COMMAND,
        description=(
            "Run every scenario behind the paper's Tables 1-5 on the reduced model and MuJoCo, "
            "with isolation runs, a passive-steering study and a path-feedback study, and write "
            "report.md, report.json, summary.md and figures."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    p.add_argument(
        "--out",
        default=None,
        metavar="DIR",
        help="output folder, new or empty (default: renders/paper, or renders/paper-N if taken)",
    )
    p.add_argument("--workers", type=_workers, default=2, help="worker processes")
    p.add_argument("--quick", action="store_true", help="a reduced set of short runs (smoke test)")
    p.add_argument("--no-figures", action="store_true", help="skip the PNG figures")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    return p


def main(argv: list[str] | None = None) -> int:
    """Exit 0 done, 2 bad input, 1 if a run raised an error (it is in the report)."""
    try:
        args = build_parser().parse_args(argv)
        out, _ = claim_folder(args.out, DEFAULT_OUT)  # before the suite: a bad --out fails now
    except (_BadInputError, ValueError) as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    specs = suite(quick=args.quick)
    start = time.perf_counter()
    records = run_suite(specs, workers=args.workers, progress=not args.quiet)
    wall = time.perf_counter() - start
    info = {
        "command": COMMAND + (" --quick" if args.quick else ""),
        "runs": len(specs),
        "unique_runs": len({r["same_as"] for r in records.values()}),
        "workers": args.workers,
        "wall_time_s": wall,
    }
    report = build_report(records, out, info, figures=not args.no_figures)
    errors = [k for k, r in records.items() if r.get("status") == "error"]
    print(f"report: {report} ({len(specs)} runs in {wall:.1f} s)")
    if errors:
        print(f"{len(errors)} run(s) failed, see the report: {', '.join(errors)}", file=sys.stderr)
        return 1
    return 0

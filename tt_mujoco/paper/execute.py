"""Running the suite: each run with its per-run analysis (in worker processes), deduplicated."""

from __future__ import annotations

import dataclasses
import json
import math
import time
from collections.abc import Callable, Iterable, Mapping
from concurrent.futures import as_completed

import numpy as np
from scipy.integrate import cumulative_trapezoid

from tt_mujoco import guard
from tt_mujoco.analysis.metrics import (
    finite_prefix_length,
    follower_offtrack,
    signed_lateral_error,
)
from tt_mujoco.executor import Executors
from tt_mujoco.outputs import json_safe
from tt_mujoco.paper.suite import SERIES_POINTS, SETTLE_DISTANCE, V_MIN, RunSpec
from tt_mujoco.progress import progress_bar
from tt_mujoco.sim import Scenario, build, simulate
from tt_mujoco.vehicle.steering import steady_offtrack

#: A run's rows are used up to the first that is not finite in any of these.
_FINITE_COLUMNS = ("t", "x", "y", "v", "omega", "omega_d")


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

    t, v, w, wd = (np.asarray(ts[k], dtype=float) for k in ("t", "v", "omega", "omega_d"))
    n = finite_prefix_length(ts, _FINITE_COLUMNS)
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


def steady_mask(path, s_tractor: np.ndarray, reverse: bool, spacing: float) -> np.ndarray:
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

    n = finite_prefix_length(ts, _FINITE_COLUMNS)
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
    steady = steady_mask(path, s_tractor, scenario.reverse, spacing) & have
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

    start = time.perf_counter()
    record = {"key": key, "scenario": json_safe(scenario.to_dict())}
    try:
        built = build(scenario)
        result = simulate(built)
        ts = result.timeseries
        polyline = result.reference_polyline
        path = built.path
        split = curvature_split(ts, path, polyline)
        series_split = split.pop("series")
        n = finite_prefix_length(ts, _FINITE_COLUMNS)
        xy = np.column_stack([ts["x"][:n], ts["y"][:n]])
        plant_params = built.plant_params
        record.update(
            status=result.status,
            message=result.message,
            metrics=result.metrics,
            config=result.config,
            curvature_split=split,
            offtrack=_offtrack_summary(ts, path, scenario, plant_params),
            cross_track={
                "rms": result.metrics["cross_track_rms"],
                "max": result.metrics["cross_track_max"],
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
        Worker processes (:class:`tt_mujoco.executor.Executors`); 1 runs in this process.
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

    bar = progress_bar(len(todo), "paper suite", "run", enabled=progress)
    done: dict[str, dict] = {}
    try:
        if workers == 1:
            for spec in todo:
                done[spec.key] = runner(spec.key, spec.scenario, spec.keep_series)
                bar.update()
        else:
            # the sweep's process pool
            executors = Executors(workers, None, guard.ignore_stop_signals)
            pool = executors.open()
            try:
                futures = {
                    pool.submit(runner, s.key, s.scenario, s.keep_series): s.key for s in todo
                }
                for fut in as_completed(futures):
                    done[futures[fut]] = fut.result()
                    bar.update()
            finally:
                executors.close(cancel=len(done) < len(todo))
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

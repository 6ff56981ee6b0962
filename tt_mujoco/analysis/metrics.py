"""Tracking metrics of a finished run (their names, units and the registry of extra metrics:
:mod:`tt_mujoco.analysis.metric_names`).

A run is a mapping of column name -> 1-D array, one sample per control step (SI units, radians),
as logged by the simulation loop: ``t, x, y, phi, v, omega, x0, y0, x_ref, y_ref, v_d, omega_d,
T_r_cmd, T_l_cmd, slip_lateral, slip_lateral_trailer, slip_left, slip_right, eq_violation`` are
used here (other columns are ignored). :func:`compute_metrics` turns it into the numbers of
``metrics.json`` (docs/model.md Section 11); the RMS values are the quantities of the paper's
Section 6
tables (docs/model.md Section 10).

Distances to a path are exact distances to its polyline (:mod:`tt_mujoco.analysis.geometry`).

A user metric is a function ``fn(timeseries, path) -> float | dict`` (``path`` a
:class:`~tt_mujoco.reference.paths.ReferencePath`), named in ``Scenario.metrics`` (``--metric``)
by a name registered in :data:`METRICS` or by hook ``module:function`` / ``file.py:function``;
its value lands in ``metrics.json`` under that name, in the summary table and in sweep tables.
"""

from __future__ import annotations

import math
import numbers
import re
from collections.abc import Mapping, Sequence

import numpy as np

from tt_mujoco.analysis.geometry import Polyline, PolylineProjection
from tt_mujoco.analysis.metric_names import (
    DEFAULT_SUMMARY_KEYS,
    METRIC_UNITS,
    METRICS,
    RUN_KEYS,
    TEXT_METRICS,
    builtin_key,
    metric_name,
    metric_unit,
    resolve_metrics,
    summary_table,
)
from tt_mujoco.analysis.offtrack import (
    as_polyline,
    distance_to_polyline,
    signed_lateral_error,
    trailer_offtrack,
)
from tt_mujoco.analysis.tracks import moves

__all__ = [
    "CORE_COLUMNS",
    "DEFAULT_SUMMARY_KEYS",
    "DIAGNOSTIC_COLUMNS",
    "METRICS",
    "METRIC_UNITS",
    "OPTIONAL_COLUMNS",
    "REQUIRED_COLUMNS",
    "RUN_KEYS",
    "TEXT_METRICS",
    "Polyline",
    "PolylineProjection",
    "builtin_key",
    "compute_metrics",
    "distance_to_polyline",
    "error_signals",
    "finite_prefix_length",
    "follower_offtrack",
    "max_abs",
    "merge_metrics",
    "metric_name",
    "metric_unit",
    "resolve_metrics",
    "rmse",
    "run_error_signals",
    "signed_lateral_error",
    "summary_table",
    "trailer_offtrack",
]

#: Columns whose first non-finite value ends the usable part of a run (a diverged run's state,
#: target and commands all turn non-finite together).
CORE_COLUMNS = (
    "t",
    "x",
    "y",
    "phi",
    "v",
    "omega",
    "x0",
    "y0",
    "x_ref",
    "y_ref",
    "v_d",
    "omega_d",
    "T_r_cmd",
    "T_l_cmd",
)

#: Plant diagnostics: a plant that cannot measure one (e.g. slip in the reduced model) may log
#: NaN, so their maxima skip NaN instead of truncating the run.
DIAGNOSTIC_COLUMNS = (
    "slip_lateral",
    "slip_lateral_trailer",
    "slip_left",
    "slip_right",
    "eq_violation",
)

#: Every column :func:`compute_metrics` needs.
REQUIRED_COLUMNS = CORE_COLUMNS + DIAGNOSTIC_COLUMNS
#: Columns used when present: the reference heading (along-track error), the yaw-rate target
#: the controller tracked (path feedback), whether the disturbance was clipped.
OPTIONAL_COLUMNS = ("theta_ref", "omega_d_tracked", "dist_clipped")

# Relative margin under which a commanded torque counts as saturated: a controller that clips its
# own output to exactly the limit must count as saturated despite rounding.
SATURATION_MARGIN = 1e-9


def rmse(x) -> float:
    """Root of the mean of ``x**2`` over all samples (NaN if empty or if any sample is NaN)."""
    x = np.asarray(x, dtype=float).ravel()
    if x.size == 0:
        return math.nan
    return float(np.sqrt(np.mean(x * x)))


def max_abs(x) -> float:
    """Largest ``|x|`` over all samples (NaN if empty or if any sample is NaN)."""
    x = np.asarray(x, dtype=float).ravel()
    if x.size == 0:
        return math.nan
    return float(np.max(np.abs(x)))


def _nanmax_abs(*arrays: np.ndarray) -> float:
    """Largest ``|value|`` over the non-NaN entries of all arrays; NaN if there are none."""
    values = np.concatenate([np.abs(np.asarray(a, dtype=float).ravel()) for a in arrays])
    values = values[~np.isnan(values)]
    return float(values.max()) if values.size else math.nan


def finite_prefix_length(columns: Mapping[str, np.ndarray], names: Sequence[str]) -> int:
    """How many leading rows are finite in every column of ``names`` (a run that diverged
    is cut before its first NaN or infinity)."""
    bad = np.zeros(len(columns[names[0]]), dtype=bool)
    for name in names:
        bad |= ~np.isfinite(np.asarray(columns[name], dtype=float))
    hits = np.flatnonzero(bad)
    return int(hits[0]) if hits.size else bad.size


def _check_inputs(ts) -> tuple[dict[str, np.ndarray], int]:
    """The run's required columns as float arrays and its length, checked."""
    if not isinstance(ts, Mapping):
        raise ValueError(f"ts must be a mapping of column name -> array, got {type(ts).__name__}")
    missing = [name for name in REQUIRED_COLUMNS if name not in ts]
    if missing:
        raise ValueError(f"time series lacks required columns {missing}")
    columns = {}
    for name in REQUIRED_COLUMNS:
        try:
            col = np.asarray(ts[name], dtype=float)
        except (TypeError, ValueError) as err:
            raise ValueError(f"column {name!r} must be numeric: {err}") from None
        if col.ndim != 1:
            raise ValueError(f"column {name!r} must be 1-D, got shape {col.shape}")
        columns[name] = col
    n = len(columns["t"])
    wrong = {name: len(c) for name, c in columns.items() if len(c) != n}
    if wrong:
        raise ValueError(f"all columns must have the length of 't' ({n}), got {wrong}")
    if n == 0:
        raise ValueError("time series must hold at least one sample, got 0")
    return columns, n


def _check_limit(torque_limit) -> None:
    if (
        isinstance(torque_limit, bool)
        or not isinstance(torque_limit, numbers.Real)
        or not math.isfinite(torque_limit)
        or torque_limit <= 0
    ):
        raise ValueError(f"torque_limit must be a finite number > 0 (N m), got {torque_limit!r}")


def error_signals(
    c: Mapping[str, np.ndarray], reference_polyline, reverse: bool = False, driven=None
) -> dict[str, np.ndarray]:
    """The tracking errors of a run, sample by sample (docs/metrics.md defines each).

    Parameters
    ----------
    c : mapping of str -> ndarray
        Columns with finite positions (``t, x, y, x0, y0, x_ref, y_ref, v, v_d, omega,
        omega_d``; ``theta_ref`` and ``omega_d_tracked`` are used when present).
    reference_polyline : array_like or Polyline
    reverse : bool
        The run drives the path backwards (the trailer leads).
    driven : Polyline, optional
        ``Polyline`` of the leading unit's positions (the tractor's driving forward, the
        trailer's reversing), when the caller has it already (built here otherwise).

    Returns
    -------
    dict of ndarray
        ``e_v``, ``e_omega`` (against the reference target), ``e_omega_tracked`` (against the
        yaw-rate target the controller tracked, when path feedback changed it); ``lateral``
        (P to the path, ends clamped, signed: the paper's lateral deviation); ``cross_track``
        (P to the path continued by its end tangents, signed, + left of the direction of travel),
        ``along_track`` (P's lead, + ahead, or lag against the reference point along the path's
        tangent there; NaN without ``theta_ref``); ``trailer_offtrack`` (the following unit to the
        path the leading one drove, NaN where it does not count) and ``trailer_lateral`` (P0's
        cross-track over the same samples driving forward, over all samples reversing).
    """
    reference = as_polyline(reference_polyline)
    n = len(c["t"])
    out = {"e_v": c["v"] - c["v_d"], "e_omega": c["omega"] - c["omega_d"]}
    tracked = c.get("omega_d_tracked")
    if tracked is not None and not np.array_equal(tracked, c["omega_d"], equal_nan=True):
        out["e_omega_tracked"] = c["omega"] - tracked
    tractor = np.column_stack([c["x"], c["y"]])
    trailer = np.column_stack([c["x0"], c["y0"]])
    out["cross_track"], out["lateral"] = cross_track_and_lateral(reference, tractor)
    direction = -1.0 if reverse else 1.0
    if "theta_ref" in c:
        th = c["theta_ref"]
        ahead = (c["x"] - c["x_ref"]) * np.cos(th) + (c["y"] - c["y_ref"]) * np.sin(th)
        out["along_track"] = direction * ahead
    else:
        out["along_track"] = np.full(n, np.nan)
    leader, follower = (trailer, tractor) if reverse else (tractor, trailer)
    offtrack = trailer_offtrack(leader, follower, path=driven) if n else np.zeros(0)
    out["trailer_offtrack"] = offtrack
    trailer_cross = reference.project(trailer, extend_ends=True).signed_distance
    out["trailer_lateral"] = (
        trailer_cross if reverse else np.where(np.isnan(offtrack), np.nan, trailer_cross)
    )
    return out


def run_error_signals(
    ts: Mapping[str, np.ndarray], reference_polyline, reverse: bool = False
) -> dict[str, np.ndarray]:
    """:func:`error_signals` of a whole run, as :func:`compute_metrics` measures it: over the
    finite part of the run, the rows after it NaN (one value per row of ``ts``).

    Parameters
    ----------
    ts : mapping of str -> ndarray
        The run's columns (:data:`REQUIRED_COLUMNS`, and :data:`OPTIONAL_COLUMNS` where present).
    reference_polyline : array_like, shape (M, 2), or Polyline
    reverse : bool
        The run drives the path backwards (the trailer leads).

    Returns
    -------
    dict of ndarray
        :func:`error_signals`' signals, each of ``ts``' length.
    """
    columns, n_total = _check_inputs(ts)
    n, c = _finite_part(ts, columns)
    driven = None if reverse else _driven_path(np.column_stack([c["x"], c["y"]]))
    signals = error_signals(c, as_polyline(reference_polyline), reverse, driven)
    after = np.full(n_total - n, np.nan)
    return {name: np.concatenate([values, after]) for name, values in signals.items()}


def _sample_period(t, all_t) -> float:
    """The median spacing of the run's finite times ``all_t``, its finite part's ``t``
    checked to increase strictly."""
    if t.size >= 2 and np.any(np.diff(t) <= 0.0):
        i = int(np.flatnonzero(np.diff(t) <= 0.0)[0]) + 1
        raise ValueError(
            f"column 't' must strictly increase, got t[{i}] = {t[i]!r} after t[{i - 1}] = "
            f"{t[i - 1]!r}"
        )
    all_t = all_t[np.isfinite(all_t)]
    return float(np.median(np.diff(all_t))) if all_t.size >= 2 else math.nan


def _finite_part(ts, columns) -> tuple[int, dict[str, np.ndarray]]:
    """``(n, c)``: the length of the run's finite part and its columns cut to it (the optional
    ones too)."""
    n = finite_prefix_length(columns, CORE_COLUMNS)
    c = {name: col[:n] for name, col in columns.items()}
    for name in OPTIONAL_COLUMNS:
        if name in ts:
            c[name] = np.asarray(ts[name], dtype=float)[:n]
    return n, c


def cross_track_and_lateral(reference: Polyline, points) -> tuple[np.ndarray, np.ndarray]:
    """Signed distances to the path with its ends continued as rays, and without.

    The rays serve only points whose nearest point lies beyond an end: elsewhere the nearest
    point without them is the same one (the path without its rays is a part of the path with
    them, and it holds that nearest point), so only the others are projected again.
    """
    with_rays = reference.project(points, extend_ends=True)
    lateral = with_rays.signed_distance.copy()
    arc = with_rays.arc_length
    beyond = ~((arc >= 0.0) & (arc <= reference.length))  # NaN rows too: NaN again
    if beyond.any():
        lateral[beyond] = reference.project(np.asarray(points)[beyond]).signed_distance
    return with_rays.signed_distance, lateral


def compute_metrics(
    ts: Mapping[str, np.ndarray],
    reference_polyline,
    torque_limit: float,
    reverse: bool = False,
    signals: Mapping[str, np.ndarray] | None = None,
) -> dict[str, float | int | str]:
    """Summarise a run (docs/model.md Section 11, ``metrics.json``).

    Parameters
    ----------
    ts : mapping of str -> ndarray, each shape (N,)
        The run's columns (see the module docstring), sampled at the control steps.
    reference_polyline : array_like, shape (M, 2), or Polyline
        The reference path, vertices in the direction of travel.
    torque_limit : float
        Actuator limit (N m; 15 for the paper, docs/model.md Section 1).
    reverse : bool
        The run drives the path backwards (the trailer leads).
    signals : mapping, optional
        :func:`run_error_signals` of this run with the same polyline and ``reverse``, when the
        caller has them already (the run's figures draw them); computed here otherwise.

    Returns
    -------
    dict
        Every RMS is the root of the mean of the squared error over the samples (uniform
        sampling); every maximum is over the samples. Errors are ``e_v = v - v_d`` and
        ``e_omega = omega - omega_d`` with the true velocities (the paper's Section 6 errors).

        - ``rmse_v``, ``max_abs_v`` (m/s); ``rmse_omega``, ``max_abs_omega`` (rad/s), against
          the reference target; with path feedback also ``rmse_omega_tracked``,
          ``max_abs_omega_tracked`` against the yaw-rate target the controller was given.
        - ``rmse_lateral``, ``max_lateral``: P to the reference polyline (m), its ends clamped
          (the paper's lateral deviation; P running past the end counts as distance to the end).
        - ``cross_track_rms``, ``cross_track_max``: P to the path continued by its end tangents
          (m): progress past the end is along-track, not cross-track.
        - ``along_track_rms``, ``along_track_max``: P's lead or lag against the reference point
          along the path's tangent there (m), in the direction of travel.
        - ``rmse_position``, ``max_position``: P to the reference point (x_ref, y_ref) (m).
        - ``leading_cross_track_rms``, ``leading_cross_track_max``: the cross-track of the unit
          that leads the motion: the tractor's (``cross_track_*``) driving forward, the last
          trailer's axle reversing;
        - ``trailer_offtrack_rms``, ``trailer_offtrack_max``: the following unit (the trailer's
          P0 forward, the tractor's P reversing; ``offtrack_follower`` says which) to the path
          the leading unit drove, over the ``trailer_offtrack_samples`` samples after the
          follower passed the leader's start (see :func:`trailer_offtrack`).
        - ``trailer_rmse_lateral``, ``trailer_max_lateral``: P0's cross-track against the
          reference path over the same samples (forward; all samples reversing), counted in
          ``trailer_lateral_samples``. NaN where no sample counts.
        - ``eq_violation_max`` (rad): max ``|beta - eta phi|``.
        - ``slip_lateral_max``: max of ``|slip_lateral|`` and ``|slip_lateral_trailer|``;
          ``slip_longitudinal_max``: max of ``|slip_left|`` and ``|slip_right|`` (m/s).
          These three skip NaN entries (a plant may not provide them); NaN if all are NaN.
        - ``torque_saturation_fraction``: share of samples where ``|T_r_cmd|`` or ``|T_l_cmd|``
          exceeds ``torque_limit * (1 - 1e-9)`` (a request clipped to exactly the limit counts).
        - ``phi_max_abs_deg``: max ``|phi|`` in degrees.
        - ``steps``: N, all samples given. ``finite_samples``: length of the finite prefix, the
          samples before the first non-finite value of any of :data:`CORE_COLUMNS`; every other
          metric uses only these samples (NaN if there are none).
        - ``sample_period_s``: median spacing of ``t``; ``sim_time_s``: time covered by the finite
          prefix, ``t[n-1] - t[0] + sample_period_s`` (each sample stands for one step), 0 if
          ``n = 0``.

    Raises
    ------
    ValueError
        On missing or malformed columns, a bad polyline or torque limit, or a ``t`` that does not
        strictly increase over the finite prefix.
    """
    columns, n_total = _check_inputs(ts)
    _check_limit(torque_limit)
    reference = as_polyline(reference_polyline)
    n, c = _finite_part(ts, columns)
    t = c["t"]
    sample_period = _sample_period(t, columns["t"])

    # Driving forward every trailer follows the tractor: its driven path is built once.
    driven = None if reverse else _driven_path(np.column_stack([c["x"], c["y"]]))
    if signals is None:
        signals = error_signals(c, reference, reverse, driven)
    else:  # run_error_signals' of this run
        signals = {name: np.asarray(values, dtype=float)[:n] for name, values in signals.items()}
    metrics: dict[str, float | int] = {}
    metrics["rmse_v"] = rmse(signals["e_v"])
    metrics["max_abs_v"] = max_abs(signals["e_v"])
    metrics["rmse_omega"] = rmse(signals["e_omega"])
    metrics["max_abs_omega"] = max_abs(signals["e_omega"])
    if "e_omega_tracked" in signals:
        metrics["rmse_omega_tracked"] = rmse(signals["e_omega_tracked"])
        metrics["max_abs_omega_tracked"] = max_abs(signals["e_omega_tracked"])
    metrics["rmse_lateral"] = rmse(signals["lateral"])
    metrics["max_lateral"] = max_abs(signals["lateral"])
    metrics["cross_track_rms"] = rmse(signals["cross_track"])
    metrics["cross_track_max"] = max_abs(signals["cross_track"])
    metrics["along_track_rms"] = rmse(signals["along_track"])
    metrics["along_track_max"] = max_abs(signals["along_track"])
    position = np.hypot(c["x"] - c["x_ref"], c["y"] - c["y_ref"])
    metrics["rmse_position"] = rmse(position)
    metrics["max_position"] = max_abs(position)
    trailer_lateral = signals["trailer_lateral"]
    trailer_lateral = trailer_lateral[~np.isnan(trailer_lateral)]
    metrics["trailer_rmse_lateral"] = rmse(trailer_lateral)
    metrics["trailer_max_lateral"] = max_abs(trailer_lateral)
    metrics["trailer_lateral_samples"] = int(trailer_lateral.size)
    offtrack = signals["trailer_offtrack"]
    offtrack = offtrack[~np.isnan(offtrack)]
    metrics["trailer_offtrack_rms"] = rmse(offtrack)
    metrics["trailer_offtrack_max"] = max_abs(offtrack)
    metrics["trailer_offtrack_samples"] = int(offtrack.size)
    metrics["offtrack_follower"] = "tractor" if reverse else "trailer"

    metrics["phi_max_abs_deg"] = math.degrees(max_abs(c["phi"]))
    metrics["eq_violation_max"] = _nanmax_abs(c["eq_violation"])
    metrics["slip_lateral_max"] = _nanmax_abs(c["slip_lateral"], c["slip_lateral_trailer"])
    metrics["slip_longitudinal_max"] = _nanmax_abs(c["slip_left"], c["slip_right"])
    threshold = torque_limit * (1.0 - SATURATION_MARGIN)
    saturated = (np.abs(c["T_r_cmd"]) > threshold) | (np.abs(c["T_l_cmd"]) > threshold)
    metrics["torque_saturation_fraction"] = float(saturated.mean()) if n else math.nan
    if "dist_clipped" in ts:
        clipped = np.asarray(ts["dist_clipped"], dtype=float)[:n]
        metrics["disturbance_clipped_fraction"] = float(np.mean(clipped > 0)) if n else math.nan

    metrics.update(train_metrics(ts, n, reference, metrics, reverse, driven))
    # The unit that leads the motion: the tractor forward, the last trailer reversing.
    last = trailer_count(ts)
    if not reverse:
        lead = ("cross_track_rms", "cross_track_max")
    elif last == 1:
        lead = ("trailer_rmse_lateral", "trailer_max_lateral")
    else:
        lead = (f"trailer_{last}_rmse_lateral", f"trailer_{last}_max_lateral")
    metrics["leading_cross_track_rms"] = metrics[lead[0]]
    metrics["leading_cross_track_max"] = metrics[lead[1]]
    metrics["steps"] = int(n_total)
    metrics["finite_samples"] = int(n)
    metrics["sample_period_s"] = sample_period
    metrics["sim_time_s"] = float(t[-1] - t[0] + sample_period) if n else 0.0
    return metrics


def trailer_count(ts: Mapping[str, np.ndarray]) -> int:
    """N, the number of trailers whose columns a time series holds (``x0``, ``x0_2``, ...)."""
    n = 1
    while f"x0_{n + 1}" in ts:
        n += 1
    return n


def train_metrics(
    ts, n: int, reference, first: Mapping, reverse: bool = False, driven=None
) -> dict:
    """Metrics of trailers 2..N and the worst over the train (docs/metrics.md), over the first
    ``n`` samples; empty for one trailer.

    Trailer k's ``trailer_k_offtrack_rms``/``_max`` measure P_k against the path the tractor's
    P drove, like trailer 1's. Reversing, every unit is measured against the path the unit
    ahead of it in the motion drove: the tractor against trailer 1's (``trailer_offtrack_*``,
    ``offtrack_follower``), trailer k < N against trailer k + 1's (``trailer_k_offtrack_*``,
    trailer 1's as ``trailer_1_offtrack_*``); the last trailer leads and has none (NaN).
    ``trailer_k_rmse_lateral``/``_max_lateral`` is trailer k's cross-track over the same
    samples and ``trailer_k_phi_max_abs_deg`` its hitch angle. ``train_offtrack_rms_worst``,
    ``train_offtrack_max_worst`` and ``train_phi_max_abs_deg`` take the worst unit,
    ``first`` (the run's own metrics) included. ``driven`` is the tractor's driven path
    driving forward, when the caller has built it.
    """
    count = trailer_count(ts)
    if count == 1:
        return {}
    col = {name: np.asarray(ts[name], dtype=float)[:n] for name in ("x", "y")}
    for k in range(2, count + 1):
        for name in ("x0", "y0", "phi"):
            col[f"{name}_{k}"] = np.asarray(ts[f"{name}_{k}"], dtype=float)[:n]
    axles = [np.column_stack([np.asarray(ts[f"{q}0"], dtype=float)[:n] for q in "xy"])]
    axles += [np.column_stack([col[f"x0_{k}"], col[f"y0_{k}"]]) for k in range(2, count + 1)]
    tractor = np.column_stack([col["x"], col["y"]])
    tractor_path = driven  # forward, every trailer follows it: built once
    out: dict = {}
    worst_rms = [first["trailer_offtrack_rms"]]
    worst_max = [first["trailer_offtrack_max"]]
    worst_phi = [first["phi_max_abs_deg"]]
    if reverse:  # trailer 1 follows trailer 2 (forward its figures are ``first``'s)
        offtrack = trailer_offtrack(axles[1], axles[0])
        offtrack = offtrack[~np.isnan(offtrack)]
        out["trailer_1_offtrack_rms"] = rmse(offtrack)
        out["trailer_1_offtrack_max"] = max_abs(offtrack)
        worst_rms.append(out["trailer_1_offtrack_rms"])
        worst_max.append(out["trailer_1_offtrack_max"])
    for k in range(2, count + 1):
        follower = axles[k - 1]
        if reverse:  # the last trailer leads and follows nothing
            offtrack = trailer_offtrack(axles[k], follower) if k < count else np.full(n, np.nan)
        else:
            if tractor_path is None:
                tractor_path = _driven_path(tractor)
            offtrack = trailer_offtrack(tractor, follower, path=tractor_path)
        cross = reference.project(follower, extend_ends=True).signed_distance
        counted = ~np.isnan(offtrack) if not reverse else np.ones(n, dtype=bool)
        out[f"trailer_{k}_offtrack_rms"] = rmse(offtrack[~np.isnan(offtrack)])
        out[f"trailer_{k}_offtrack_max"] = max_abs(offtrack[~np.isnan(offtrack)])
        out[f"trailer_{k}_rmse_lateral"] = rmse(cross[counted])
        out[f"trailer_{k}_max_lateral"] = max_abs(cross[counted])
        out[f"trailer_{k}_phi_max_abs_deg"] = math.degrees(max_abs(col[f"phi_{k}"]))
        worst_rms.append(out[f"trailer_{k}_offtrack_rms"])
        worst_max.append(out[f"trailer_{k}_offtrack_max"])
        worst_phi.append(out[f"trailer_{k}_phi_max_abs_deg"])
    out["train_offtrack_rms_worst"] = _worst(worst_rms)
    out["train_offtrack_max_worst"] = _worst(worst_max)
    out["train_phi_max_abs_deg"] = _worst(worst_phi)
    return out


#: The samples each of the metrics that count their own were taken over (the others: every
#: finite sample, ``finite_samples``).
_OWN_SAMPLES = {
    "trailer_offtrack_rms": "trailer_offtrack_samples",
    "trailer_rmse_lateral": "trailer_lateral_samples",
}


def merge_metrics(parts: Sequence[Mapping]) -> dict:
    """The metrics of consecutive pieces of one run, each computed on its own rows (a
    maneuver's legs, each against its own path and leading unit), as one: counts and times
    add up, every RMS is the root of the mean square over all the samples it counted, every
    maximum the largest, every fraction the mean over the samples, the worst unit's RMS
    recomputed from the merged units'; text and the sample period are the last piece's."""
    parts = [part for part in parts if part.get("finite_samples")]
    if not parts:
        return {}
    out: dict = {}
    for name in dict.fromkeys(name for part in parts for name in part):
        having = [part for part in parts if name in part]
        values = [part[name] for part in having]
        if any(isinstance(value, str) for value in values) or name == "sample_period_s":
            out[name] = values[-1]
        elif name in ("steps", "sim_time_s") or name.endswith("_samples"):
            out[name] = sum(values)
        elif "max" in name:
            out[name] = _worst(values)
        else:
            weights = np.array(
                [part.get(_OWN_SAMPLES.get(name, "finite_samples"), 0) for part in having],
                dtype=float,
            )
            values = np.array(values, dtype=float)
            kept = np.isfinite(values) & (weights > 0)
            if not kept.any():
                out[name] = math.nan
                continue
            squared = "rms" in name or name.startswith("rmse")
            mean = np.average(values[kept] ** 2 if squared else values[kept], weights=weights[kept])
            out[name] = float(math.sqrt(mean) if squared else mean)
    units = [name for name in out if re.fullmatch(r"trailer(_\d+)?_offtrack_rms", name)]
    if "train_offtrack_rms_worst" in out:
        out["train_offtrack_rms_worst"] = _worst([out[name] for name in units])
    return out


def _driven_path(leader) -> Polyline | None:
    """The leader's driven path, or None where it never moved (nothing to follow)."""
    if moves(leader):
        return Polyline(leader)
    return None


def _worst(values) -> float:
    finite = [v for v in values if math.isfinite(v)]
    return max(finite) if finite else math.nan


def follower_offtrack(ts, reverse: bool = False) -> np.ndarray:
    """Off-tracking of the following axle from the leading axle's path, sample by sample (m).

    Forward the trailer (P0) follows the tractor (P): this is
    :func:`tt_mujoco.analysis.metrics.trailer_offtrack`. Reversing, the trailer leads, so the roles
    swap:
    the distance from P to the path P0 has driven so far. NaN until the follower has passed the
    leader's starting point.
    """
    p = np.column_stack([ts["x"], ts["y"]])
    p0 = np.column_stack([ts["x0"], ts["y0"]])
    ok = np.all(np.isfinite(p), axis=1) & np.all(np.isfinite(p0), axis=1)
    n = int(np.argmin(ok)) if not ok.all() else len(ok)
    out = np.full(len(ok), np.nan)
    if n >= 2:
        out[:n] = trailer_offtrack(p0[:n], p[:n]) if reverse else trailer_offtrack(p[:n], p0[:n])
    return out

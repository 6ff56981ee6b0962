"""The names of a run's metrics: their units, the CLI's summary table, and the registry of a
user's extra metrics with the keys they may not take (:mod:`tt_mujoco.analysis.metrics`
computes the values)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from tt_mujoco.registry import Registry, is_hook

__all__ = [
    "DEFAULT_SUMMARY_KEYS",
    "METRICS",
    "METRIC_UNITS",
    "RUN_KEYS",
    "TEXT_METRICS",
    "builtin_key",
    "metric_name",
    "metric_unit",
    "resolve_metrics",
    "summary_table",
]

#: Rows of the CLI's printed summary, in order.
DEFAULT_SUMMARY_KEYS = (
    "rmse_v",
    "max_abs_v",
    "rmse_omega",
    "max_abs_omega",
    "rmse_lateral",
    "max_lateral",
    "cross_track_rms",
    "along_track_rms",
    "rmse_position",
    "max_position",
    "trailer_rmse_lateral",
    "trailer_offtrack_rms",
    "trailer_offtrack_max",
    "phi_max_abs_deg",
    "eq_violation_max",
    "slip_lateral_max",
    "slip_longitudinal_max",
    "torque_saturation_fraction",
    "sim_time_s",
    "steps",
    "finite_samples",
)

#: The unit of every built-in metric that is a number ("" for a count or a fraction); a
#: trailer's own metric (``trailer_2_offtrack_rms``) has its one-trailer form's unit
#: (:func:`metric_unit`). docs/metrics.md defines each.
METRIC_UNITS = {
    **dict.fromkeys(("rmse_v", "max_abs_v", "slip_lateral_max", "slip_longitudinal_max"), "m/s"),
    **dict.fromkeys(
        ("rmse_omega", "max_abs_omega", "rmse_omega_tracked", "max_abs_omega_tracked"), "rad/s"
    ),
    **dict.fromkeys(
        (
            *("rmse_lateral", "max_lateral", "cross_track_rms", "cross_track_max"),
            *("along_track_rms", "along_track_max", "rmse_position", "max_position"),
            *("trailer_rmse_lateral", "trailer_max_lateral", "trailer_offtrack_rms"),
            *("trailer_offtrack_max", "leading_cross_track_rms", "leading_cross_track_max"),
            *("train_offtrack_rms_worst", "train_offtrack_max_worst"),
        ),
        "m",
    ),
    **dict.fromkeys(("phi_max_abs_deg", "train_phi_max_abs_deg"), "deg"),
    "eq_violation_max": "rad",
    **dict.fromkeys(("sample_period_s", "sim_time_s", "wall_time_s"), "s"),
    **dict.fromkeys(
        (
            *("torque_saturation_fraction", "disturbance_clipped_fraction", "steps"),
            *("finite_samples", "trailer_lateral_samples", "trailer_offtrack_samples"),
        ),
        "",
    ),
}


def metric_unit(name: str) -> str | None:
    """The unit of the built-in metric ``name`` ("" for a pure number), None for one that is
    not built in (a user's metric: its unit is its author's)."""
    if name in METRIC_UNITS:
        return METRIC_UNITS[name]
    parts = name.split("_")
    if len(parts) > 2 and parts[0] == "trailer" and parts[1].isdigit():
        rest = "_".join(parts[2:])  # trailer_2_offtrack_rms, trailer_2_phi_max_abs_deg
        return METRIC_UNITS.get(f"trailer_{rest}", METRIC_UNITS.get(rest))
    return None


def _format_value(value) -> str:
    if isinstance(value, bool | np.bool_):
        return str(bool(value))
    if isinstance(value, int | np.integer):
        return str(int(value))
    if isinstance(value, float | np.floating):
        return f"{float(value):.6g}"
    return str(value)


def summary_table(metrics: Mapping[str, object], keys: Sequence[str] = DEFAULT_SUMMARY_KEYS) -> str:
    """Plain-text table of selected metrics, for the CLI's printed summary.

    Names are left-aligned, values right-aligned; floats use 6 significant digits; then each
    built-in metric's unit (:func:`metric_unit`).

    Parameters
    ----------
    metrics : mapping
        E.g. the result of :func:`~tt_mujoco.analysis.metrics.compute_metrics`, with more
        entries or not.
    keys : sequence of str
        Rows, in order.

    Raises
    ------
    ValueError
        If a key is not in ``metrics``.
    """
    keys = list(keys)
    missing = [k for k in keys if k not in metrics]
    if missing:
        raise ValueError(
            f"summary keys {missing} are not in the metrics; available: {sorted(metrics)}"
        )
    if not keys:
        return ""
    values = [_format_value(metrics[k]) for k in keys]
    name_width = max(len(k) for k in keys)
    value_width = max(len(v) for v in values)
    return "\n".join(
        f"{k:<{name_width}}  {v:>{value_width}}  {metric_unit(k) or ''}".rstrip()
        for k, v in zip(keys, values, strict=True)
    )


#: Extra metric name -> function ``fn(timeseries, path) -> float`` (or None). ``METRICS.register``
#: adds one; a hook ``module:function`` or ``file.py:function`` needs no registration.
METRICS = Registry("metric", called_as=("timeseries", "path"))


#: The keys ``metrics.json`` holds beside the metrics: the run's outcome, its configuration and
#: its parts' reports (no user's metric may take one).
RUN_KEYS = (
    *("status", "message", "notes", "config", "metric_errors", "reversing"),
    *("controller", "faults", "terrain", "ground", "world"),
)
#: Built-in metrics that are a word, not a number.
TEXT_METRICS = ("offtrack_follower",)


def builtin_key(name: str) -> bool:
    """Whether ``metrics.json`` keeps ``name`` for a built-in metric or the run's own entry."""
    return metric_unit(name) is not None or name in TEXT_METRICS or name in RUN_KEYS


def resolve_metrics(specs) -> dict:
    """``{name: function}`` for the names and hooks in ``specs``.

    Raises
    ------
    ValueError
        A bad name or hook, or one whose key (:func:`metric_name`) is a built-in metric's, the
        run's own (:data:`RUN_KEYS`) or another of ``specs``': its value would replace theirs,
        or be replaced.
    """
    out, given = {}, {}
    for spec in specs:
        named = isinstance(spec, str) and not is_hook(spec) and spec not in METRICS
        if named and builtin_key(spec.strip()):
            raise ValueError(
                f"metric {spec!r} is not allowed: every run's metrics.json holds it (a "
                "built-in metric, or the run's own entry); --metric adds one of yours (a "
                "registered name, or a hook 'package.module:function' or "
                "'path/to/file.py:function')"
            )
        fn = METRICS.resolve(spec)
        METRICS.check_call(fn, spec)
        name = metric_name(spec)
        if builtin_key(name):
            raise ValueError(
                f"metric {spec!r} is not allowed: it would land under {name!r} in metrics.json, "
                "which holds the run's own value there; rename the function (or register the "
                "metric under another name)"
            )
        if name in out:
            raise ValueError(
                f"metric {spec!r} is not allowed: metric {given[name]!r} lands under {name!r} "
                "already; rename one of the two functions"
            )
        out[name], given[name] = fn, spec
    return out


def metric_name(spec: str) -> str:
    """The key a metric lands under in ``metrics.json``: the registered name, or the
    function's name of a hook."""
    return spec.rsplit(":", 1)[-1] if ":" in spec else spec

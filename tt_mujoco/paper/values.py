"""A run's metric read from its records, and a number as the report prints it."""

from __future__ import annotations

import math

import numpy as np

__all__ = ["fmt", "metric_of"]


def metric_of(records, key: str, metric: str) -> float:
    rec = records.get(key)
    if not rec or rec.get("status") == "error":
        return math.nan
    value = rec.get("metrics", {}).get(metric)
    return math.nan if value is None else float(value)


def fmt(value, digits: int = 4) -> str:
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

"""The time series of a run: its columns, and their assembly from the logged steps."""

from __future__ import annotations

import numpy as np

from tt_mujoco.sim.parts.measure import TRAIN_FIELDS, Measurement

__all__ = ["COLUMNS", "LOOP_COLUMNS", "UNITS", "assemble_columns", "train_columns", "unit_of"]

#: Time-series columns, one row per control step (SI units, radians). See
#: :mod:`tt_mujoco.analysis.metrics`.
COLUMNS = (
    "t",
    "x",
    "y",
    "theta",
    "phi",
    "beta",
    "v",
    "omega",
    "x0",
    "y0",
    "theta0",
    "v0",
    "theta_l",
    "theta_r",
    "s",
    "x_ref",
    "y_ref",
    "v_d",
    "omega_d",
    "v_d_dot",
    "omega_d_dot",
    "v_meas",
    "omega_meas",
    "T_r",
    "T_l",
    "T_r_cmd",
    "T_l_cmd",
    "dist_T_r",
    "dist_T_l",
    "slip_lateral",
    "slip_lateral_trailer",
    "slip_left",
    "slip_right",
    "eq_violation",
    "kappa_d",
    "theta_ref",
    "omega_d_tracked",
    "dist_clipped",
)

#: The unit of every column (written into a Parquet file's metadata).
UNITS = {
    **dict.fromkeys(("t", "sim_time"), "s"),
    **dict.fromkeys(("x", "y", "x0", "y0", "s", "x_ref", "y_ref"), "m"),
    **dict.fromkeys(("theta", "phi", "beta", "theta0", "theta_l", "theta_r"), "rad"),
    **dict.fromkeys(("theta_ref", "eq_violation"), "rad"),
    **dict.fromkeys(("v", "v0", "v_d", "v_meas"), "m/s"),
    **dict.fromkeys(("slip_lateral", "slip_lateral_trailer", "slip_left", "slip_right"), "m/s"),
    **dict.fromkeys(("omega", "omega_d", "omega_meas", "omega_d_tracked"), "rad/s"),
    "v_d_dot": "m/s^2",
    "omega_d_dot": "rad/s^2",
    **dict.fromkeys(("T_r", "T_l", "T_r_cmd", "T_l_cmd", "dist_T_r", "dist_T_l"), "N m"),
    "kappa_d": "1/m",
    "dist_clipped": "1 (0 or 1)",
}

LOOP_COLUMNS = (
    "t",
    "s",
    "v_d",
    "omega_d",
    "v_d_dot",
    "omega_d_dot",
    "v_meas",
    "omega_meas",
    "T_r",
    "T_l",
    "T_r_cmd",
    "T_l_cmd",
    "dist_T_r",
    "dist_T_l",
    "kappa_d",
    "omega_d_tracked",
    "dist_clipped",
)


def train_columns(n_trailers: int) -> tuple[str, ...]:
    """The columns of trailers 2..N, after :data:`COLUMNS`: ``x0_k, y0_k, theta0_k, phi_k,
    beta_k, v0_k`` for each k (trailer 1 keeps ``x0, y0, theta0, phi, beta, v0``)."""
    return tuple(f"{name}_{k}" for k in range(2, n_trailers + 1) for name in TRAIN_FIELDS)


def unit_of(column: str) -> str | None:
    """The unit of a time-series column, trailer k's included (None if unknown)."""
    if column in UNITS:
        return UNITS[column]
    base, _, k = column.rpartition("_")
    return UNITS.get(base) if k.isdigit() else None


def assemble_columns(measured: list, logged: list, eta: float) -> dict[str, np.ndarray]:
    """The time series in :data:`COLUMNS` order from the per-step measurement rows and the
    loop's own values (``x_ref``, ``y_ref``, ``theta_ref`` are left NaN for the caller to fill)."""
    n = len(logged)
    # Transposed once, so that every column is a contiguous row (not a strided copy each).
    meas = np.asarray(measured, dtype=float).reshape(n, len(Measurement._fields)).T.copy()
    loop = np.asarray(logged, dtype=float).reshape(n, len(LOOP_COLUMNS)).T.copy()
    cols = dict(zip(Measurement._fields, meas, strict=True))
    cols.update(zip(LOOP_COLUMNS, loop, strict=True))
    cols["eq_violation"] = cols["beta"] - eta * cols["phi"]
    cols["x_ref"] = np.full(n, np.nan)
    cols["y_ref"] = np.full(n, np.nan)
    cols["theta_ref"] = np.full(n, np.nan)
    return {name: np.ascontiguousarray(cols[name]) for name in COLUMNS}

"""Curvature-scheduled passive steering on a running plant."""

from __future__ import annotations

import math

import numpy as np

from tt_mujoco.sim.plant import Plant
from tt_mujoco.vehicle.params import Params
from tt_mujoco.vehicle.steering import (
    SCHEDULE_TOLERANCE,
    exact_same_path_eta,
    exact_train_same_path_etas,
)

__all__ = ["EtaScheduler"]


class EtaScheduler:
    """Curvature-scheduled passive steering: eta = :func:`exact_same_path_eta` of the local
    curvature, applied to a running plant (the paper's eta(s) idea, docs/model.md Section 3).

    Parameters
    ----------
    plant : tt_mujoco.sim.plant.Plant
        The running plant; its :meth:`~tt_mujoco.sim.plant.Plant.set_eta` applies the gain.
    params : Params
        The plant's parameters (L, L0 and the initial eta).
    tolerance : float
        Re-apply eta only when it moved by more than this (see :data:`SCHEDULE_TOLERANCE`).

    Notes
    -----
    The controllers' nominal model keeps the scenario's constant eta; eta enters Mbar only
    through the trailer wheels (docs/model.md Section 4), and the scheduled gains stay within
    [-0.160, -0.143] for |kappa| <= 2 1/m, so the mismatch is a small model error the controllers
    treat like any other.
    """

    def __init__(self, plant, params: Params, tolerance: float = SCHEDULE_TOLERANCE):
        if not (isinstance(tolerance, int | float) and math.isfinite(tolerance) and tolerance >= 0):
            raise ValueError(f"tolerance={tolerance!r} is not allowed: it must be a number >= 0")
        self.L, self.L0 = params.L, params.L0
        self.lengths = [(t.L, t.L0) for t in params.trailers]
        self.tolerance = float(tolerance)
        self.eta = params.eta
        self.etas = params.etas
        self.updates = 0
        self._kappa: float | None = None
        # (first sample, eta) for every change: sample j was reached under the eta in force
        # during the step before it.
        self._changes: list[tuple[int, float]] = [(0, self.eta)]
        if not isinstance(plant, Plant):
            raise ValueError(
                f"plant={type(plant).__name__} is not allowed: use a tt_mujoco.sim.plant.Plant"
            )
        self._plant = plant

    def update(self, kappa: float, step: int = 0) -> float:
        """Schedule eta for curvature ``kappa`` (1/m) before the step after sample ``step``.

        Returns the eta now in force (it governs the plant from sample ``step + 1`` on).
        """
        if kappa == self._kappa:  # arcs: constant curvature, nothing to recompute
            return self.eta
        self._kappa = kappa
        if len(self.lengths) > 1:  # a train: every trailer's own exact gain
            etas = tuple(exact_train_same_path_etas(kappa, self.lengths))
        else:
            etas = (exact_same_path_eta(kappa, self.L, self.L0),)
        if max(abs(a - b) for a, b in zip(etas, self.etas, strict=True)) > self.tolerance:
            self._apply(etas)
            self._changes.append((step + 1, self.eta))
        return self.eta

    def eta_series(self, n: int) -> np.ndarray:
        """The eta in force at each of ``n`` logged samples (for ``beta - eta phi``)."""
        out = np.empty(n)
        for (start, eta), (stop, _) in zip(
            self._changes, [*self._changes[1:], (n, 0.0)], strict=True
        ):
            out[start : max(start, min(stop, n))] = eta
        return out

    def _apply(self, etas: tuple) -> None:
        self._plant.set_etas(etas)
        self.etas, self.eta = etas, etas[0]
        self.updates += 1

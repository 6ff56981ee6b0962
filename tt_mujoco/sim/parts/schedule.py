"""Scheduled passive steering on a running plant: by the target's curvature
(:class:`EtaScheduler`) or by each trailer's place on the path (:class:`PathEtaScheduler`)."""

from __future__ import annotations

import math

import numpy as np

from tt_mujoco.defaults import DRIVEN_PATH_GAIN
from tt_mujoco.sim.parts.measure import ROW_X0, ROW_Y0
from tt_mujoco.sim.parts.plant import Plant
from tt_mujoco.vehicle.params import Params
from tt_mujoco.vehicle.path_schedule import (
    PathSchedule,
    driven_path,
)
from tt_mujoco.vehicle.steering import (
    SCHEDULE_TOLERANCE,
    exact_same_path_eta_of,
    exact_train_same_path_etas_of,
)

__all__ = [
    "CURVATURE_SCHEDULE",
    "PATH_SCHEDULE",
    "EtaScheduler",
    "PathEtaScheduler",
    "curvature_gains_of",
    "eta_series_of",
    "gains_moved",
]

#: How the step schedules the gains (its steering record's ``kind``; 0: constant gains): the
#: path schedule (:class:`PathEtaScheduler`) and the curvature schedule (:class:`EtaScheduler`)
PATH_SCHEDULE, CURVATURE_SCHEDULE = 1, 2


class EtaScheduler:
    """Curvature-scheduled passive steering: eta = :func:`exact_same_path_eta` of the local
    curvature, applied to a running plant (the paper's eta(s) idea, docs/model.md Section 3).

    Parameters
    ----------
    plant : tt_mujoco.sim.parts.plant.Plant
        The running plant; its :meth:`~tt_mujoco.sim.parts.plant.Plant.set_eta` applies the gain.
    params : Params
        The plant's parameters (L, L0 and the initial eta).
    tolerance : float
        Re-apply eta only when it moved by more than this (see :data:`SCHEDULE_TOLERANCE`).

    Notes
    -----
    The step schedules the gains from its steering record (:func:`curvature_gains_of` and
    :func:`gains_moved`, in :func:`tt_mujoco.sim.loop.closed_loop.actuate_step`); the scheduler
    applies the first gains; what the run did stays in its steering record. Every change
    reaches the controller through
    :meth:`~tt_mujoco.controllers.base.Controller.steering_changed` (the loop calls it), and the
    built-in laws rebuild their nominal model with the gains in force: eta enters Mbar through
    the trailer wheels (docs/model.md Section 4). With the curvature schedule the gains stay
    within [-0.159, -0.143] for |kappa| <= 2 1/m; with the path schedule they range over
    [-3, 3].
    """

    def __init__(self, plant, params: Params, tolerance: float = SCHEDULE_TOLERANCE):
        if not (isinstance(tolerance, int | float) and math.isfinite(tolerance) and tolerance >= 0):
            raise ValueError(f"tolerance={tolerance!r} is not allowed: it must be a number >= 0")
        self.lengths = [(t.L, t.L0) for t in params.trailers]
        self.tolerance = float(tolerance)
        self.eta = params.eta
        #: the first gains, which the episode's steering record starts from and changes
        self.etas = params.etas
        if not isinstance(plant, Plant):
            raise ValueError(
                f"plant={type(plant).__name__} is not allowed: use a "
                "tt_mujoco.sim.parts.plant.Plant"
            )
        self._plant = plant

    def _apply(self, etas: tuple) -> None:
        """The first gains ``etas`` in force in the plant."""
        self._plant.set_etas(etas)
        self.etas, self.eta = etas, etas[0]


def eta_series_of(changes, n: int) -> np.ndarray:
    """The first trailer's gain in force at each of ``n`` logged samples, from ``changes``:
    ``(first sample, gains)`` of every change, the first at sample 0 (sample j was reached
    under the gains in force during the step before it)."""
    out = np.empty(n)
    for (start, gains), (stop, _) in zip(changes, [*changes[1:], (n, None)], strict=True):
        out[start : max(start, min(stop, n))] = gains[0]
    return out


class PathEtaScheduler(EtaScheduler):
    """Path-scheduled passive steering: trailer k's gain is the path schedule's eta_k at its
    own axle's arc length (:mod:`tt_mujoco.vehicle.path_schedule`, docs/model.md Section 13).

    Parameters
    ----------
    plant : tt_mujoco.sim.parts.plant.Plant
        The running plant.
    params : Params
        The plant's parameters.
    schedule : PathSchedule
        The tabulated schedule of the scenario's path and train.
    start_s : float
        The tractor's arc length at the start (the path's end when reversing): each axle's
        projection starts from the schedule's place for it there.
    tolerance : float
        As :class:`EtaScheduler`.
    steps : int
        The run's control steps (how much of the tractor's driven path to hold).
    reverse : bool
        Backing up: the axles lead the tractor and take the table's steering, with no
        feedback to the tractor's path.
    gain : float
        The feedback's gain driving forward (1/m; 0: the table's steering alone).

    Notes
    -----
    Each step projects every axle onto the path (Newton steps from its previous arc length)
    and looks its gain up there, so a trailer that is off its schedule gets the gain of where
    it is, not of where the tractor is. Driving forward, the steering it is given is the one
    that turns it onto the path the tractor drove (:func:`~tt_mujoco.vehicle.path_schedule.
    driven_steering_of`): along the path's tangent from the trailer's heading as it is, less
    ``atan(gain e)`` where it stands ``e`` beside that path. The plant starts on
    the gains of where its axles stand (before the first step). A gain that sweeps [-3, 3] and
    changes sign along the path is no fixed linkage ratio, so the plant's axles are steered by
    an actuator (:meth:`~tt_mujoco.sim.parts.plant.Plant.steer_by_actuator`).
    """

    def __init__(
        self,
        plant,
        params: Params,
        schedule: PathSchedule,
        start_s: float = 0.0,
        tolerance: float = SCHEDULE_TOLERANCE,
        steps: int = 0,
        reverse: bool = False,
        gain: float = DRIVEN_PATH_GAIN,
    ):
        super().__init__(plant, params, tolerance)
        if schedule.n_trailers != len(self.lengths):
            raise ValueError(
                f"schedule for {schedule.n_trailers} trailers is not allowed: the plant has "
                f"{len(self.lengths)}"
            )
        self.schedule = schedule
        #: the path the tractor drove (steps + 1 control steps are logged at most)
        self.driven = driven_path(steps + 1, start_s, 0.0 if reverse else float(gain))
        #: each axle's first arc length on the path (the steering record's from there)
        self.arc_lengths = schedule.arc_lengths_at(start_s)
        for k, (x, y) in enumerate(_axle_positions(plant.measure())):
            self.arc_lengths[k] = schedule.project(self.arc_lengths[k], x, y)
        start = tuple(schedule.eta(k, s) for k, s in enumerate(self.arc_lengths))
        plant.steer_by_actuator()
        self._apply(start)


def curvature_gains_of(kappa: float, lengths, out) -> bool:
    """The exact same-path gains at curvature ``kappa`` of trailers with ``lengths`` (rows of
    L_k, L0_k) into ``out``: each trailer's own in a train (docs/model.md Section 12). False
    where the path is too tight for some axle to reach it: the gains in force are then kept
    (the compiled episode shares it)."""
    if len(lengths) > 1:
        return exact_train_same_path_etas_of(kappa, lengths, out) == 0
    out[0] = exact_same_path_eta_of(kappa, lengths[0][0], lengths[0][1])
    return not math.isnan(out[0])


def gains_moved(etas, current, tolerance: float) -> bool:
    """Whether any of the scheduled ``etas`` moved from the ``current`` ones by more than
    ``tolerance`` (then all are applied; the compiled episode shares it)."""
    for i in range(len(etas)):
        if abs(etas[i] - current[i]) > tolerance:
            return True
    return False


def _axle_positions(me) -> list[tuple[float, float]]:
    """Every trailer's axle midpoint (x, y) in a measurement, trailer 1 first."""
    return [(me.x0, me.y0), *((row[ROW_X0], row[ROW_Y0]) for row in getattr(me, "train", ()))]

"""A planned maneuver with cusps (:class:`tt_mujoco.world.plan.Plan` of more than one leg),
driven leg by leg.

Each leg is a run of its own, from rest to rest: driving forward the tractor leads, backing up
the last trailer's axle does (the hitch cascade, or whatever drives the scenario backing up).
A leg starts where the last one stopped: the tractor's measured pose and hitch angles, at rest,
on a fresh plant (on MuJoCo, the wheels' spin angles and the settled contacts of the last
leg are not carried over; the train is at rest and straight to within the tracking error).
A leg that stops (a collision, a jackknife, the time limit) stops the maneuver. A train that
stopped off the next leg's start drives that leg as planned: the hitch cascade takes the offset
back. Planning again from where it stood was tried and measured worse (the loading bay, two
trailers, 20 dB noise, 1000 seeds: 961 reached, against 986; every start lost was one with a
cusp, at 5 cm and at 25 cm off alike): a fresh plan from a train not quite straight starts
backing worse than the planned leg does.

The maneuver's result is one run: the legs' time series joined (time running on), the
reference the legs' paths in the order driven, the legs' metrics merged
(:func:`~tt_mujoco.analysis.metrics.merge_metrics`: each leg measured against its own path,
its own leading unit), the world's report over the joined series, and under
``world.plan.legs`` each leg's own (when it ran, how it ended, how far its leading point was
from its path). A user's metric is given the joined series and the last leg's path.
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np

from tt_mujoco.analysis.metrics import RUN_KEYS, merge_metrics
from tt_mujoco.controllers import controller_class
from tt_mujoco.sim.build import Build, LegStart, build, reversing_drive
from tt_mujoco.sim.simulate import Result, drive_leg, driven_leg, finish, user_metric
from tt_mujoco.sim.usercode import users_copy
from tt_mujoco.world.part import world_report

__all__ = ["drive", "final_state", "leg_rng"]

#: Never less than this is left to a leg's wall-clock limit (s): an alarm of 0 is none.
_LEAST_LIMIT = 1e-3


def final_state(ts: dict, n_trailers: int) -> tuple[tuple, tuple]:
    """``(pose, phis)``: the tractor's pose ``(x, y, theta)`` and the hitch angles
    phi_1..phi_N in the last row of a time series."""
    pose = (float(ts["x"][-1]), float(ts["y"][-1]), float(ts["theta"][-1]))
    names = ["phi", *(f"phi_{k}" for k in range(2, n_trailers + 1))]
    return pose, tuple(float(ts[name][-1]) for name in names)


def leg_rng(seed: int, index: int) -> np.random.Generator:
    """The noise of leg ``index`` of a maneuver of ``seed``: the run's own for the first leg,
    one of its own for each later one."""
    return np.random.default_rng([seed, index] if index else seed)


def _leg_progress(progress, index: int, legs: int):
    """The maneuver's progress from a leg's: each leg an equal share."""
    if progress is None:
        return None
    return lambda done, total: progress(round(1000 * (index + done / max(total, 1))), 1000 * legs)


def drive(first: Build, progress=None, on_step=None, checkpoint=None) -> Result:
    """Drive the maneuver whose first leg ``first`` is (see the module); the arguments and
    the result as :func:`tt_mujoco.sim.simulate.simulate`'s. The checkpoint file holds the
    rows of the leg that runs."""
    plan = first.plan
    asked = dataclasses.replace(first.scenario, reverse=plan.legs[-1].reverse)
    began = time.perf_counter()
    driven = []  # (build, stepper, result) of each leg that ran
    stop = None  # why a leg could not start
    built = first
    for index in range(len(plan.legs)):
        if index:
            pose, phis = final_state(driven[-1][2].timeseries, built.plant_params.n_trailers)
            try:
                built = build(asked, LegStart(plan, index, pose, phis))
            except ValueError as err:  # where the last leg stopped, this one cannot start
                # (a user's controller failing to be made again, a unit left the bounds):
                # after the run began, a stop that keeps what was driven
                stop = f"leg {index + 1} of {len(plan.legs)} could not start: {err}"
                break
        rng = leg_rng(asked.seed, index)
        left = max(asked.time_limit_s - (time.perf_counter() - began), _LEAST_LIMIT)
        stepper, controller, status, message, wall = drive_leg(
            built, rng, left, _leg_progress(progress, index, len(plan.legs)), on_step, checkpoint
        )
        result = finish(built, stepper, controller, status, message, wall)
        driven.append((built, stepper, result))
        if status != "ok" or not len(result.timeseries["t"]):
            break
    return _joined(asked, plan, driven, stop)


def _run_keys(metrics: dict, asked, last: dict) -> None:
    """The controller's report and the metric errors as the last leg gave them, and what
    drives the backing legs (said though the run stopped before any of them backed up)."""
    for key in ("controller", "metric_errors"):
        if key in last and key not in metrics:
            metrics[key] = last[key]
    reversing = reversing_drive(asked, controller_class(asked.controller))
    if reversing is not None:
        metrics["reversing"] = reversing


def _joined(asked, plan, driven, stop: str | None = None) -> Result:
    """One result of the legs that ran (``stop``: why the next could not start)."""
    offsets, t0 = [], 0.0
    for built, _, result in driven:
        offsets.append(t0)
        if len(result.timeseries["t"]):
            t0 += float(result.timeseries["t"][-1]) + built.control_dt
    keys = list(driven[0][2].timeseries)
    ts = {}
    for key in keys:
        parts = [result.timeseries[key] for _, _, result in driven]
        if key == "t":
            parts = [part + offset for part, offset in zip(parts, offsets, strict=True)]
        ts[key] = np.concatenate(parts)
    # the reference as driven: a leg backing up drives its path from its end
    lines = [
        result.reference_polyline[::-1] if built.scenario.reverse else result.reference_polyline
        for built, _, result in driven
    ]
    polyline = np.concatenate(lines)
    last_built, last_stepper, last = driven[-1]
    own = set(last_built.extra_metrics) | set(RUN_KEYS) | {"wall_time_s"}
    metrics = merge_metrics(
        [{k: v for k, v in result.metrics.items() if k not in own} for _, _, result in driven]
    ) or {"steps": 0, "finite_samples": 0, "sim_time_s": 0.0}
    for name, fn in last_built.extra_metrics.items():
        metrics[name], error = user_metric(fn, ts, users_copy(last_built.path))
        if error is not None:
            metrics.setdefault("metric_errors", {})[name] = error
    clearance = np.concatenate(
        [stepper.world_clearance[: len(result.timeseries["t"])] for _, stepper, result in driven]
    )
    collision = last_stepper.collision
    if collision is not None:
        unit, obstacle, t, gap = collision
        collision = (unit, obstacle, t + offsets[-1], gap)
    metrics["world"] = world_report(
        last_built.world, last_built.plant_params, ts, clearance, collision
    )
    report = plan.report()
    for leg, (built, _, result), offset in zip(report["legs"], driven, offsets, strict=False):
        t = result.timeseries["t"]
        driven_leg(leg, built.scenario.reverse, result.metrics, t, result.status, offset)
    metrics["world"]["plan"] = report
    _run_keys(metrics, asked, last.metrics)
    metrics["wall_time_s"] = sum(result.wall_time_s for _, _, result in driven)
    status = "failed" if stop is not None else last.status
    metrics["status"] = status
    notes = []
    for _, _, result in driven:
        notes += [note for note in result.notes if note not in notes]
    notes.append(
        f"the maneuver has {plan.cusps} cusp{'s' if plan.cusps > 1 else ''}: its legs were "
        "driven one after the other, each from rest where the last stopped"
    )
    message = f"completed {t0:.3f} s in {len(plan.legs)} legs"
    if stop is not None:
        message = stop
    elif last.status != "ok":
        stopped = plan.legs[len(driven) - 1].direction
        message = f"leg {len(driven)} of {len(plan.legs)} ({stopped}): {last.message}"
    config = dict(last.config)
    config["scenario"] = asked.to_dict()
    config["target"] = {**config["target"], "duration_s": float(t0)}
    return Result(
        scenario=asked,
        timeseries=ts,
        metrics=metrics,
        status=status,
        message=message,
        reference_polyline=polyline,
        wall_time_s=metrics["wall_time_s"],
        config=config,
        details=last.details,
        notes=notes,
    )

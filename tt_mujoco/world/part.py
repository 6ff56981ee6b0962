"""The world as a part of the run: its record for the step, its checks before the run and its
report after it.

Before the run (:func:`check_world`): every obstacle, the goal and the start are checked
against the run's vehicle, and a world that cannot be driven is bad input (a
:class:`~tt_mujoco.world.world.WorldError` naming the obstacle). During it, the step checks the
units' footprints (:mod:`tt_mujoco.vehicle.footprint`) against the obstacles at every control
step (:func:`tt_mujoco.sim.loop.closed_loop.sense_step`, :mod:`tt_mujoco.world.contact`) and logs
the
least gap. After it, :func:`world_report` gives ``metrics.json`` its ``world`` section.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from tt_mujoco.vehicle.footprint import footprints, unit_names
from tt_mujoco.vehicle.params import Params
from tt_mujoco.vehicle.reduced import hitch_and_axle
from tt_mujoco.world import contact
from tt_mujoco.world.world import World, WorldError

__all__ = [
    "WorldRecord",
    "check_goal",
    "check_world",
    "no_world_record",
    "outside_bounds",
    "start_problem",
    "unit_poses",
    "world_record",
    "world_report",
]


class WorldRecord(NamedTuple):
    """A world's obstacles and the units' footprints, as the step reads them: the world part's
    record (:data:`tt_mujoco.sim.loop.records.LoopRecord` holds it as ``world``)."""

    #: every unit's footprint (tractor first: N + 1 rows of rear, front, half width) and, as the
    #: step measures them, their poses (x, y, heading); a unit's corners (4 x 2, scratch)
    boxes: np.ndarray
    poses: np.ndarray
    corners: np.ndarray
    #: the obstacles (empty: no world): their corners (M x V x 2, counter-clockwise, each
    #: ``sizes[o]`` of them) and the circles around them (M x (x, y, radius))
    polygons: np.ndarray
    sizes: np.ndarray
    circles: np.ndarray
    #: per control step, the least gap between a unit and an obstacle (m)
    clearance: np.ndarray


def no_world_record(n_units: int = 2) -> WorldRecord:
    """The record of a run with no world: no obstacles, so the step checks nothing."""
    return WorldRecord(
        boxes=np.zeros((n_units, 3)),
        poses=np.zeros((n_units, 3)),
        corners=np.zeros((4, 2)),
        polygons=np.zeros((0, 4, 2)),
        sizes=np.zeros(0, dtype=np.int64),
        circles=np.zeros((0, 3)),
        clearance=np.zeros(0),
    )


def _obstacle_arrays(world: World, p: Params):
    polygons = world.polygons(footprints(p)[-1])
    most = max((len(poly) for poly in polygons), default=4)
    table = np.zeros((len(polygons), most, 2))
    circles = np.zeros((len(polygons), 3))
    for o, poly in enumerate(polygons):
        table[o, : len(poly)] = poly
        centre = poly.mean(axis=0)
        circles[o] = (*centre, float(np.max(np.hypot(*(poly - centre).T))))
    return table, np.array([len(poly) for poly in polygons], dtype=np.int64), circles


def world_record(world: World | None, p: Params, steps: int) -> WorldRecord:
    """The record the step checks ``world``'s obstacles with, for vehicle ``p`` and a run of
    ``steps`` control steps."""
    if world is None or not world.all_obstacles:
        return no_world_record(p.n_trailers + 1)
    polygons, sizes, circles = _obstacle_arrays(world, p)
    return WorldRecord(
        boxes=footprints(p),
        poses=np.zeros((p.n_trailers + 1, 3)),
        corners=np.zeros((4, 2)),
        polygons=polygons,
        sizes=sizes,
        circles=circles,
        clearance=np.full(steps + 1, math.inf),
    )


def unit_poses(pose, hitches, p: Params) -> np.ndarray:
    """Every unit's pose ``(x, y, heading)`` (tractor first) for the tractor at ``pose`` and
    hitch angles ``hitches`` (rad), from the hitch geometry (docs/model.md Section 1)."""
    x, y, heading = pose
    poses = [(x, y, heading)]
    for t, phi in zip(p.trailers, hitches, strict=True):
        trailer_heading = heading - phi
        _, _, x, y = hitch_and_axle(x, y, heading, trailer_heading, t.L, t.L0)
        heading = trailer_heading
        poses.append((x, y, heading))
    return np.array(poses, dtype=float)


def _first_touch(record: WorldRecord, poses: np.ndarray, units) -> tuple[float, int, int]:
    boxes = record.boxes[list(units)]
    return contact.clearance_of(
        poses, boxes, record.polygons, record.sizes, record.circles, record.corners
    )


def outside_bounds(bounds, points) -> bool:
    """Whether any of ``points`` (rows of x, y, ...) lies outside ``bounds`` (x_min, x_max,
    y_min, y_max)."""
    x_min, x_max, y_min, y_max = bounds
    return bool(np.any((points[:, 0] < x_min) | (points[:, 0] > x_max))) or bool(
        np.any((points[:, 1] < y_min) | (points[:, 1] > y_max))
    )


def start_problem(
    world: World, record: WorldRecord, p: Params, pose, hitches, margin: float = 0.0
) -> str | None:
    """Why the train of ``p`` cannot start in ``world`` (its ``record``:
    :func:`world_record`) with the tractor at ``pose`` and ``hitches`` (a unit's axle outside
    the bounds, or a unit within ``margin`` of an obstacle), or None."""
    start = unit_poses(pose, hitches, p)
    if world.bounds is not None and outside_bounds(world.bounds, start[:, :2]):
        return (
            f"the start is not allowed: a unit's axle lies outside world {world.name!r}'s "
            f"bounds {list(world.bounds)}"
        )
    obstacles = world.all_obstacles
    gap, unit, obstacle = _first_touch(record, start, range(p.n_trailers + 1))
    if obstacles and gap <= margin:
        where = "stands on" if gap <= 0.0 else f"comes within {margin:g} m of"
        return (
            f"the start is not allowed: the {unit_names(p.n_trailers)[unit]} {where} obstacle "
            f"{obstacles[obstacle].name!r} of world {world.name!r} (the run starts with the "
            f"tractor at x={pose[0]:g}, y={pose[1]:g} m, heading {math.degrees(pose[2]):g} deg)"
        )
    return None


def check_world(world: World | None, p: Params, pose, hitches) -> None:
    """Raise a :class:`WorldError` when ``world`` cannot be driven by vehicle ``p`` starting at
    ``pose`` with ``hitches``: a bay narrower than the last unit, a goal or a start on an
    obstacle or outside the bounds."""
    if world is None:
        return
    record = world_record(world, p, 0)
    problem = start_problem(world, record, p, pose, hitches)
    if problem is not None:
        raise WorldError(problem)
    check_goal(world, p, record)


def check_goal(world: World, p: Params, record: WorldRecord | None = None) -> None:
    """Raise a :class:`WorldError` when ``world``'s goal cannot be reached by vehicle ``p``,
    whatever the path: a bay narrower or shallower than the last unit, a goal outside the
    bounds or on an obstacle (a planner asks before it searches)."""
    record = world_record(world, p, 0) if record is None else record
    boxes, obstacles = footprints(p), world.all_obstacles
    goal = world.goal
    if goal is None:
        return
    width = 2 * boxes[-1][2]
    if goal.bay is not None and goal.bay.width <= width:
        raise WorldError(
            f"goal bay width={goal.bay.width!r} m is not allowed: the last trailer is "
            f"{width:g} m wide; use a width > {width:g} m"
        )
    if goal.bay is not None and goal.bay.back <= -boxes[-1][0]:
        raise WorldError(
            f"goal bay back={goal.bay.back!r} m is not allowed: the last trailer reaches "
            f"{-boxes[-1][0]:g} m behind its axle; use back > {-boxes[-1][0]:g} m"
        )
    at_goal = np.array([[goal.x, goal.y, math.radians(goal.heading_deg)]])
    if world.bounds is not None and outside_bounds(world.bounds, at_goal[:, :2]):
        raise WorldError(
            f"goal x={goal.x!r}, y={goal.y!r} is not allowed: it lies outside world "
            f"{world.name!r}'s bounds {list(world.bounds)}"
        )
    gap, _, obstacle = _first_touch(record, at_goal, [len(boxes) - 1])
    if obstacles and gap <= 0.0:
        raise WorldError(
            f"goal x={goal.x!r}, y={goal.y!r}, heading_deg={goal.heading_deg!r} is not allowed: "
            f"the last trailer there would stand on obstacle {obstacles[obstacle].name!r}"
        )


def world_report(world: World, p: Params, ts, clearance: np.ndarray, collision) -> dict:
    """The ``world`` section of ``metrics.json``: the least clearance over the logged rows,
    the collision that stopped the run (``(unit, obstacle, t, gap)`` or None) and, with a
    goal, where the last axle ended against it."""
    names = unit_names(p.n_trailers)
    logged = clearance[: len(ts["t"])]
    finite = logged[np.isfinite(logged)]
    report = {
        "name": world.name,
        "obstacles": len(world.all_obstacles),
        "min_clearance_m": float(finite.min()) if finite.size else None,
        "collision": None,
    }
    if collision is not None:
        unit, obstacle, t, gap = collision
        report["collision"] = {
            "unit": names[unit],
            "obstacle": world.all_obstacles[obstacle].name,
            "t": t,
            "depth_m": -gap,
        }
    goal = world.goal
    if goal is None or not len(ts["t"]):
        return report
    n = p.n_trailers
    suffix = "" if n == 1 else f"_{n}"
    x, y = float(ts[f"x0{suffix}"][-1]), float(ts[f"y0{suffix}"][-1])
    heading = float(ts[f"theta0{suffix}"][-1])
    heading_error = math.remainder(heading - math.radians(goal.heading_deg), math.tau)
    position_error = math.hypot(x - goal.x, y - goal.y)
    hitches = [float(ts["phi"][-1]), *(float(ts[f"phi_{k}"][-1]) for k in range(2, n + 1))]
    report["goal"] = {
        "position_error_m": position_error,
        "heading_error_deg": math.degrees(heading_error),
        "final_hitch_deg": [math.degrees(phi) for phi in hitches],
        "reached": bool(
            collision is None
            and position_error <= goal.position_tolerance
            and abs(math.degrees(heading_error)) <= goal.heading_tolerance_deg
        ),
    }
    return report

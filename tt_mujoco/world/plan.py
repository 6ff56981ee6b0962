"""A path for the tractor that takes the train from its start to the world's goal, forward or
backing up, clear of every obstacle (``--traj plan``).

With the passive steering the project uses (same-path gains), every axle follows the tractor's
path; so a path for the tractor is a path for the whole train, and where each unit stands at
any moment is the path's axle chain (:func:`tt_mujoco.vehicle.path_schedule.axle_chain`, the
path continued along its end tangents). At the goal the train stands straight, its last axle on
the goal pose: the tractor then stands ``D`` (the train's length from the tractor's axle to the
last axle, straight) ahead of it along the goal's heading.

- **Backing up**: the run drives the path backwards (:class:`~tt_mujoco.reference.reverse.
  ReverseTarget`, the last axle leading), from the tractor's start at the path's end to the
  tractor's place at the goal at its start. The path: from the tractor at the goal, straight
  out along the goal's heading for an ``exit`` length, a Dubins word
  (:mod:`tt_mujoco.world.dubins`) to the pose ``D`` behind the tractor's start, then straight
  ``D`` to the start (the train starts straight, so its axles are on that straight).
- **Forward**: from the tractor's start, a Dubins word to the goal pose ``exit`` short of it,
  then straight ``exit + D`` to the tractor's place at the goal.

The candidates (each exit length of :data:`EXITS`, each radius of :data:`RADII` scaled by the
train's least radius, each Dubins word) are tried shortest first, the long exits before the
short ones; the first whose every unit
keeps ``margin`` from every obstacle at every sample (``step`` apart along the path) is the
plan. Every formula it uses is the project's own: the axle chain, the footprints and the
contact check (:mod:`tt_mujoco.world.contact`).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from tt_mujoco.reference.paths import ArcsPath
from tt_mujoco.vehicle.params import Params
from tt_mujoco.vehicle.path_schedule import axle_chain
from tt_mujoco.world import contact
from tt_mujoco.world.dubins import dubins_words
from tt_mujoco.world.part import start_problem, world_record
from tt_mujoco.world.world import World, WorldError

__all__ = [
    "EXITS",
    "MARGIN",
    "PLAN",
    "RADII",
    "Plan",
    "PlanError",
    "plan_path",
    "planned",
    "start_pose",
    "train_length",
]

#: ``Scenario.traj`` of a run whose path is planned to its world's goal.
PLAN = "plan"
#: How many starts are drawn before a world's start region is called too crowded.
START_DRAWS = 1000

#: The clearance every unit keeps from every obstacle along a plan (m).
MARGIN = 0.05
#: The straight lengths out of (or into) the goal tried, as multiples of the train's length
#: ``D``: the long ones first (the train then ends a straight as long as itself, on which the
#: hitch cascade straightens it), the short ones where no long one is clear.
EXITS = ((1.0, 1.5, 2.0), (0.0, 0.25, 0.5))
#: The turning radii tried, as multiples of the train's least radius (:func:`least_radius`).
RADII = (1.0, 1.25, 1.5, 2.0, 3.0)
#: The least turning radius of one trailer's plan (m): the hitch cascade backs the paper's
#: vehicle around R = 1.5 m (the reversing S-curve); each further trailer adds a third of it
#: (:func:`least_radius`).
LEAST_RADIUS = 1.5
#: The spacing of the samples the plan is checked at (m), and every how many of them a first
#: look is taken.
STEP, COARSE = 0.05, 8


class PlanError(WorldError):
    """No plan: the message says why and how far the best candidate got."""


@dataclass(frozen=True)
class Plan:
    """A planned path and how it was found."""

    #: the tractor's path (consecutive arcs, in closed form)
    path: ArcsPath
    #: "reverse" (the run backs it up) or "forward"
    direction: str
    #: the Dubins word, its radius (m), the straight exit (m)
    word: str
    radius: float
    exit: float
    #: the least clearance of any unit along it (m), the candidates tried, the time taken (s)
    clearance: float
    candidates: int
    planning_time_s: float

    def report(self) -> dict:
        """The plan as ``metrics.json``'s ``world.plan`` gives it."""
        return {
            "direction": self.direction,
            "word": self.word,
            "radius_m": self.radius,
            "exit_m": self.exit,
            "length_m": float(self.path.length),
            "clearance_m": self.clearance,
            "candidates": self.candidates,
            "planning_time_s": self.planning_time_s,
        }


def train_length(p: Params) -> float:
    """``D``: from the tractor's axle to the last trailer's axle, the train straight (m)."""
    return float(sum(t.L + t.L0 for t in p.trailers))


def least_radius(p: Params) -> float:
    """The least turning radius a plan uses for this train (m)."""
    return LEAST_RADIUS * (1.0 + (p.n_trailers - 1) / 3.0)


def _ahead(pose, distance: float):
    x, y, heading = pose
    return x + distance * math.cos(heading), y + distance * math.sin(heading), heading


def _arcs(start, pieces) -> ArcsPath:
    """The path from ``start`` through ``pieces`` ``(length, kappa)`` (zero lengths left out)."""
    segments = [(length, kappa) for length, kappa in pieces if length > 1e-9]
    return ArcsPath("plan", start, segments)


def _word_pieces(word) -> list[tuple[float, float]]:
    turn = {"L": 1.0 / word.radius, "R": -1.0 / word.radius, "S": 0.0}
    return [(length, turn[kind]) for kind, length in zip(word.kinds, word.lengths, strict=True)]


def clearance_along(
    path, p: Params, record, step: float = STEP, below: float = -math.inf
) -> tuple[float, float]:
    """``(gap, reached)``: the least gap between any unit of ``p`` and any obstacle of a
    world's ``record`` (:func:`~tt_mujoco.world.part.world_record`) with the tractor at arc
    lengths ``step`` apart along ``path``, every unit on the path's axle chain, and the
    fraction of the samples looked at. With ``below``, it stops at the first sample whose gap
    is under it, looking first at every :data:`COARSE`-th sample (a path that fails is most
    often told there, and those samples are among the others), and gaps of ``below`` or more
    are not told apart (the gap is then ``below``)."""
    cap = math.inf if below == -math.inf else below
    if not record.sizes.size:
        return math.inf, 1.0
    s = np.linspace(0.0, path.length, max(2, math.ceil(path.length / step) + 1))
    lengths = [(t.L, t.L0) for t in p.trailers]
    poses = np.zeros((p.n_trailers + 1, 3))

    def gaps(arcs):
        """Each sample's least gap, the units placed on the axle chain."""
        x, y, heading = path.pose(arcs)
        chain = axle_chain(path, arcs, lengths)
        for i in range(len(arcs)):
            poses[0] = x[i], y[i], heading[i]
            for k, axle in enumerate(chain, start=1):
                poses[k] = axle["x"][i], axle["y"][i], axle["theta"][i]
            gap, _, _ = contact.clearance_of(
                poses,
                record.boxes,
                record.polygons,
                record.sizes,
                record.circles,
                record.corners,
                cap,
            )
            yield i, gap

    if below > -math.inf:
        for i, gap in gaps(s[::COARSE]):
            if gap < below:
                return gap, i * COARSE / len(s)
    least = math.inf
    for i, gap in gaps(s):
        least = min(least, gap)
        if least < below:
            return least, (i + 1) / len(s)
    return least, 1.0


def plan_path(
    world: World,
    p: Params,
    start,
    reverse: bool,
    margin: float = MARGIN,
    deadline: float | None = None,
) -> Plan:
    """The shortest candidate path (see the module) from the tractor's ``start`` pose
    ``(x, y, heading)`` (the train straight) to ``world``'s goal that keeps ``margin`` (m)
    from every obstacle; a :class:`PlanError` when none does (or when ``deadline``, a
    ``time.monotonic()`` value, passes first)."""
    began = time.perf_counter()
    goal = world.goal
    if goal is None:
        raise WorldError(f"world {world.name!r} has no goal to plan a path to")
    d = train_length(p)
    goal_pose = (goal.x, goal.y, math.radians(goal.heading_deg))
    tractor_at_goal = _ahead(goal_pose, d)
    tail_at_start = _ahead(start, -d)
    base = least_radius(p)
    record = world_record(world, p, 0)
    candidates = []
    for tier, exits in enumerate(EXITS):
        for exit_length in (d * share for share in exits):
            for scale in RADII:
                radius = base * scale
                if reverse:
                    out = _ahead(tractor_at_goal, exit_length)
                    words = dubins_words(out, tail_at_start, radius)
                else:
                    words = dubins_words(start, _ahead(goal_pose, -exit_length), radius)
                candidates += [(tier, w.length + exit_length, exit_length, w) for w in words]
    candidates.sort(key=lambda c: c[:2])
    best, tried = 0.0, 0
    for _, _, exit_length, word in candidates:
        if deadline is not None and time.monotonic() > deadline:
            break
        tried += 1
        if reverse:
            pieces = [(exit_length, 0.0), *_word_pieces(word), (d, 0.0)]
            path = _arcs(tractor_at_goal, pieces)
        else:
            pieces = [*_word_pieces(word), (exit_length + d, 0.0)]
            path = _arcs(start, pieces)
        gap, reached = clearance_along(path, p, record, below=margin)
        best = max(best, reached)
        if gap >= margin:  # clear: its exact clearance, for the report
            gap, _ = clearance_along(path, p, record)
            return Plan(
                path=path,
                direction="reverse" if reverse else "forward",
                word=word.kinds,
                radius=word.radius,
                exit=exit_length,
                clearance=gap,
                candidates=tried,
                planning_time_s=time.perf_counter() - began,
            )
    why = "its time limit passed" if tried < len(candidates) else "none is clear"
    closest = f"; the best is clear for {100 * best:.0f} % of it" if tried else ""
    raise PlanError(
        f"no path to world {world.name!r}'s goal from x={start[0]:.3f}, y={start[1]:.3f} m, "
        f"heading {math.degrees(start[2]):.1f} deg "
        f"({'backing up' if reverse else 'forward'}): {tried} of {len(candidates)} candidates "
        f"tried, {why} with a margin of {margin:g} m{closest}"
    )


def start_pose(world: World, p: Params, seed: int) -> tuple[float, float, float]:
    """The tractor's start in ``world`` for a run of ``seed`` (the train straight behind it):
    its given pose, or one drawn from its ranges, again until every unit keeps
    :data:`MARGIN` from every obstacle (the draws have a stream of their own, so the run's
    noise is as without them)."""
    if world.start is None:
        raise WorldError(f"world {world.name!r} has no start: give [start] x, y, heading_deg")
    rng = np.random.default_rng([seed, 0x5747])
    record, problem = world_record(world, p, 0), None
    for _ in range(START_DRAWS if world.start.drawn else 1):
        pose = world.start.draw(rng)
        problem = start_problem(world, record, p, pose, (0.0,) * p.n_trailers, MARGIN)
        if problem is None:
            return pose
    if world.start.drawn:
        problem = (
            f"world {world.name!r}'s start is not allowed: none of {START_DRAWS} starts drawn "
            f"from its ranges keeps the train inside its bounds and {MARGIN:g} m from its "
            "obstacles"
        )
    raise WorldError(problem)


def planned(world: World, p: Params, seed: int, reverse: bool, deadline=None) -> Plan:
    """The plan of a run of ``seed`` in ``world`` (its start: :func:`start_pose`)."""
    return plan_path(world, p, start_pose(world, p, seed), reverse, deadline=deadline)

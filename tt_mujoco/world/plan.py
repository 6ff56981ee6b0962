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

- **Backing up into a short bay**: where the straight out of the goal cannot hold the whole
  train (a bay right after a turn), the path starts at the goal pose itself, straight out for
  a share of :data:`GOAL_STRAIGHTS` of ``D`` (never shorter than the last trailer), then the
  Dubins word and the straight ``D`` to the start. The run then stops with the tractor at
  ``stop_s`` along it (:attr:`Leg.stop_s`), where the axle chain puts the last axle on the
  path's start: the train ends on the curve, its last axle on the goal pose.
- **Backing up with a cusp** (when no path backs in directly): the train drives forward to a
  cusp, stops, and backs in. The leg it backs: from the tractor at the goal, straight out for
  an exit, an arc (of :data:`CUSP_TURNS`, at a radius of :data:`CUSP_RADII`) and a straight
  to the cusp (2 ``D`` where it is clear, else ``D``: :data:`CUSP_STRAIGHTS`), on which the
  trailers straighten after the forward leg's last turn. The forward leg: a Dubins word from
  the start to that last straight, then along it to the cusp.

The candidates (each exit length of :data:`EXITS`, each radius of :data:`RADII` scaled by the
train's least radius, each Dubins word) are tried shortest first, the long exits before the
short ones, then the plans with a cusp, and last those that end on a curve (its train ends
less precisely: the trailers there follow the tractor's path only as closely as their gains
let them in a change of curvature); the first whose every unit keeps ``margin`` from every
obstacle, and every axle inside the world's bounds, at every sample (``step`` apart along each
leg) is the plan. Where none is, the last resort is a search over the poses where the train
stands straight (:mod:`tt_mujoco.world.roadmap`: plans with several cusps). Every formula it
uses is the project's own: the axle chain, the footprints and the contact check
(:mod:`tt_mujoco.world.contact`).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace

import numpy as np

from tt_mujoco.reference.paths import ArcsPath
from tt_mujoco.vehicle.footprint import unit_names
from tt_mujoco.vehicle.params import Params
from tt_mujoco.vehicle.path_schedule import axle_chain
from tt_mujoco.world.clearance import clearance_along
from tt_mujoco.world.dubins import ahead, arcs_path, dubins_words, word_pieces
from tt_mujoco.world.part import check_goal, start_problem, world_record
from tt_mujoco.world.roadmap import roadmap_route
from tt_mujoco.world.world import World, WorldError

__all__ = [
    "CURVE_HEADING_SHARE",
    "CUSP_EXITS",
    "CUSP_RADII",
    "CUSP_STRAIGHTS",
    "CUSP_TURNS",
    "EXITS",
    "GOAL_STRAIGHTS",
    "MARGIN",
    "NO_PLAN",
    "PLAN",
    "RADII",
    "START_REFUSED",
    "BestCandidate",
    "Leg",
    "Plan",
    "PlanError",
    "StartError",
    "plan_path",
    "planned",
    "start_pose",
    "train_end_on",
    "train_length",
]

#: ``Scenario.traj`` of a run whose path is planned to its world's goal.
PLAN = "plan"
#: The statuses of a sweep's run whose start has no plan, or a plan the run cannot drive as
#: asked (a row, not the sweep's end: :class:`StartError`).
NO_PLAN, START_REFUSED = "no_plan", "start_refused"
#: How many starts are drawn before a world's start region is called too crowded.
START_DRAWS = 1000

#: The clearance every unit keeps from every obstacle along a plan (m).
MARGIN = 0.05
#: The straight lengths out of (or into) the goal tried, as multiples of the train's length
#: ``D``: the long ones first (the train then ends a straight as long as itself, on which the
#: hitch cascade straightens it), the short ones where no long one is clear.
EXITS = ((1.0, 1.5, 2.0), (0.0, 0.25, 0.5))
#: The straights out of the goal pose tried, as multiples of ``D``, where no straight of the
#: whole train is clear (the train then ends on the curve beyond it).
GOAL_STRAIGHTS = (0.9, 0.8, 0.7, 0.6, 0.5)
#: The share of the goal's heading tolerance a plan ending on a curve may spend: there the last
#: trailer's heading is its hitch's, which the unit ahead of it on the curve places off the
#: path's tangent; the rest is left to the tracking.
CURVE_HEADING_SHARE = 0.5
#: The turning radii tried, as multiples of the train's least radius (:func:`least_radius`).
RADII = (1.0, 1.25, 1.5, 2.0, 3.0)
#: The least turning radius of one trailer's plan (m): the hitch cascade backs the paper's
#: vehicle around R = 1.5 m (the reversing S-curve); each further trailer adds a third of it
#: (:func:`least_radius`).
LEAST_RADIUS = 1.5
#: Where no plan at the least radius is clear, turns down to this share of it are tried (the
#: cascade backs circles that tight as closely: ``benchmarks/reversing_radius.py``).
TIGHT_RADIUS_SHARE = 0.7
#: A cusp's place: the straight out of the goal before the arc (multiples of ``D``), the arc's
#: turn (rad, left positive) and radius (multiples of the least radius).
CUSP_EXITS = (0.5, 1.0, 2.0)
CUSP_TURNS = (0.0, math.pi / 4, -math.pi / 4, math.pi / 2, -math.pi / 2)
CUSP_RADII = (1.0, 1.5)
#: The straight the train drives into a cusp, as multiples of ``D``, the long one tried first:
#: after the forward leg's last turn the passively steered trailers straighten only with the
#: distance driven (the ones further back more slowly), and the backing leg starts from where
#: they then stand (tests/test_maneuver.py).
CUSP_STRAIGHTS = (2.0, 1.0)


class StartError(WorldError):
    """A run's start (drawn by its seed) cannot be driven as asked: in a sweep, that run's
    outcome (a row with the status :attr:`status`), not its configuration's fault."""

    status = START_REFUSED


@dataclass(frozen=True)
class BestCandidate:
    """The candidate of a planning with no plan that got furthest before it was blocked: what
    a figure of the failure draws (:func:`tt_mujoco.viz.plan_figure.plot_best_candidate`).

    Attributes
    ----------
    world : World
    params : Params
        The train planned for.
    start : tuple of float
        The tractor's start ``(x, y, heading)`` (m, rad).
    word : str
        The candidate's name in the failure's message.
    polyline : numpy.ndarray
        The tractor's path, ``(n, 2)`` (m).
    reached : float
        The fraction of it that is clear.
    poses : numpy.ndarray
        Every unit's ``(x, y, heading)`` where it was blocked (the tractor first).
    unit, obstacle : str or None
        The unit that came too close, and the obstacle (None: the world's bounds).
    """

    world: World
    params: Params
    start: tuple
    word: str
    polyline: np.ndarray
    reached: float
    poses: np.ndarray
    unit: str
    obstacle: str | None


class PlanError(StartError):
    """No plan: the message says why and how far the best candidate got; :attr:`best` is that
    candidate (a :class:`BestCandidate`, None where none was tried)."""

    status = NO_PLAN

    def __init__(self, message: str, best: BestCandidate | None = None):
        super().__init__(message)
        self.best = best

    def __reduce__(self):  # a sweep's worker sends the message, not the drawing's data
        return type(self), (str(self),)


@dataclass(frozen=True)
class Leg:
    """One leg of a plan: the tractor's path and the way it is driven. A leg is driven from
    rest to rest; backing up (``"reverse"``), the run drives the path from its end to its
    start, the last axle leading."""

    #: the tractor's path (consecutive arcs, in closed form)
    path: ArcsPath
    #: "forward" or "reverse"
    direction: str
    #: its pieces, as letters: a Dubins word ("LSR"), or the backing leg's "S", "SLS", ...
    word: str
    #: the radius of its arcs (m; 0 for a straight)
    radius: float
    #: backing up, the tractor's arc length on ``path`` where the leg ends, with the last axle
    #: at the path's start (m; 0: the tractor ends at the path's start, the train straight
    #: beyond it)
    stop_s: float = 0.0

    @property
    def reverse(self) -> bool:
        return self.direction == "reverse"

    @property
    def driven_length(self) -> float:
        """How far the tractor drives along the leg (m)."""
        return float(self.path.length) - self.stop_s

    def report(self) -> dict:
        return {
            "direction": self.direction,
            "word": self.word,
            "radius_m": self.radius,
            "length_m": float(self.path.length),
            "stop_s_m": self.stop_s,
        }


@dataclass(frozen=True)
class Plan:
    """A planned maneuver, its legs driven one after the other, and how it was found."""

    legs: tuple[Leg, ...]
    #: the straight exit out of (or into) the goal beyond the train standing in it (m;
    #: negative: the straight out of the goal is this much shorter than the train, which ends
    #: on the curve beyond it)
    exit: float
    #: the least clearance of any unit along it (m), the candidates tried, the time taken (s)
    clearance: float
    candidates: int
    planning_time_s: float

    @property
    def cusps(self) -> int:
        """The direction switches: one between each two legs."""
        return len(self.legs) - 1

    def report(self) -> dict:
        """The plan as ``metrics.json``'s ``world.plan`` gives it."""
        last = self.legs[-1]
        return {
            "direction": last.direction,
            "word": " + ".join(leg.word for leg in self.legs),
            "radius_m": last.radius if not self.cusps else self.legs[0].radius,
            "exit_m": self.exit,
            "length_m": float(sum(leg.driven_length for leg in self.legs)),
            "cusps": self.cusps,
            "legs": [leg.report() for leg in self.legs],
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


def _direct(start, goal_pose, d, base, reverse):
    """The candidates without a cusp: ``((tier, length), exit, origin, pieces, word)``."""
    tractor_at_goal = ahead(goal_pose, d)
    tail_at_start = ahead(start, -d)
    for tier, exits in enumerate(EXITS):
        for exit_length in (d * share for share in exits):
            for scale in RADII:
                if reverse:
                    out = ahead(tractor_at_goal, exit_length)
                    for word in dubins_words(out, tail_at_start, base * scale):
                        pieces = [(exit_length, 0.0), *word_pieces(word), (d, 0.0)]
                        key = (tier, word.length + exit_length)
                        yield key, exit_length, tractor_at_goal, pieces, word
                else:
                    for word in dubins_words(start, ahead(goal_pose, -exit_length), base * scale):
                        pieces = [*word_pieces(word), (exit_length + d, 0.0)]
                        yield (tier, word.length + exit_length), exit_length, start, pieces, word


def _on_curve(start, goal_pose, d, base, last_unit: float):
    """The backing candidates that start at the goal pose, ``((straight, length), exit,
    origin, pieces, word)``: the longest straight out of the goal first (the train ends on the
    curve beyond it, its last axle at the start, :func:`train_end_on`)."""
    tail_at_start = ahead(start, -d)
    straights = {max(d * share, last_unit) for share in GOAL_STRAIGHTS}
    for straight in (length for length in straights if length < d):
        for scale in RADII:
            for word in dubins_words(ahead(goal_pose, straight), tail_at_start, base * scale):
                pieces = [(straight, 0.0), *word_pieces(word), (d, 0.0)]
                yield (-straight, word.length + straight), straight - d, goal_pose, pieces, word


def _prefix(pieces, length: float) -> tuple:
    """The ``(length, kappa)`` pieces of a path's first ``length`` (m), rounded: a key."""
    out, done = [], 0.0
    for piece, kappa in pieces:
        if done >= length:
            break
        out.append((round(min(piece, length - done), 9), round(kappa, 9)))
        done += piece
    return tuple(out)


def train_end_on(path, p: Params) -> tuple[float, float] | None:
    """``(stop_s, heading_error)``: the tractor's arc length on ``path`` at which every axle of
    ``p``'s train lies on it and the last one at its start
    (:func:`~tt_mujoco.vehicle.path_schedule.axle_chain`), and how far the last trailer's
    heading is then from the path's start's (rad, absolute); None where the path turns too
    tightly for the chain."""
    lengths = [(t.L, t.L0) for t in p.trailers]
    d = train_length(p)
    try:  # the last axle's arc length grows with the tractor's: bracket its zero on a grid
        grid = np.linspace(0.75 * d, 1.25 * d, 11)
        last = axle_chain(path, grid, lengths)[-1]["s"]
        i = int(np.searchsorted(last, 0.0))
        if not 0 < i < len(grid):
            return None
        slope = (last[i] - last[i - 1]) / (grid[i] - grid[i - 1])
        s = grid[i - 1] - last[i - 1] / slope
        for _ in range(8):  # Newton's steps with the grid's slope
            axle = axle_chain(path, np.array([s]), lengths)[-1]
            if abs(axle["s"][0]) < 1e-7:
                heading = float(axle["theta"][0]) - path.pose_at(0.0)[2]
                return float(s), abs(math.remainder(heading, math.tau))
            s -= float(axle["s"][0]) / slope
    except ValueError:
        pass
    return None


def _backing_legs(goal_pose, d, base):
    """The legs a cusp plan backs in on, each ``(tier, leg, exit, straight)``: from the tractor
    at the goal straight out, an arc of :data:`CUSP_TURNS` and a straight (of
    :data:`CUSP_STRAIGHTS`, tier its index) to the cusp."""
    tractor_at_goal = ahead(goal_pose, d)
    for tier, straight in enumerate(d * share for share in CUSP_STRAIGHTS):
        for share in CUSP_EXITS:
            exit_length = d * share
            for turn in CUSP_TURNS:
                for scale in CUSP_RADII if turn else (0.0,):
                    radius = base * scale
                    kappa = math.copysign(1.0 / radius, turn) if turn else 0.0
                    arc = abs(turn) * radius
                    pieces = [(exit_length, 0.0), (arc, kappa), (straight, 0.0)]
                    word = "S" if not turn else ("SLS" if turn > 0 else "SRS")
                    leg = Leg(arcs_path(tractor_at_goal, pieces), "reverse", word, radius)
                    yield tier, leg, exit_length, straight


def _with_cusp(start, goal_pose, d, base):
    """The candidates with one cusp, ``((tier, length), exit, backing leg, word, straight)``:
    the forward leg a Dubins word from ``start`` to the backing leg's last straight, then along
    it (the long straights of :data:`CUSP_STRAIGHTS` first)."""
    for tier, backing, exit_length, straight in _backing_legs(goal_pose, d, base):
        approach = backing.path.pose_at(backing.path.length - straight)
        for scale in RADII:
            for word in dubins_words(start, approach, base * scale):
                length = word.length + straight + backing.path.length
                yield (tier, length), exit_length, backing, word, straight


class _Search:
    """One planning's bookkeeping: which candidates are clear (keeping ``margin``), the one
    that got furthest before it was blocked, how many were tried, and the plan or the
    message it ends in."""

    def __init__(self, world: World, p: Params, margin: float):
        self.world, self.p, self.margin = world, p, margin
        self.record = world_record(world, p, 0)
        self.began = time.perf_counter()
        self.best, self.tried, self.total, self.late = 0.0, 0, 0, False
        self.worst = {}  # where the candidate that got furthest was blocked
        # the last resort's poses and the edges between them checked (tt_mujoco.world.roadmap)
        self.roadmap_poses = self.roadmap_edges = 0

    def out_of_time(self, deadline: float | None) -> bool:
        """Whether ``deadline`` (a ``time.monotonic()`` value, None: none) has passed; once
        it has, the planning is :attr:`late`."""
        self.late = self.late or (deadline is not None and time.monotonic() > deadline)
        return self.late

    def next_candidate(self, deadline: float | None) -> bool:
        """Whether another candidate may be tried (``deadline`` not passed); counts it."""
        if self.out_of_time(deadline):
            return False
        self.tried += 1
        return True

    def clear(self, path, word: str = "", s_from: float = 0.0) -> bool:
        """Whether every unit keeps the margin along ``path`` (and the bounds), the tractor
        from ``s_from`` on."""
        where = {}
        gap, reached = clearance_along(
            path,
            self.p,
            self.record,
            below=self.margin,
            bounds=self.world.bounds,
            blocked=where,
            s_from=s_from,
        )
        if gap < self.margin and reached > self.best:  # the blocked one that got furthest
            self.best = reached
            self.worst.clear()
            self.worst.update(where, word=word, path=path)
        return gap >= self.margin

    def found(self, legs, exit_length: float) -> Plan:
        clearance = min(
            clearance_along(leg.path, self.p, self.record, s_from=leg.stop_s)[0] for leg in legs
        )
        return Plan(
            legs=tuple(legs),
            exit=exit_length,
            clearance=clearance,
            candidates=self.tried,
            planning_time_s=time.perf_counter() - self.began,
        )

    def failure(self, start, reverse: bool) -> PlanError:
        """No candidate is clear (or the time ran out): what was tried, and how far the best
        one got and what blocked it."""
        why = (
            f"its time limit passed before one clear by {self.margin:g} m was found"
            if self.late
            else f"none is clear with a margin of {self.margin:g} m"
        )
        closest, worst, margin = "", self.worst, self.margin
        if self.tried and worst:
            names = unit_names(self.p.n_trailers)
            obstacles = self.world.all_obstacles
            what = (
                "leaves the world's bounds"
                if worst.get("obstacle") is None
                else f"comes within {margin:g} m of {obstacles[worst['obstacle']].name!r}"
            )
            closest = (
                f"; the best ({worst['word']}) is clear for {math.floor(100 * self.best)} % of "
                f"it, then the {names[worst['unit']]} {what} (the tractor at x={worst['x']:.2f}, "
                f"y={worst['y']:.2f} m)"
            )
        roadmap = (
            f" (and {self.roadmap_edges} edges between {self.roadmap_poses} poses where the "
            "train stands straight)"
            if self.roadmap_poses
            else ""
        )
        return PlanError(
            f"no path to world {self.world.name!r}'s goal from x={start[0]:.3f}, "
            f"y={start[1]:.3f} m, heading {math.degrees(start[2]):.1f} deg "
            f"({'backing up' if reverse else 'forward'}): {self.tried - self.roadmap_edges} of "
            f"{self.total} candidates tried{roadmap}, {why}{closest}"
            f"{'' if reverse else '; --reverse plans the train backing in'}",
            self._best_candidate(start) if self.tried and worst else None,
        )

    def _best_candidate(self, start) -> BestCandidate:
        worst, obstacles = self.worst, self.world.all_obstacles
        path = worst["path"]
        x, y, _ = path.pose(np.linspace(0.0, path.length, max(2, math.ceil(path.length / 0.05))))
        return BestCandidate(
            world=self.world,
            params=self.p,
            start=tuple(float(v) for v in start),
            word=worst["word"],
            polyline=np.column_stack([x, y]),
            reached=self.best,
            poses=worst["poses"],
            unit=unit_names(self.p.n_trailers)[worst["unit"]],
            obstacle=None if worst["obstacle"] is None else obstacles[worst["obstacle"]].name,
        )


def plan_path(
    world: World,
    p: Params,
    start,
    reverse: bool,
    margin: float = MARGIN,
    deadline: float | None = None,
    radius_share: float = 1.0,
) -> Plan:
    """The shortest candidate plan (see the module) from the tractor's ``start`` pose
    ``(x, y, heading)`` (the train straight) to ``world``'s goal that keeps ``margin`` (m)
    from every obstacle, its turns at least ``radius_share`` times :func:`least_radius`; a
    :class:`PlanError` when none does (or when ``deadline``, a ``time.monotonic()`` value,
    passes first)."""
    search = _Search(world, p, margin)
    goal = world.goal
    if goal is None:
        raise WorldError(f"world {world.name!r} has no goal to plan a path to")
    check_goal(world, p, search.record)  # outside the world, on an obstacle: not searched for
    d = train_length(p)
    goal_pose = (goal.x, goal.y, math.radians(goal.heading_deg))
    base = least_radius(p) * radius_share
    direction = "reverse" if reverse else "forward"
    direct = sorted(_direct(start, goal_pose, d, base, reverse), key=lambda c: c[0])
    search.total += len(direct)
    for _, exit_length, origin, pieces, word in direct:
        if not search.next_candidate(deadline):
            break
        path = arcs_path(origin, pieces)
        if search.clear(path, f"{word.kinds} at {word.radius:.3g} m"):
            return search.found([Leg(path, direction, word.kinds, word.radius)], exit_length)
    if reverse and not search.late:
        cusped = sorted(_with_cusp(start, goal_pose, d, base), key=lambda c: c[0])
        search.total += len(cusped)
        backing_clear: dict[int, bool] = {}
        for _, exit_length, backing, word, straight in cusped:
            if not search.next_candidate(deadline):
                break
            key = id(backing)
            if key not in backing_clear:
                backing_clear[key] = search.clear(backing.path, f"backing {backing.word}")
            if not backing_clear[key]:
                continue
            forward = arcs_path(start, [*word_pieces(word), (straight, 0.0)])
            if search.clear(forward, f"forward {word.kinds} at {word.radius:.3g} m, then backing"):
                legs = [Leg(forward, "forward", word.kinds, word.radius), backing]
                return search.found(legs, exit_length)
    if reverse and not search.late:  # last: a train that ends on a curve ends less precisely
        last_unit = p.trailers[-1].L + p.trailers[-1].L0
        heading_allowed = CURVE_HEADING_SHARE * math.radians(goal.heading_tolerance_deg)
        curved = sorted(_on_curve(start, goal_pose, d, base, last_unit), key=lambda c: c[0])
        search.total += len(curved)
        ends = {}  # where the train ends depends only on the path's first 1.5 D
        for _, exit_length, origin, pieces, word in curved:
            if not search.next_candidate(deadline):
                break
            path = arcs_path(origin, pieces)
            key = _prefix(pieces, 1.5 * d)
            if key not in ends:
                ends[key] = train_end_on(path, p)
            if ends[key] is None or ends[key][1] > heading_allowed:
                continue
            stop = ends[key][0]
            label = f"{word.kinds} at {word.radius:.3g} m, the train ending on its curve"
            if search.clear(path, label, s_from=stop):
                leg = Leg(path, direction, word.kinds, word.radius, stop)
                return search.found([leg], exit_length)
    if not search.late:  # the last resort: a search over where the train stands straight
        route = roadmap_route(search, start, ahead(goal_pose, d), d, base, reverse, deadline)
        if route is not None:
            legs = [
                Leg(arcs_path(origin, pieces), leg_direction, word, radius)
                for leg_direction, origin, pieces, word, radius in route[0]
            ]
            return search.found(legs, route[1])
    raise search.failure(start, reverse)


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
    """The plan of a run of ``seed`` in ``world`` (its start: :func:`start_pose`); where none
    is clear at the least radius (a narrow aisle), one with :data:`TIGHT_RADIUS_SHARE` of it."""
    start, began = start_pose(world, p, seed), time.perf_counter()
    try:
        return plan_path(world, p, start, reverse, deadline=deadline)
    except PlanError as err:
        if deadline is not None and time.monotonic() >= deadline:
            raise
        try:
            plan = plan_path(
                world, p, start, reverse, deadline=deadline, radius_share=TIGHT_RADIUS_SHARE
            )
        except PlanError:
            raise err from None
    return replace(plan, planning_time_s=time.perf_counter() - began)  # both searches

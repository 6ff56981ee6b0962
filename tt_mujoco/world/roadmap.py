"""The planner's last resort: a search over the poses where the train stands straight, for a
goal no candidate of :mod:`tt_mujoco.world.plan` reaches (a world that needs more than one
cusp, a start facing a dead end, a way round obstacles no single Dubins word finds).

A *node* is a tractor pose with the train straight behind it: the start, poses drawn over the
world (a fixed stream, so a start's plan is the same on every route), and the goal (the tractor
``D`` ahead of the goal pose). An *edge* drives the train from one node to another in one
direction, in the same kinematics as every plan (the path's axle chain):

- **forward** from ``a`` to ``b``: from ``a``, the shortest Dubins word to ``b``'s pose
  ``ROADMAP_STRAIGHT`` ``D`` short of it, then straight into ``b`` (the train is straight on it
  when it stops there);
- **backing** from ``a`` to ``b``: the path from ``b``, straight out for ``ROADMAP_EXIT`` ``D``
  (on which the hitch cascade settles the train), the shortest Dubins word, and straight into
  ``a`` (the train stood on that straight before backing); the run drives it from its end.

Consecutive edges of one direction join into one leg; a change of direction is a cusp, and
costs :data:`CUSP_COST` ``D`` of path. The search is lazy (Bohlin and Kavraki's lazy PRM): the
shortest route through edges not yet known to be blocked is found, its edges are checked
(every unit keeps the margin, every axle inside the bounds: the same check as every candidate),
a blocked one is dropped, and the search runs again, until a route is clear, no route is left
(more nodes are drawn, up to :data:`ROADMAP_ROUNDS` times) or the deadline passes.
"""

from __future__ import annotations

import heapq
import math

import numpy as np

from tt_mujoco.world.dubins import ahead, arcs_path, dubins_words, word_pieces
from tt_mujoco.world.part import start_problem

__all__ = [
    "CUSP_COST",
    "GOAL_EXITS",
    "LINE_POSES",
    "LINE_STEP",
    "MAX_TURN",
    "ROADMAP_EXIT",
    "ROADMAP_NEIGHBOURS",
    "ROADMAP_NODES",
    "ROADMAP_RADIUS",
    "ROADMAP_ROUNDS",
    "ROADMAP_STRAIGHT",
    "roadmap_route",
]

#: Poses drawn in each round, and the rounds drawn before the search gives up.
ROADMAP_NODES, ROADMAP_ROUNDS = 300, 3
#: The edges tried out of each node in each direction: to the nodes whose Dubins word would be
#: shortest, judged by where it starts and ends (:meth:`_Roadmap.near`), and to the goal.
ROADMAP_NEIGHBOURS = 20
#: The straight into a node, and out of the node a backing edge ends at, as multiples of ``D``.
ROADMAP_STRAIGHT, ROADMAP_EXIT = 1.0, 0.5
#: The straights out of the goal an edge into it tries, as multiples of ``D``, the long first
#: (on it the train settles straight, as :data:`tt_mujoco.world.plan.EXITS`' long ones).
GOAL_EXITS = (1.0, 0.5, 0.0)
#: The turning radius of every edge, as a multiple of the train's least radius (the middle of
#: the candidates' radii: backing a train round its least radius is the hardest to track).
ROADMAP_RADIUS = 1.25
#: The spacing of the poses along the start's and the goal's lines, as a multiple of ``D``,
#: and the most poses on each side of each line (a world may be 10 km wide).
LINE_STEP, LINE_POSES = 1.5, 50
#: The most an edge's arcs turn, together (rad): a loop between two nodes is never the way to
#: go (the route through other nodes, or a cusp, is), and checking it costs the most.
MAX_TURN = 1.1 * math.pi
#: What a cusp costs, as path length in multiples of ``D``: the train stops and starts again.
CUSP_COST = 4.0
#: The stream the nodes are drawn from (fixed: the plan depends on the start, never on a seed).
_NODE_STREAM = 0x524F4144

_FORWARD, _BACKING = 1, 2
#: Poses closer than this (m, rad) are one.
_SAME = 1e-6
#: Every how many nodes the search looks at the clock.
_LOOK_EVERY = 64


class _Edge:
    """A drive from node ``a`` to node ``b``: the path (``origin`` and ``(length, kappa)``
    ``pieces``, in the direction the tractor faces), its length, its label, and (into the
    goal) its straight out of the goal."""

    __slots__ = ("exit", "label", "length", "origin", "pieces")

    def __init__(self, origin, pieces, label: str, exit_length: float = 0.0):
        self.origin, self.label, self.exit = origin, label, exit_length
        self.pieces = list(pieces)
        self.length = float(sum(length for length, _ in self.pieces))


def _word(a, b, radius: float):
    """``(pieces, label)`` of the shortest Dubins word from pose ``a`` to ``b`` whose arcs turn
    through :data:`MAX_TURN` at most; none where they are one pose (the words' angles
    wrap there to whole loops); None: no such word."""
    turned = math.remainder(b[2] - a[2], math.tau)
    if math.hypot(b[0] - a[0], b[1] - a[1]) < _SAME and abs(turned) < _SAME:
        return [], "S"
    for word in dubins_words(a, b, radius):
        arcs = (
            length for kind, length in zip(word.kinds, word.lengths, strict=True) if kind != "S"
        )
        if sum(arcs) <= MAX_TURN * radius:
            return word_pieces(word), word.kinds
    return None


def _edge(a, b, direction: int, radius: float, straight: float, exit_length: float):
    """The edge from pose ``a`` to pose ``b`` (see the module), or None (no Dubins word)."""
    if direction == _FORWARD:
        word = _word(a, ahead(b, -straight), radius)
        if word is None:
            return None
        return _Edge(a, [*word[0], (straight, 0.0)], word[1], exit_length)
    word = _word(ahead(b, exit_length), ahead(a, -straight), radius)
    if word is None:
        return None
    return _Edge(b, [(exit_length, 0.0), *word[0], (straight, 0.0)], word[1], exit_length)


class _Roadmap:
    """The nodes (0: the start, 1: the goal, the drawn ones after), their neighbours and the
    edges known so far."""

    def __init__(self, world, p, record, start, goal_tractor, d, radius, margin):
        self.world, self.p, self.record, self.margin = world, p, record, margin
        self.d, self.radius = d, radius
        self.poses = [tuple(start), tuple(goal_tractor)]
        self.rng = np.random.default_rng(_NODE_STREAM)
        self.region = self._region(start, goal_tractor)
        self.edges: dict[tuple[int, int, int], _Edge | None] = {}
        self.neighbours: dict[int, list[int]] = {}
        self.variant: dict[tuple[int, int, int], int] = {}  # an edge into the goal's exit

    def _region(self, start, goal_tractor):
        """Where poses are drawn: the world's bounds, or round its start, goal and obstacles
        with room to turn."""
        if self.world.bounds is not None:
            return self.world.bounds
        xs = [start[0], goal_tractor[0]]
        ys = [start[1], goal_tractor[1]]
        for corners, size in zip(self.record.polygons, self.record.sizes, strict=True):
            xs += list(corners[:size, 0])
            ys += list(corners[:size, 1])
        room = 2.0 * self.d + 2.0 * self.radius
        return min(xs) - room, max(xs) + room, min(ys) - room, max(ys) + room

    def _lines(self):
        """The poses along the start's and the goal's headings, :data:`LINE_STEP` ``D`` apart
        (a corridor the train starts in, the way out of the goal), as far as the region
        reaches (:data:`LINE_POSES` on each side at most)."""
        x_min, x_max, y_min, y_max = self.region
        reach = math.hypot(x_max - x_min, y_max - y_min)
        for k in range(1, min(int(reach / (LINE_STEP * self.d)), LINE_POSES) + 1):
            yield ahead(self.poses[0], -k * LINE_STEP * self.d)
            yield ahead(self.poses[0], k * LINE_STEP * self.d)
            yield ahead(self.poses[1], k * LINE_STEP * self.d)

    def grow(self, count: int) -> None:
        """Draw ``count`` poses (the first time, the poses along the start's and goal's
        lines too); keep those where the straight train keeps the margin."""
        x_min, x_max, y_min, y_max = self.region
        hitches = (0.0,) * self.p.n_trailers
        drawn = (
            (
                float(self.rng.uniform(x_min, x_max)),
                float(self.rng.uniform(y_min, y_max)),
                float(self.rng.uniform(-math.pi, math.pi)),
            )
            for _ in range(count)
        )
        lines = self._lines() if len(self.poses) == 2 else ()
        for pose in (*lines, *drawn):
            inside = x_min <= pose[0] <= x_max and y_min <= pose[1] <= y_max
            if inside and not start_problem(
                self.world, self.record, self.p, pose, hitches, self.margin
            ):
                self.poses.append(pose)
        self.neighbours.clear()
        poses = np.array(self.poses)
        straight, exit_length = ROADMAP_STRAIGHT * self.d, ROADMAP_EXIT * self.d
        # where an edge's Dubins word ends (into b: b's pose the straight short of it) and
        # where it starts (out of a: a's pose; backing, b's the exit beyond it)
        self._ends = {
            _FORWARD: self._keys_of(poses, -straight),
            _BACKING: self._keys_of(poses, exit_length),
        }
        self._starts = {
            _FORWARD: self._keys_of(poses, 0.0),
            _BACKING: self._keys_of(poses, -straight),
        }

    def _keys_of(self, poses: np.ndarray, along: float) -> np.ndarray:
        """Poses moved ``along`` their headings, as points in which a distance weighs a turn
        by the radius."""
        return np.column_stack(
            [
                poses[:, 0] + along * np.cos(poses[:, 2]),
                poses[:, 1] + along * np.sin(poses[:, 2]),
                self.radius * np.cos(poses[:, 2]),
                self.radius * np.sin(poses[:, 2]),
            ]
        )

    def near(self, i: int, direction: int) -> list[int]:
        """The nodes an edge from node ``i`` in ``direction`` is tried to: those whose word's
        end lies nearest a radius beyond where the word starts (the words there are short),
        and the goal."""
        key = (i, direction)
        if key not in self.neighbours:
            start = self._starts[direction][i].copy()
            if direction == _FORWARD:  # a word starts at a and ends at b's approach
                ahead_of = start
                ahead_of[:2] += start[2:]  # the radius along the heading
                gaps = np.linalg.norm(self._ends[_FORWARD] - ahead_of, axis=1)
            else:  # a backing word runs from b's exit to a's straight: b's exit lies behind
                behind = start
                behind[:2] -= start[2:]
                gaps = np.linalg.norm(self._ends[_BACKING] - behind, axis=1)
            gaps[i] = math.inf
            count = min(ROADMAP_NEIGHBOURS, len(gaps) - 1)
            order = np.argpartition(gaps, count - 1)[:count] if count > 0 else []
            near = {int(j) for j in order} | ({1} - {i})  # the goal: always tried
            self.neighbours[key] = sorted(near)
        return self.neighbours[key]

    def edge(self, a: int, b: int, direction: int) -> _Edge | None:
        key = (a, b, direction)
        if key not in self.edges:
            exit_share = GOAL_EXITS[self.variant.get(key, 0)] if b == 1 else ROADMAP_EXIT
            exit_length = exit_share * self.d
            straight = ROADMAP_STRAIGHT * self.d
            if b == 1 and direction == _FORWARD:  # into the goal: the exit is the straight's
                straight += exit_length
            self.edges[key] = _edge(
                self.poses[a], self.poses[b], direction, self.radius, straight, exit_length
            )
        return self.edges[key]

    def drop(self, key) -> bool:
        """Give up edge ``key`` (blocked): False, or True when an edge into the goal has a
        shorter straight out of it left to try in its place."""
        if key[1] != 1 or self.variant.get(key, 0) + 1 >= len(GOAL_EXITS):
            return False
        self.variant[key] = self.variant.get(key, 0) + 1
        del self.edges[key]
        return True


def _shortest(roadmap: _Roadmap, directions, into_goal, blocked: set, late) -> list | None:
    """The cheapest route of edges ``(a, b, direction)`` from the start (node 0) to the goal
    (node 1), arriving there in ``into_goal``, leaving out ``blocked`` edges; None: none, or
    ``late()`` said the time is up (it is asked every :data:`_LOOK_EVERY` nodes)."""
    cusp = CUSP_COST * roadmap.d
    best = {(0, 0): 0.0}
    came: dict[tuple[int, int], tuple] = {}
    queue = [(0.0, 0, 0)]
    popped = 0
    while queue:
        if popped % _LOOK_EVERY == 0 and late():
            return None
        popped += 1
        cost, node, last = heapq.heappop(queue)
        if cost > best.get((node, last), math.inf):
            continue
        if node == 1 and last == into_goal:
            route, state = [], (node, last)
            while state in came:
                state, edge = came[state]
                route.append(edge)
            return route[::-1]
        if node == 1:
            continue
        for direction in directions:
            for other in roadmap.near(node, direction):
                key = (node, other, direction)
                if key in blocked or (other == 1 and direction != into_goal):
                    continue
                edge = roadmap.edge(*key)
                if edge is None:
                    continue
                step = edge.length + (cusp if last and last != direction else 0.0)
                state = (other, direction)
                if cost + step < best.get(state, math.inf):
                    best[state] = cost + step
                    came[state] = ((node, last), key)
                    heapq.heappush(queue, (cost + step, other, direction))
    return None


def roadmap_route(search, start, goal_tractor, d: float, base: float, reverse: bool, deadline):
    """``(legs, exit)``: each leg ``(direction, origin, pieces, word, radius)`` of the route found
    (see the module), the last edge's straight out of the goal; None when none is found.
    ``search`` is the planning's bookkeeping (:class:`tt_mujoco.world.plan._Search`): it
    counts the edges checked, keeps the one blocked furthest along, and holds the deadline."""
    radius = ROADMAP_RADIUS * base
    roadmap = _Roadmap(
        search.world, search.p, search.record, start, goal_tractor, d, radius, search.margin
    )
    directions = (_FORWARD, _BACKING) if reverse else (_FORWARD,)
    into_goal = _BACKING if reverse else _FORWARD
    blocked: set = set()
    clear: set = set()

    def late() -> bool:
        return search.out_of_time(deadline)

    for _ in range(ROADMAP_ROUNDS):
        if late():
            return None
        roadmap.grow(ROADMAP_NODES)
        search.roadmap_poses = len(roadmap.poses)
        while (route := _shortest(roadmap, directions, into_goal, blocked, late)) is not None:
            for key in route:
                if key in clear:
                    continue
                if not search.next_candidate(deadline):
                    return None
                search.roadmap_edges += 1
                edge = roadmap.edge(*key)
                if not search.clear(arcs_path(edge.origin, edge.pieces), f"roadmap {edge.label}"):
                    if not roadmap.drop(key):
                        blocked.add(key)
                    break
                clear.add(key)
            else:
                route = _shortcut(roadmap, route, search, deadline)
                return _legs(roadmap, route), roadmap.edge(*route[-1]).exit
    return None


def _runs(route):
    """The route's edges in runs of one direction, in the order driven."""
    run = []
    for key in route:
        if run and key[2] != run[-1][2]:
            yield run
            run = []
        run.append(key)
    if run:
        yield run


def _shortcut(roadmap: _Roadmap, route: list, search, deadline) -> list:
    """The route with each run of edges of one direction replaced by one edge from its first
    node to its last, where that edge exists and is clear (a roadmap's route through drawn
    poses makes detours, and each node joined adds a change of curvature to track)."""
    out = []
    for run in _runs(route):
        whole = (run[0][0], run[-1][1], run[0][2])
        direct = roadmap.edge(*whole) if len(run) > 1 else None
        if (
            direct is not None
            and direct.length < sum(roadmap.edge(*one).length for one in run)
            and search.next_candidate(deadline)
            and search.clear(arcs_path(direct.origin, direct.pieces), f"roadmap {direct.label}")
        ):
            run = [whole]
        out += run
    return out


def _legs(roadmap: _Roadmap, route) -> list[tuple]:
    """The route's edges joined into legs ``(direction, origin, pieces, word, radius)``, one
    per run of a direction: forward, the edges' pieces in the order driven; backing, in the
    reverse order (each backing edge's path runs from where it ends)."""
    legs = []
    for run in _runs(route):
        edges = [roadmap.edge(*one) for one in run]
        forward = run[0][2] == _FORWARD
        ordered = edges if forward else edges[::-1]
        pieces = [piece for edge in ordered for piece in edge.pieces]
        word = "+".join(edge.label for edge in ordered)
        direction = "forward" if forward else "reverse"
        legs.append((direction, ordered[0].origin, pieces, word, roadmap.radius))
    return legs

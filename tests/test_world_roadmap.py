"""The planner's last resort (tt_mujoco.world.roadmap): edges between poses where the train
stands straight, and the plans with several cusps it finds where no candidate of
tt_mujoco.world.plan does (a train facing a dead end: tests/generated_worlds.py dead_end)."""

import math
from pathlib import Path

import numpy as np
import pytest

from tt_mujoco.vehicle.params import Params
from tt_mujoco.vehicle.path_schedule import axle_chain
from tt_mujoco.world import roadmap
from tt_mujoco.world.clearance import clearance_along
from tt_mujoco.world.dubins import ahead, arcs_path
from tt_mujoco.world.part import world_record
from tt_mujoco.world.plan import MARGIN, PlanError, planned, train_length
from tt_mujoco.world.roadmap import (
    _BACKING,
    _FORWARD,
    GOAL_EXITS,
    MAX_TURN,
    ROADMAP_EXIT,
    ROADMAP_STRAIGHT,
    _edge,
    _word,
)
from tt_mujoco.world.world import read_world, world_from_table

RADIUS, D = 1.875, 0.7
EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "worlds" / "dead_end.toml"


def _pose_pairs(count=60):
    rng = np.random.default_rng(7)
    for _ in range(count):
        a = (*rng.uniform(-5.0, 5.0, 2), rng.uniform(-math.pi, math.pi))
        b = (*rng.uniform(-5.0, 5.0, 2), rng.uniform(-math.pi, math.pi))
        yield tuple(map(float, a)), tuple(map(float, b))


def _same_pose(one, two, atol=1e-6):
    np.testing.assert_allclose(one[:2], two[:2], atol=atol)
    assert abs(math.remainder(one[2] - two[2], math.tau)) < atol


@pytest.mark.parametrize("direction", [_FORWARD, _BACKING])
def test_an_edge_joins_its_poses_on_straights_the_train_stands_on(direction):
    """Forward, the path runs from a to b; backing, from b (straight out for the exit) to a:
    and both end on a straight of ROADMAP_STRAIGHT D, on which the train stands at the end
    it is driven from (forward: the straight behind a is the path continued)."""
    straight, exit_length = ROADMAP_STRAIGHT * D, ROADMAP_EXIT * D
    made = 0
    for a, b in _pose_pairs():
        edge = _edge(a, b, direction, RADIUS, straight, exit_length)
        if edge is None:  # every word turns more than MAX_TURN
            continue
        made += 1
        path = arcs_path(edge.origin, edge.pieces)
        first, last = (a, b) if direction == _FORWARD else (b, a)
        _same_pose(path.pose_at(0.0), first)
        _same_pose(path.pose_at(path.length), last)
        assert edge.pieces[-1] == (pytest.approx(straight), 0.0)
        if direction == _BACKING:
            assert edge.pieces[0] == (pytest.approx(exit_length), 0.0)
        turned = sum(abs(kappa) * length for length, kappa in edge.pieces)
        assert turned <= MAX_TURN + 1e-9
    assert made >= 12, made  # of the 60 pairs: 18 forward, 12 backing


def test_one_pose_is_joined_by_no_word_and_a_loop_by_none():
    """Where a word's start and end are one pose, the join is empty (Dubins' angles wrap
    there to a whole loop); a pose just behind another is reached only by a loop, refused."""
    assert _word((1.0, 2.0, 0.3), (1.0, 2.0, 0.3), RADIUS) == ([], "S")
    assert _word((0.0, 0.0, 0.0), (-0.5, 0.0, 0.0), RADIUS) is None
    pieces, _ = _word((0.0, 0.0, 0.0), (3.0, 0.0, 0.0), RADIUS)
    assert sum(length for length, _ in pieces) == pytest.approx(3.0)


def _dead_end(trailers: int, draw: int | None):
    """A dead end drawn by tests/generated_worlds.py (draw None: examples/worlds/dead_end.toml)."""
    from generated_worlds import dead_end

    p = Params().with_trailers(trailers)
    if draw is None:
        return read_world(
            Path(__file__).resolve().parents[1] / "examples" / "worlds" / "dead_end.toml"
        ), p
    table = dead_end(np.random.default_rng([trailers, draw]), train_length(p))
    return world_from_table(table, "dead end"), p


def _leg_ends(leg):
    """``(start, end)``: the tractor's pose where the leg is driven from and to."""
    path = leg.path
    first, last = path.pose_at(leg.stop_s), path.pose_at(path.length)
    return (last, first) if leg.reverse else (first, last)


#: (trailers, draw) of dead ends no candidate plan leaves (measured: the candidates' search
#: ends without a plan, and the roadmap's has two cusps), and whether it is planned twice; the
#: draw None is the example (examples/worlds/dead_end.toml).
DEAD_ENDS = [(2, None, True), (3, 4, False)]


@pytest.mark.parametrize(("trailers", "draw", "twice"), DEAD_ENDS)
def test_a_train_facing_a_dead_end_backs_out_and_turns_with_cusps(trailers, draw, twice):
    """The plan backs out first (the corridor's end is ahead), switches direction at least
    once, keeps the margin along every leg (checked five times finer) and the bounds, each
    leg starts where the last ended, and its last leg puts the last axle on the goal."""
    world, p = _dead_end(trailers, draw)
    seed = draw or 0
    plan = planned(world, p, seed, reverse=True)
    assert plan.cusps >= 1 and plan.legs[0].reverse and plan.legs[-1].reverse
    pairs = list(zip(plan.legs, plan.legs[1:], strict=False))
    assert all(one.reverse != two.reverse for one, two in pairs)
    record = world_record(world, p, 0)
    for leg in plan.legs:
        fine, _ = clearance_along(leg.path, p, record, step=0.01, s_from=leg.stop_s)
        assert fine > MARGIN - 0.01
        assert clearance_along(leg.path, p, record, bounds=world.bounds)[0] > -math.inf
    for one, two in pairs:
        _same_pose(_leg_ends(one)[1], _leg_ends(two)[0], atol=1e-9)
    last = axle_chain(plan.legs[-1].path, np.array([0.0]), [(t.L, t.L0) for t in p.trailers])
    goal = world.goal
    np.testing.assert_allclose([last[-1]["x"][0], last[-1]["y"][0]], [goal.x, goal.y], atol=1e-6)
    assert plan.report()["cusps"] == plan.cusps
    if not twice:
        return
    # a second planning gives the same plan: the poses are drawn from a fixed stream
    again = planned(world, p, seed, reverse=True)
    assert again.report()["word"] == plan.report()["word"]
    assert again.report()["legs"] == plan.report()["legs"]


def test_the_goal_edge_tries_shorter_exits_before_giving_up():
    """An edge into the goal blocked with the long exit is tried again with each shorter one
    of GOAL_EXITS, then dropped."""
    world, p = _dead_end(2, 0)
    built = roadmap._Roadmap(
        world, p, world_record(world, p, 0), (5.0, 0.0, 0.0), (3.0, 0.0, 0.0), D, RADIUS, MARGIN
    )
    built.grow(0)
    key = (0, 1, _BACKING)
    exits = []
    while True:
        exits.append(built.edge(*key).exit)
        if not built.drop(key):
            break
    assert exits == pytest.approx([share * D for share in GOAL_EXITS])


def test_no_route_names_the_roadmap_in_its_message():
    """A goal walled in all round: the candidates and the roadmap both fail, and the message
    says how many of the roadmap's edges were checked between how many poses."""
    world, p = _dead_end(1, 0)
    table, goal = world.table, world.table["goal"]
    x, y, _ = ahead((goal["x"], goal["y"], math.radians(goal["heading_deg"])), 1.6)
    wall = {"kind": "box", "name": "wall off", "x": x, "y": y, "length": 0.3, "width": 3.0}
    wall["heading_deg"] = goal["heading_deg"]
    walled = world_from_table({**table, "obstacle": [*table["obstacle"], wall]}, "walled")
    with pytest.raises(PlanError, match=r"edges between \d+ poses where the train stands"):
        planned(walled, p, 0, reverse=True)


def test_a_passed_deadline_stops_the_roadmap_before_it_draws_or_checks_anything():
    """The roadmap looks at the clock before each round and during each search, as the
    candidates do before each check: past the deadline it ends at once, and the planning's
    message says its time limit passed."""
    import time

    from tt_mujoco.world.plan import _Search, least_radius

    world, p = _dead_end(2, 0)
    search = _Search(world, p, MARGIN)
    start = (5.0, 0.0, 0.0)
    route = roadmap.roadmap_route(
        search, start, (0.0, 0.0, 0.0), D, least_radius(p), True, time.monotonic() - 1.0
    )
    assert route is None and search.late
    assert search.roadmap_poses == 0 and search.roadmap_edges == 0
    with pytest.raises(PlanError, match="its time limit passed"):
        planned(world, p, 0, reverse=True, deadline=time.monotonic() - 1.0)
    never = roadmap._Roadmap(world, p, search.record, start, (0.0, 0.0, 0.0), D, RADIUS, MARGIN)
    never.grow(50)
    assert roadmap._shortest(never, (_FORWARD, _BACKING), _BACKING, set(), lambda: True) is None

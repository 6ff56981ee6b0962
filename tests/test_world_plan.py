"""Planned maneuvers (tt_mujoco.world.plan, tt_mujoco.world.dubins): the Dubins words reach
their goal and are shortest, a plan keeps its margin at every point (checked more finely than
the planner checks it), starts are the seed's on every route, and a world with no way through
is one message (exit 2)."""

import json
import math
import pickle
import time

import numpy as np
import pytest
import tomli_w

from tt_mujoco import run
from tt_mujoco.sim import Scenario, build, simulate
from tt_mujoco.vehicle.params import Params
from tt_mujoco.vehicle.path_schedule import axle_chain
from tt_mujoco.world.builtin import WORLDS, parse_world
from tt_mujoco.world.clearance import clearance_along
from tt_mujoco.world.dubins import dubins_words, sample_word
from tt_mujoco.world.part import start_problem, world_record
from tt_mujoco.world.plan import (
    CURVE_HEADING_SHARE,
    MARGIN,
    TIGHT_RADIUS_SHARE,
    PlanError,
    least_radius,
    plan_path,
    planned,
    start_pose,
)
from tt_mujoco.world.plan import train_length as chain_length
from tt_mujoco.world.world import WorldError, world_from_table


def test_every_dubins_word_appears_and_reaches_its_goal():
    rng = np.random.default_rng(0)
    seen = set()
    for _ in range(500):
        start = (*rng.uniform(-2, 2, 2), rng.uniform(-np.pi, np.pi))
        goal = (*rng.uniform(-5, 5, 2), rng.uniform(-np.pi, np.pi))
        radius = rng.uniform(0.5, 2.0)
        words = dubins_words(start, goal, radius)
        assert words, (start, goal)
        for word in words:
            seen.add(word.kinds)
            end = sample_word(start, word, 0.01)[-1]
            assert math.hypot(end[0] - goal[0], end[1] - goal[1]) < 1e-6
        lengths = [w.length for w in words]
        assert lengths == sorted(lengths)
        assert lengths[0] >= math.hypot(goal[0] - start[0], goal[1] - start[1]) - 1e-9
    assert seen == {"LSL", "RSR", "LSR", "RSL", "RLR", "LRL"}


def test_the_shortest_word_to_a_pose_straight_ahead_is_the_straight():
    (word,) = dubins_words((0, 0, 0), (3, 0, 0), 1.0)[:1]
    assert word.kinds in ("LSL", "RSR") and word.length == pytest.approx(3.0)


#: A world to drive into forward: a gap between two crates, the goal beyond it.
GATE = {
    "goal": {"x": 5.0, "y": 1.0, "heading_deg": 0.0},
    "obstacle": [
        {"kind": "box", "name": "crate south", "x": 3.0, "y": 0.2, "length": 0.6, "width": 0.8},
        {"kind": "box", "name": "crate north", "x": 3.0, "y": 1.8, "length": 0.6, "width": 0.8},
    ],
}


@pytest.mark.parametrize("trailers", [1, 2])
@pytest.mark.parametrize(
    ("table", "start", "reverse"),
    [(WORLDS["yard"], (1.0, -1.5, math.pi / 2), True), (GATE, (-1.0, -1.5, 0.0), False)],
    ids=["yard backing up", "gate forward"],
)
def test_a_plan_keeps_its_margin_everywhere_and_ends_at_the_goal(trailers, table, start, reverse):
    p = Params().with_trailers(trailers) if trailers > 1 else Params()
    world = world_from_table(table, "w")
    plan = plan_path(world, p, start, reverse)
    assert plan.cusps == 0
    # Checked five times finer than the planner looks: the margin holds between its samples.
    fine, _ = clearance_along(plan.legs[0].path, p, world_record(world, p, 0), step=0.01)
    assert fine > MARGIN - 0.01
    assert plan.clearance > MARGIN
    path = plan.legs[0].path
    goal = world.goal
    tractor_end = np.array(path.pose_at(0.0 if reverse else path.length))
    tractor_start = np.array(path.pose_at(path.length if reverse else 0.0))
    d = chain_length(p)
    heading = math.radians(goal.heading_deg)
    expected = (goal.x + d * math.cos(heading), goal.y + d * math.sin(heading))
    np.testing.assert_allclose(tractor_end[:2], expected, atol=1e-9)
    np.testing.assert_allclose(tractor_start[:2], start[:2], atol=1e-9)


def test_a_start_is_the_seeds_and_clear():
    p = Params()
    world = parse_world("loading_bay")
    poses = [start_pose(world, p, seed) for seed in range(20)]
    assert poses == [start_pose(world, p, seed) for seed in range(20)]
    assert len(set(poses)) == 20
    for pose in poses:
        assert start_problem(world, world_record(world, p, 0), p, pose, (0.0,), MARGIN) is None
        assert 0.0 <= pose[0] <= 7.0 and -1.5 <= pose[1] <= 0.3


def test_a_planned_run_reaches_the_bay_with_noise():
    """Backing into the loading bay from seed 1's start, 20 dB noise, MuJoCo: the last axle
    ends within the goal's 1 cm and 0.05 rad (measured 1.5 mm, 0.11 deg), every unit clear."""
    result = simulate(
        Scenario(world="loading_bay", traj="plan", reverse=True, seed=1, noise_snr_db=20.0)
    )
    assert result.status == "ok"
    world = result.metrics["world"]
    assert world["goal"]["reached"], world
    assert world["goal"]["position_error_m"] < 0.01
    assert world["min_clearance_m"] > 0.0
    assert world["plan"]["direction"] == "reverse"


def test_three_trailers_back_into_the_alley_and_end_on_its_curve():
    """The alley's dock is shorter than three trailers plus their turning radius: the plan
    ends with the train on the curve, and the run stops there, clear of every wall, the last
    axle within 15 mm of the goal: measured 11.6 mm here (the reduced plant, no noise; the
    trailers' shape at the end is their gains' transient out of the turn, not the path's chain),
    at most 12.8 mm over 38 planned MuJoCo runs with 20 dB noise
    (benchmarks/results/bench_maneuvers--world_alley_seeds_50_trailers_3_disturbance_none.txt)."""
    scenario = Scenario(
        world="alley", traj="plan", reverse=True, trailers=3, seed=4, plant="reduced",
        disturbance="none",
    )  # fmt: skip
    result = simulate(scenario)
    assert result.status == "ok", result.message
    world = result.metrics["world"]
    (leg,) = world["plan"]["legs"]
    assert leg["stop_s_m"] > 0.0 and world["plan"]["exit_m"] < 0.0
    assert world["goal"]["position_error_m"] < 0.015, world["goal"]
    assert abs(world["goal"]["heading_error_deg"]) < math.degrees(0.05)  # the tolerance
    assert world["min_clearance_m"] > 0.0


def test_the_same_seed_plans_the_same_maneuver_on_every_route(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    scenario = Scenario(world="yard", traj="plan", reverse=True, seed=4, plant="reduced")
    api = simulate(scenario).metrics["world"]["plan"]
    code = run.main(
        [
            *("--world", "yard", "--traj", "plan", "--reverse", "--seed", "4"),
            *("--plant", "reduced", "--no-video", "--no-plots", "--quiet", "--out", "cli"),
        ]
    )
    assert code == 0
    cli = json.loads((tmp_path / "cli" / "metrics.json").read_text())["world"]["plan"]
    for key in ("word", "radius_m", "exit_m", "length_m", "clearance_m"):
        assert cli[key] == api[key]
    assert build(scenario).initial_pose == build(scenario).initial_pose


def test_a_world_with_no_way_through_is_one_message(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    walled = dict(WORLDS["loading_bay"])
    walled["obstacle"] = [
        *walled["obstacle"],
        {
            "kind": "wall",
            "name": "barrier",
            "start": [-3, 0.6],
            "end": [7.5, 0.6],
            "thickness": 0.05,
        },
    ]
    walled["obstacle"][-1]["thickness"] = 0.05
    walled["start"] = {"x": 2.0, "y": -1.0, "heading_deg": 0.0}
    (tmp_path / "walled.toml").write_text(tomli_w.dumps(walled))
    temporary = tmp_path / "tmp"
    temporary.mkdir()
    monkeypatch.setenv("TMPDIR", str(temporary))
    monkeypatch.setattr("tempfile.tempdir", None)
    argv = ["--world", "walled.toml", "--traj", "plan", "--reverse", "--out", "o", "--quiet"]
    code = run.main(argv)
    err = capsys.readouterr().err
    assert code == 2 and "no path to world" in err and "candidates tried" in err, err
    # where the candidate that got furthest was blocked, and by what
    assert "then the " in err and ("'barrier'" in err or "bounds" in err), err
    assert len(err.strip().splitlines()) == 1
    assert not (tmp_path / "o").exists()
    # its figure: beside the crash files, named in the message, a whole PNG, nothing else
    (figure,) = temporary.iterdir()
    assert err.strip().endswith(f"; the best candidate is drawn in {figure}"), err
    assert figure.name.startswith("tt_mujoco-no-plan-") and figure.suffix == ".png"
    assert figure.read_bytes().startswith(b"\x89PNG\r\n\x1a\n")
    # --no-plots draws nothing
    assert run.main([*argv, "--no-plots", "--time-limit", "2"]) == 2
    err = capsys.readouterr().err
    assert "no path to world" in err and "drawn" not in err, err
    assert list(temporary.iterdir()) == [figure] and not (tmp_path / "o").exists()


def test_plan_without_a_world_is_refused(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    code = run.main(["--traj", "plan", "--out", "o", "--quiet"])
    assert code == 2 and "without a world" in capsys.readouterr().err


def _units_along(leg, p, step=0.01):
    """Every unit's pose (x, y, heading) at samples ``step`` apart along a leg (the tractor
    from its stop on, where the leg ends on a curve)."""
    path = leg.path
    s = np.linspace(leg.stop_s, path.length, max(2, int(leg.driven_length / step) + 1))
    x, y, heading = path.pose(s)
    chain = axle_chain(path, s, [(t.L, t.L0) for t in p.trailers])
    units = [np.column_stack([x, y, heading])]
    units += [np.column_stack([a["x"], a["y"], a["theta"]]) for a in chain]
    return units


#: Starts the loading bay's train cannot back in from directly (it faces away from the
#: building, too close to turn): a forward leg first, a cusp, then backing in.
FACING_AWAY = [(5.8, -0.8, -math.pi / 2), (6.9, -0.9, -1.73), (1.5, -0.8, -math.pi / 2)]


@pytest.mark.parametrize("trailers", [1, 2])
@pytest.mark.parametrize("start", FACING_AWAY)
def test_a_plan_with_a_cusp_joins_its_legs_and_keeps_its_margin_and_bounds(trailers, start):
    p = Params().with_trailers(trailers) if trailers > 1 else Params()
    world = parse_world("loading_bay")
    plan = plan_path(world, p, start, reverse=True)
    assert plan.cusps == 1, plan.report()
    forward, backing = plan.legs
    assert (forward.direction, backing.direction) == ("forward", "reverse")
    # the forward leg starts at the start and ends where the backing leg starts (its far end)
    np.testing.assert_allclose(forward.path.pose_at(0.0), start, atol=1e-9)
    np.testing.assert_allclose(
        forward.path.pose_at(forward.path.length),
        backing.path.pose_at(backing.path.length),
        atol=1e-9,
    )
    d = chain_length(p)
    goal = world.goal
    heading = math.radians(goal.heading_deg)
    expected = (goal.x + d * math.cos(heading), goal.y + d * math.sin(heading))
    np.testing.assert_allclose(backing.path.pose_at(0.0)[:2], expected, atol=1e-9)
    record = world_record(world, p, 0)
    x_min, x_max, y_min, y_max = world.bounds
    for leg in plan.legs:
        fine, _ = clearance_along(leg.path, p, record, step=0.01)
        assert fine > MARGIN - 0.01
        for unit in _units_along(leg, p):
            assert (unit[:, 0] >= x_min).all() and (unit[:, 0] <= x_max).all()
            assert (unit[:, 1] >= y_min).all() and (unit[:, 1] <= y_max).all()
    report = plan.report()
    assert report["cusps"] == 1 and [leg["direction"] for leg in report["legs"]] == [
        "forward",
        "reverse",
    ]
    assert report["length_m"] == pytest.approx(forward.path.length + backing.path.length)


def test_driving_forward_a_plan_has_no_cusp():
    """Forward only, the train reaches no goal that faces out of a dead end: one message."""
    world = parse_world("loading_bay")
    with pytest.raises(PlanError, match="forward"):
        plan_path(world, Params(), FACING_AWAY[0], reverse=False)


@pytest.mark.parametrize("name", sorted(WORLDS))
def test_no_plan_leaves_its_world(name):
    """Every axle stays inside the world's bounds along every leg of the seeds' plans."""
    world = parse_world(name)
    p = Params()
    x_min, x_max, y_min, y_max = world.bounds
    for seed in range(6):
        try:
            plan = planned(world, p, seed, reverse=True)
        except PlanError:
            continue
        for leg in plan.legs:
            for unit in _units_along(leg, p, step=0.05):
                assert x_min <= unit[:, 0].min() and unit[:, 0].max() <= x_max, (name, seed)
                assert y_min <= unit[:, 1].min() and unit[:, 1].max() <= y_max, (name, seed)


#: Generated worlds the planner is checked in (tests/generated_worlds.py), each from its seed.
GENERATED = range(16)


@pytest.mark.parametrize("world_seed", GENERATED)
def test_a_plan_in_a_generated_world_keeps_its_promises(world_seed):
    """In worlds no one drew, every plan found keeps the margin (checked five times finer)
    and the bounds along every leg, joins its legs, and ends with the last axle on the goal."""
    from generated_worlds import random_world

    world = world_from_table(random_world(np.random.default_rng(world_seed)), "generated")
    p = Params()
    record = world_record(world, p, 0)
    x_min, x_max, y_min, y_max = world.bounds
    planned_any = False
    for seed in range(2):
        try:
            plan = planned(world, p, seed, reverse=True)
        except PlanError:
            continue
        planned_any = True
        for leg in plan.legs:
            fine, _ = clearance_along(leg.path, p, record, step=0.01, s_from=leg.stop_s)
            assert fine > MARGIN - 0.01, (world_seed, seed)
            for unit in _units_along(leg, p, step=0.05):
                assert x_min <= unit[:, 0].min() and unit[:, 0].max() <= x_max
                assert y_min <= unit[:, 1].min() and unit[:, 1].max() <= y_max
        for one, two in zip(plan.legs, plan.legs[1:], strict=False):
            np.testing.assert_allclose(
                one.path.pose_at(one.path.length), two.path.pose_at(two.path.length), atol=1e-9
            )
        _assert_ends_on_the_goal(plan.legs[-1], p, world.goal)
    assert planned_any, f"generated world {world_seed}: no start planned (the generator's fault?)"


def _assert_ends_on_the_goal(leg, p, goal, atol=1e-6):
    """With the tractor where the leg ends, the axle chain puts the last axle on the goal,
    heading as the goal does (a leg ending on a curve: within the share of the goal's
    tolerance the planner allows it)."""
    last = axle_chain(leg.path, np.array([leg.stop_s]), [(t.L, t.L0) for t in p.trailers])[-1]
    heading = math.radians(goal.heading_deg)
    np.testing.assert_allclose([last["x"][0], last["y"][0]], [goal.x, goal.y], atol=atol)
    allowed = CURVE_HEADING_SHARE * math.radians(goal.heading_tolerance_deg) if leg.stop_s else 0
    assert abs(math.remainder(last["theta"][0] - heading, math.tau)) <= allowed + atol


#: (trailers, the dock's length beyond D in least radii, draw): docks where no plan stands the
#: whole train straight. Not every draw has a plan ending on a curve either (the train's
#: turn needs room, and the last trailer's heading must be within the share of the goal's
#: tolerance the planner allows): these are draws that have one.
TURNED_BAYS = [(2, 0.45, 0), (2, 0.45, 1), (2, 0.3, 2), (3, 0.6, 0), (3, 0.6, 2)]


@pytest.mark.parametrize(("trailers", "share", "draw"), TURNED_BAYS)
def test_a_bay_right_after_a_turn_is_backed_into_with_the_train_ending_on_the_curve(
    trailers, share, draw
):
    """A dock shorter than the train plus its least turning radius (tests/generated_worlds.py
    turned_bay, at a random place, heading and side): no plan stands the whole train straight
    in it, so the last leg starts at the goal pose and stops with the tractor on the curve.
    The plan keeps its margin (five times finer), and the chain puts the last axle on the goal."""
    from generated_worlds import turned_bay

    from tt_mujoco.world.plan import least_radius

    p = Params().with_trailers(trailers)
    d = chain_length(p)
    rng = np.random.default_rng([trailers, draw])
    world = world_from_table(turned_bay(rng, d + share * least_radius(p)), "turned bay")
    plan = planned(world, p, draw, reverse=True)
    (leg,) = plan.legs
    assert leg.stop_s > 0.0 and plan.exit < 0.0, plan.report()
    assert plan.report()["legs"][0]["stop_s_m"] == leg.stop_s
    fine, _ = clearance_along(leg.path, p, world_record(world, p, 0), step=0.01, s_from=leg.stop_s)
    assert fine > MARGIN - 0.01
    _assert_ends_on_the_goal(leg, p, world.goal)
    x_min, x_max, y_min, y_max = world.bounds
    for unit in _units_along(leg, p, step=0.05):
        assert x_min <= unit[:, 0].min() and unit[:, 0].max() <= x_max
        assert y_min <= unit[:, 1].min() and unit[:, 1].max() <= y_max


def test_no_plan_names_the_blocked_candidate_when_a_backing_leg_was_clear(monkeypatch):
    """A cusp plan's backing leg that is clear while every forward leg to it is not: the
    message names the blocked candidate that got furthest (a clear leg is no candidate)."""
    from tt_mujoco.world import plan as plan_module

    monkeypatch.setattr(plan_module, "LEAST_RADIUS", 2.5)  # turns too wide for the bay
    monkeypatch.setattr(plan_module, "TIGHT_RADIUS_SHARE", 1.0)  # and no tighter ones
    with pytest.raises(PlanError, match="then the ") as caught:
        planned(parse_world("loading_bay"), Params().with_trailers(3), 0, reverse=True)
    assert "is clear for" in str(caught.value)
    best = caught.value.best  # what the failure's figure draws (tt_mujoco.viz.plan_figure)
    assert f"the best ({best.word})" in str(caught.value)
    assert best.poses.shape == (4, 3) and 0.0 < best.reached < 1.0
    assert best.unit in str(caught.value) and np.isfinite(best.polyline).all()
    again = pickle.loads(pickle.dumps(caught.value))  # a sweep's worker sends the message
    assert type(again) is PlanError and str(again) == str(caught.value)


@pytest.mark.parametrize(
    ("goal", "said"),
    [
        ({"x": -50.0}, "lies outside world"),
        ({"x": 3.0, "y": 3.0}, "would stand on obstacle 'block'"),
    ],
)
def test_a_goal_no_path_can_reach_is_named_before_any_search(goal, said):
    # Before: a goal outside the bounds was searched for, 1200 candidates and a roadmap,
    # then "no path": the planner now asks check_goal first, as check_world does.
    table = dict(WORLDS["loading_bay"])
    table["obstacle"] = [
        *table["obstacle"],
        {"kind": "box", "name": "block", "x": 3.0, "y": 3.0, "length": 1.0, "width": 1.0},
    ]
    table["goal"] = {**table["goal"], **goal}
    world = world_from_table(table, "blocked")
    with pytest.raises(WorldError, match=said):
        plan_path(world, Params(), (2.0, -1.0, 0.0), reverse=True, deadline=0.0)


AISLE = {  # a 1.5 m aisle with a bay off it: no turn at the least radius fits
    "bounds": [-1.0, 14.0, -3.0, 3.0],
    "start": {"x": 1.0, "y": 0.0, "heading_deg": 0.0},
    "goal": {
        "x": 11.5,
        "y": -1.6,
        "heading_deg": 90.0,
        "bay": {"width": 0.5, "depth": 1.0, "back": 0.25, "wall": 0.05},
    },
    "obstacle": [
        {"kind": "wall", "name": "north", "start": [-1.0, 0.8], "end": [14.0, 0.8]},
        {"kind": "wall", "name": "south west", "start": [-1.0, -0.8], "end": [10.5, -0.8]},
        {"kind": "wall", "name": "south east", "start": [12.5, -0.8], "end": [14.0, -0.8]},
    ],
}


def test_a_narrow_aisle_is_planned_with_the_tighter_turns_only_where_it_needs_them():
    for wall in AISLE["obstacle"]:
        wall["thickness"] = 0.1
    world = world_from_table(AISLE, "aisle")
    p = Params()
    with pytest.raises(PlanError):
        plan_path(world, p, (1.0, 0.0, 0.0), reverse=True)
    began = time.perf_counter()
    plan = planned(world, p, 0, reverse=True)
    took = time.perf_counter() - began
    # the time reported is both searches' (the first, which failed, took most of it)
    assert 0.5 * took < plan.planning_time_s <= took
    radii = [leg.radius for leg in plan.legs if leg.radius]
    least = least_radius(p)
    assert radii and TIGHT_RADIUS_SHARE * least <= min(radii) < least
    # a world the least radius fits keeps it
    bay = planned(parse_world("loading_bay"), p, 0, reverse=True)
    assert min(leg.radius for leg in bay.legs if leg.radius) >= least

"""Worlds (tt_mujoco.world): files and named worlds read and checked, bad ones refused by the
command line (exit 2, one line, nothing written), and the run's contact check on both plants
against the geometry and against MuJoCo's own contacts."""

import math

import mujoco
import numpy as np
import pytest
import tomli_w
from documents import key_paths, nested, parent_of
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tt_mujoco import run
from tt_mujoco.sim.parts.physics import Vehicle
from tt_mujoco.sim.scenario import Scenario
from tt_mujoco.sim.simulate import simulate
from tt_mujoco.vehicle.footprint import footprints
from tt_mujoco.vehicle.params import Params
from tt_mujoco.world import contact
from tt_mujoco.world.builtin import WORLDS, parse_world
from tt_mujoco.world.part import check_world, unit_poses, world_record
from tt_mujoco.world.world import KINDS, WorldError, world_from_table

LINE = "x,y\n0,0\n1,0\n2,0\n3,0\n4,0\n"
WALL = """name = "wall ahead"
[[obstacle]]
kind = "wall"
name = "the wall"
start = [2.525, -1.0]
end = [2.525, 1.0]
thickness = 0.05
"""
BOX = """name = "box aside"
[[obstacle]]
kind = "box"
name = "the box"
x = 1.5
y = 0.6
length = 0.4
width = 0.2
"""


@pytest.fixture
def workdir(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "line.csv").write_text(LINE)
    return tmp_path


def _obstacle(kind: str) -> dict:
    """A good obstacle of each kind, away from the start."""
    return {
        "box": {"kind": "box", "x": 3.0, "y": 2.0, "length": 0.5, "width": 0.3},
        "wall": {"kind": "wall", "start": [3.0, 2.0], "end": [4.0, 2.0], "thickness": 0.05},
        "polygon": {"kind": "polygon", "points": [[3, 2], [4, 2], [3.5, 3]]},
        "parked_trailer": {"kind": "parked_trailer", "x": 3.0, "y": 2.0, "heading_deg": 30},
    }[kind]


@pytest.mark.parametrize("kind", sorted(KINDS))
def test_every_kind_of_obstacle_is_read_and_convex(kind):
    world = world_from_table({"obstacle": [_obstacle(kind)]}, "w")
    (polygon,) = world.polygons(footprints(Params())[-1])
    x, y = polygon.T
    assert 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y) > 0


def _bad_tables():
    """(table, expected text) of worlds that must be refused: each key of each obstacle kind
    missing or bad, unknown keys everywhere, and shapes that are no shape."""
    cases = {}
    for kind, (required, optional) in KINDS.items():
        good = _obstacle(kind)
        for key in required:
            cases[f"{kind} without {key}"] = (
                {"obstacle": [{k: v for k, v in good.items() if k != key}]},
                repr(key),
            )
        for key in (*required, *optional):
            cases[f"{kind} {key} not a number"] = ({"obstacle": [{**good, key: "x"}]}, "'x'")
        cases[f"{kind} unknown key"] = ({"obstacle": [{**good, "colour": 1}]}, "'colour'")
    box = {**_obstacle("box"), "x": 8.0, "y": 8.0}
    goal = {"x": 1.0, "y": 1.0, "heading_deg": 0.0}
    cases |= {
        "unknown kind": ({"obstacle": [{"kind": "tree"}]}, "'tree'"),
        "unknown top key": ({"obstacles": []}, "'obstacles'"),
        "unknown goal key": ({"goal": {"x": 1, "y": 1, "heading_deg": 0, "z": 1}}, "'z'"),
        "goal without heading": ({"goal": {"x": 1, "y": 1}}, "'heading_deg'"),
        "bay unknown key": (
            {"goal": {"x": 1, "y": 1, "heading_deg": 0, "bay": {"width": 1, "door": 1}}},
            "'door'",
        ),
        "negative width": ({"obstacle": [{**_obstacle("box"), "width": -1}]}, "width=-1"),
        "nan x": ({"obstacle": [{**_obstacle("box"), "x": math.nan}]}, "x=nan"),
        "concave polygon": (
            {"obstacle": [{"kind": "polygon", "points": [[0, 5], [2, 5], [1, 5.5], [2, 6]]}]},
            "convex",
        ),
        "two points": ({"obstacle": [{"kind": "polygon", "points": [[0, 5], [2, 5]]}]}, "2 points"),
        "collinear": (
            {"obstacle": [{"kind": "polygon", "points": [[0, 5], [1, 5], [2, 5]]}]},
            "convex",
        ),
        "zero wall": (
            {"obstacle": [{"kind": "wall", "start": [3, 3], "end": [3, 3], "thickness": 0.1}]},
            "same point",
        ),
        "bad bounds": ({"bounds": [1, 0, 0, 1]}, "x_min < x_max"),
        "bounds not four": ({"bounds": [1, 2]}, "bounds=[1, 2]"),
        "obstacle not a list": ({"obstacle": 3}, "obstacle=3"),
        # a collision names the obstacle: a name is one line and one obstacle's
        "name twice": (
            {"obstacle": [{**box, "name": "crate"}, {**box, "x": 9.0, "name": "crate"}]},
            "obstacle 2 name='crate' is not allowed: obstacle 1 has it",
        ),
        "a bay wall's name": (
            {
                "goal": {**goal, "bay": {"width": 0.5, "depth": 1.2, "back": 0.25}},
                "obstacle": [{**box, "name": "bay back wall"}],
            },
            "the bay has it",
        ),
        "name over lines": ({"obstacle": [{**box, "name": "a\nb"}]}, "text on one line"),
        "name not text": ({"obstacle": [{**box, "name": ["a"]}]}, "text on one line"),
        "world name not text": ({"name": 3}, "world name=3"),
        # a number beyond any yard is a unit mistake
        "far away": ({"obstacle": [{**box, "x": 1e300}]}, "within +-10000"),
        "huge tolerance": ({"goal": {**goal, "position_tolerance": 1e9}}, "within"),
    }
    return cases


BAD_TABLES = _bad_tables()


@pytest.mark.parametrize("case", sorted(BAD_TABLES))
def test_bad_world_table_is_refused_by_name(case):
    table, expected = BAD_TABLES[case]
    with pytest.raises(WorldError, match=None) as err:
        world_from_table(table, "w")
    assert expected in str(err.value)


def _refused(argv, expected, workdir, capsys):
    out = workdir / "out"
    code = run.main([*argv, "--out", str(out), "--quiet", "--no-video", "--no-plots"])
    err = capsys.readouterr().err
    assert code == 2, err
    assert err.startswith("error: ") and len(err.strip().splitlines()) == 1, err
    assert expected in err, err
    assert "Traceback" not in err
    assert not out.exists()


@pytest.mark.parametrize("case", sorted(BAD_TABLES))
def test_bad_world_file_is_exit_2_naming_it(case, workdir, capsys):
    table, expected = BAD_TABLES[case]
    (workdir / "w.toml").write_text(tomli_w.dumps(table))
    _refused(["--traj", "line.csv", "--world", "w.toml"], expected, workdir, capsys)


def _world_file(workdir, text: str) -> str:
    (workdir / "w.toml").write_text(text)
    return "w.toml"


WORLD_CASES = {
    "no such world": ("lab", "'lab'"),
    "missing file": ("absent.toml", "'absent.toml'"),
    "start on a box": (
        '[[obstacle]]\nkind = "box"\nname = "crate"\nx = -0.5\ny = 0.0\n'
        "length = 0.2\nwidth = 0.2\n",
        "the trailer 1 stands on obstacle 'crate'",
    ),
    "start outside": ("bounds = [1.0, 5.0, -1.0, 1.0]\n", "outside world"),
    "goal on a wall": (
        '[goal]\nx = 3.0\ny = 2.0\nheading_deg = 0\n[[obstacle]]\nkind = "wall"\n'
        'name = "w"\nstart = [2.0, 2.0]\nend = [4.0, 2.0]\nthickness = 0.1\n',
        "would stand on obstacle 'w'",
    ),
    "goal outside": (
        "bounds = [-2.0, 5.0, -1.0, 1.0]\n[goal]\nx = 3.0\ny = 2.0\nheading_deg = 0\n",
        "outside world",
    ),
    "bay narrower than the trailer": (
        "[goal]\nx = 3.0\ny = 2.0\nheading_deg = 0\nbay = {width = 0.2, depth = 1, back = 0.3}\n",
        "bay width=0.2",
    ),
    "bay back inside the trailer": (
        "[goal]\nx = 3.0\ny = 2.0\nheading_deg = 0\nbay = {width = 0.5, depth = 1, back = 0.1}\n",
        "bay back=0.1",
    ),
    "not toml": ("obstacle = [\n", "is not valid TOML"),
}


@pytest.mark.parametrize("case", sorted(WORLD_CASES))
def test_world_that_cannot_be_driven_is_exit_2(case, workdir, capsys):
    text, expected = WORLD_CASES[case]
    world = text if "\n" not in text else _world_file(workdir, text)
    if case == "not toml":
        world = _world_file(workdir, text)
    _refused(["--traj", "line.csv", "--world", world], expected, workdir, capsys)


def test_world_on_terrain_is_refused(workdir, capsys):
    argv = ["--world", "yard", "--terrain", "slope:5"]
    _refused(argv, "world='yard' with terrain='slope:5", workdir, capsys)


@pytest.mark.parametrize("name", sorted(WORLDS))
@pytest.mark.parametrize("trailers", [1, 2, 3])
def test_named_worlds_can_be_driven_from_the_origin(name, trailers):
    p = Params().with_trailers(trailers) if trailers > 1 else Params()
    world = parse_world(name)
    assert world.goal is not None and world.all_obstacles and world.description
    check_world(world, p, (0.0, 0.0, 0.0), (0.0,) * trailers)


def _run(workdir, world_text, plant):
    (workdir / "w.toml").write_text(world_text)
    scenario = Scenario(traj="line.csv", world="w.toml", plant=plant, noise_snr_db=None)
    return simulate(scenario)


def test_both_plants_stop_at_the_same_wall_with_the_same_unit(workdir):
    results = {plant: _run(workdir, WALL, plant) for plant in ("reduced", "mujoco")}
    dt = 0.001
    for plant, result in results.items():
        assert result.status == "collision", plant
        collision = result.metrics["world"]["collision"]
        assert collision["unit"] == "tractor" and collision["obstacle"] == "the wall"
        ts = result.timeseries
        # the last kept row is short of the wall's face (2.5 m) by less than a step's travel
        front = ts["x"][-1] + footprints(Params())[0][1]
        assert 2.5 - 0.001 < front < 2.5, plant
        assert collision["t"] == pytest.approx(ts["t"][-1] + dt)
        assert 0 < collision["depth_m"] < 0.001
    times = [r.metrics["world"]["collision"]["t"] for r in results.values()]
    # The plants' along-track errors differ by under 0.5 mm at 0.6 m/s: a step or two.
    assert abs(times[0] - times[1]) <= 2 * dt + 1e-12


@pytest.mark.parametrize("plant", ["reduced", "mujoco"])
def test_clearance_passing_a_box_is_its_distance_from_the_track(workdir, plant):
    result = _run(workdir, BOX, plant)
    assert result.status == "ok"
    world = result.metrics["world"]
    # The box's near face is 0.5 m from the line, the units 0.12 m wide each side of it; the
    # lateral error on this line is under 0.3 mm on both plants (max_lateral).
    assert world["collision"] is None
    assert world["min_clearance_m"] == pytest.approx(0.5 - 0.12, abs=1e-3)
    assert result.metrics["max_lateral"] < 1e-3


@pytest.mark.parametrize("trailers", [1, 3])
def test_mujoco_contacts_are_the_geometric_check(trailers):
    """At random poses near the yard's parked trailers, MuJoCo finds a contact between a
    unit's footprint box and an obstacle exactly when the step's check finds a gap <= 0."""
    p = Params().with_trailers(trailers) if trailers > 1 else Params()
    world = parse_world("yard")
    vehicle = Vehicle(p, None, world)
    model, data = vehicle.model, vehicle.data
    record = world_record(world, p, 0)
    footprint_geoms = {
        model.geom(f"{u}_footprint").id: i
        for i, u in enumerate(
            ["tractor", "trailer", *(f"trailer_{k}" for k in range(2, trailers + 1))]
        )
    }
    obstacle_geoms = {model.geom(f"obstacle_{o}").id: o for o in range(len(world.all_obstacles))}
    rng = np.random.default_rng(3)
    touching = apart = 0
    for _ in range(300):
        pose = (rng.uniform(1.0, 6.0), rng.uniform(1.3, 3.3), rng.uniform(-math.pi, math.pi))
        phis = tuple(rng.uniform(-0.6, 0.6, trailers))
        vehicle.set_state(x=pose[0], y=pose[1], theta=pose[2], phi=phis)
        mujoco.mj_forward(model, data)
        poses = unit_poses(pose, phis, p)
        gap, _, _ = contact.clearance_of(
            poses, record.boxes, record.polygons, record.sizes, record.circles, record.corners
        )
        pairs = {
            tuple(sorted((int(c.geom1), int(c.geom2))))
            for c in data.contact[: data.ncon]
            if c.dist <= 0.0
        }
        found = any(
            (a in footprint_geoms and b in obstacle_geoms)
            or (b in footprint_geoms and a in obstacle_geoms)
            for a, b in pairs
        )
        if abs(gap) < 1e-4:  # touching to within MuJoCo's convex solver's tolerance
            continue
        assert found == (gap < 0), (pose, phis, gap)
        touching += gap < 0
        apart += gap > 0
    assert touching > 30 and apart > 30  # both cases were tried


# --- the reader against what a file can hold (property-based) -------------------------------

#: Anything a TOML file can give a key: numbers of every kind, text, booleans, lists, tables.
_ANY = nested(
    st.none().map(lambda _: "none")
    | st.booleans()
    | st.integers(-(10**30), 10**30)
    | st.floats(allow_nan=True, allow_infinity=True)
    | st.text(max_size=8),
    max_size=4,
)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data(), name=st.sampled_from(sorted(WORLDS)))
def test_a_world_table_with_any_value_anywhere_is_a_world_or_one_world_error(data, name):
    """A named world's table with one value replaced, or one key removed or added, anywhere:
    the reader gives a World or a WorldError naming what is wrong, never another exception."""
    import copy

    table = copy.deepcopy(WORLDS[name])
    path = data.draw(st.sampled_from(list(key_paths(table))))
    parent = parent_of(table, path)
    action = data.draw(st.sampled_from(["replace", "remove", "add"]))
    if action == "replace":
        parent[path[-1]] = data.draw(_ANY)
    elif action == "remove" and isinstance(parent, dict):
        del parent[path[-1]]
    elif isinstance(parent, dict):
        parent[data.draw(st.text(min_size=1, max_size=6))] = data.draw(_ANY)
    try:
        world = world_from_table(table, "fuzzed")
    except WorldError as err:
        assert str(err) and "\n" not in str(err)
    else:
        assert world.name


@pytest.mark.parametrize("name", sorted(WORLDS))
def test_the_copy_a_run_keeps_is_the_same_world(name):
    import tomllib

    from tt_mujoco.world.builtin import kept_world_toml, parse_world

    world = parse_world(name)
    assert world_from_table(tomllib.loads(kept_world_toml(world)), "kept") == world


def test_a_run_of_a_world_file_replays_from_its_config_anywhere(tmp_path, monkeypatch, capsys):
    # Before: config.toml kept the world file's name as given (relative), so the run's own
    # config could not be run again from another folder ("there is no such file")
    import json
    import shutil

    from tt_mujoco.world.builtin import WORLDS

    work, elsewhere = tmp_path / "work", tmp_path / "elsewhere"
    work.mkdir()
    elsewhere.mkdir()
    (work / "bay.toml").write_text(tomli_w.dumps({"name": "bay", **WORLDS["loading_bay"]}))
    monkeypatch.chdir(work)
    common = ["--traj", "plan", "--reverse", "--plant", "reduced", "--duration", "2"]
    common += ["--no-video", "--no-plots", "--quiet"]
    assert run.main(["--world", "bay.toml", *common, "--out", "first"]) == 0
    config = (work / "first" / "config.toml").read_text()
    assert f'world = "{work / "bay.toml"}"' in config
    shutil.copy(work / "first" / "config.toml", elsewhere / "again.toml")
    monkeypatch.chdir(elsewhere)
    assert run.main(["--config", "again.toml", *common, "--out", "second"]) == 0
    first = json.loads((work / "first" / "metrics.json").read_text())
    second = json.loads((elsewhere / "second" / "metrics.json").read_text())
    assert first["rmse_v"] == second["rmse_v"] and first["steps"] == second["steps"]
    capsys.readouterr()

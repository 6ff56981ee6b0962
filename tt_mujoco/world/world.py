"""A world: the obstacles a run must not touch and the goal it drives to.

A world is read from a TOML file or named (:data:`tt_mujoco.world.builtin.WORLDS`); its
coordinates are the run's (the path's frame, metres, headings in degrees in the file)::

    name = "my yard"
    bounds = [-1.0, 6.0, -2.0, 4.0]      # x_min, x_max, y_min, y_max (optional)

    [goal]                               # the pose the last trailer's axle must reach
    x = 3.0
    y = 1.5
    heading_deg = -90.0                  # the last trailer's heading there
    position_tolerance = 0.01            # m (default)
    heading_tolerance_deg = 2.8648       # deg (default: 0.05 rad)
    bay = {width = 0.5, depth = 1.2, back = 0.3, wall = 0.05}   # the slot's walls (optional)

    [start]                              # where a planned run starts (--traj plan):
    x = [0.0, 7.0]                       # the tractor's axle: a number, or a range to draw
    y = [-1.5, 0.2]                      # from with the run's seed
    heading_deg = [-180.0, 180.0]        # the train straight behind it

    [[obstacle]]
    kind = "box"                         # x, y, length, width, heading_deg (default 0)
    [[obstacle]]
    kind = "wall"                        # start = [x, y], end = [x, y], thickness
    [[obstacle]]
    kind = "polygon"                     # points = [[x, y], ...], convex
    [[obstacle]]
    kind = "parked_trailer"              # x, y, heading_deg: the run's last trailer parked

Each obstacle may have a ``name``. Every shape becomes a convex polygon
(:meth:`World.polygons`), which the step's contact check (:mod:`tt_mujoco.world.contact`) and
the MuJoCo scene (:mod:`tt_mujoco.world.mjcf`) both take.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from tt_mujoco.outputs import read_toml
from tt_mujoco.world import contact

__all__ = [
    "Bay",
    "Goal",
    "Obstacle",
    "Start",
    "World",
    "WorldError",
    "convex_ccw",
    "world_from_table",
]

#: A goal's default tolerances: the last axle within 1 cm and 0.05 rad of the goal pose.
POSITION_TOLERANCE, HEADING_TOLERANCE_DEG = 0.01, math.degrees(0.05)
#: The obstacles' kinds and the keys each takes (``name`` besides), required then optional.
KINDS = {
    "box": (("x", "y", "length", "width"), ("heading_deg",)),
    "wall": (("start", "end", "thickness"), ()),
    "polygon": (("points",), ()),
    "parked_trailer": (("x", "y"), ("heading_deg",)),
}
_TOP = ("name", "description", "bounds", "start", "goal", "obstacle")
_START = ("x", "y", "heading_deg")
_GOAL = ("x", "y", "heading_deg", "position_tolerance", "heading_tolerance_deg", "bay")
_BAY = ("width", "depth", "back", "wall")


class WorldError(ValueError):
    """A world that cannot be used: the message names the bad value and what is allowed."""


#: The largest number a world holds (m, or deg): a world 10 km across is far beyond a yard,
#: and a larger number is a unit mistake (the geometry's squares would lose every digit).
WORLD_EXTENT = 1e4


def _number(value, what: str, positive: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise WorldError(f"{what}={value!r} is not allowed: it must be a finite number")
    if positive and value <= 0:
        raise WorldError(f"{what}={value!r} is not allowed: it must be > 0")
    if abs(value) > WORLD_EXTENT:
        raise WorldError(
            f"{what}={value!r} is not allowed: a world's numbers are within +-{WORLD_EXTENT:g} "
            "(m, deg)"
        )
    return float(value)


def _name(value, what: str) -> str:
    """A name said in messages and kept in MuJoCo's model: text on one line."""
    if not isinstance(value, str) or not value.strip() or not value.isprintable():
        raise WorldError(f"{what} name={value!r} is not allowed: give it as text on one line")
    return value


def _point(value, what: str) -> tuple[float, float]:
    if not isinstance(value, list | tuple) or len(value) != 2:
        raise WorldError(f"{what}={value!r} is not allowed: it must be a point [x, y]")
    return _number(value[0], f"{what}[0]"), _number(value[1], f"{what}[1]")


def _keys(table, allowed, what: str) -> dict:
    if not isinstance(table, dict):
        raise WorldError(f"{what}={table!r} is not allowed: it must be a table")
    unknown = sorted(set(table) - set(allowed))
    if unknown:
        raise WorldError(f"{what} key {unknown[0]!r} is not allowed: use {', '.join(allowed)}")
    return table


def rectangle(x: float, y: float, heading: float, rear: float, front: float, half: float):
    """A rectangle's corners, counter-clockwise: ``x`` in ``[rear, front]`` along ``heading``
    (rad) from ``(x, y)`` and ``|y| <= half`` across it."""
    corners = np.zeros((4, 2))
    contact.unit_corners_of(x, y, heading, (rear, front, half), corners)
    return corners


def convex_ccw(points: np.ndarray, what: str) -> np.ndarray:
    """``points`` as a convex polygon's vertices counter-clockwise, or a :class:`WorldError`
    naming ``what`` when they are not a convex polygon of positive area."""
    n = len(points)
    if n < 3:
        raise WorldError(f"{what} has {n} points: a polygon needs at least 3")
    centre = points.mean(axis=0)
    order = np.argsort(np.arctan2(points[:, 1] - centre[1], points[:, 0] - centre[0]))
    ccw = points[order]
    edges = np.roll(ccw, -1, axis=0) - ccw
    following = np.roll(edges, -1, axis=0)
    turns = edges[:, 0] * following[:, 1] - edges[:, 1] * following[:, 0]
    scale = float(np.max(np.abs(points - centre))) ** 2
    if not np.all(turns > 1e-12 * scale):
        raise WorldError(
            f"{what} is not allowed: its points {points.tolist()} are not the corners of a convex "
            "polygon (split a concave shape into convex ones)"
        )
    return ccw


@dataclass(frozen=True)
class Obstacle:
    """One obstacle: its ``kind`` (:data:`KINDS`), ``name`` and the values of its keys."""

    kind: str
    name: str
    values: tuple

    def polygon(self, trailer_box) -> np.ndarray:
        """Its corners, counter-clockwise; a parked trailer takes ``trailer_box`` (the run's
        last trailer's ``(rear, front, half)``)."""
        v = dict(self.values)
        heading = math.radians(v.get("heading_deg", 0.0))
        if self.kind == "box":
            half_length, half = 0.5 * v["length"], 0.5 * v["width"]
            return rectangle(v["x"], v["y"], heading, -half_length, half_length, half)
        if self.kind == "wall":
            (x0, y0), (x1, y1) = v["start"], v["end"]
            along = math.atan2(y1 - y0, x1 - x0)
            length, half = math.hypot(x1 - x0, y1 - y0), 0.5 * v["thickness"]
            return rectangle(x0, y0, along, -half, length + half, half)
        if self.kind == "parked_trailer":
            return rectangle(v["x"], v["y"], heading, *trailer_box)
        return convex_ccw(np.array(v["points"], dtype=float), f"obstacle {self.name!r}")


@dataclass(frozen=True)
class Bay:
    """A goal's slot: inner ``width``, side walls ``depth`` long from the back wall, whose inner
    face is ``back`` behind the goal's axle; walls ``wall`` thick (m)."""

    width: float
    depth: float
    back: float
    wall: float = 0.05

    def walls(self, goal: Goal) -> tuple[Obstacle, ...]:
        """The slot's three walls as obstacles, around ``goal``."""
        h = math.radians(goal.heading_deg)
        ux, uy, nx, ny = math.cos(h), math.sin(h), -math.sin(h), math.cos(h)

        def at(along: float, across: float) -> list[float]:
            return [goal.x + along * ux + across * nx, goal.y + along * uy + across * ny]

        side, t = 0.5 * (self.width + self.wall), self.wall
        rear, opening = -self.back - 0.5 * t, -self.back + self.depth

        def wall(name: str, start, end) -> Obstacle:
            return Obstacle("wall", name, (("start", start), ("end", end), ("thickness", t)))

        return (
            wall("bay back wall", at(rear, -side), at(rear, side)),
            wall("bay left wall", at(rear, side), at(opening, side)),
            wall("bay right wall", at(rear, -side), at(opening, -side)),
        )


@dataclass(frozen=True)
class Goal:
    """The pose the last trailer's axle must reach (m, deg), within the tolerances."""

    x: float
    y: float
    heading_deg: float
    position_tolerance: float = POSITION_TOLERANCE
    heading_tolerance_deg: float = HEADING_TOLERANCE_DEG
    bay: Bay | None = None


@dataclass(frozen=True)
class Start:
    """Where a planned run starts: the tractor's axle ``x``, ``y`` (m) and ``heading_deg``,
    each a value or a ``(low, high)`` range drawn from uniformly."""

    x: float | tuple[float, float]
    y: float | tuple[float, float]
    heading_deg: float | tuple[float, float]

    def draw(self, rng) -> tuple[float, float, float]:
        """A pose ``(x, y, heading)`` (m, rad): the fixed values, the ranges drawn."""

        def value(v):
            return float(rng.uniform(*v)) if isinstance(v, tuple) else v

        x, y, heading = value(self.x), value(self.y), value(self.heading_deg)
        return x, y, math.radians(heading)

    @property
    def drawn(self) -> bool:
        """Whether any of the values is a range."""
        return any(isinstance(v, tuple) for v in (self.x, self.y, self.heading_deg))


@dataclass(frozen=True)
class World:
    """Obstacles, an optional goal and start, and optional ``bounds`` (x_min, x_max, y_min,
    y_max)."""

    name: str
    obstacles: tuple[Obstacle, ...] = ()
    goal: Goal | None = None
    bounds: tuple[float, float, float, float] | None = None
    description: str = ""
    start: Start | None = None
    #: the table it was read from (a world file's contents), to keep beside a run
    table: dict | None = field(default=None, compare=False, repr=False)

    @property
    def all_obstacles(self) -> tuple[Obstacle, ...]:
        """The obstacles, then the goal's bay walls."""
        walls = self.goal.bay.walls(self.goal) if self.goal and self.goal.bay else ()
        return (*self.obstacles, *walls)

    def polygons(self, trailer_box) -> list[np.ndarray]:
        """Every obstacle's corners (:attr:`all_obstacles`' order), counter-clockwise."""
        return [o.polygon(trailer_box) for o in self.all_obstacles]


def _obstacle(table, i: int) -> Obstacle:
    what = f"obstacle {i + 1}"
    kind = table.get("kind") if isinstance(table, dict) else None
    if not isinstance(kind, str) or kind not in KINDS:
        raise WorldError(f"{what} kind={kind!r} is not allowed: use one of {', '.join(KINDS)}")
    required, optional = KINDS[kind]
    _keys(table, ("kind", "name", *required, *optional), what)
    name = _name(table["name"], what) if "name" in table else f"{kind} {i + 1}"
    values = []
    for key in (*required, *optional):
        if key not in table:
            if key in required:
                raise WorldError(f"{what} ({kind}) needs {key!r}: it takes {', '.join(required)}")
            continue
        value = table[key]
        if key in ("start", "end"):
            value = _point(value, f"{what} {key}")
        elif key == "points":
            if not isinstance(value, list):
                raise WorldError(f"{what} points={value!r} is not allowed: give [[x, y], ...]")
            value = tuple(_point(p, f"{what} points[{j}]") for j, p in enumerate(value))
        else:
            value = _number(value, f"{what} {key}", key in ("length", "width", "thickness"))
        values.append((key, value))
    obstacle = Obstacle(kind, name, tuple(values))
    if kind == "polygon":
        obstacle.polygon(None)  # convex, or a WorldError now
    if kind == "wall" and dict(values)["start"] == dict(values)["end"]:
        raise WorldError(f"{what} ({name!r}) is not allowed: its start and end are the same point")
    return obstacle


def _goal(table) -> Goal:
    _keys(table, _GOAL, "goal")
    for key in ("x", "y", "heading_deg"):
        if key not in table:
            raise WorldError(f"goal needs {key!r}: it takes x, y, heading_deg")
    values = {
        k: _number(table[k], f"goal {k}", k.endswith("tolerance") or k.endswith("tolerance_deg"))
        for k in _GOAL[:-1]
        if k in table
    }
    bay = None
    if "bay" in table:
        bay_table = _keys(table["bay"], _BAY, "goal bay")
        for key in ("width", "depth", "back"):
            if key not in bay_table:
                raise WorldError(f"goal bay needs {key!r}: it takes {', '.join(_BAY)}")
        bay = Bay(**{k: _number(v, f"goal bay {k}", True) for k, v in bay_table.items()})
    return Goal(**values, bay=bay)


def _start(table) -> Start:
    _keys(table, _START, "start")
    values = {}
    for key in _START:
        if key not in table:
            raise WorldError(f"start needs {key!r}: it takes {', '.join(_START)}")
        value = table[key]
        if isinstance(value, list):
            if len(value) != 2:
                raise WorldError(
                    f"start {key}={value!r} is not allowed: give a number or [low, high]"
                )
            low, high = (_number(v, f"start {key}") for v in value)
            if not low <= high:
                raise WorldError(f"start {key}={value!r} is not allowed: low <= high")
            values[key] = (low, high)
        else:
            values[key] = _number(value, f"start {key}")
    return Start(**values)


def world_from_table(table, name: str) -> World:
    """A :class:`World` from a parsed TOML table (the file's contents), checked."""
    _keys(table, _TOP, f"world {name!r}")
    obstacles = table.get("obstacle", [])
    if not isinstance(obstacles, list):
        raise WorldError(f"obstacle={obstacles!r} is not allowed: use [[obstacle]] tables")
    bounds = table.get("bounds")
    if bounds is not None:
        if not isinstance(bounds, list) or len(bounds) != 4:
            raise WorldError(f"bounds={bounds!r} is not allowed: give [x_min, x_max, y_min, y_max]")
        bounds = tuple(_number(b, f"bounds[{i}]") for i, b in enumerate(bounds))
        if not (bounds[0] < bounds[1] and bounds[2] < bounds[3]):
            raise WorldError(
                f"bounds={list(bounds)} is not allowed: x_min < x_max and y_min < y_max"
            )
    world = World(
        name=_name(table["name"], "world") if "name" in table else name,
        obstacles=tuple(_obstacle(t, i) for i, t in enumerate(obstacles)),
        goal=_goal(table["goal"]) if "goal" in table else None,
        bounds=bounds,
        description=str(table.get("description", "")),
        start=_start(table["start"]) if "start" in table else None,
        table=copy.deepcopy(dict(table)),
    )
    seen: dict[str, int] = {}
    walls = {o.name for o in world.all_obstacles[len(world.obstacles) :]}  # the goal's bay
    for i, obstacle in enumerate(world.obstacles):  # a collision names it: one name, one obstacle
        if obstacle.name in seen or obstacle.name in walls:
            holder = f"obstacle {seen[obstacle.name] + 1}" if obstacle.name in seen else "the bay"
            raise WorldError(
                f"obstacle {i + 1} name={obstacle.name!r} is not allowed: {holder} has it; "
                "give each obstacle its own name"
            )
        seen[obstacle.name] = i
    return world


def read_world(path: Path) -> World:
    """The world in TOML file ``path``."""
    try:
        table = read_toml(path, "world file")
    except ValueError as err:
        raise WorldError(str(err)) from None
    return world_from_table(table, path.stem)

"""The named worlds, and the one reader of ``Scenario.world``: ``"none"``, a name or a file.

Each named world is the table a world file would hold (:func:`tt_mujoco.world.world.
world_from_table` reads both). They are sized for the paper's vehicle (units 0.3-0.4 m long,
0.24 m wide); the run starts at the origin heading +x, the trailers behind it, clear of every
obstacle for up to three trailers.
"""

from __future__ import annotations

import functools
import os
from pathlib import Path

from tt_mujoco.registry import shown
from tt_mujoco.world.world import World, WorldError, read_world, world_from_table

__all__ = ["KEPT_WORLD", "NO_WORLD", "WORLDS", "kept_world_toml", "parse_world"]

#: ``Scenario.world`` of a run with no world.
NO_WORLD = "none"


def _wall(name, start, end, thickness=0.05) -> dict:
    return {"kind": "wall", "name": name, "start": start, "end": end, "thickness": thickness}


def _parked(name, x, y, heading_deg) -> dict:
    return {"kind": "parked_trailer", "name": name, "x": x, "y": y, "heading_deg": heading_deg}


#: The named worlds, as world files' tables.
WORLDS = {
    "loading_bay": {
        "description": "a building's front with one bay to back the last trailer into",
        "bounds": [-4.0, 11.0, -6.0, 3.5],
        "start": {"x": [0.0, 7.0], "y": [-1.5, 0.3], "heading_deg": [-180.0, 180.0]},
        "goal": {
            "x": 4.0,
            "y": 2.0,
            "heading_deg": -90.0,
            "bay": {"width": 0.5, "depth": 1.2, "back": 0.25, "wall": 0.05},
        },
        "obstacle": [
            _wall("building front west", [0.5, 1.025], [3.675, 1.025]),
            _wall("building front east", [4.325, 1.025], [11.0, 1.025]),
        ],
    },
    "alley": {
        "description": "a corridor 2 m wide turning 90 deg left, ending in a dock",
        "bounds": [-3.0, 7.0, -1.5, 5.0],
        "start": {"x": [-1.0, 1.0], "y": [-0.1, 0.1], "heading_deg": [175.0, 185.0]},
        "goal": {"x": 5.6, "y": 4.0, "heading_deg": -90.0},
        "obstacle": [
            _wall("alley south wall", [-3.0, -1.025], [6.625, -1.025]),
            _wall("alley north wall", [-3.0, 1.025], [4.575, 1.025]),
            _wall("alley east wall", [6.625, -1.025], [6.625, 4.425]),
            _wall("alley west wall", [4.575, 1.025], [4.575, 4.425]),
            _wall("dock", [4.575, 4.425], [6.625, 4.425]),
        ],
    },
    "yard": {
        "description": "an open yard with a row of parked trailers and one free slot",
        "bounds": [-4.0, 11.0, -7.0, 4.0],
        "start": {"x": [0.0, 7.0], "y": [-2.5, 0.5], "heading_deg": [-180.0, 180.0]},
        "goal": {"x": 3.6, "y": 3.0, "heading_deg": -90.0},
        "obstacle": [
            _parked("parked trailer 1", 2.0, 3.0, -90.0),
            _parked("parked trailer 2", 2.8, 3.0, -90.0),
            _parked("parked trailer 3", 4.4, 3.0, -90.0),
            _parked("parked trailer 4", 5.2, 3.0, -90.0),
            _wall("yard fence", [0.5, 3.5], [7.0, 3.5]),
        ],
    },
}


@functools.lru_cache(maxsize=32)
def _world(text: str) -> World | None:
    if text == NO_WORLD:
        return None
    if text in WORLDS:
        return world_from_table(WORLDS[text], text)
    path = Path(text)
    if path.suffix == ".toml":
        if not path.is_file():
            what = "there is no such file" if not path.exists() else "it is not a regular file"
            raise WorldError(f"world file {text!r} is not allowed: {what}")
        return read_world(path)
    raise WorldError(
        f"world={text!r} is not allowed: use {NO_WORLD}, one of {', '.join(WORLDS)}, or a "
        "world file path/to/world.toml"
    )


#: The copy of its world a run keeps in its folder: what re-renders and conversions read
#: (:func:`tt_mujoco.runfolder.read_run`), whatever has become of the world file (or of a
#: named world) since.
KEPT_WORLD = "world.toml"


def kept_world_toml(world: World) -> str:
    """``world`` as the TOML file a run keeps (:data:`KEPT_WORLD`)."""
    import tomli_w

    return tomli_w.dumps({**(world.table or {}), "name": world.name})


def parse_world(value) -> World | None:
    """The world ``Scenario.world`` names: None for ``"none"``, a named world, or the world
    file at that path (its contents read each time the file changes; a path object too)."""
    if isinstance(value, os.PathLike):
        value = os.fspath(value)
    if not isinstance(value, str) or not value.strip():
        raise WorldError(
            f"world={shown(value)} is not allowed: use {NO_WORLD}, one of {', '.join(WORLDS)}, "
            "or a world file path/to/world.toml"
        )
    text = value.strip()
    if text.endswith(".toml") and Path(text).is_file():
        stat = Path(text).stat()
        return _file_world(text, stat.st_mtime_ns, stat.st_size)
    return _world(text)


@functools.lru_cache(maxsize=32)
def _file_world(text: str, mtime_ns: int, size: int) -> World:
    return read_world(Path(text))

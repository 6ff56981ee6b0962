"""Worlds no one drew: a goal bay at a random pose, obstacles of every kind scattered around it
(clear of the bay's mouth), a start region a few metres out. The planner and the maneuvers are
tested on these as well as on the named worlds, so nothing is tuned to the shipped ones."""

import math

import numpy as np


def random_world(rng: np.random.Generator) -> dict:
    """A world file's table, drawn from ``rng``."""
    gx, gy = (float(v) for v in rng.uniform(-2.0, 2.0, 2))
    gh = float(rng.uniform(-180.0, 180.0))
    h = math.radians(gh)
    mouth = [(gx + d * math.cos(h), gy + d * math.sin(h)) for d in np.linspace(0.0, 4.0, 9)]
    obstacles = []
    kinds = ("box", "wall", "polygon", "parked_trailer")
    for i in range(int(rng.integers(2, 7))):
        for _ in range(100):  # clear of the bay and its mouth
            x, y = (float(v) for v in rng.uniform(-8.0, 8.0, 2))
            if min(math.hypot(x - a, y - b) for a, b in mouth) > 2.0:
                break
        kind = kinds[i % len(kinds)]
        name = f"{kind} {i + 1}"
        heading = float(rng.uniform(0.0, 180.0))
        if kind == "box":
            size = rng.uniform(0.3, 1.5, 2)
            obstacles.append(
                {
                    "kind": kind,
                    "name": name,
                    "x": x,
                    "y": y,
                    "length": float(size[0]),
                    "width": float(size[1]),
                    "heading_deg": heading,
                }
            )
        elif kind == "wall":
            half = float(rng.uniform(0.5, 1.5))
            dx, dy = half * math.cos(math.radians(heading)), half * math.sin(math.radians(heading))
            obstacles.append(
                {
                    "kind": kind,
                    "name": name,
                    "start": [x - dx, y - dy],
                    "end": [x + dx, y + dy],
                    "thickness": 0.1,
                }
            )
        elif kind == "polygon":
            angles = np.sort(rng.uniform(0.0, 2.0 * math.pi, 5))
            radius = float(rng.uniform(0.3, 0.8))
            points = [[x + radius * math.cos(a), y + radius * math.sin(a)] for a in angles]
            obstacles.append({"kind": kind, "name": name, "points": points})
        else:
            obstacles.append({"kind": kind, "name": name, "x": x, "y": y, "heading_deg": heading})
    turn = float(rng.uniform(-1.0, 1.0))
    sx, sy = gx + 6.0 * math.cos(h + turn), gy + 6.0 * math.sin(h + turn)
    return {
        "bounds": [-12.0, 12.0, -12.0, 12.0],
        "start": {
            "x": [sx - 1.0, sx + 1.0],
            "y": [sy - 1.0, sy + 1.0],
            "heading_deg": [-180.0, 180.0],
        },
        "goal": {
            "x": gx,
            "y": gy,
            "heading_deg": gh,
            "bay": {"width": 0.5, "depth": 1.2, "back": 0.25, "wall": 0.05},
        },
        "obstacle": obstacles,
    }


def turned_bay(rng: np.random.Generator, dock_length: float) -> dict:
    """A world file's table: a corridor 2.0-2.4 m wide that turns 90 deg, left or right, into a
    dock ``dock_length`` (m) from the first leg's centre line to the goal, at a random place and
    heading; the start in the first leg, facing away from the turn (the train backs into it)."""
    width = float(rng.uniform(2.0, 2.4))
    side = float(rng.choice([-1.0, 1.0]))  # the dock's side of the first leg
    h, w = width / 2.0, 0.05
    corner = 5.6  # the dock's centre line, along the first leg
    local = {  # the walls in the corridor's frame: the first leg along +x, the dock towards +y
        "outer wall": ([-4.5, -h - w / 2], [corner + h + w / 2, -h - w / 2]),
        "inner wall": ([-4.5, h + w / 2], [corner - h - w / 2, h + w / 2]),
        "far wall": ([corner + h + w / 2, -h - w / 2], [corner + h + w / 2, dock_length + 0.5]),
        "near wall": ([corner - h - w / 2, h + w / 2], [corner - h - w / 2, dock_length + 0.5]),
        "dock": (
            [corner - h - w / 2, dock_length + 0.45],
            [corner + h + w / 2, dock_length + 0.45],
        ),
    }
    turn = float(rng.uniform(-math.pi, math.pi))
    ox, oy = (float(v) for v in rng.uniform(-3.0, 3.0, 2))
    c, s = math.cos(turn), math.sin(turn)

    def placed(x, y):
        y *= side
        return [ox + c * x - s * y, oy + s * x + c * y]

    obstacles = [
        {"kind": "wall", "name": name, "start": placed(*a), "end": placed(*b), "thickness": w}
        for name, (a, b) in local.items()
    ]
    gx, gy = placed(corner, dock_length)
    sx, sy = placed(-1.0, 0.0)
    corners = [
        placed(x, y) for x in (-4.7, corner + h + 0.3) for y in (-h - 0.3, dock_length + 0.7)
    ]
    xs, ys = [p[0] for p in corners], [p[1] for p in corners]
    facing = math.degrees(turn) + 180.0
    return {
        "bounds": [min(xs), max(xs), min(ys), max(ys)],
        "start": {
            "x": [sx - 0.3, sx + 0.3],
            "y": [sy - 0.3, sy + 0.3],
            "heading_deg": [facing - 3.0, facing + 3.0],
        },
        "goal": {"x": gx, "y": gy, "heading_deg": math.degrees(turn + side * math.pi / 2) + 180.0},
        "obstacle": obstacles,
    }


def dead_end(rng: np.random.Generator, train_length: float) -> dict:
    """A world file's table: a yard with a dead-end corridor 1.4-2.0 m wide off its east side
    (at a random height, two or three times the train long) and a goal bay at a random pose
    in the yard's west half, its way out (two trains long, and a metre) inside the yard; the
    train starts in the corridor facing its closed end, so every plan starts backing out, and a
    bay facing the wrong way needs cusps."""
    width = float(rng.uniform(1.4, 2.0))
    cy = float(rng.uniform(-2.5, 2.5))
    length = float(rng.uniform(2.0, 3.0)) * train_length + 1.0
    x0, x1 = 6.0 - length, 6.0
    half = width / 2
    for _ in range(100):  # the way out of the bay (two trains long, and a metre) in the yard
        gx, gy = float(rng.uniform(-6.0, -1.0)), float(rng.uniform(-4.0, 4.0))
        gh = float(rng.uniform(-180.0, 180.0))
        out = 2.0 * train_length + 1.0
        ox, oy = gx + out * math.cos(math.radians(gh)), gy + out * math.sin(math.radians(gh))
        # the bay 1.5 m clear of the corridor: a goal on its wall is no world (refused)
        clear = gx < x0 - 1.5 or abs(gy - cy) > half + 1.5
        if -8.5 <= ox <= x0 - 0.5 and -5.5 <= oy <= 5.5 and clear:
            break
    walls = [
        ("corridor north", [x0, cy + half], [x1, cy + half]),
        ("corridor south", [x0, cy - half], [x1, cy - half]),
        ("corridor end", [x1, cy - half], [x1, cy + half]),
    ]
    return {
        "bounds": [-9.0, 6.5, -6.0, 6.0],
        "start": {"x": [x1 - 1.0, x1 - 0.6], "y": [cy - 0.05, cy + 0.05], "heading_deg": [-3, 3]},
        "goal": {
            "x": gx,
            "y": gy,
            "heading_deg": gh,
            "bay": {"width": 0.5, "depth": 1.2, "back": 0.25, "wall": 0.05},
        },
        "obstacle": [
            {"kind": "wall", "name": name, "start": a, "end": b, "thickness": 0.05}
            for name, a, b in walls
        ],
    }

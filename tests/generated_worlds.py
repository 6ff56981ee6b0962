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

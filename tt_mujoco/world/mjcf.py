"""A world's obstacles as the MuJoCo scene's geoms.

Each obstacle is a prism (a mesh of its polygon's corners at the floor and at
:data:`OBSTACLE_HEIGHT`) fixed to the world. Collisions are by bit
(:data:`tt_mujoco.vehicle.footprint.OBSTACLE_BITS`): an obstacle meets only the units'
footprint boxes (:func:`tt_mujoco.vehicle.mjcf.vehicle_xml` with ``footprints=True``), never
the wheels or the floor, so that the scene's contacts are the step's contact check's
(:mod:`tt_mujoco.world.contact`) between the same shapes.
"""

from __future__ import annotations

from tt_mujoco.vehicle.footprint import OBSTACLE_BITS

__all__ = ["OBSTACLE_HEIGHT", "obstacles_xml"]

#: How tall an obstacle stands (m): above every unit's footprint box.
OBSTACLE_HEIGHT = 0.3


def _g(x: float) -> str:
    return f"{x:.10g}"


def obstacles_xml(polygons, names) -> tuple[str, str]:
    """``(assets, geoms)`` of the scene for obstacle ``polygons`` (counter-clockwise corners)
    named ``names``: one mesh asset and one geom each, named ``obstacle_<index>``."""
    assets, geoms = [], []
    contype, conaffinity = OBSTACLE_BITS
    for o, (polygon, name) in enumerate(zip(polygons, names, strict=True)):
        vertices = " ".join(
            f"{_g(x)} {_g(y)} {_g(z)}" for z in (0.0, OBSTACLE_HEIGHT) for x, y in polygon
        )
        assets.append(f'<mesh name="obstacle_{o}" vertex="{vertices}"/>')
        label = name.replace('"', "'").replace("<", "(").replace(">", ")").replace("&", "+")
        geoms.append(
            f'<geom name="obstacle_{o}" type="mesh" mesh="obstacle_{o}" contype="{contype}" '
            f'conaffinity="{conaffinity}" rgba="0.55 0.55 0.6 1"/><!-- {label} -->'
        )
    return "\n    ".join(assets), "\n    ".join(geoms)

"""The ground under the vehicle: flat, or a constant grade (docs/model.md Section 16).

A plane of constant grade ``a`` rising along the heading ``h`` is, in the plane's own frame, the
flat floor under a tilted gravity: ``g_plane = (-g sin(a) cos(h), -g sin(a) sin(h), -g cos(a))``.
The MuJoCo plant runs it that way, so the paths, the measurements and the metrics stay in the
plane's coordinates (a path painted on the slope) and every contact force is the physical one:
the wheels press on the ground with ``cos(a)`` of the weight and gravity pulls along it with
``sin(a)``. The reduced plant has flat ground only.

A free body on the grade accelerates at ``g sin(a)`` down the fall line: that is the constant
part of the paper's Delta_1 a grade stands for (3.5 m/s^2 is about 21 deg).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from tt_mujoco.registry import check_finite_fields

__all__ = ["GRAVITY", "MAX_GRADE_DEG", "Terrain", "parse_terrain"]

#: Standard gravity (m/s^2), MuJoCo's default ``opt.gravity`` magnitude.
GRAVITY = 9.81
#: Steepest grade allowed: the tyres' friction (1 by default) holds a vehicle up to 45 deg.
MAX_GRADE_DEG = 45.0


@dataclass(frozen=True)
class Terrain:
    """Flat ground (``grade_deg = 0``) or a constant grade rising along ``heading_deg``."""

    grade_deg: float = 0.0
    heading_deg: float = 0.0

    def __post_init__(self) -> None:
        check_finite_fields(self, "terrain", ("grade_deg", "heading_deg"))
        if not 0.0 <= self.grade_deg < MAX_GRADE_DEG:
            raise ValueError(
                f"terrain grade {self.grade_deg!r} deg is not allowed: use 0 <= grade < "
                f"{MAX_GRADE_DEG:g} deg"
            )

    @property
    def flat(self) -> bool:
        return self.grade_deg == 0.0

    @property
    def gravity(self) -> tuple[float, float, float]:
        """Gravity in the plane's frame (m/s^2), see the module docstring."""
        a, h = math.radians(self.grade_deg), math.radians(self.heading_deg)
        along = GRAVITY * math.sin(a)
        return (-along * math.cos(h), -along * math.sin(h), -GRAVITY * math.cos(a))

    @property
    def world_rotation(self) -> tuple[tuple[float, float, float], ...]:
        """The rotation from the plane's frame to the world's (row-major 3 x 3): the plane
        turned by the grade about the horizontal axis across the heading. It takes the plane's
        normal to ``(-sin(a) cos(h), -sin(a) sin(h), cos(a))`` and world gravity to
        :attr:`gravity`; the video draws the ground with it, as a slope."""
        a, h = math.radians(self.grade_deg), math.radians(self.heading_deg)
        ux, uy = -math.sin(h), math.cos(h)  # the axis; the rotation is by -a about it
        c, s = math.cos(-a), math.sin(-a)
        return (
            (c + ux * ux * (1 - c), ux * uy * (1 - c), uy * s),
            (ux * uy * (1 - c), c + uy * uy * (1 - c), -ux * s),
            (-uy * s, ux * s, c),
        )

    @property
    def equivalent_delta1(self) -> float:
        """``g sin(grade)`` (m/s^2): a free body's acceleration down the fall line."""
        return GRAVITY * math.sin(math.radians(self.grade_deg))

    def spec(self) -> str:
        """The text :func:`parse_terrain` reads back."""
        return "flat" if self.flat else f"slope:{self.grade_deg:g}:{self.heading_deg:g}"


def parse_terrain(text) -> Terrain:
    """``"flat"`` or ``"slope:GRADE_DEG[:HEADING_DEG]"`` (heading of the rise, default 0: the
    grade climbs along +x).

    Raises
    ------
    ValueError
        Naming the text and what is allowed.
    """
    allowed = "use 'flat' or 'slope:GRADE_DEG[:HEADING_DEG]', e.g. 'slope:5:90'"
    if isinstance(text, Terrain):
        return text
    if not isinstance(text, str):
        raise ValueError(f"terrain={text!r} is not allowed: {allowed}")
    parts = [p.strip() for p in text.strip().split(":")]
    kind = parts[0].lower()
    if kind == "flat" and len(parts) == 1:
        return Terrain()
    if kind != "slope" or len(parts) not in (2, 3):
        raise ValueError(f"terrain={text!r} is not allowed: {allowed}")
    try:
        numbers = [float(p) for p in parts[1:]]
    except ValueError:
        raise ValueError(f"terrain={text!r} is not allowed: {allowed}") from None
    return Terrain(*numbers)

"""The ground under the vehicle: flat, a constant grade, a ramp or a rough ground
(docs/model.md Section 16).

A plane of constant grade ``a`` rising along the heading ``h`` is, in the plane's own frame, the
flat floor under a tilted gravity: ``g_plane = (-g sin(a) cos(h), -g sin(a) sin(h), -g cos(a))``.
The MuJoCo plant runs it that way, so the paths, the measurements and the metrics stay in the
plane's coordinates (a path painted on the slope) and every contact force is the physical one:
the wheels press on the ground with ``cos(a)`` of the weight and gravity pulls along it with
``sin(a)``. The reduced plant has flat ground only.

A ramp (:class:`Ramp`) and a rough ground (:class:`Rough`) are shapes, not a tilt: the scene
gets their geoms (:mod:`tt_mujoco.sim.parts.relief` places them along the run's path) and gravity
stays vertical. Here are only their specs, checked.

A free body on the grade accelerates at ``g sin(a)`` down the fall line: that is the constant
part of the paper's Delta_1 a grade stands for (3.5 m/s^2 is about 21 deg).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from tt_mujoco.registry import check_finite_fields
from tt_mujoco.schema_values import number_text

__all__ = ["GRAVITY", "MAX_GRADE_DEG", "Ramp", "Rough", "Terrain", "parse_terrain"]

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

    def report(self) -> dict:
        """What a run's ``metrics.json`` says of this ground (its ``terrain`` entry)."""
        return {
            "grade_deg": self.grade_deg,
            "heading_deg": self.heading_deg,
            # the paper's Delta_1 bias a free body on this grade would see
            "equivalent_delta1": self.equivalent_delta1,
        }


@dataclass(frozen=True)
class Ramp:
    """Flat ground up to the path's arc length ``start_s``, then a plane rising at
    ``grade_deg`` along the path's direction there; level again after ``length`` metres of
    rise (measured horizontally; None: it rises to the ground's end)."""

    start_s: float
    grade_deg: float
    length: float | None = None

    def __post_init__(self) -> None:
        check_finite_fields(self, "terrain ramp", ("start_s", "grade_deg"))
        if self.start_s < 0.0:
            raise ValueError(
                f"terrain ramp start_s={self.start_s!r} m is not allowed: it is an arc length "
                "of the path, >= 0"
            )
        if not 0.0 < self.grade_deg < MAX_GRADE_DEG:
            raise ValueError(
                f"terrain ramp grade {self.grade_deg!r} deg is not allowed: use 0 < grade < "
                f"{MAX_GRADE_DEG:g} deg"
            )
        if self.length is not None:
            check_finite_fields(self, "terrain ramp", ("length",))
            if self.length <= 0.0:
                raise ValueError(
                    f"terrain ramp length={self.length!r} m is not allowed: it must be > 0"
                )

    flat = False
    gravity = None

    @property
    def equivalent_delta1(self) -> float:
        """``g sin(grade)`` (m/s^2) on the ramp, as for :class:`Terrain`."""
        return GRAVITY * math.sin(math.radians(self.grade_deg))

    def spec(self) -> str:
        tail = "" if self.length is None else f":{self.length:g}"
        return f"ramp:{self.start_s:g}:{self.grade_deg:g}{tail}"

    def report(self) -> dict:
        return {
            "ramp_start_s": self.start_s,
            "grade_deg": self.grade_deg,
            "ramp_length_m": self.length,
            "equivalent_delta1": self.equivalent_delta1,
        }


#: Bounds of a rough ground's amplitude (m): the wheels (radius 0.05 m by default) climb a
#: bump of a fraction of their radius; 0.2 m is far beyond what this vehicle can drive.
MAX_ROUGH_AMPLITUDE = 0.2
#: Shortest wavelength (m): the heightfield samples it 8 times a wavelength.
MIN_ROUGH_WAVELENGTH = 0.05


@dataclass(frozen=True)
class Rough:
    """A rough ground: a sum of plane waves of about ``wavelength`` in random directions and
    phases drawn from ``seed``, scaled so its highest and lowest points are ``+-amplitude``."""

    amplitude: float
    wavelength: float
    seed: int = 0

    def __post_init__(self) -> None:
        check_finite_fields(self, "terrain rough", ("amplitude", "wavelength"))
        if not 0.0 < self.amplitude <= MAX_ROUGH_AMPLITUDE:
            raise ValueError(
                f"terrain rough amplitude={self.amplitude!r} m is not allowed: use 0 < "
                f"amplitude <= {MAX_ROUGH_AMPLITUDE:g} m"
            )
        if not self.wavelength >= MIN_ROUGH_WAVELENGTH:
            raise ValueError(
                f"terrain rough wavelength={self.wavelength!r} m is not allowed: use "
                f"wavelength >= {MIN_ROUGH_WAVELENGTH:g} m"
            )
        if isinstance(self.seed, bool) or not isinstance(self.seed, int) or self.seed < 0:
            raise ValueError(
                f"terrain rough seed={self.seed!r} is not allowed: it must be an integer >= 0"
            )

    flat = False
    gravity = None
    equivalent_delta1 = 0.0

    def spec(self) -> str:
        return f"rough:{self.amplitude:g}:{self.wavelength:g}:{self.seed}"

    def report(self) -> dict:
        return {"amplitude_m": self.amplitude, "wavelength_m": self.wavelength, "seed": self.seed}


_ALLOWED = (
    "use 'flat', 'slope:GRADE_DEG[:HEADING_DEG]', 'ramp:START_S_M:GRADE_DEG[:LENGTH_M]' or "
    "'rough:AMPLITUDE_M:WAVELENGTH_M[:SEED]', e.g. 'slope:5:90', 'ramp:2:5', 'rough:0.01:0.5'"
)
#: Each kind's constructor and how many numbers it takes (at least, at most).
_KINDS = {"slope": (Terrain, 1, 2), "ramp": (Ramp, 2, 3), "rough": (Rough, 2, 3)}


def parse_terrain(text) -> Terrain | Ramp | Rough:
    """``"flat"``, ``"slope:GRADE_DEG[:HEADING_DEG]"`` (heading of the rise, default 0: the
    grade climbs along +x), ``"ramp:START_S_M:GRADE_DEG[:LENGTH_M]"`` or
    ``"rough:AMPLITUDE_M:WAVELENGTH_M[:SEED]"``.

    Raises
    ------
    ValueError
        Naming the text and what is allowed.
    """
    if isinstance(text, Terrain | Ramp | Rough):
        return text
    if not isinstance(text, str):
        raise ValueError(f"terrain={text!r} is not allowed: {_ALLOWED}")
    parts = [p.strip() for p in text.strip().split(":")]
    kind = parts[0].lower()
    if kind == "flat" and len(parts) == 1:
        return Terrain()
    if kind not in _KINDS or not _KINDS[kind][1] <= len(parts) - 1 <= _KINDS[kind][2]:
        raise ValueError(f"terrain={text!r} is not allowed: {_ALLOWED}")
    make = _KINDS[kind][0]
    numbers = [number_text(p) for p in parts[1:]]
    if None in numbers:
        raise ValueError(f"terrain={text!r} is not allowed: {_ALLOWED}")
    if make is Rough and len(numbers) == 3:
        if not numbers[2].is_integer():
            raise ValueError(
                f"terrain={text!r} is not allowed: the seed {parts[3]!r} must be an integer >= 0"
            )
        numbers[2] = int(numbers[2])
    return make(*numbers)

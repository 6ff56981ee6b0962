"""Wind on the tractor and the trailer bodies (docs/model.md Section 18).

``Scenario.wind = "SPEED[:DIRECTION_DEG[:GUST_STD]]"``: a wind of mean speed SPEED (m/s) blowing
toward DIRECTION_DEG (from +x, default 0), plus gusts along it, a first-order (Ornstein-Uhlenbeck)
process of standard deviation GUST_STD (m/s, default 0) and time constant :data:`GUST_TIME`,
drawn from the run's seed. Each body feels the quadratic drag of the air relative to it,

    F = 1/2 rho C_d A |w - u| (w - u),

at its centre of mass, with ``u`` the velocity of its axle point (P for the tractor, P0 for
the trailer) and ``C_d A`` the body's drag area (``Params.drag_area_tractor``,
``drag_area_trailer``, the same from every side). MuJoCo plant only.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from tt_mujoco.exact import hypot_of
from tt_mujoco.registry import check_finite_fields
from tt_mujoco.schema_values import number_text
from tt_mujoco.sim.parts import measure

__all__ = [
    "AIR_DENSITY",
    "GUST_TIME",
    "DragConstants",
    "Wind",
    "blow_of",
    "drag_force",
    "drag_moment",
    "gusts_step",
    "parse_wind",
    "wind_wrenches_of",
]

#: Air density at sea level, 15 deg C (kg/m^3).
AIR_DENSITY = 1.225
#: Time constant of the gusts (s).
GUST_TIME = 2.0
#: Fastest mean wind accepted (m/s): a hurricane's.
MAX_WIND = 60.0


@dataclass(frozen=True)
class Wind:
    """A wind of ``speed`` m/s toward ``direction_deg`` with gusts of ``gust_std`` m/s."""

    speed: float = 0.0
    direction_deg: float = 0.0
    gust_std: float = 0.0

    def __post_init__(self) -> None:
        check_finite_fields(self, "wind", ("speed", "direction_deg", "gust_std"))
        if not 0.0 <= self.speed <= MAX_WIND:
            raise ValueError(
                f"wind speed {self.speed!r} m/s is not allowed: use 0 to {MAX_WIND:g} m/s"
            )
        if not 0.0 <= self.gust_std <= MAX_WIND:
            raise ValueError(
                f"wind gust_std {self.gust_std!r} m/s is not allowed: use 0 to {MAX_WIND:g} m/s"
            )

    @property
    def calm(self) -> bool:
        return self.speed == 0.0 and self.gust_std == 0.0

    def spec(self) -> str:
        """The text :func:`parse_wind` reads back."""
        if self.calm:
            return "none"
        return f"{self.speed:g}:{self.direction_deg:g}:{self.gust_std:g}"

    def speeds(self, rng: np.random.Generator, steps: int, dt: float) -> np.ndarray:
        """The wind speed along its direction at each of ``steps + 1`` control steps (m/s)."""
        out = np.full(steps + 1, float(self.speed))
        if self.gust_std > 0.0:
            keep = math.exp(-dt / GUST_TIME)
            kick = self.gust_std * math.sqrt(1.0 - keep * keep)
            draws = rng.standard_normal(steps + 1)
            gust = self.gust_std * draws[0]  # started in its stationary distribution
            for k in range(steps + 1):
                out[k] += gust
                gust = keep * gust + kick * draws[k]
        return out


def parse_wind(text) -> Wind:
    """``"none"`` or ``"SPEED[:DIRECTION_DEG[:GUST_STD]]"``.

    Raises
    ------
    ValueError
        Naming the text and what is allowed.
    """
    allowed = "use 'none' or 'SPEED[:DIRECTION_DEG[:GUST_STD]]' (m/s, deg, m/s), e.g. '8:90:2'"
    if isinstance(text, Wind):
        return text
    if not isinstance(text, str):
        raise ValueError(f"wind={text!r} is not allowed: {allowed}")
    if text.strip().lower() == "none":
        return Wind()
    parts = [p.strip() for p in text.split(":")]
    if not 1 <= len(parts) <= 3:
        raise ValueError(f"wind={text!r} is not allowed: {allowed}")
    numbers = [number_text(p) for p in parts]
    if None in numbers:
        raise ValueError(f"wind={text!r} is not allowed: {allowed}")
    return Wind(*numbers)


def drag_moment(lever: float, heading: float, force_x: float, force_y: float) -> float:
    """The yaw moment (N m) about a body's centre of mass of a force ``(F_x, F_y)`` acting
    ``lever`` metres ahead of it along ``heading`` (rad): ``r x F`` with ``r`` along the
    heading."""
    return lever * (math.cos(heading) * force_y - math.sin(heading) * force_x)


def drag_force(wind_x: float, wind_y: float, u_x: float, u_y: float, drag_area: float):
    """``(F_x, F_y)`` (N): the drag of the air moving at ``(wind_x, wind_y)`` on a body moving
    at ``(u_x, u_y)`` (m/s) with drag area ``drag_area`` (m^2) (the compiled episode shares
    it)."""
    rel_x, rel_y = wind_x - u_x, wind_y - u_y
    scale = 0.5 * AIR_DENSITY * drag_area * hypot_of(rel_x, rel_y)
    return scale * rel_x, scale * rel_y


class DragConstants(NamedTuple):
    """The bodies' drag areas (m^2) and how far ahead of its centre of mass each body's drag
    acts (m), named as the :class:`~tt_mujoco.vehicle.params.Params` fields they come from."""

    drag_area_tractor: float
    drag_area_trailer: float
    drag_centre_tractor: float
    drag_centre_trailer: float


def wind_wrenches_of(wind, motion, drag):
    """The wind's ``(F_x, F_y, M_z)`` on the tractor's body, then on the trailer's: six numbers
    (N, N, N m), for air moving at ``wind = (w_x, w_y)`` (m/s) and the bodies' ``motion = (v,
    theta, v0, theta0, beta)`` as measured; the trailer moves along its axle's rolling direction
    ``theta0 + beta`` (``drag``: :class:`DragConstants`; the compiled episode shares it)."""
    wind_x, wind_y = wind
    v, theta, v0, theta0, beta = motion
    tx, ty = drag_force(
        wind_x, wind_y, v * math.cos(theta), v * math.sin(theta), drag.drag_area_tractor
    )
    alpha = theta0 + beta
    rx, ry = drag_force(
        wind_x, wind_y, v0 * math.cos(alpha), v0 * math.sin(alpha), drag.drag_area_trailer
    )
    tractor_moment = drag_moment(drag.drag_centre_tractor, theta, tx, ty)
    trailer_moment = drag_moment(drag.drag_centre_trailer, theta0, rx, ry)
    return tx, ty, tractor_moment, rx, ry, trailer_moment


def gusts_step(weather, k, measurement) -> None:
    """The wind's wrenches on the tractor and the trailer over step ``k``, at the
    measured motion, into ``weather.wrenches``."""
    speed = weather.speeds[k]
    air = (speed * weather.direction[0], speed * weather.direction[1])
    motion = (
        measurement[measure.V],
        measurement[measure.THETA],
        measurement[measure.V0],
        measurement[measure.THETA0],
        measurement[measure.BETA],
    )
    wrenches = wind_wrenches_of(air, motion, weather.drag)
    for i in range(6):
        weather.wrenches[i] = wrenches[i]


def blow_of(mj, wrench, gusts) -> None:
    """The wind's ``gusts`` (``F_x, F_y, M_z``) on the tractor, then on the
    trailer, added to the tractor's chassis wrench when the disturbance is one."""
    tractor, trailer = mj.xfrc_applied[mj.tractor_body], mj.xfrc_applied[mj.trailer_bodies[0]]
    if wrench:
        tractor[0] += gusts[0]
        tractor[1] += gusts[1]
        tractor[5] += gusts[2]
    else:
        tractor[0], tractor[1], tractor[5] = gusts[0], gusts[1], gusts[2]
    trailer[0], trailer[1], trailer[5] = gusts[3], gusts[4], gusts[5]

"""Ground shapes placed along the run's path: a ramp and a rough ground (docs/model.md
Section 16).

A :class:`~tt_mujoco.sim.parts.terrain.Ramp` or :class:`~tt_mujoco.sim.parts.terrain.Rough` spec
says what
the ground is relative to the path; :func:`relief_of` places it in the world from the run's
reference polyline (the one every run keeps as ``reference_path.parquet``), so the physics and
a video drawn later from the run's folder build the very same ground. A relief gives the
scene's ground geoms (:meth:`geoms_xml`) and the height under any point (:meth:`height`), which
places the vehicle resting on it at the start and in every video frame.

Both are exact for MuJoCo's own geometry: a ramp is two boxes whose top faces are the planes
of :meth:`RampRelief.height`; a rough ground is a heightfield, which MuJoCo splits into two
triangles a cell along the diagonal from node (row, col) to (row + 1, col + 1), as
:meth:`RoughRelief.height` does.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from tt_mujoco.sim.parts.terrain import Ramp, Rough
from tt_mujoco.vehicle.mjcf import floor_xml

__all__ = ["MAX_RELIEF_NODES", "RampRelief", "RoughRelief", "ground_margin", "relief_of"]

#: Most heightfield nodes a rough ground may have (its scene's XML carries every height).
MAX_RELIEF_NODES = 400_000
#: Plane waves summed into a rough ground.
ROUGH_WAVES = 24
#: A rough ground's samples per wavelength.
SAMPLES_PER_WAVELENGTH = 8


def ground_margin(params) -> float:
    """How far (m) the ground's shapes reach beyond the path: the train's length, which
    stands behind the tractor at the start, plus 1.5 m."""
    return 1.5 + params.L + sum(t.L + t.L0 for t in params.train)


def _num(x: float) -> str:
    return repr(float(x))


@dataclass(frozen=True)
class RampRelief:
    """A ramp in world coordinates: its foot crosses ``(x0, y0)`` across ``heading`` (rad), it
    rises at ``grade_deg`` along ``heading`` for ``run`` metres (horizontal), then is level.
    ``reach`` (m) is how far its boxes extend, ahead and to each side."""

    x0: float
    y0: float
    heading: float
    grade_deg: float
    run: float
    reach: float
    level_top: bool

    @property
    def rise(self) -> float:
        """The ramp's height at its top (m)."""
        return self.run * math.tan(math.radians(self.grade_deg))

    def height(self, x, y) -> np.ndarray:
        """The ground's height (m) at points ``(x, y)``."""
        along = (np.asarray(x) - self.x0) * math.cos(self.heading) + (
            np.asarray(y) - self.y0
        ) * math.sin(self.heading)
        return np.tan(math.radians(self.grade_deg)) * np.clip(along, 0.0, self.run)

    def geoms_xml(self) -> tuple[str, str]:
        """``(assets, geoms)`` for the scene's worldbody: the floor and the ramp's boxes."""
        a = math.radians(self.grade_deg)
        u = np.array([math.cos(self.heading), math.sin(self.heading), 0.0])
        side = np.array([-u[1], u[0], 0.0])
        slope = math.cos(a) * u + np.array([0.0, 0.0, math.sin(a)])  # up the ramp
        normal = np.cross(slope, side)
        foot = np.array([self.x0, self.y0, 0.0])
        half_length = 0.5 * self.run / math.cos(a)
        thickness = 0.5 * (self.rise + 0.1)  # half; reaches below the floor everywhere
        centre = foot + half_length * slope - thickness * normal
        axes = " ".join(_num(c) for c in (*slope, *side))
        sizes = f"{_num(half_length)} {_num(self.reach)} {_num(thickness)}"
        geoms = [
            floor_xml(),
            f'<geom name="ramp" type="box" size="{sizes}" pos="{" ".join(map(_num, centre))}" '
            f'xyaxes="{axes}" material="groundplane"/>',
        ]
        if self.level_top:
            top = foot + self.run * u + 0.5 * self.reach * u
            top[2] = self.rise - thickness
            sizes = f"{_num(0.5 * self.reach)} {_num(self.reach)} {_num(thickness)}"
            axes = " ".join(_num(c) for c in (*u, *side))
            geoms.append(
                f'<geom name="ramp_top" type="box" size="{sizes}" '
                f'pos="{" ".join(map(_num, top))}" xyaxes="{axes}" material="groundplane"/>'
            )
        return "", "\n    ".join(geoms)

    def report(self) -> dict:
        return {
            "ramp_foot_xy": [self.x0, self.y0],
            "ramp_heading_deg": math.degrees(self.heading),
            "ramp_rise_m": self.rise,
        }


@dataclass(frozen=True, eq=False)
class RoughRelief:
    """A heightfield: ``heights[row, col]`` (m) at ``x = x_min + col * spacing``,
    ``y = y_min + row * spacing``."""

    x_min: float
    y_min: float
    spacing: float
    heights: np.ndarray

    def height(self, x, y) -> np.ndarray:
        """The ground's height (m) at points ``(x, y)``: MuJoCo's triangles (module
        docstring); beyond the grid, the floor at the grid's lowest height."""
        z = self.heights
        rows, cols = z.shape
        u = (np.asarray(x, dtype=float) - self.x_min) / self.spacing
        v = (np.asarray(y, dtype=float) - self.y_min) / self.spacing
        inside = (u >= 0) & (u <= cols - 1) & (v >= 0) & (v <= rows - 1)
        c = np.clip(np.floor(u).astype(int), 0, cols - 2)
        r = np.clip(np.floor(v).astype(int), 0, rows - 2)
        du, dv = np.clip(u - c, 0.0, 1.0), np.clip(v - r, 0.0, 1.0)
        z00, z11 = z[r, c], z[r + 1, c + 1]
        lower = z00 + du * (z[r, c + 1] - z00) + dv * (z11 - z[r, c + 1])  # du >= dv
        upper = z00 + dv * (z[r + 1, c] - z00) + du * (z11 - z[r + 1, c])
        return np.where(inside, np.where(du >= dv, lower, upper), z.min())

    def geoms_xml(self) -> tuple[str, str]:
        z = self.heights
        rows, cols = z.shape
        low, high = float(z.min()), float(z.max())
        rx, ry = 0.5 * (cols - 1) * self.spacing, 0.5 * (rows - 1) * self.spacing
        # MuJoCo reads the elevation's first row as the grid's last (y = y_max) and rescales
        # it to [0, 1] times size[2] above the geom's position.
        elevation = " ".join(f"{h:.9g}" for h in z[::-1].ravel())
        assets = (
            f'<hfield name="rough" nrow="{rows}" ncol="{cols}" '
            f'size="{_num(rx)} {_num(ry)} {_num(high - low)} 0.05" elevation="{elevation}"/>'
        )
        centre = f"{_num(self.x_min + rx)} {_num(self.y_min + ry)} {_num(low)}"
        geoms = (
            floor_xml(low)
            + f'\n    <geom name="rough" type="hfield" hfield="rough" pos="{centre}" '
            'material="groundplane"/>'
        )
        return assets, geoms

    def report(self) -> dict:
        return {"grid_spacing_m": self.spacing, "grid_nodes": int(self.heights.size)}


def _point_at(polyline: np.ndarray, s: float) -> tuple[float, float, float]:
    """``(x, y, heading)`` at arc length ``s`` along ``polyline``."""
    steps = np.diff(polyline, axis=0)
    lengths = np.hypot(steps[:, 0], steps[:, 1])
    ends = np.cumsum(lengths)
    i = min(int(np.searchsorted(ends, s)), len(lengths) - 1)
    before = ends[i] - lengths[i]
    f = (s - before) / lengths[i] if lengths[i] > 0 else 0.0
    x, y = polyline[i] + f * steps[i]
    return float(x), float(y), math.atan2(steps[i, 1], steps[i, 0])


def _rough_heights(spec: Rough, xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
    rng = np.random.default_rng(spec.seed)
    k = 2 * math.pi / spec.wavelength * rng.uniform(0.7, 1.4, ROUGH_WAVES)
    direction = rng.uniform(0.0, math.pi, ROUGH_WAVES)
    phase = rng.uniform(0.0, 2 * math.pi, ROUGH_WAVES)
    gx, gy = np.meshgrid(xs, ys)
    z = np.zeros_like(gx)
    for kj, dj, pj in zip(k, direction, phase, strict=True):
        z += np.cos(kj * (math.cos(dj) * gx + math.sin(dj) * gy) + pj)
    return spec.amplitude * z / np.abs(z).max()


def relief_of(spec, polyline, params) -> RampRelief | RoughRelief | None:
    """The ground shape of terrain ``spec`` placed along ``polyline`` (the run's reference,
    ``(M, 2)``) for the vehicle ``params``; None for flat ground or a grade (a tilt of
    gravity, not a shape).

    Raises
    ------
    ValueError
        A ramp starting beyond the path the run can reach, or a rough ground that needs more
        than :data:`MAX_RELIEF_NODES` nodes.
    """
    if not isinstance(spec, Ramp | Rough):
        return None
    polyline = np.asarray(polyline, dtype=float).reshape(-1, 2)
    margin = ground_margin(params)
    low, high = polyline.min(axis=0) - margin, polyline.max(axis=0) + margin
    if isinstance(spec, Ramp):
        steps = np.diff(polyline, axis=0)
        length = float(np.hypot(steps[:, 0], steps[:, 1]).sum())
        if spec.start_s > length:
            raise ValueError(
                f"terrain ramp start_s={spec.start_s!r} m is not allowed: the run reaches "
                f"{length:.6g} m of its path"
            )
        x0, y0, heading = _point_at(polyline, spec.start_s)
        reach = float(np.hypot(*(high - low)))
        run = reach if spec.length is None else spec.length
        return RampRelief(x0, y0, heading, spec.grade_deg, run, reach, spec.length is not None)
    spacing = spec.wavelength / SAMPLES_PER_WAVELENGTH
    cols, rows = (int(n) for n in np.ceil((high - low) / spacing) + 1)
    if rows * cols > MAX_RELIEF_NODES:
        raise ValueError(
            f"terrain {spec.spec()!r} is not allowed: a wavelength of {spec.wavelength:g} m over "
            f"this path's {high[0] - low[0]:.3g} x {high[1] - low[1]:.3g} m ground takes "
            f"{rows * cols} heightfield nodes, at most {MAX_RELIEF_NODES} are allowed (use a "
            "longer wavelength)"
        )
    xs = low[0] + spacing * np.arange(cols)
    ys = low[1] + spacing * np.arange(rows)
    return RoughRelief(float(low[0]), float(low[1]), spacing, _rough_heights(spec, xs, ys))

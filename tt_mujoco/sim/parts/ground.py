"""Patches of the ground with another friction coefficient: ice, gravel (MuJoCo plant).

``Scenario.ground`` lists patches, each a text spec:

- ``band:S0:S1:MU``: the stretch of the path from arc length S0 to S1 (m), across its whole
  width: a wheel is on it while its nearest path point lies in [S0, S1];
- ``rect:X0:Y0:X1:Y1:MU``: the rectangle of the floor between the corners (X0, Y0), (X1, Y1).

A wheel on a patch rolls with the patch's friction coefficient MU, elsewhere with the
scenario's ``friction``; where patches overlap the first listed counts. The MuJoCo plant sets
each wheel's contact friction every control step from where the wheel touches the floor (its
contact geoms have the higher priority, so theirs is the contact's coefficient); ``metrics.json``
reports for each patch the time a wheel spent on it and the wheels' largest slips there.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from types import SimpleNamespace

import numpy as np

from tt_mujoco.reference.feedback import path_errors_of
from tt_mujoco.schema_values import number_text

__all__ = [
    "GroundPatches",
    "Patch",
    "ground_report",
    "ground_step",
    "parse_patch",
    "parse_patches",
    "patch_contains_of",
    "wheel_frictions_of",
]

_ALLOWED = (
    "use 'band:S0:S1:MU' (m along the path) or 'rect:X0:Y0:X1:Y1:MU' (m), e.g. 'band:2:3:0.1'"
)
#: Bounds of a patch's friction coefficient.
MU_RANGE = (0.01, 10.0)


@dataclass(frozen=True)
class Patch:
    """One patch: ``kind`` "band" (``bounds = (s0, s1)``) or "rect" (``(x0, y0, x1, y1)``)."""

    kind: str
    bounds: tuple
    mu: float

    def spec(self) -> str:
        return ":".join([self.kind, *(f"{b:g}" for b in self.bounds), f"{self.mu:g}"])

    def contains(self, x: float, y: float, s: float) -> bool:
        return patch_contains_of(_KINDS.index(self.kind), _row(self.bounds), x, y, s)


#: A patch's kind as a number (the compiled episode's), and its bounds as a row of four.
_KINDS = ("band", "rect")


def _row(bounds) -> tuple:
    return (*bounds, *[0.0] * (4 - len(bounds)))


def patch_contains_of(kind: int, bounds, x: float, y: float, s: float) -> bool:
    """Whether a patch holds the point ``(x, y)`` whose nearest path point is at arc length
    ``s``: a band (``kind`` 0, ``bounds = (s0, s1, -, -)``) the stretch s0 <= s <= s1, a
    rectangle (1, ``(x0, y0, x1, y1)``) its corners' box (the compiled episode shares it)."""
    if kind == 0:
        return bounds[0] <= s <= bounds[1]
    x0, y0, x1, y1 = bounds[0], bounds[1], bounds[2], bounds[3]
    return min(x0, x1) <= x <= max(x0, x1) and min(y0, y1) <= y <= max(y0, y1)


def wheel_frictions_of(path, points, arcs, patches, out) -> int:
    """Each wheel's friction coefficient into ``out``, for the wheels' contact ``points`` ((n,
    2): x, y), and the bit mask of the patches some wheel is on. ``patches = (kinds, bounds,
    mus, base_mu)`` (:func:`patch_contains_of`; the first listed counts); with ``arcs`` (each
    wheel's arc length, updated) a band is measured along ``path`` from each wheel's nearest
    point, else ``arcs`` is empty (the compiled episode shares it)."""
    kinds, bounds, mus, base_mu = patches
    mask = 0
    for i in range(points.shape[0]):
        x, y = points[i, 0], points[i, 1]
        s = math.nan
        if len(arcs):
            s = path_errors_of(path, arcs[i], x, y, 0.0)[0]
            arcs[i] = s
        mu = base_mu
        for j in range(len(kinds)):
            if patch_contains_of(kinds[j], bounds[j], x, y, s):
                mu = mus[j]
                mask |= 1 << j
                break
        out[i] = mu
    return mask


def parse_patch(text) -> Patch:
    """A :class:`Patch` from its text (module docstring).

    Raises
    ------
    ValueError
        Naming the text and what is allowed.
    """
    if isinstance(text, Patch):
        return text
    if not isinstance(text, str):
        raise ValueError(f"ground patch {text!r} is not allowed: {_ALLOWED}")
    kind, *parts = (p.strip() for p in text.split(":"))
    need = {"band": 3, "rect": 5}.get(kind.lower())
    if need is None or len(parts) != need:
        raise ValueError(f"ground patch {text!r} is not allowed: {_ALLOWED}")
    numbers = [number_text(p) for p in parts]
    if None in numbers:
        raise ValueError(f"ground patch {text!r} is not allowed: {_ALLOWED}")
    if not all(math.isfinite(n) for n in numbers):
        raise ValueError(f"ground patch {text!r} is not allowed: its numbers must be finite")
    *bounds, mu = numbers
    low, high = MU_RANGE
    if not low <= mu <= high:
        raise ValueError(
            f"ground patch {text!r}: friction {mu!r} is not allowed: use {low:g} to {high:g}"
        )
    if kind.lower() == "band" and not 0.0 <= bounds[0] < bounds[1]:
        raise ValueError(
            f"ground patch {text!r}: the band {bounds[0]!r} to {bounds[1]!r} m is not allowed: "
            "use 0 <= S0 < S1"
        )
    return Patch(kind.lower(), tuple(bounds), mu)


def parse_patches(specs) -> tuple[Patch, ...]:
    """Validate a list of patch specs (see :func:`parse_patch`)."""
    if isinstance(specs, str) or not isinstance(specs, list | tuple):
        raise ValueError(f"ground={specs!r} is not allowed: give a list of patch specs")
    return tuple(parse_patch(s) for s in specs)


class GroundPatches:
    """Which patch each wheel stands on, step by step (the plant asks).

    Parameters
    ----------
    patches : sequence of Patch
    path : tt_mujoco.reference.path_base.ReferencePath
        The path the bands are measured along.
    base_mu : float
        The friction coefficient off the patches.
    """

    def __init__(self, patches, path, base_mu: float):
        self.patches = tuple(patches)
        self.path = path
        self.base_mu = float(base_mu)
        self._bands = any(p.kind == "band" for p in self.patches)
        # the path as wheel_frictions_of reads it (path_errors_of's pose and curvature)
        self._path_record = SimpleNamespace(
            pose_at=path.pose_at, curvature_and_rate=path.curvature_and_rate
        )
        self.kinds = np.array([_KINDS.index(p.kind) for p in self.patches], dtype=np.int64)
        self.bounds = np.array([_row(p.bounds) for p in self.patches], dtype=float).reshape(-1, 4)
        self.mus = np.array([p.mu for p in self.patches], dtype=float)

    def start(self, points) -> np.ndarray:
        """Each wheel's arc length to start from, for the wheels' contact ``points``: the
        nearest point of a coarse table of the path (empty without bands). The episode's
        ground record keeps them from there, step by step."""
        if not self._bands:
            return np.zeros(0)
        grid = np.linspace(0.0, self.path.length, 2001)
        table = np.array([self.path.pose_at(s)[:2] for s in grid])
        points = np.asarray(points, dtype=float)
        return np.array([grid[np.argmin(np.hypot(*(table - point).T))] for point in points])

    def frictions(self, points) -> tuple[list[float], int]:
        """``(mu of each wheel, bit mask of the patches some wheel is on)`` for the wheels'
        contact points ``points`` (an (n, 2) array of x, y), from the :meth:`start` arc
        lengths: a query (the step reads the record, :func:`ground_step`)."""
        points = np.asarray(points, dtype=float)
        arcs = self.start(points)
        mus = np.empty(points.shape[0])
        patches = (self.kinds, self.bounds, self.mus, self.base_mu)
        mask = wheel_frictions_of(self._path_record, points, arcs, patches, mus)
        return mus.tolist(), mask


def ground_report(patches, masks, ts) -> list[dict]:
    """Per patch: its spec, the time some wheel spent on it (s) and the largest tractor-wheel
    and lateral slips (m/s) over those steps, for ``metrics.json``."""
    t = np.asarray(ts["t"])
    masks = list(masks)
    if masks and len(masks) < len(t):  # the row after the last step: where the wheels were
        masks += [masks[-1]] * (len(t) - len(masks))
    masks = np.asarray(masks, dtype=np.int64)
    n = min(len(masks), len(t))
    dt = float(t[1] - t[0]) if len(t) > 1 else 0.0
    report = []
    for j, patch in enumerate(patches):
        on = np.zeros(len(t), dtype=bool)
        on[:n] = (masks[:n] >> j) & 1 == 1
        entry = {"patch": patch.spec(), "mu": patch.mu, "time_s": float(on.sum() * dt)}
        for key, columns in (
            ("slip_longitudinal_max", ("slip_left", "slip_right")),
            ("slip_lateral_max", ("slip_lateral", "slip_lateral_trailer")),
        ):
            values = [np.abs(np.asarray(ts[c])[on]) for c in columns if c in ts]
            values = [v[np.isfinite(v)] for v in values]
            entry[key] = float(max(v.max() for v in values)) if on.any() and values else None
        report.append(entry)
    return report


def ground_step(patches, target) -> int:
    """The friction patches: each wheel's friction set from where it stands
    (GroundPatches.frictions); the bit mask of the patches some wheel is on."""
    points, xpos = patches.points, patches.geom_xpos
    for i in range(patches.geoms.size):
        points[i, 0], points[i, 1] = xpos[patches.geoms[i], 0], xpos[patches.geoms[i], 1]
    table = (patches.kinds, patches.bounds, patches.mus, patches.base_mu)
    mask = wheel_frictions_of(target, points, patches.arcs, table, patches.frictions)
    for i in range(patches.geoms.size):
        patches.geom_friction[patches.geoms[i], 0] = patches.frictions[i]
    return mask

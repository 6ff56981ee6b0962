"""Path-scheduled passive steering: the gains eta_k(s) that keep every axle on the tractor's path
(docs/model.md Section 13).

For a tractor whose axle midpoint P runs exactly along a reference path with its heading on the
path's tangent, the geometry alone fixes where each trailer must be for its axle to lie on the
same path: the hitch O_k is a distance L_k behind the unit ahead (along that unit's heading),
and the axle P_k is the point of the path a distance L0_k from O_k, behind it. The trailer's
heading theta_k points from P_k to O_k, so the hitch angle is ``phi_k = theta_{k-1} - theta_k``;
P_k rolls along the path's tangent there, so its steering angle is
``beta_k = heading(s_k) - theta_k``. Their ratio is the gain ``eta_k = beta_k / phi_k`` that
makes the passive law ``beta_k = eta_k phi_k`` (paper eq. 2) roll P_k along the path: the set of
poses with every axle on the path is then invariant under the pure-rolling kinematics, in either
direction of travel, transients included.

Before the path's start the path continues along its first tangent (as
:meth:`~tt_mujoco.reference.path_base.ReferencePath.pose` does), so a train standing straight
behind a tractor at s = 0 starts on the schedule.

Where the ratio is not a usable gain the schedule is bounded:

- where |beta_k / phi_k| exceeds ``eta_max`` (near an inflection phi_k passes through zero while
  beta_k does not: no gain can give that steering), the gain is clipped to the bound, the
  bounded gain nearest the steering asked for; where phi_k is zero to rounding (a straight
  stretch), the ratio is interpolated from its neighbours;
- everything is tabulated once per path on the tractor's arc length (:func:`path_schedule`), and
  looked up at run time by each trailer's own arc length, the projection of its axle onto the
  path, and its hitch angle as it is (:meth:`PathSchedule.gain`), so that a trailer off its
  schedule still gets the steering of where it is.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from tt_mujoco.compiled_form import compiled_form
from tt_mujoco.vehicle.steering import wrap_angle

__all__ = [
    "BLEND_PHI",
    "DEFAULT_ETA_MAX",
    "DrivenPath",
    "PathSchedule",
    "axle_chain",
    "driven_path",
    "nearest_arc_length",
    "path_schedule",
]

#: Bound on |eta_k| of the path schedule (the bound the issue's study used; the paper's eta = 3).
DEFAULT_ETA_MAX = 3.0
#: Tractor arc-length spacing (m) of the tabulated schedule: cubic interpolation on it is exact
#: to ~1e-10 in eta on the paper's paths (tests/test_path_schedule.py).
TABLE_SPACING = 0.002
#: Hitch angle (rad) below which :meth:`PathSchedule.gain` leans on the table's gain rather than
#: on the path's steering (3 deg: 1 deg left a 3-trailer train on MuJoCo's cycloid 34 mm off,
#: its hitches crossing zero in the start's shaking; docs/model.md Section 13).
BLEND_PHI = math.radians(3.0)
#: |phi_k| (rad) below which beta_k / phi_k is rounding noise, not a gain.
_PHI_TINY = 1e-7
#: Bisection steps for the axle's arc length: brackets of ~1 m shrink below 1e-15 m.
_BISECTIONS = 56


def axle_chain(path, s, lengths, bisections: int = _BISECTIONS):
    """Where every axle lies on the path when the tractor's P is at arc length ``s``.

    Parameters
    ----------
    path : tt_mujoco.reference.path_base.ReferencePath
        The tractor's path (continued along its end tangents beyond its ends).
    s : array_like
        Tractor arc lengths (m).
    lengths : sequence of (L_k, L0_k)
        Trailers 1..N: hitch behind the unit ahead, axle behind the hitch (m).
    bisections : int
        Bisection steps for each axle's arc length (its bracket, about 2 (L + L0) long, halves
        with each): the default places it to rounding; a planner's clearance check needs
        far less.

    Returns
    -------
    list of dict
        Per trailer, arrays over ``s``: ``s`` (the axle's arc length), ``x``, ``y`` (the axle),
        ``theta`` (the trailer's heading), ``phi``, ``beta`` (rad).

    Raises
    ------
    ValueError
        Where the path curves so tightly that an axle's circle about its hitch does not meet it
        behind the hitch.
    """
    s_ahead = np.asarray(s, dtype=float)
    fx, fy, fth = path.pose(s_ahead)
    chain = []
    for k, (L, L0) in enumerate(lengths, start=1):
        ox, oy = fx - L * np.cos(fth), fy - L * np.sin(fth)

        def excess(sk, ox=ox, oy=oy, L0=L0):
            x, y, _ = path.pose(sk)
            return (x - ox) ** 2 + (y - oy) ** 2 - L0 * L0

        # Bracket: O lies about L behind the unit ahead, the axle about L0 behind O.
        hi = s_ahead - min(L, 0.999 * L0) if L >= L0 else s_ahead.copy()
        lo = s_ahead - 2.0 * (L + L0) - 0.1
        unbracketed = (excess(hi) >= 0.0) | (excess(lo) <= 0.0)
        if np.any(unbracketed):
            bad = float(s_ahead.flat[np.flatnonzero(unbracketed)[0]])
            raise ValueError(
                f"path {path.name!r} at s={bad:.4g} m is not allowed for the path schedule: "
                f"trailer {k}'s axle (L={L:g} m, L0={L0:g} m) cannot be placed on it"
            )
        for _ in range(bisections):
            mid = 0.5 * (lo + hi)
            inside = excess(mid) < 0.0
            hi = np.where(inside, mid, hi)
            lo = np.where(inside, lo, mid)
        sk = 0.5 * (lo + hi)
        px, py, tangent = path.pose(sk)
        thk = np.arctan2(oy - py, ox - px)
        chain.append(
            {
                "s": sk,
                "x": px,
                "y": py,
                "theta": thk,
                "phi": wrap_angle(fth - thk),
                "beta": wrap_angle(tangent - thk),
            }
        )
        s_ahead, fx, fy, fth = sk, px, py, thk
    return chain


def _bounded_gain(phi: np.ndarray, beta: np.ndarray, eta_max: float):
    """``(eta, exact)``: beta / phi clipped to [-eta_max, eta_max] (interpolated where phi is
    zero to rounding), and where that is the exact ratio.

    Clipping is the bounded gain nearest the steering the geometry asks for at each point:
    ``|beta - eta phi|`` is smallest over |eta| <= eta_max there. (Interpolating across the
    clipped stretch instead, or across |phi| < 1 deg, left 25-40 % more off-tracking on the
    S-curve in the kinematic ideal.)
    """
    defined = np.abs(phi) > _PHI_TINY
    ratio = np.divide(beta, phi, out=np.zeros_like(phi), where=defined)
    if not defined.any():
        return np.zeros_like(phi), defined
    index = np.arange(phi.size)
    ratio = np.interp(index, index[defined], ratio[defined])
    exact = np.abs(ratio) <= eta_max
    return np.clip(ratio, -eta_max, eta_max), exact


@dataclass(frozen=True)
class PathSchedule:
    """The tabulated path schedule of one path and train (from :func:`path_schedule`).

    Attributes
    ----------
    path : ReferencePath
        The path it was built for.
    s_tractor : ndarray
        The tractor arc lengths of the table (m).
    axles : tuple of dict
        Per trailer, :func:`axle_chain`'s arrays plus ``eta`` (the bounded gain) and ``exact``
        (True where it is the exact ratio beta / phi, False where the bound clipped it).
    eta_max : float
        The bound on |eta_k|.
    """

    path: object
    s_tractor: np.ndarray
    axles: tuple
    eta_max: float

    def __post_init__(self) -> None:
        # Per trailer, the lookup table (s, eta, d eta/ds, beta, d beta/ds) as plain lists (the
        # per-step lookup reads scalars); derived from the arrays above, so the object stays a
        # value.
        def table(axle):
            s = axle["s"]
            columns = (s, axle["eta"], np.gradient(axle["eta"], s))
            columns += (axle["beta"], np.gradient(axle["beta"], s))
            return tuple(column.tolist() for column in columns)

        object.__setattr__(self, "tables", tuple(table(axle) for axle in self.axles))

    @property
    def n_trailers(self) -> int:
        return len(self.axles)

    def eta(self, k: int, s_axle: float) -> float:
        """Trailer ``k``'s gain (k = 0 for trailer 1) where its axle is at arc length ``s_axle``.

        Cubic Hermite interpolation of the table; held at the table's end values beyond it.
        """
        return table_eta_of(self.tables[k], s_axle)

    def gain(self, k: int, s_axle: float, phi: float) -> float:
        """Trailer ``k``'s gain at arc length ``s_axle`` with the hitch angle ``phi`` (rad) as
        it is, bounded to ``eta_max`` (:func:`blended_gain_of`)."""
        return table_gain_of(self.tables[k], s_axle, phi, (BLEND_PHI, self.eta_max))

    def arc_lengths_at(self, s_tractor: float) -> list[float]:
        """Each axle's arc length on the schedule when the tractor is at ``s_tractor`` (the
        nearest table entry): where a run's projections start."""
        i = min(int(np.searchsorted(self.s_tractor, s_tractor)), self.s_tractor.size - 1)
        return [float(axle["s"][i]) for axle in self.axles]

    def project(self, s_guess: float, x: float, y: float) -> float:
        """Arc length of the path point nearest (x, y) (:func:`nearest_arc_length`)."""
        return nearest_arc_length(self.path, s_guess, x, y)

    def axle_gain(
        self, k: int, s_guess: float, point, heading: float, phi: float, driven: DrivenPath
    ) -> tuple[float, float]:
        """``(s, eta)``: trailer ``k``'s axle at ``point = (x, y)`` projected onto the path from
        ``s_guess``, and its gain there with its trailer heading ``heading`` and hitch angle
        ``phi`` as they are, steered towards ``driven`` (:func:`axle_gain_of`)."""
        bounds = (BLEND_PHI, self.eta_max)
        return axle_gain_of(self.path, s_guess, point, heading, phi, self.tables[k], bounds, driven)


@compiled_form("the target record's path (target_step.pose_at), not a path object")
def path_pose(path, s: float) -> tuple[float, float, float]:
    """The path's pose at ``s`` (:meth:`~tt_mujoco.reference.path_base.ReferencePath.pose_at`),
    as the path schedule and the path feedback read it; the compiled episode gives it the same
    for its path record."""
    return path.pose_at(s)


def nearest_arc_length(path, s_guess: float, x: float, y: float) -> float:
    """Arc length of the path point nearest (x, y), by Newton steps from ``s_guess``
    (:func:`nearest_arc_length_of`)."""
    return nearest_arc_length_of(path, s_guess, x, y)


def nearest_arc_length_of(path, s: float, x: float, y: float) -> float:
    """Arc length of the path point nearest (x, y), by Newton steps from ``s``; the pose is
    :func:`path_pose`'s (the compiled episode shares it).

    Converges in two or three steps from the previous control step's value (an axle moves
    millimetres a step); the path continues along its end tangents beyond its ends.
    """
    for _ in range(4):
        px, py, heading = path_pose(path, s)
        ds = (x - px) * math.cos(heading) + (y - py) * math.sin(heading)
        s += ds
        if abs(ds) < 1e-12:
            break
    return s


def bisect_right_of(xs, x: float) -> int:
    """Where ``x`` goes in the ascending ``xs``, after its equals (:func:`bisect.bisect_right`;
    the compiled episode shares it)."""
    lo, hi = 0, len(xs)
    while lo < hi:
        mid = (lo + hi) // 2
        if x < xs[mid]:
            hi = mid
        else:
            lo = mid + 1
    return lo


def hermite_of(i: int, xs, ys, slopes, x: float) -> float:
    """Cubic Hermite interpolation of ``(xs, ys, slopes)`` at ``x``, ``i =
    bisect_right_of(xs, x)``; held beyond the ends (the compiled episode shares it)."""
    if i <= 0:
        return ys[0]
    if i >= len(xs):
        return ys[len(xs) - 1]
    x0, x1 = xs[i - 1], xs[i]
    h = x1 - x0
    u = (x - x0) / h
    w2 = (1.0 - u) * (1.0 - u)  # not ** 2: Python's pow may differ from the product by an ulp
    h00 = (1.0 + 2.0 * u) * w2
    h10 = u * w2
    h01 = u * u * (3.0 - 2.0 * u)
    h11 = u * u * (u - 1.0)
    return h00 * ys[i - 1] + h10 * h * slopes[i - 1] + h01 * ys[i] + h11 * h * slopes[i]


def blended_gain_of(eta: float, steering: float, phi: float, bounds) -> float:
    """The gain nearest both the steering the path asks for and the table's gain, with the
    hitch angle ``phi`` as it is; ``bounds = (w, eta_max)`` (the compiled episode shares it).

        eta* = (beta_k(s) phi + w^2 eta_k(s)) / (phi^2 + w^2),   clipped to |eta*| <= eta_max,

    minimises ``(eta* phi - beta_k(s))^2 + w^2 (eta* - eta_k(s))^2``. On the schedule
    (``phi = phi_k(s)``) it is the table's gain exactly. Off it, a hitch well away from zero
    gets the path's steering, ``beta ~ beta_k(s)``, and a hitch near zero the table's gain, so
    ``beta = eta* phi`` is continuous in ``phi``, and in ``s`` wherever the table is. Where the
    table's gain flips sign (the clipped crossing of an inflection) a hitch lagging its
    schedule by a few degrees still gets a share ``w^2 / (phi^2 + w^2)`` of the flip
    (docs/model.md Section 13).
    """
    blend, eta_max = bounds
    w2 = blend * blend
    blended = (steering * phi + w2 * eta) / (phi * phi + w2)
    return min(max(blended, -eta_max), eta_max)


def table_eta_of(table, s: float) -> float:
    """The gain ``eta_k(s)`` of an axle's ``table = (s, eta, d eta/ds, beta, d beta/ds)``: cubic
    Hermite, held beyond its ends (the compiled episode shares it)."""
    xs = table[0]
    return hermite_of(bisect_right_of(xs, s), xs, table[1], table[2], s)


def table_gain_of(table, s: float, phi: float, bounds) -> float:
    """:func:`blended_gain_of` of an axle's table's gain and steering ``beta_k(s)`` at arc
    length ``s`` (the compiled episode shares it)."""
    xs = table[0]
    i = bisect_right_of(xs, s)  # one search for both columns: this runs every control step
    eta = hermite_of(i, xs, table[1], table[2], s)
    steering = hermite_of(i, xs, table[3], table[4], s)
    return blended_gain_of(eta, steering, phi, bounds)


class DrivenPath(NamedTuple):
    """The path the tractor drove, as its offset from the reference path by arc length: where
    the path schedule's feedback steers the axles (:func:`driven_steering_of`)."""

    #: the tractor's arc lengths, ascending (the first ``count[0]`` hold), and its signed
    #: offsets from the reference path there (m, left positive)
    arcs: np.ndarray
    offsets: np.ndarray
    #: how many are held (int64, shape (1,)), and the tractor's arc length at the last step
    #: (shape (1,): where the next projection starts)
    count: np.ndarray
    tractor: np.ndarray
    #: the feedback's gain (1/m; ``Scenario.driven_path_gain`` driving forward); 0 reversing,
    #: where the axles lead the tractor, or as asked: the table's steering
    gain: float


def driven_path(capacity: int, start_s: float, gain: float) -> DrivenPath:
    """An empty :class:`DrivenPath` for ``capacity`` control steps, the tractor at ``start_s``."""
    return DrivenPath(
        arcs=np.zeros(max(1, capacity)),
        offsets=np.zeros(max(1, capacity)),
        count=np.zeros(1, dtype=np.int64),
        tractor=np.array([float(start_s)]),
        gain=float(gain),
    )


def signed_offset_of(pose, x: float, y: float) -> float:
    """How far (x, y) stands left of a path point ``pose = (x, y, heading)``
    (:func:`path_pose`), across its tangent (m; the compiled episode shares it)."""
    px, py, heading = pose
    return (y - py) * math.cos(heading) - (x - px) * math.sin(heading)


def record_driven_of(path, driven: DrivenPath, x: float, y: float) -> None:
    """Log the tractor at (x, y): projected onto the path from its last arc length, its offset
    kept where it has gone further along the path than ever before (the compiled episode
    shares it)."""
    s = nearest_arc_length_of(path, driven.tractor[0], x, y)
    driven.tractor[0] = s
    n = driven.count[0]
    if (n == 0 or s > driven.arcs[n - 1]) and n < driven.arcs.size:
        driven.arcs[n] = s
        driven.offsets[n] = signed_offset_of(path_pose(path, s), x, y)
        driven.count[0] = n + 1


def driven_offset_of(driven: DrivenPath, s: float) -> float:
    """The tractor's offset from the reference path where it passed arc length ``s``, linear
    between the logged ones and held beyond them (the compiled episode shares it)."""
    n = driven.count[0]
    if n == 0:
        return 0.0
    arcs, offsets = driven.arcs, driven.offsets
    if s <= arcs[0]:
        return offsets[0]
    if s >= arcs[n - 1]:
        return offsets[n - 1]
    hi = bisect_right_of(arcs[:n], s)  # arcs[hi - 1] <= s < arcs[hi]
    lo = hi - 1
    return offsets[lo] + (s - arcs[lo]) / (arcs[hi] - arcs[lo]) * (offsets[hi] - offsets[lo])


def driven_steering_of(path, s: float, point, heading: float, driven: DrivenPath) -> float:
    """The steering of an axle at ``point`` (arc length ``s``) whose trailer heads ``heading``:
    along the path's tangent there, turned back by ``atan(gain e)`` where it stands ``e``
    beside the path the tractor drove (the compiled episode shares it).

    On the schedule it is the table's ``beta_k(s)`` (``heading(s_k) - theta_k``, ``e = 0``).
    """
    pose = path_pose(path, s)  # once: the tangent and the offset both read it
    beside = signed_offset_of(pose, point[0], point[1]) - driven_offset_of(driven, s)
    return wrap_angle(pose[2] - heading) - math.atan(driven.gain * beside)


def axle_gain_of(path, s_guess: float, point, heading: float, phi: float, table, bounds, driven):
    """``(s, eta)``: the axle at ``point = (x, y)`` projected onto the path from ``s_guess``
    (:func:`nearest_arc_length_of`), and its gain there (:func:`blended_gain_of` of the
    table's gain and :func:`driven_steering_of`; reversing, :func:`table_gain_of`). The
    compiled episode shares it."""
    s = nearest_arc_length_of(path, s_guess, point[0], point[1])
    if driven.gain == 0.0:
        return s, table_gain_of(table, s, phi, bounds)
    steering = driven_steering_of(path, s, point, heading, driven)
    return s, blended_gain_of(table_eta_of(table, s), steering, phi, bounds)


def path_schedule(path, lengths, eta_max: float = DEFAULT_ETA_MAX, spacing: float = TABLE_SPACING):
    """Tabulate the path schedule of a path and a train once.

    Parameters
    ----------
    path : ReferencePath
        The tractor's reference path.
    lengths : sequence of (L_k, L0_k)
        Trailers 1..N.
    eta_max : float
        Bound on |eta_k| (> 0).
    spacing : float
        Tractor arc-length spacing of the table (m, > 0).

    Returns
    -------
    PathSchedule

    Raises
    ------
    ValueError
        For a bad bound or spacing, or a path too tight for an axle (:func:`axle_chain`).
    """
    for name, value in (("eta_max", eta_max), ("spacing", spacing)):
        if isinstance(value, bool) or not isinstance(value, int | float) or not value > 0:
            raise ValueError(f"{name}={value!r} is not allowed: it must be a number > 0")
        if not math.isfinite(value):
            raise ValueError(f"{name}={value!r} is not allowed: it must be finite")
    n = max(3, math.ceil(path.length / spacing) + 1)
    s = np.linspace(0.0, path.length, n)
    chain = axle_chain(path, s, lengths)
    for axle in chain:
        axle["eta"], axle["exact"] = _bounded_gain(axle["phi"], axle["beta"], float(eta_max))
    return PathSchedule(path=path, s_tractor=s, axles=tuple(chain), eta_max=float(eta_max))

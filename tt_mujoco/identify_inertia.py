"""A train's masses and inertias fitted to a log with its wheels' torques, and a payload found
where it was put on (``python -m tt_mujoco.identify LOG --fit Mr,... [--payload K]``).

The reduced model (docs/model.md Sections 4 and 12) written for the generalised momentum
``p = Mbar(phi) V``::

    dp/dt = B tau + dMbar/dt V - Cbar(phi, V) V,

is linear in every mass and inertia: ``Mbar`` and ``Cbar V`` are sums over the bodies of each
body's mass or inertia times a function of the hitch angles and ``V``
(:func:`tt_mujoco.vehicle.train.mass_and_bias_of`, evaluated here with one parameter at 1 and
the others at 0). The fit is an output-error one: the log is cut into segments of
:data:`SEGMENT_S`; in each, ``V`` is simulated from the segment's first velocity (a free
parameter of the fit) under the logged torques, along the logged hitch angles, and compared with
the logged ``V``. Noise on ``v`` and ``omega`` is then noise on what is compared only, and
biases nothing; a fit by equations (momenta or energies by differences of the logged ``V``)
reads that noise into its regressors and, at 20 dB, comes out 10 % to several times off
(measured while choosing the method: ``docs/identify.md``).

The torques are the wheels' (N m), each row's held until the next (a log of the commands as
sent, at their own rate); ``dMbar/dt V`` is taken along the logged hitch angles, so that the
momentum and the velocity stay one another's through the model's ``Mbar``.

A payload (``--payload K``): a mass put on trailer K's bed at some time of the log, its yaw
inertia in the bed's proportion (``Ird / Mr``, as the run's ``payload`` fault puts one). Its
time is where adding it explains the log best (a score test of every candidate time against the
fit without it, :data:`PAYLOAD_STEP_S` apart, then every grid step around the best); its mass is
then fitted with the rest.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from tt_mujoco.vehicle.params import Params
from tt_mujoco.vehicle.train import TRAILER_ROW, TrainConstants, mass_and_bias_of, train_constants
from tt_mujoco.vehicle_log import (
    NOISY_DB,
    LogError,
    confounded,
    estimates_report,
    input_snr_db,
    noise_std,
)

__all__ = [
    "INERTIAL",
    "InertiaFit",
    "Payload",
    "check_payload",
    "fit_inertia",
    "inertia_keys",
]

#: The tractor's masses and inertias a fit can take (Params fields).
TRACTOR_INERTIAL = ("Mf", "Mw", "Ifd", "Iwd", "Iw")
#: Each trailer's.
TRAILER_INERTIAL = ("Mr", "Mc1", "Mc2", "Ird", "Ic1", "Ic2")
#: Every mass and inertia a fit can take.
INERTIAL = TRACTOR_INERTIAL + TRAILER_INERTIAL
#: The length (s) of the segments the log is cut into, each simulated from its own first
#: velocity: long enough that the torques move V well beyond its noise, short enough that the
#: model's small errors (a tyre's creep) do not add up.
SEGMENT_S = 2.0
#: The simulation's step at most (s); the logged V is averaged over each step.
GRID_S = 0.01
#: The window (s) of the local cubic fit noisy hitch angles are smoothed with (below
#: :data:`tt_mujoco.vehicle_log.NOISY_DB`): they enter the model, where their noise biases the
#: masses (errors in the variables), not what the model is compared with.
PHI_WINDOW_S = 0.5
#: An estimate whose 95 % half width is beyond this fraction of it is not told by the log: it
#: is reported, and the vehicle keeps its given value.
TOLD_WITHIN = 0.5
#: Candidate payload times are this far apart (s) before the search narrows to the grid.
PAYLOAD_STEP_S = 0.5


def inertia_keys(p: Params, fit) -> tuple[list, list[str], np.ndarray]:
    """The ``(unit, field)`` keys (unit 0 the tractor, k trailer k), names (``Mr``, or ``Mr_2``
    in a train) and values in ``p`` of the masses and inertias ``fit`` names."""
    n = p.n_trailers
    keys = [(0, f) for f in fit if f in TRACTOR_INERTIAL]
    keys += [(k, f) for k in range(1, n + 1) for f in fit if f in TRAILER_INERTIAL]
    names = [f if k == 0 or n == 1 else f"{f}_{k}" for k, f in keys]
    values = [getattr(p if k == 0 else p.trailers[k - 1], f) for k, f in keys]
    return keys, names, np.array(values, dtype=float)


def _constants(c: TrainConstants, values: dict) -> TrainConstants:
    """``c`` with its masses and inertias from ``values`` (``(unit, field) -> value``), every
    other one 0; the geometry kept."""
    tractor = {f: float(values.get((0, f), 0.0)) for f in TRACTOR_INERTIAL}
    rows = tuple(
        tuple(
            float(values.get((k, name), 0.0)) if name in TRAILER_INERTIAL else value
            for name, value in zip(TRAILER_ROW, row, strict=True)
        )
        for k, row in enumerate(c.trailers, 1)
    )
    return c._replace(**tractor, trailers=rows)


def _all_values(p: Params) -> dict:
    values = {(0, f): getattr(p, f) for f in TRACTOR_INERTIAL}
    for k, trailer in enumerate(p.trailers, 1):
        values.update({(k, f): getattr(trailer, f) for f in TRAILER_INERTIAL})
    return values


def _coefficients(phis: np.ndarray, constants: list) -> tuple[np.ndarray, np.ndarray]:
    """For each of ``constants`` and each row of ``phis``: ``Mbar`` as ``(M11, M12, M22)`` and
    ``-Cbar(phi, V) V`` as the quadratic forms ``V^T Q V`` of its two components, ``Q`` as
    ``(q11, q12, q22)``: shapes ``(J, rows, 3)`` and ``(J, rows, 2, 3)``."""
    rows = [[float(x) for x in row] for row in phis]
    mass = np.zeros((len(constants), len(rows), 3))
    quad = np.zeros((len(constants), len(rows), 2, 3))
    out = [[0.0, 0.0, 0.0] for _ in range(phis.shape[1])]
    for j, c in enumerate(constants):
        for i, phi in enumerate(rows):
            ok, m, (a1, a2) = mass_and_bias_of(phi, 1.0, 0.0, c, out)
            _, _, (d1, d2) = mass_and_bias_of(phi, 0.0, 1.0, c, out)
            _, _, (s1, s2) = mass_and_bias_of(phi, 1.0, 1.0, c, out)
            if not ok:
                raise LogError(f"the log's hitch angles {phi} reach the train's singularity")
            mass[j, i] = m
            # V^T Q V at e1, e2 and e1 + e2 give q11, q22 and q11 + 2 q12 + q22
            quad[j, i, 0] = (-a1, -(s1 - a1 - d1) / 2.0, -d1)
            quad[j, i, 1] = (-a2, -(s2 - a2 - d2) / 2.0, -d2)
    return mass, quad


def _smooth_angles(phis: np.ndarray, period: float) -> np.ndarray:
    """Each hitch angle smoothed by a local cubic over :data:`PHI_WINDOW_S` (Savitzky and
    Golay's filter: a hitch angle turns over seconds, so the cubic follows it unbiased)."""
    from scipy.signal import savgol_filter

    width = 2 * int(PHI_WINDOW_S / period / 2.0) + 1
    if width <= 5:
        return phis
    return savgol_filter(phis, width, 3, axis=0, mode="interp")


def _averaged(x: np.ndarray, centres: np.ndarray, half: int) -> np.ndarray:
    """``x`` averaged over the ``2 half + 1`` samples around each of ``centres`` (fewer at the
    log's ends)."""
    total = np.concatenate([[0.0], np.cumsum(x)])
    lo = np.maximum(centres - half, 0)
    hi = np.minimum(centres + half + 1, x.size)
    return (total[hi] - total[lo]) / (hi - lo)


@dataclasses.dataclass(frozen=True)
class Payload:
    """A payload found in a log: on ``trailer``, from ``time`` (s, to ``time_step_s``; the
    times the log does not tell from it at a nominal 95 %, ``time_interval``: measured, it is
    too narrow, docs/identify.md), of ``mass`` (kg) with its 95 % half width."""

    trailer: int
    time: float
    time_step_s: float
    time_interval: tuple
    mass: float
    mass_half_width: float

    @property
    def found(self) -> bool:
        """Whether the log shows one: its mass's 95 % interval leaves out 0 (a negative mass is
        a load taken off)."""
        return abs(self.mass) > self.mass_half_width


@dataclasses.dataclass(frozen=True)
class InertiaFit:
    """A fit's estimates, their 95 % half widths and correlations, the fitted train, the rms of
    the simulated ``v`` and ``omega`` against the log, and the payload found (or None)."""

    names: tuple
    #: The Params fields fitted (``Mr`` for ``Mr_1`` and ``Mr_2``), each once.
    fields: tuple
    estimates: np.ndarray
    half_widths: np.ndarray
    correlation: np.ndarray
    params: Params
    output_rms: tuple
    segments: int
    payload: Payload | None = None
    #: What the report draws: the grid's times, the log's ``(v, omega)`` averaged on it and
    #: the fitted train's simulated from each segment's start (segments, steps[, 2]).
    simulated: tuple | None = dataclasses.field(default=None, compare=False, repr=False)

    def confounded(self) -> list[tuple[str, str, float]]:
        """The pairs this log does not tell apart: ``(a, b, correlation)``."""
        return confounded(self.names, self.correlation)

    @property
    def told(self) -> np.ndarray:
        """Whether the log tells each estimate (:func:`_told`)."""
        return _told(self.estimates, self.half_widths)

    def markdown(self, log, title: bool) -> str:
        """The fit as a Markdown section (under a title naming ``log`` where ``title``)."""
        lines = [f"# Identified from {log}", ""] if title else [""]
        lines += ["| mass or inertia | estimate | 95 % interval |", "|---|---|---|"]
        rows = zip(self.names, self.estimates, self.half_widths, self.told, strict=True)
        for n, e, h, told in rows:
            kept = "" if told else " (not told by this log: the vehicle keeps its given value)"
            lines.append(f"| {n} | {e:.6g} | {e - h:.6g} .. {e + h:.6g}{kept} |")
        v_rms, omega_rms = self.output_rms
        lines += [
            "",
            f"Simulated from the torques over {self.segments} segments: v {v_rms:.3g} m/s rms "
            f"and omega {omega_rms:.3g} rad/s rms from the log.",
        ]
        if self.payload is not None:
            load = self.payload
            within = (
                f"{load.mass:.4g} kg, 95 % interval {load.mass - load.mass_half_width:.4g} .. "
                f"{load.mass + load.mass_half_width:.4g} kg"
            )
            low, high = load.time_interval
            lines.append(
                f"A payload on trailer {load.trailer} from t = {load.time:.2f} s (not told from "
                f"{low:.2f} .. {high:.2f} s): {within}."
                if load.found
                else f"No payload on trailer {load.trailer}: the likeliest step ({within}, at "
                f"t = {load.time:.2f} s) is within its interval of none."
            )
        for a, b, rho in self.confounded():
            lines.append(
                f"- {a} and {b} are not told apart by this log (correlation {rho:+.3f}): fix "
                "one of them (--fit), or log a run whose speed and turning vary apart."
            )
        return "\n".join(lines) + "\n"

    def report(self) -> dict:
        """The fit as strict-JSON-ready numbers."""
        out = {
            **estimates_report(self.names, self.estimates, self.half_widths, self.correlation),
            "not_told": [n for n, told in zip(self.names, self.told, strict=True) if not told],
            "simulated_rms": {"v": self.output_rms[0], "omega": self.output_rms[1]},
            "segments": self.segments,
        }
        if self.payload is not None:
            out["payload"] = {**dataclasses.asdict(self.payload), "found": self.payload.found}
        return out


class _Log:
    """What the fit compares: the log on the simulation's grid, cut into segments, and the
    model's terms along it."""

    def __init__(self, t, v, omega, phis, torques, p: Params, keys, extra=()):
        period = float(np.median(np.diff(t)))
        step = max(1, int(round(GRID_S / period)))
        grid = np.arange(0, t.size, step)
        per_segment = int(round(SEGMENT_S / (step * period)))
        self.segments = grid.size // per_segment
        if self.segments < 2:
            raise LogError(
                f"the log is {t[-1] - t[0]:.3g} s long: fitting masses takes at least two "
                f"segments of {SEGMENT_S:g} s"
            )
        grid = grid[: self.segments * per_segment]
        self.t = t[grid]
        self.lanes = np.arange(grid.size).reshape(self.segments, per_segment)
        self.dt = np.diff(self.t)
        c = train_constants(p)
        if min(input_snr_db(phi) for phi in phis.T) < NOISY_DB:
            phis = _smooth_angles(phis, period)
        known = {key: value for key, value in _all_values(p).items() if key not in keys}
        constants = [_constants(c, {key: 1.0}) for key in keys]
        constants += [_constants(c, values) for values in extra] + [_constants(c, known)]
        self.mass, self.quad = _coefficients(phis[grid], constants)
        T_r, T_l = torques
        force = np.column_stack([(T_r + T_l) / p.r, p.d * (T_r - T_l) / (2.0 * p.r)])
        impulse = np.vstack([[0.0, 0.0], np.cumsum(force[:-1] * np.diff(t)[:, None], axis=0)])
        self.impulse = np.diff(impulse[grid], axis=0)  # each held torque over its rows
        half = step // 2
        self.V = np.column_stack([_averaged(x, grid, half) for x in (v, omega)])
        noise = np.array([noise_std(x) for x in (v, omega)]) / math.sqrt(2 * half + 1)
        spread = np.sqrt(np.mean(self.V**2, axis=0))
        scale = np.maximum(noise, 1e-3 * spread)
        scale[scale == 0.0] = 1.0  # a channel that never moves (no turn: omega 0) tells nothing
        self.weight = 1.0 / scale

    def simulate(self, x: np.ndarray, starts: np.ndarray, payload=None) -> np.ndarray:
        """``V`` of every segment (``(segments, rows, 2)``) from its first velocity ``starts``
        with the masses and inertias ``x`` (and ``payload``, ``(mass, on)``: that mass where the
        grid mask ``on`` is true). Heun's steps on the momentum; a torque's impulse exact."""
        weights = np.ones((self.mass.shape[0], self.t.size))
        weights[: x.size] = np.asarray(x)[:, None]
        if self.mass.shape[0] > x.size + 1:  # the payload's terms, before the known ones
            weights[x.size] = 0.0 if payload is None else np.where(payload[1], payload[0], 0.0)
        mass = np.einsum("jn,jnk->nk", weights, self.mass)
        quad = np.einsum("jn,jnck->nck", weights, self.quad)
        out = np.empty((*self.lanes.shape, 2))
        starts = np.ascontiguousarray(starts, dtype=float).reshape(-1, 2)
        _heun()(mass, quad, self.impulse, self.dt, self.lanes, starts, out)
        return out

    def residuals(self, simulated: np.ndarray) -> np.ndarray:
        return ((simulated - self.V[self.lanes]) * self.weight).ravel()


def heun_lanes(mass, quad, impulse, dt, lanes, starts, out) -> None:
    """Every segment's ``V`` into ``out`` (segments, rows, 2) from its first velocity
    ``starts[s]``: Heun's steps on the momentum ``p = Mbar V`` over the grid rows ``lanes[s]``,
    ``Mbar`` as ``mass`` rows ``(M11, M12, M22)``, ``-Cbar V`` as the quadratic forms ``quad``
    rows ``((q11, q12, q22), (...))``, each step's torque impulse exact and ``dMbar V`` taken
    along the grid (plain numbers: numba compiles it, :func:`_heun`)."""
    for s in range(lanes.shape[0]):
        v, w = starts[s, 0], starts[s, 1]
        i = lanes[s, 0]
        p1 = mass[i, 0] * v + mass[i, 1] * w
        p2 = mass[i, 1] * v + mass[i, 2] * w
        out[s, 0, 0], out[s, 0, 1] = v, w
        for k in range(lanes.shape[1] - 1):
            i, j = lanes[s, k], lanes[s, k + 1]
            h = dt[i]
            d11, d12, d22 = (
                mass[j, 0] - mass[i, 0],
                mass[j, 1] - mass[i, 1],
                mass[j, 2] - mass[i, 2],
            )
            f1 = quad[i, 0, 0] * v * v + 2.0 * quad[i, 0, 1] * v * w + quad[i, 0, 2] * w * w
            f2 = quad[i, 1, 0] * v * v + 2.0 * quad[i, 1, 1] * v * w + quad[i, 1, 2] * w * w
            det = mass[j, 0] * mass[j, 2] - mass[j, 1] * mass[j, 1]
            g1 = p1 + impulse[i, 0] + h * f1 + d11 * v + d12 * w
            g2 = p2 + impulse[i, 1] + h * f2 + d12 * v + d22 * w
            gv = (mass[j, 2] * g1 - mass[j, 1] * g2) / det
            gw = (mass[j, 0] * g2 - mass[j, 1] * g1) / det
            e1 = quad[j, 0, 0] * gv * gv + 2.0 * quad[j, 0, 1] * gv * gw + quad[j, 0, 2] * gw * gw
            e2 = quad[j, 1, 0] * gv * gv + 2.0 * quad[j, 1, 1] * gv * gw + quad[j, 1, 2] * gw * gw
            mv, mw = 0.5 * (v + gv), 0.5 * (w + gw)
            p1 += impulse[i, 0] + 0.5 * h * (f1 + e1) + d11 * mv + d12 * mw
            p2 += impulse[i, 1] + 0.5 * h * (f2 + e2) + d12 * mv + d22 * mw
            v = (mass[j, 2] * p1 - mass[j, 1] * p2) / det
            w = (mass[j, 0] * p2 - mass[j, 1] * p1) / det
            out[s, k + 1, 0], out[s, k + 1, 1] = v, w


_COMPILED = []


def _heun():
    """:func:`heun_lanes` compiled (once per process; numba caches it on disk)."""
    if not _COMPILED:
        from numba import njit

        _COMPILED.append(njit(cache=True)(heun_lanes))
    return _COMPILED[0]


def _told(estimates: np.ndarray, half_widths: np.ndarray) -> np.ndarray:
    """Whether the log tells each estimate: its 95 % interval within :data:`TOLD_WITHIN` of it
    (a log that does not excite it leaves it anywhere)."""
    return half_widths < TOLD_WITHIN * np.abs(estimates)


#: How far (m/s, rad/s) the fit may miss a channel the log never moves.
FLAT_MISS = 1e-3


def check_payload(trailer: int, trailers: int) -> None:
    """Raise a :class:`LogError` unless ``trailer`` is one of the train's ``trailers``."""
    if not 1 <= trailer <= trailers:
        raise LogError(f"--payload {trailer} is not allowed: the train has trailers 1..{trailers}")


def fit_inertia(t, v, omega, phis, torques, p: Params, fit=("Mr",), payload=None) -> InertiaFit:
    """Fit the masses and inertias ``fit`` names (of :data:`INERTIAL`, every trailer's) of
    train ``p`` (the others known as ``p`` has them, and the guess) to a log's ``t``, ``v``,
    ``omega``, hitch angles ``phis`` (rows, N) and wheel ``torques`` ``(T_r, T_l)`` (see the
    module). ``payload``: the trailer (1..N) a payload was put on at some time of the log, to
    be found; None: no payload.

    Raises
    ------
    LogError
        A parameter that is not a mass or inertia, a payload on no trailer of the train, a log
        too short, or one that reaches the train's singularity.
    """
    unknown = [name for name in fit if name not in INERTIAL]
    if unknown:
        raise LogError(f"{unknown[0]!r} is not a mass or inertia: choose from {INERTIAL}")
    keys, names, x0 = inertia_keys(p, fit)
    if not keys and payload is None:
        raise LogError("nothing to fit: name a mass or inertia, or look for a payload")
    bed = None
    if payload is not None:
        check_payload(payload, p.n_trailers)
        bed = p.trailers[payload - 1]
    # a payload's mass per kg: on the bed at P0, its yaw inertia in the bed's proportion
    extra = [] if bed is None else [{(payload, "Mr"): 1.0, (payload, "Ird"): bed.Ird / bed.Mr}]
    log = _Log(t, v, omega, phis, torques, p, keys, extra)
    x, starts, jac, residuals = _least_squares(log, x0)
    found = None
    if bed is not None:
        found = _payload_time(log, x, starts, jac, residuals, 0.01 * bed.Mr)
        x, starts, jac, residuals = _least_squares(log, np.append(x, 0.0), log.t >= found)
        for _ in range(3):  # the score test's time, moved while a closer one fits better
            profile = _time_profile(log, x, starts, jac, found)
            better = float(profile[0][int(np.argmin(profile[1]))])
            if better == found:
                break
            found = better
            x, starts, jac, residuals = _least_squares(log, x, log.t >= found)
        else:  # moved at every turn: the profile of the last fit
            profile = _time_profile(log, x, starts, jac, found)
    covariance, correlation, inflation = _statistics(log, jac, residuals, x.size)
    half = 1.96 * np.sqrt(np.diag(covariance))
    mass = None
    if found is not None:
        within = _time_interval(profile, jac, residuals, float(inflation[-1]))
        step = float(np.median(log.dt))
        mass = Payload(payload, float(found), step, within, float(x[-1]), float(half[-1]))
        x, half, correlation = x[:-1], half[:-1], correlation[:-1, :-1]
    on = None if mass is None else (mass.mass, log.t >= found)
    simulated = log.simulate(x, starts, on)
    error = simulated - log.V[log.lanes]
    missed = np.sqrt(np.mean(error**2, axis=(0, 1)))
    spread = np.sqrt(np.mean(log.V**2, axis=0))
    # the model explains less of V than V's own size (a channel the log never moves, omega
    # on a straight, is missed only beyond a rounding's worth)
    if np.any(np.where(spread > 0.0, missed > spread, missed > FLAT_MISS)):
        raise LogError(
            f"the fitted model misses the log's v by {missed[0]:.3g} m/s rms and its omega by "
            f"{missed[1]:.3g} rad/s (their own rms: {spread[0]:.3g}, {spread[1]:.3g}): are the "
            "torques the wheels' in N m (T_r, T_l), and the vehicle's masses near the given ones?"
        )
    told = _told(x, half)  # the others stay as given
    return InertiaFit(
        tuple(names),
        tuple(dict.fromkeys(field for _, field in keys)),
        x,
        half,
        correlation,
        _with(p, {key: value for key, value, ok in zip(keys, x, told, strict=True) if ok}),
        tuple(float(m) for m in missed),
        log.segments,
        mass,
        (log.t[log.lanes], log.V[log.lanes], simulated),
    )


def _least_squares(log: _Log, x0: np.ndarray, on=None):
    """The fit of ``x`` (from ``x0``; its last the payload's mass where ``on``, a mask of the
    grid, is given) and every segment's first velocity: the estimates, the first velocities,
    the Jacobian and the residuals there."""
    from scipy.optimize import least_squares

    count = x0.size

    def residuals(z):
        x, starts = z[:count], z[count:]
        if on is None:
            return log.residuals(log.simulate(x, starts))
        return log.residuals(log.simulate(x[:-1], starts, (x[-1], on)))

    def jacobian(z):
        """Forward differences: one simulation per parameter, and one for every segment's
        first v (and one for its omega) at once, each segment's rows depending on its own."""
        base = residuals(z)
        jac = np.zeros((base.size, z.size))
        steps = 1e-6 * np.maximum(np.abs(z), 1e-3)
        for i in range(count):
            moved = z.copy()
            moved[i] += steps[i]
            jac[:, i] = (residuals(moved) - base) / steps[i]
        rows = log.lanes.shape[1] * 2
        for channel in (0, 1):
            moved = z.copy()
            moved[count + channel :: 2] += steps[count + channel :: 2]
            slope = (residuals(moved) - base).reshape(-1, rows)
            for s in range(log.lanes.shape[0]):
                column = count + 2 * s + channel
                jac[s * rows : (s + 1) * rows, column] = slope[s] / steps[column]
        return jac

    z0 = np.concatenate([x0, log.V[log.lanes[:, 0]].ravel()])
    with np.errstate(all="ignore"):  # a trial step may leave every vehicle: its residuals say
        start = residuals(z0)
        if np.all(np.isfinite(start)):
            result = least_squares(residuals, z0, jac=jacobian, x_scale="jac", method="lm")
    if not np.all(np.isfinite(start)) or not np.all(np.isfinite(result.fun)):
        raise LogError(
            "the model's velocities run away under the log's torques: are the torques the "
            "wheels' in N m (T_r, T_l), and the vehicle's masses near the given ones?"
        )
    return result.x[:count], result.x[count:], jacobian(result.x), result.fun


def _statistics(log: _Log, jac, residuals, count: int):
    """The first ``count`` estimates' covariance (the wider of the plain and the
    segment-clustered one: the residuals within a segment are not independent where the model
    is not the vehicle), their correlations (the design's alone) and each variance over the
    plain one."""
    try:
        bread = np.linalg.inv(jac.T @ jac)
    except np.linalg.LinAlgError:
        bread = np.full((jac.shape[1],) * 2, np.inf)
    dof = max(residuals.size - jac.shape[1], 1)
    plain = bread * float(residuals @ residuals) / dof
    segments = log.lanes.shape[0]
    clusters = np.repeat(np.arange(segments), log.lanes.shape[1] * 2)
    scores = np.zeros((segments, jac.shape[1]))
    np.add.at(scores, clusters, jac * residuals[:, None])
    clustered = bread @ (scores.T @ scores) @ bread * segments / max(segments - 1, 1)
    variance = np.maximum(np.diag(plain), np.diag(clustered))[:count]
    block = bread[:count, :count]
    with np.errstate(invalid="ignore", divide="ignore"):
        scale = np.sqrt(np.abs(np.diag(block)))
        correlation = block / np.outer(scale, scale)
        inflation = variance / np.diag(plain)[:count]
    return np.diag(variance), correlation, inflation


def _payload_time(log: _Log, x, starts, jac, residuals, probe: float) -> float:
    """The time a payload explains the log best: the score test of a payload (``probe`` kg,
    a small step for its residuals' slope) from each candidate time against the fit without
    one (``x``, ``starts``, its Jacobian and residuals), :data:`PAYLOAD_STEP_S` apart from a
    segment after the start to a segment before the end, then every grid step around the
    best."""
    basis, _ = np.linalg.qr(jac)
    residuals = residuals - basis @ (basis.T @ residuals)
    base = log.residuals(log.simulate(x, starts))

    def score(at: float) -> float:
        slope = (log.residuals(log.simulate(x, starts, (probe, log.t >= at))) - base) / probe
        rest = float(slope @ slope) - float(np.sum((basis.T @ slope) ** 2))
        return float(slope @ residuals) ** 2 / rest if rest > 0.0 else 0.0

    first, last = log.t[0] + SEGMENT_S, log.t[-1] - SEGMENT_S
    coarse = np.arange(first, last, PAYLOAD_STEP_S)
    if coarse.size == 0:
        raise LogError(f"the log is too short to find a payload in (at least {3 * SEGMENT_S:g} s)")
    best = coarse[int(np.argmax([score(at) for at in coarse]))]
    near = log.t[(log.t >= best - PAYLOAD_STEP_S) & (log.t <= best + PAYLOAD_STEP_S)]
    return float(near[int(np.argmax([score(at) for at in near]))])


def _time_profile(log: _Log, x, starts, jac, found: float):
    """The payload's candidate times near ``found`` and what each leaves of the least squares:
    the fit with the payload (``x``, its mass last, ``starts``, its Jacobian) moved to each
    grid time within a segment, after one Gauss-Newton step of every parameter (the score test
    judged a payload of none; a real one is not small). Not within a segment of either end of
    the log: a payload there is a mass of the bed (``--fit Mr``)."""
    basis, _ = np.linalg.qr(jac)
    first, last = log.t[0] + SEGMENT_S, log.t[-1] - SEGMENT_S  # as the score test's
    near = log.t[(log.t >= max(found - SEGMENT_S, first)) & (log.t <= min(found + SEGMENT_S, last))]

    def left(at: float) -> float:
        r = log.residuals(log.simulate(x[:-1], starts, (x[-1], log.t >= at)))
        return float(np.sum((r - basis @ (basis.T @ r)) ** 2))

    return near, np.array([left(at) for at in near])


def _time_interval(profile, jac, residuals, inflation: float) -> tuple[float, float]:
    """The payload times the log does not tell from the best at 95 %: where the ``profile``
    (:func:`_time_profile` of the fit with the payload, ``jac`` and ``residuals`` its own)
    stays within 3.84 residual variances of its least, the variance ``inflation`` times the
    plain one (the clustered intervals' ratio: residuals within a segment are not
    independent). Reaching an end of the profile's window, the interval is at least that
    wide."""
    times, left = profile
    variance = float(residuals @ residuals) / max(residuals.size - jac.shape[1], 1)
    inside = times[left <= left.min() + 3.84 * variance * max(inflation, 1.0)]
    return float(inside.min()), float(inside.max())


def _with(p: Params, values: dict) -> Params:
    """``p`` with the masses and inertias ``values`` (``(unit, field) -> value``):
    :meth:`~tt_mujoco.vehicle.params.Params.with_unit_fields`."""
    try:
        return p.with_unit_fields(values)
    except ValueError as err:
        raise LogError(f"the fit leads to no vehicle ({err})") from None

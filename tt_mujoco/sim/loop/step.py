"""The closed-loop step's own arithmetic, written once for both loops.

The closed loop's step (:mod:`tt_mujoco.sim.loop.closed_loop`: sense, noise, target, law,
saturation, disturbance, log, advance), which CPython runs and numba compiles, calls these
plain-number functions for every check and clip in it. They take and return plain floats
(numba compiles them from this source, :mod:`tt_mujoco.sim.loop.kernel_sources`).
"""

from __future__ import annotations

import math

from tt_mujoco.sim.parts.measure import ROW_BETA, ROW_PHI
from tt_mujoco.vehicle.reduced import COS_BETA_MIN

__all__ = [
    "BLEW_UP",
    "COLLISION",
    "FINISHED",
    "JACKKNIFE",
    "LAW_FAILED",
    "PAYLOAD",
    "RAISED",
    "RUNNING",
    "SINGULAR",
    "WARNING",
    "clip",
    "clip_pair",
    "hitch_stop",
    "noisy",
    "stop_code",
]

#: How a stretch of steps ended: still running, the episode's end, or why it stopped; or
#: PAYLOAD: the reduced plant's constants change before this step's advance (a payload fault),
#: which the caller applies before it advances the step and goes on; or RAISED: Python code the
#: kernel called back raised (``stop.raised``), which the kernel's caller raises; or
#: COLLISION: a unit touched an obstacle of the world (:mod:`tt_mujoco.world.contact`).
RUNNING, FINISHED, BLEW_UP, JACKKNIFE, WARNING, LAW_FAILED, SINGULAR, PAYLOAD, RAISED = range(9)
COLLISION = 9


def stop_code(x: float, v: float, omega: float, phi: float, beta: float, limits) -> int:
    """:data:`BLEW_UP` when the state is not finite or faster than ``limits.max_speed``,
    :data:`JACKKNIFE` when a hitch reached ``limits.jackknife_phi`` or its axle
    ``limits.jackknife_beta`` (rad), else :data:`RUNNING`."""
    if not (math.isfinite(x) and math.isfinite(v) and math.isfinite(omega)):
        return BLEW_UP
    if abs(v) > limits.max_speed:
        return BLEW_UP
    if abs(phi) >= limits.jackknife_phi or abs(beta) >= limits.jackknife_beta:
        return JACKKNIFE
    return RUNNING


def hitch_stop(rows, hitch_limits, jackknife_beta: float) -> int:
    """The index of the first trailer k >= 2 (row ``k - 2`` of ``rows``, with ``phi_k`` and
    ``beta_k`` in its columns ``ROW_PHI`` and ``ROW_BETA``) whose hitch reached its limit
    ``hitch_limits[k - 2]`` or whose axle reached ``jackknife_beta`` (rad), or -1."""
    for i in range(len(rows)):
        row = rows[i]
        if abs(row[ROW_PHI]) >= hitch_limits[i] or abs(row[ROW_BETA]) >= jackknife_beta:
            return i
    return -1


def noisy(value: float, std: float, noise, index: int) -> float:
    """``value`` plus ``std`` times the episode's ``index``-th standard normal draw."""
    return value + std * noise[index]


def clip(value: float, limit: float) -> float:
    """``value`` held within ``[-limit, limit]``."""
    return -limit if value < -limit else (limit if value > limit else value)


def first_singular_of(phis, c, stop) -> None:
    """The first trailer of the train ``c`` at cos(eta_k phi_k) < COS_BETA_MIN (the model's
    singularity) into ``stop`` (phi, eta)."""
    for k in range(len(c.trailers)):
        eta = c.trailers[k][2]
        if math.cos(eta * phis[k]) < COS_BETA_MIN:
            stop.phi, stop.eta = phis[k], eta
            return


def clip_pair(first: float, second: float, bound: float) -> tuple[float, float, float]:
    """Both values held within ``[-bound, bound]``, and 1.0 if either was clipped (else 0.0)."""
    if abs(first) > bound or abs(second) > bound:
        return max(-bound, min(bound, first)), max(-bound, min(bound, second)), 1.0
    return first, second, 0.0

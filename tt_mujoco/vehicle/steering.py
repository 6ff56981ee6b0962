"""Passive trailer steering beyond a constant gear: exact same-path gains and off-tracking
measures (docs/model.md Section 3).

The trailer axle is steered by ``beta = eta * phi`` (paper eq. 2). Three facts drive this module:

- **Exact same-path gain.** In a steady turn of radius R every body rotates about one centre C.
  The trailer axle midpoint P0 lies on the tractor's own path when ``|C P0| = R``; with the hitch
  O at ``|C O| = sqrt(R^2 + L^2)`` and ``|O P0| = L0`` this fixes the articulation,
  ``2 L0 (R sin(phi) - L cos(phi)) = L^2 + L0^2`` (law of cosines in the triangle C, O, P0),
  and the rolling direction of P0 (perpendicular to C P0) fixes beta. ``eta = beta / phi`` is then
  the gain that holds P0 on the path at curvature 1/R: :func:`exact_same_path_eta`.
- **Its small-curvature limit is (L - L0) / (L + L0)** = -1/7 = -0.1429 for the paper's L = 0.3 m,
  L0 = 0.4 m, not the half-difference gain ``-(L0 - L) / (2 L0)`` = -0.125, which leaves an
  off-tracking proportional to kappa (docs/model.md Section 3, ``tests/test_reduced.py``); the
  project's ``same_path`` preset uses this limit.
  Linearising gives ``phi = kappa (L + L0) / (1 - eta)`` from the kinematics (paper eq. 13 at
  phi_dot = 0) and ``phi = kappa (L + L0)^2 / (2 L0)`` from the geometry; equating them gives
  ``1 - eta = 2 L0 / (L + L0)``. With eta = -0.125 the steady off-tracking at R = 1.5 m is
  -2.87 mm (the -2.9 mm first predicted for it); with -1/7 it is -0.27 mm, and with the exact
  eta(1/R) zero
  (``tests/test_steering.py`` checks all three against the reduced kinematics).
- **eta > 1 is stable only in reverse** (docs/model.md Section 3):
  :class:`tt_mujoco.reference.reverse.ReverseTarget` drives a path backwards, trailer first, so
  that the paper's eta = 3 can be shown doing what it is good at.

:class:`tt_mujoco.sim.parts.schedule.EtaScheduler` applies the exact gain of the local curvature
to a
running plant.
"""

from __future__ import annotations

import math

import numpy as np

from tt_mujoco.exact import hypot_of
from tt_mujoco.vehicle.params import (
    Params,
    same_path_eta,
    train_same_path_etas_of,
)
from tt_mujoco.vehicle.reduced import phi_rate_of

__all__ = [
    "exact_same_path_eta",
    "exact_train_same_path_etas",
    "followed_gain_of",
    "followed_gains_of",
    "same_path_eta_limit",
    "steady_articulation",
    "steady_offtrack",
    "steady_train",
    "trailer_followed_gain_of",
    "wrap_angle",
]

#: Below this |kappa| (1/m) the exact gain is its limit (the error is O(kappa^2), < 1e-12 here).
_KAPPA_TINY = 1e-6
#: The scheduler re-applies eta only when it moved by more than this. The constraint then lags the
#: schedule by at most 1e-5 * |phi| < 1e-5 rad, below MuJoCo's own equality violation (~3e-5 rad,
#: docs/model.md Section 5), and the reduced plant rebuilds its Params only when needed.
SCHEDULE_TOLERANCE = 1e-5


def same_path_eta_limit(L: float, L0: float) -> float:
    """The exact same-path gain for gentle turns: ``(L - L0) / (L + L0)`` (see module docstring).

    -1/7 for the paper's L = 0.3 m, L0 = 0.4 m (Section 6.1). The ``same_path`` preset.
    """
    return same_path_eta(L, L0)


def _same_path_geometry(kappa: float, L: float, L0: float) -> tuple[float, float]:
    """``(phi, beta)`` of the steady turn at |kappa| in which P0 runs on the tractor's path."""
    phi, beta = same_path_geometry_of(kappa, L, L0)
    if math.isnan(phi):
        R = 1.0 / abs(kappa)
        r_min = math.sqrt(max(((L * L + L0 * L0) / (2.0 * L0)) ** 2 - L * L, 0.0))
        raise ValueError(
            f"kappa={kappa!r} is not allowed: no trailer pose puts P0 on a path of radius "
            f"{R:.4g} m (it needs R >= {r_min:.4g} m)"
        )
    return phi, beta


def same_path_geometry_of(kappa: float, L: float, L0: float) -> tuple[float, float]:
    """``(phi, beta)`` of the steady turn at |kappa| (> 0) in which P0 runs on the tractor's
    path; NaNs where no pose does (the compiled episode shares it)."""
    R = 1.0 / abs(kappa)
    hyp = hypot_of(R, L)
    ratio = (L * L + L0 * L0) / (2.0 * L0 * hyp)
    if ratio > 1.0:
        return math.nan, math.nan
    # 2 L0 (R sin(phi) - L cos(phi)) = L^2 + L0^2  <=>  sin(phi - atan2(L, R)) = ratio.
    phi = math.atan2(L, R) + math.asin(ratio)
    # Tractor at P = (R, 0) heading +y, turning about C = 0; O = (R, -L); P0 = O - L0 e(theta0),
    # theta0 = pi/2 - phi. P0 rolls along the tangent of its circle, atan2(P0) + pi/2, so
    # beta = alpha - theta0 = atan2(P0) + phi.
    x0 = R - L0 * math.sin(phi)
    y0 = -L - L0 * math.cos(phi)
    beta = math.atan2(y0, x0) + phi
    return phi, beta


def exact_same_path_eta(kappa: float, L: float, L0: float) -> float:
    """The constant-curvature steering gain that puts P0 exactly on the tractor's path.

    Parameters
    ----------
    kappa : float
        Curvature of the tractor's path (1/m); the gain is even in kappa.
    L, L0 : float
        Link lengths P-O and O-P0 (m).

    Returns
    -------
    float
        ``eta = beta / phi`` of the steady turn with ``|C P0| = R`` (module docstring);
        :func:`same_path_eta_limit` for ``|kappa| < 1e-6``.

    Raises
    ------
    ValueError
        If the curvature is so tight that no such pose exists.
    """
    kappa = float(kappa)
    if not math.isfinite(kappa):
        raise ValueError(f"kappa={kappa!r} is not allowed: it must be finite")
    eta = exact_same_path_eta_of(kappa, L, L0)
    if math.isnan(eta):
        _same_path_geometry(kappa, L, L0)  # says why
    return eta


def exact_same_path_eta_of(kappa: float, L: float, L0: float) -> float:
    """:func:`exact_same_path_eta` in plain numbers, NaN where no pose exists (the compiled
    episode shares it)."""
    if abs(kappa) < _KAPPA_TINY:
        return same_path_eta(L, L0)
    phi, beta = same_path_geometry_of(kappa, L, L0)
    return beta / phi


def steady_offtrack(kappa: float, params: Params) -> float:
    """Analytic steady-state off-tracking (m): P0's turning radius minus the tractor's.

    Negative: P0 runs inside the tractor's path; positive: outside. Uses the steady articulation
    of the kinematics ((:func:`steady_articulation`)), NaN where there is none.
    The
    steady turn is the same in either direction of travel; for eta > 1 it is stable only
    reversing (docs/model.md Section 3).
    """
    kappa = float(kappa)
    if kappa == 0.0:
        return 0.0
    phi = steady_articulation(abs(kappa), params)
    if not math.isfinite(phi):
        return math.nan
    R = 1.0 / abs(kappa)
    # Same frame as _same_path_geometry: P0 = O - L0 e(pi/2 - phi).
    return math.hypot(R - params.L0 * math.sin(phi), -params.L - params.L0 * math.cos(phi)) - R


def steady_articulation(kappa: float, params: Params | None = None) -> float:
    """Steady-state articulation phi (rad) while the tractor turns with constant curvature.

    Solves ``phi_dot = 0`` in docs/model.md Section 2 with ``omega = kappa v``:
    ``sin((eta - 1) phi) + kappa (L0 cos(eta phi) + L cos((eta - 1) phi)) = 0``, taking the
    root that grows continuously from phi = 0 at kappa = 0 and staying where cos(beta) > 0.
    Returns nan if there is none (eta = 1, or the articulation would reach the singularity).
    Used to justify :data:`DEFAULT_MAX_CURVATURE`.
    """
    p = Params() if params is None else params
    eta, L, L0 = p.eta, p.L, p.L0
    kappa = float(kappa)
    if kappa == 0.0:
        return 0.0
    if eta == 1.0:
        return math.nan

    def residual(phi: float) -> float:
        return math.sin((eta - 1.0) * phi) + kappa * (
            L0 * math.cos(eta * phi) + L * math.cos((eta - 1.0) * phi)
        )

    # Near phi = 0 the residual is (eta - 1) phi + kappa (L0 + L): the root's sign follows.
    sign = math.copysign(1.0, -kappa * (eta - 1.0))
    reach = min(math.pi, p.phi_singular * (1.0 - 1e-9))
    grid = np.linspace(0.0, sign * reach, 4001)
    values = [residual(float(g)) for g in grid]
    for i in range(len(grid) - 1):
        if values[i] == 0.0 or values[i] * values[i + 1] < 0.0:
            from scipy.optimize import brentq  # scipy costs a run that never calls this

            return float(brentq(residual, grid[i], grid[i + 1], xtol=1e-13))
    return math.nan


def exact_train_same_path_etas(kappa: float, lengths) -> list[float]:
    """The constant-curvature gains that put every trailer's axle on the tractor's path.

    Parameters
    ----------
    kappa : float
        Curvature of the tractor's path (1/m); the gains are even in kappa.
    lengths : sequence of (L_k, L0_k)
        Trailers 1..N.

    Returns
    -------
    list of float
        ``eta_k = beta_k / phi_k`` of the steady turn in which P_1..P_N all lie on the circle of
        radius R = 1/|kappa| (docs/model.md Section 12): trailer by trailer, O_k is fixed by the
        body in front, P_k is where the circle of radius L0_k about O_k meets the path's circle
        behind O_k, and P_k's rolling direction, the circle's tangent, fixes beta_k. Trailer 1's
        gain is :func:`exact_same_path_eta`. Below |kappa| = 1e-6 the small-curvature limits
        (:func:`tt_mujoco.vehicle.params.train_same_path_etas`).

    Raises
    ------
    ValueError
        If the curvature is so tight that some trailer's axle cannot reach the path.
    """
    kappa = float(kappa)
    if not math.isfinite(kappa):
        raise ValueError(f"kappa={kappa!r} is not allowed: it must be finite")
    lengths = [(float(L), float(L0)) for L, L0 in lengths]
    etas = [0.0] * len(lengths)
    k = exact_train_same_path_etas_of(kappa, lengths, etas)
    if k:
        raise ValueError(
            f"kappa={kappa!r} is not allowed: trailer {k}'s axle cannot reach a path of "
            f"radius {1.0 / abs(kappa):.4g} m"
        )
    return etas


def exact_train_same_path_etas_of(kappa: float, lengths, out) -> int:
    """:func:`exact_train_same_path_etas` of ``lengths`` (N rows of L_k, L0_k) into ``out``;
    0, or the first trailer (from 1) whose axle cannot reach the path (the compiled episode
    shares it)."""
    if abs(kappa) < _KAPPA_TINY:
        train_same_path_etas_of(lengths, out)
        return 0
    R = 1.0 / abs(kappa)
    # Turning left about C = 0: the tractor's P at (R, 0) heading +y.
    fx, fy, fth = R, 0.0, 0.5 * math.pi
    for k in range(len(lengths)):
        L, L0 = lengths[k][0], lengths[k][1]
        ox, oy = fx - L * math.cos(fth), fy - L * math.sin(fth)
        dist = hypot_of(ox, oy)
        a = (R * R - L0 * L0 + dist * dist) / (2.0 * dist)
        if R * R - a * a < 0.0:
            return k + 1
        h = math.sqrt(R * R - a * a)
        ux, uy = ox / dist, oy / dist
        # The meeting point behind O (clockwise from it, as the train turns left).
        px, py = a * ux + h * uy, a * uy - h * ux
        thk = math.atan2(oy - py, ox - px)
        alpha = math.atan2(py, px) + 0.5 * math.pi
        phi = wrap_angle(fth - thk)
        beta = wrap_angle(alpha - thk)
        out[k] = beta / phi
        fx, fy, fth = px, py, thk
    return 0


def followed_gain_of(eta: float, phi_rate: float, slew_rate: float) -> float:
    """The gain an actuated axle follows at hitch rate ``phi_rate`` (rad/s): ``eta`` while the
    steering it asks for turns no faster than the axle can, ``|eta phi_rate| <= slew_rate``;
    else the share of it the axle gives, ``eta slew_rate / |eta phi_rate|`` (docs/model.md
    Section 13: what the controllers' model takes under the path schedule). Plain numbers (the
    compiled episode shares it)."""
    need = abs(eta * phi_rate)
    if need <= slew_rate:
        return eta
    return eta * (slew_rate / need)


def trailer_followed_gain_of(
    phi: float, v: float, omega: float, eta: float, L: float, L0: float, slew_rate: float
) -> float:
    """:func:`followed_gain_of` of one trailer (hitch ``phi``, gain ``eta``, lengths ``L``,
    ``L0``) at its hitch rate with the tractor at ``(v, omega)`` (paper eq. 13,
    :func:`~tt_mujoco.vehicle.reduced.phi_rate_of`). Plain numbers (the compiled episode
    shares it)."""
    s_v, s_omega = phi_rate_of(phi, eta, L, L0)
    return followed_gain_of(eta, s_v * v + s_omega * omega, slew_rate)


def followed_gains_of(etas, rates, slew_rate: float, out) -> None:
    """:func:`followed_gain_of` of every trailer of a train into ``out``: trailer k's gain
    ``etas[k]`` at its hitch rate ``rates[k][0]`` (the rows of
    :func:`~tt_mujoco.vehicle.train.trailer_rates_of`). Plain numbers (the compiled episode
    shares it)."""
    for k in range(len(etas)):
        out[k] = followed_gain_of(etas[k], rates[k][0], slew_rate)


def wrap_angle(angle):
    """``angle`` (rad, a float or an array) wrapped into [-pi, pi)."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def steady_train(kappa: float, params: Params) -> tuple[list[float], list[float]]:
    """Steady articulations and off-tracking of every trailer at constant curvature.

    Solves ``phi_k_dot = 0`` trailer by trailer with ``omega = kappa v`` on the reduced
    kinematics (docs/model.md Section 12), taking each root nearest to 0, and places the train on
    the tractor's circle.

    Returns
    -------
    phis : list of float
        phi_1..phi_N (rad); NaN from the first trailer without a steady state.
    offtracks : list of float
        |C P_k| - R (m): + outside the tractor's path, - inside.
    """
    from tt_mujoco.vehicle import train  # the train's kinematics (imports this module's peers)

    kappa = float(kappa)
    n = params.n_trailers
    if kappa == 0.0:
        return [0.0] * n, [0.0] * n
    phis = [0.0] * n
    for k in range(n):

        def rate(phi: float, k: int = k) -> float:
            trial = phis[:k] + [phi] + [0.0] * (n - k - 1)
            return train.trailer_rates(trial, 1.0, kappa, params)[k][0]

        reach = min(math.pi / 2, params.phi_singulars[k] * (1.0 - 1e-6))
        root = math.nan
        grid = np.linspace(0.0, reach, 2001)
        for sign in (1.0, -1.0):
            values = [rate(sign * g) for g in grid]
            for i in range(len(grid) - 1):
                if values[i] == 0.0 or values[i] * values[i + 1] < 0.0:
                    from scipy.optimize import brentq

                    candidate = brentq(rate, sign * grid[i], sign * grid[i + 1], xtol=1e-15)
                    if math.isnan(root) or abs(candidate) < abs(root):
                        root = candidate
                    break
        if math.isnan(root):
            return phis[:k] + [math.nan] * (n - k), [math.nan] * n
        phis[k] = float(root)
    R = 1.0 / kappa
    places = train.poses(R, 0.0, 0.5 * math.pi, phis, params)
    return phis, [math.hypot(px, py) - abs(R) for _, _, px, py, _ in places]

"""The analytic reduced model: kinematics q_dot = S(q) V and dynamics V_dot = f + g tau.

Conventions are those of docs/model.md Sections 1-4: ``q = (x, y, theta, phi, theta_l, theta_r)``,
``V = (v, omega)``, ``tau = (T_r, T_l)``, ``phi = theta - theta0``, ``beta = eta * phi``.

Kinematics follow the paper's eqs. (12), (13) and (16)-(17) with the signs restored. The
dynamics are derived body by body (Kane's method), *not* from the paper's Appendix A, which is
wrong in several entries. With every body's velocity written in the tractor frame as
``A_b(phi) V`` (translation) and ``c_b(phi) . V`` (rotation or wheel spin), the reduced equations
are

    Mbar(phi) V_dot + Cbar(phi, V) V = B tau,
    Mbar = sum_b m_b A_b^T A_b + I_b c_b^T c_b,
    Cbar V = omega * gamma * Omega V + phi_dot * N(phi) V,

where ``Omega = [[0, -1], [1, 0]]`` comes from the rotation of the tractor frame,
``gamma = sum_b m_b det(A_b) = -(Mc1 + Mc2) L / 2`` (only the two rods have a full-rank A_b) and
``N = sum_b m_b A_b^T dA_b/dphi + I_b c_b^T dc_b/dphi``, so that ``N + N^T = dMbar/dphi``
(which makes the model conserve energy). The closed forms of Mbar and N are in
:func:`_inertia_terms`.

Everything here is plain float arithmetic on scalars, because the controllers call
:func:`dynamics` at every control step.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from tt_mujoco.vehicle.params import Params

__all__ = [
    "ModelConstants",
    "ReducedPlant",
    "SingularityError",
    "coriolis_force",
    "dynamics",
    "dynamics_scalar",
    "hitch_and_axle",
    "input_matrix",
    "kinematics",
    "kinetic_energy",
    "mass_matrix",
    "mass_terms",
    "matched_torque",
    "phi_rate",
    "rolling_rates",
    "solve_dynamics",
    "torque_for_force",
    "trailer_pose",
    "trailer_rows",
    "trailer_velocity",
]

#: cos(beta) below this is treated as the singularity |eta phi| = pi/2 (docs/model.md Section 2).
COS_BETA_MIN = 1e-3


class SingularityError(FloatingPointError):
    """The articulation reached |eta * phi| = pi/2, where the trailer kinematics are singular."""

    def __init__(self, phi: float, eta: float):
        self.phi = phi
        self.eta = eta
        super().__init__(
            f"phi={math.degrees(phi):.2f} deg with eta={eta:g} puts beta=eta*phi at "
            f"{math.degrees(eta * phi):.2f} deg: the trailer kinematics are singular at "
            "|beta| = 90 deg (jackknife)"
        )


def _cos_beta(phi: float, eta: float) -> float:
    cb = math.cos(eta * phi)
    if cb < COS_BETA_MIN:
        raise SingularityError(phi, eta)
    return cb


def phi_rate(phi: float, p: Params) -> tuple[float, float]:
    """Row ``s`` of S for the articulation: ``phi_dot = s[0] v + s[1] omega`` (paper eq. 13).

    ``phi_dot = [sin(beta - phi) v + (L0 cos(beta) + L cos(beta - phi)) omega] / (L0 cos(beta))``.
    """
    _cos_beta(phi, p.eta)
    return phi_rate_of(phi, p.eta, p.L, p.L0)


def phi_rate_of(phi: float, eta: float, L: float, L0: float) -> tuple[float, float]:
    """:func:`phi_rate` from plain numbers (no singularity check): the form the compiled
    episode (:mod:`tt_mujoco.sim.loop.compiled`) shares."""
    cb = math.cos(eta * phi)
    psi = (eta - 1.0) * phi  # beta - phi
    return math.sin(psi) / (L0 * cb), 1.0 + L * math.cos(psi) / (L0 * cb)


def kinematics(q, V, p: Params) -> np.ndarray:
    """``q_dot = S(q) V`` (paper eqs. 16-17 with signs restored, docs/model.md Section 2).

    Parameters
    ----------
    q : array_like, shape (6,)
        ``(x, y, theta, phi, theta_l, theta_r)``.
    V : array_like, shape (2,)
        ``(v, omega)``.
    p : Params

    Returns
    -------
    ndarray, shape (6,)
    """
    return np.array(rolling_rates(float(q[2]), float(q[3]), float(V[0]), float(V[1]), p))


def rolling_rates(theta: float, phi: float, v: float, omega: float, p: Params) -> tuple:
    """``q_dot = S(q) V`` as plain floats: ``(x_dot, y_dot, theta_dot, phi_dot, theta_l_dot,
    theta_r_dot)`` (docs/model.md Section 2); :func:`kinematics` and the plant use it."""
    _cos_beta(phi, p.eta)
    return rolling_rates_of(theta, phi, v, omega, p)


def rolling_rates_of(theta, phi, v, omega, c) -> tuple:
    """:func:`rolling_rates` without the singularity check; ``c`` is anything with the fields
    ``eta, L, L0, r, d`` (:class:`Params`, or :class:`ModelConstants` in compiled code)."""
    s1, s2 = phi_rate_of(phi, c.eta, c.L, c.L0)
    r = c.r
    spin = c.d * omega / (2.0 * r)
    return (
        v * math.cos(theta),
        v * math.sin(theta),
        omega,
        s1 * v + s2 * omega,
        v / r - spin,
        v / r + spin,
    )


def selection_matrix(q, p: Params) -> np.ndarray:
    """S(q), shape (6, 2), so that ``q_dot = S(q) V``."""
    theta, phi = float(q[2]), float(q[3])
    s1, s2 = phi_rate(phi, p)
    return np.array(
        [
            [math.cos(theta), 0.0],
            [math.sin(theta), 0.0],
            [0.0, 1.0],
            [s1, s2],
            [1.0 / p.r, -p.d / (2.0 * p.r)],
            [1.0 / p.r, p.d / (2.0 * p.r)],
        ]
    )


def constraint_matrix(q, p: Params) -> np.ndarray:
    """F(q), shape (4, 6): the rolling constraints ``F(q) q_dot = 0`` (paper eqs. 14-15).

    Rows: no side slip of P; right and left wheel rolling; the articulation (eq. 13) written
    as a constraint. ``F(q) S(q) = 0`` (paper eq. 18).
    """
    theta, phi = float(q[2]), float(q[3])
    s1, s2 = phi_rate(phi, p)
    c, s = math.cos(theta), math.sin(theta)
    half = p.d / 2.0
    return np.array(
        [
            [-s, c, 0.0, 0.0, 0.0, 0.0],
            [c, s, half, 0.0, 0.0, -p.r],
            [c, s, -half, 0.0, -p.r, 0.0],
            [s1 * c, s1 * s, s2, -1.0, 0.0, 0.0],
        ]
    )


def trailer_rows(phi: float, p: Params) -> tuple[tuple, tuple, tuple]:
    """The trailer's velocity maps, rows over ``V = (v, omega)`` (docs/model.md Section 4):
    ``k`` (``v0 = k.V``), ``s`` (``phi_dot = s.V``, :func:`phi_rate`) and ``a``
    (``alpha_dot = a.V``, the trailer axle's heading rate)."""
    cb = _cos_beta(phi, p.eta)
    s1, s2 = phi_rate(phi, p)
    k = (math.cos(phi) / cb, p.L * math.sin(phi) / cb)
    a = ((p.eta - 1) * s1, 1 + (p.eta - 1) * s2)
    return k, (s1, s2), a


def trailer_velocity(phi: float, V, p: Params) -> tuple[float, float]:
    """Trailer axle speed ``v0`` and heading rate ``theta0_dot`` (paper eq. 12 and Section 6.1).

    ``v0 = (v cos(phi) + L omega sin(phi)) / cos(beta)``, ``theta0_dot = omega - phi_dot``.
    """
    v, omega = float(V[0]), float(V[1])
    _cos_beta(phi, p.eta)
    s1, s2 = phi_rate(phi, p)
    return trailer_speed_of(phi, v, omega, p.eta, p.L), omega - (s1 * v + s2 * omega)


def trailer_speed_of(phi: float, v: float, omega: float, eta: float, L: float) -> float:
    """The trailer axle's speed ``v0`` of :func:`trailer_velocity` from plain numbers."""
    return (v * math.cos(phi) + L * omega * math.sin(phi)) / math.cos(eta * phi)


def trailer_pose(x: float, y: float, theta: float, phi: float, p: Params):
    """Hitch O, trailer axle midpoint P0 and trailer heading theta0 (docs/model.md Section 1).

    Returns
    -------
    O : ndarray, shape (2,)
    P0 : ndarray, shape (2,)
    theta0 : float
    """
    theta0 = theta - phi
    ox, oy, x0, y0 = hitch_and_axle(x, y, theta, theta0, p.L, p.L0)
    return np.array([ox, oy]), np.array([x0, y0]), theta0


def hitch_and_axle(x: float, y: float, theta: float, theta0: float, L: float, L0: float):
    """``(ox, oy, x0, y0)``: the hitch ``O = P - L e(theta)`` and the trailer axle midpoint
    ``P0 = O - L0 e(theta0)`` as plain floats (docs/model.md Section 1)."""
    ox, oy = x - L * math.cos(theta), y - L * math.sin(theta)
    return ox, oy, ox - L0 * math.cos(theta0), oy - L0 * math.sin(theta0)


def input_matrix(p: Params) -> np.ndarray:
    """B, mapping ``tau = (T_r, T_l)`` to forces on ``(v, omega)`` (docs/model.md §4)."""
    k = p.d / (2.0 * p.r)
    return np.array([[1.0 / p.r, 1.0 / p.r], [k, -k]])


def _lumped(p: Params) -> tuple[float, float, float, float, float, float]:
    """Lumped inertias of docs/model.md Section 4: m_t, J_t, m_0, J_a, J_0, gamma (cached on ``p``,
    which is frozen, because the controllers ask for them every step)."""
    cached = p.__dict__.get("_lumped_cache")
    if cached is not None:
        return cached
    spin = p.Iw / p.r**2
    m_t = p.Mf + 2 * p.Mw + p.Mc1 + 2 * spin
    J_t = p.Ifd + 2 * p.Iwd + p.Ic1 + p.Mc1 * p.L**2 / 4 + p.Mw * p.d**2 / 2 + spin * p.d**2 / 2
    m_0 = p.Mr + 2 * p.Mw + 2 * spin
    J_a = 2 * p.Iwd + p.Mw * p.d**2 / 2 + spin * p.d**2 / 2
    J_0 = p.Ird + p.Ic2
    gamma = -(p.Mc1 + p.Mc2) * p.L / 2
    lumped = (m_t, J_t, m_0, J_a, J_0, gamma)
    object.__setattr__(p, "_lumped_cache", lumped)
    return lumped


class ModelConstants(NamedTuple):
    """The reduced model's constants as plain numbers (docs/model.md Section 4): what the
    plain-number functions below, and the compiled episode, read by name."""

    eta: float
    L: float
    L0: float
    m_t: float
    J_t: float
    J_a: float
    J_0: float
    #: Mc2 / 4: rod 2's share, whose cross term with the trailer's translation is kept apart
    q: float
    #: m_0 + Mc2 / 4: ``kappa kappa^T`` collects the trailer's translation and rod 2's
    mk: float
    gamma: float
    r: float
    d: float


def _constants(p: Params) -> ModelConstants:
    """The :class:`ModelConstants` of ``p``, cached on ``p`` like :func:`_lumped`."""
    cached = p.__dict__.get("_constants_cache")
    if cached is None:
        m_t, J_t, m_0, J_a, J_0, gamma = _lumped(p)
        q = p.Mc2 / 4.0
        cached = ModelConstants(p.eta, p.L, p.L0, m_t, J_t, J_a, J_0, q, m_0 + q, gamma, p.r, p.d)
        object.__setattr__(p, "_constants_cache", cached)
    return cached


model_constants = _constants


def with_eta_of(c: ModelConstants, eta: float) -> ModelConstants:
    """``c`` with the steering gain ``eta``: the lumped constants do not depend on it (the
    compiled episode shares it)."""
    return ModelConstants(
        eta, c.L, c.L0, c.m_t, c.J_t, c.J_a, c.J_0, c.q, c.mk, c.gamma, c.r, c.d
    )  # fmt: skip


def _inertia_terms(phi: float, p: Params):
    """Mbar(phi) and N(phi) as nested tuples, plus the articulation row s (see
    :func:`_compute_inertia_terms`).

    Within a control step the controller's model and the matched disturbance ask for the same
    angle, so the last ``(phi, terms)`` is kept on ``p`` itself (a hit skips the terms). It is one
    tuple written in one assignment: runs in threads that share ``p`` read either the old pair
    or the new one, never a mix, and runs with other parameters never see it.
    """
    last = p.__dict__.get("_last_terms")
    if last is not None and last[0] == phi:
        return last[1]
    terms = _compute_inertia_terms(phi, p)
    object.__setattr__(p, "_last_terms", (phi, terms))
    return terms


def _compute_inertia_terms(phi: float, p: Params):
    """Mbar(phi) and N(phi) as nested tuples, plus the articulation row s.

    Velocity maps (tractor frame), with psi = beta - phi = (eta - 1) phi:
    ``v0 = kappa.V``, ``kappa = (cos phi, L sin phi) / cos beta``; ``phi_dot = s.V``;
    ``theta0_dot = sigma.V``, ``sigma = (0, 1) - s``; ``alpha_dot = a.V``,
    ``a = (0, 1) + (eta - 1) s``; rod 2's cross term uses ``n = (cos psi, -L sin psi)`` and
    ``dn/dphi = (eta - 1) m``, ``m = (-sin psi, -L cos psi)``.
    """
    constants = _constants(p)
    if math.cos(constants.eta * phi) < COS_BETA_MIN:
        raise SingularityError(phi, constants.eta)
    return inertia_terms_of(phi, constants)


def inertia_terms_of(phi: float, c: ModelConstants):
    """:func:`_compute_inertia_terms` from plain numbers (no singularity check): the form the
    compiled episode shares."""
    eta, L, L0, m_t, J_t, J_a, J_0, q, mk = c.eta, c.L, c.L0, c.m_t, c.J_t, c.J_a, c.J_0, c.q, c.mk
    cb = math.cos(eta * phi)
    sb = math.sin(eta * phi)
    cphi, sphi = math.cos(phi), math.sin(phi)
    psi = (eta - 1.0) * phi
    cpsi, spsi = math.cos(psi), math.sin(psi)
    cb2 = cb * cb

    k1, k2 = cphi / cb, L * sphi / cb
    dk1 = (-sphi * cb + cphi * eta * sb) / cb2
    dk2 = L * (cphi * cb + sphi * eta * sb) / cb2

    s1, s2 = spsi / (L0 * cb), 1.0 + L * cpsi / (L0 * cb)
    ds1 = ((eta - 1.0) * cpsi * cb + spsi * eta * sb) / (L0 * cb2)
    ds2 = L * (-(eta - 1.0) * spsi * cb + cpsi * eta * sb) / (L0 * cb2)

    g1, g2 = -s1, 1.0 - s2  # sigma
    dg1, dg2 = -ds1, -ds2
    a1, a2 = (eta - 1.0) * s1, 1.0 + (eta - 1.0) * s2
    da1, da2 = (eta - 1.0) * ds1, (eta - 1.0) * ds2
    n1, n2 = cpsi, -L * spsi
    m1, m2 = -spsi, -L * cpsi

    M11 = m_t + q + mk * k1 * k1 + J_a * a1 * a1 + J_0 * g1 * g1 + 2 * q * n1 * k1
    M22 = J_t + q * L * L + mk * k2 * k2 + J_a * a2 * a2 + J_0 * g2 * g2 + 2 * q * n2 * k2
    M12 = mk * k1 * k2 + J_a * a1 * a2 + J_0 * g1 * g2 + q * (n1 * k2 + k1 * n2)

    e1 = eta - 1.0
    N11 = mk * k1 * dk1 + J_a * a1 * da1 + J_0 * g1 * dg1 + q * (e1 * m1 * k1 + n1 * dk1)
    N12 = mk * k1 * dk2 + J_a * a1 * da2 + J_0 * g1 * dg2 + q * (e1 * m1 * k2 + n1 * dk2)
    N21 = mk * k2 * dk1 + J_a * a2 * da1 + J_0 * g2 * dg1 + q * (e1 * m2 * k1 + n2 * dk1)
    N22 = mk * k2 * dk2 + J_a * a2 * da2 + J_0 * g2 * dg2 + q * (e1 * m2 * k2 + n2 * dk2)
    return (M11, M12, M22), (N11, N12, N21, N22), (s1, s2)


def mass_matrix(phi: float, p: Params) -> np.ndarray:
    """Reduced mass matrix Mbar(phi), shape (2, 2), symmetric positive definite (docs/model.md §4).

    At the paper's parameters, eta = 3, phi = 0: ``diag(133.0, 12.844)``.
    """
    (M11, M12, M22), _, _ = _inertia_terms(phi, p)
    return np.array([[M11, M12], [M12, M22]])


def _coriolis(phi: float, v: float, omega: float, p: Params):
    return coriolis_of(_inertia_terms(phi, p), _lumped(p)[5], v, omega)


def coriolis_of(terms, gamma: float, v: float, omega: float):
    """``(Mbar, Cbar V)`` from :func:`inertia_terms_of`'s terms and gamma (plain numbers)."""
    (M11, M12, M22), (N11, N12, N21, N22), (s1, s2) = terms
    phi_dot = s1 * v + s2 * omega
    c1 = -gamma * omega * omega + phi_dot * (N11 * v + N12 * omega)
    c2 = gamma * omega * v + phi_dot * (N21 * v + N22 * omega)
    return (M11, M12, M22), (c1, c2)


def matched_torque(phi: float, a_v: float, a_omega: float, p: Params) -> tuple[float, float]:
    """Wheel torques ``(T_r, T_l) = g(phi)^-1 (a_v, a_omega) = B^-1 Mbar(phi) a``: the matched
    input that adds the acceleration ``a`` to ``(v_dot, omega_dot)`` (docs/model.md Section 8)."""
    return torque_for_force_of(_inertia_terms(phi, p)[0], a_v, a_omega, p.r, p.d)


def mass_terms(phi: float, p: Params) -> tuple[float, float, float]:
    """``Mbar(phi)`` as plain floats ``(M11, M12, M22)`` (see :func:`mass_matrix`)."""
    return _inertia_terms(phi, p)[0]


def torque_for_force(mass: tuple, a_v: float, a_omega: float, p: Params) -> tuple[float, float]:
    """``B^-1 Mbar a`` for ``Mbar`` given as ``(M11, M12, M22)``: the wheel torques that add the
    acceleration ``a`` (the one trailer's :func:`matched_torque`, or a train's)."""
    return torque_for_force_of(mass, a_v, a_omega, p.r, p.d)


def torque_for_force_of(mass: tuple, a_v: float, a_omega: float, r: float, d: float):
    """:func:`torque_for_force` from plain numbers."""
    M11, M12, M22 = mass
    force = M11 * a_v + M12 * a_omega  # generalized force on v
    moment = M12 * a_v + M22 * a_omega  # ... and on omega
    # B^-1 with B = [[1/r, 1/r], [d/(2r), -d/(2r)]].
    common = 0.5 * r * force
    diff = r * moment / d
    return common + diff, common - diff


def coriolis_force(phi: float, V, p: Params) -> np.ndarray:
    """``Cbar(phi, V) V``, the velocity-product forces of the reduced model, shape (2,)."""
    _, c = _coriolis(phi, float(V[0]), float(V[1]), p)
    return np.array(c)


def dynamics_scalar(phi: float, v: float, omega: float, p: Params):
    """:func:`dynamics` as six plain floats ``(f1, f2, g11, g12, g21, g22)``: the controllers'
    per-step call, without array allocation."""
    mass, bias = _coriolis(phi, v, omega, p)
    return solve_dynamics_of(mass, bias, p.r, p.d)


def solve_dynamics(mass: tuple, bias: tuple, p: Params):
    """``(f1, f2, g11, g12, g21, g22)`` of ``V_dot = f + g tau`` from ``Mbar`` as
    ``(M11, M12, M22)`` and ``Cbar V`` as ``(c1, c2)``: ``f = -Mbar^-1 Cbar V``,
    ``g = Mbar^-1 B`` (one trailer's or a train's)."""
    return solve_dynamics_of(mass, bias, p.r, p.d)


def solve_dynamics_of(mass: tuple, bias: tuple, r: float, d: float):
    """:func:`solve_dynamics` from plain numbers."""
    M11, M12, M22 = mass
    c1, c2 = bias
    det = M11 * M22 - M12 * M12
    i11, i12, i22 = M22 / det, -M12 / det, M11 / det
    b = 1.0 / r
    k = d / (2.0 * r)
    return (
        -(i11 * c1 + i12 * c2),
        -(i12 * c1 + i22 * c2),
        i11 * b + i12 * k,
        i11 * b - i12 * k,
        i12 * b + i22 * k,
        i12 * b - i22 * k,
    )


def dynamics(phi: float, V, p: Params) -> tuple[np.ndarray, np.ndarray]:
    """``V_dot = f + g tau`` (docs/model.md Section 4; the paper's eqs. 21-22 in exact form).

    Parameters
    ----------
    phi : float
        Articulation angle theta - theta0 (rad).
    V : array_like, shape (2,)
        ``(v, omega)``.
    p : Params

    Returns
    -------
    f : ndarray, shape (2,)
        ``-Mbar^-1 Cbar V``; homogeneous quadratic in V, so ``f(phi, 0) = 0``.
    g : ndarray, shape (2, 2)
        ``Mbar^-1 B``, columns for ``(T_r, T_l)``.
    """
    f1, f2, g11, g12, g21, g22 = dynamics_scalar(phi, float(V[0]), float(V[1]), p)
    return np.array([f1, f2]), np.array([[g11, g12], [g21, g22]])


def kinetic_energy(phi: float, V, p: Params) -> float:
    """``0.5 V^T Mbar(phi) V``: the whole vehicle's kinetic energy under rolling."""
    V = np.asarray(V, dtype=float)
    return 0.5 * float(V @ mass_matrix(phi, p) @ V)


class ReducedPlant:
    """The reduced model as a plant: state ``(x, y, theta, phi, theta_l, theta_r, v, omega)``.

    Integrated with classical RK4 at a fixed step, holding the torque and the disturbance
    constant over the step (zero-order hold, as a digital controller applies them).

    Parameters
    ----------
    params : Params
        The plant's (true) parameters; a controller may use different, nominal ones.
    state : array_like, shape (8,), optional
        Initial state, zeros by default.
    """

    STATE_NAMES = ("x", "y", "theta", "phi", "theta_l", "theta_r", "v", "omega")

    def __init__(self, params: Params, state=None):
        self.params = params
        self.state = np.zeros(8) if state is None else np.array(state, dtype=float)
        self.time = 0.0

    def derivative(self, state, tau, accel_disturbance=(0.0, 0.0)) -> list[float]:
        """Time derivative of the state for wheel torques ``tau`` and an additive
        disturbance ``accel_disturbance`` in ``(v_dot, omega_dot)`` (docs/model.md Section 8):
        :func:`derivative_of`, raising :class:`SingularityError` at the singularity."""
        c = _constants(self.params)
        a_v, a_w = accel_disturbance
        ok, rates = derivative_of(state, float(tau[0]), float(tau[1]), a_v, a_w, c)
        if not ok:
            raise SingularityError(state[3], c.eta)
        return list(rates)

    def step(self, tau, dt: float, accel_disturbance=(0.0, 0.0)) -> np.ndarray:
        """Advance by ``dt`` with RK4 (:func:`rk4_step_of`); raises :class:`SingularityError`
        at a jackknife."""
        y = [float(c) for c in self.state]
        c = _constants(self.params)
        a_v, a_w = float(accel_disturbance[0]), float(accel_disturbance[1])
        ok, phi, new = rk4_step_of(y, float(tau[0]), float(tau[1]), a_v, a_w, c, dt)
        if not ok:
            raise SingularityError(phi, c.eta)
        self.state = np.array(new)
        self.time += dt
        return self.state


def nominal_of(phi: float, v: float, omega: float, c: ModelConstants) -> tuple:
    """``(f1, f2, g11, g12, g21, g22)`` of ``V_dot = f + g tau`` at ``(phi, v, omega)`` from
    plain numbers, without the singularity check (the compiled episode shares it)."""
    mass, bias = coriolis_of(inertia_terms_of(phi, c), c.gamma, v, omega)
    return solve_dynamics_of(mass, bias, c.r, c.d)


def derivative_of(y, T_r: float, T_l: float, a_v: float, a_w: float, c: ModelConstants):
    """``(ok, dy/dt)`` of the state ``y = (x, y, theta, phi, theta_l, theta_r, v, omega)``:
    kinematics of eqs. 16-17, dynamics ``f + g tau`` plus the acceleration ``(a_v, a_w)``;
    ``ok`` is False (rates zero) at the singularity ``cos(eta phi) < COS_BETA_MIN``."""
    theta, phi, v, omega = y[2], y[3], y[6], y[7]
    if math.cos(c.eta * phi) < COS_BETA_MIN:
        return False, (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    f1, f2, g11, g12, g21, g22 = nominal_of(phi, v, omega, c)
    x_dot, y_dot, theta_dot, phi_dot, thl_dot, thr_dot = rolling_rates_of(theta, phi, v, omega, c)
    v_dot = f1 + g11 * T_r + g12 * T_l + a_v
    w_dot = f2 + g21 * T_r + g22 * T_l + a_w
    return True, (x_dot, y_dot, theta_dot, phi_dot, thl_dot, thr_dot, v_dot, w_dot)


def rk4_step_of(y, T_r: float, T_l: float, a_v: float, a_w: float, c: ModelConstants, dt):
    """One classical RK4 step of :func:`derivative_of`, inputs held over it: ``(ok, phi,
    new state)``; ``ok`` False with the stage's phi where a stage meets the singularity."""
    ok, k1 = derivative_of(y, T_r, T_l, a_v, a_w, c)
    if not ok:
        return False, y[3], k1
    stage = rk4_stage(y, k1, 0.5 * dt)
    ok, k2 = derivative_of(stage, T_r, T_l, a_v, a_w, c)
    if not ok:
        return False, stage[3], k2
    stage = rk4_stage(y, k2, 0.5 * dt)
    ok, k3 = derivative_of(stage, T_r, T_l, a_v, a_w, c)
    if not ok:
        return False, stage[3], k3
    stage = rk4_stage(y, k3, dt)
    ok, k4 = derivative_of(stage, T_r, T_l, a_v, a_w, c)
    if not ok:
        return False, stage[3], k4
    return True, y[3], rk4_combine(y, k1, k2, k3, k4, dt / 6.0)


def rk4_stage(y, k, c: float) -> tuple:
    """``y + c k`` over the 8 states: the state at which RK4 takes its next slope (a tuple: the
    compiled step allocates nothing)."""
    return (
        y[0] + c * k[0], y[1] + c * k[1], y[2] + c * k[2], y[3] + c * k[3],
        y[4] + c * k[4], y[5] + c * k[5], y[6] + c * k[6], y[7] + c * k[7],
    )  # fmt: skip


def rk4_combine(y, k1, k2, k3, k4, h: float) -> tuple:
    """RK4's new state ``y + h (k1 + 2 k2 + 2 k3 + k4)`` over the 8 states, ``h = dt / 6``."""
    return (
        rk4_update(y, k1, k2, k3, k4, h, 0), rk4_update(y, k1, k2, k3, k4, h, 1),
        rk4_update(y, k1, k2, k3, k4, h, 2), rk4_update(y, k1, k2, k3, k4, h, 3),
        rk4_update(y, k1, k2, k3, k4, h, 4), rk4_update(y, k1, k2, k3, k4, h, 5),
        rk4_update(y, k1, k2, k3, k4, h, 6), rk4_update(y, k1, k2, k3, k4, h, 7),
    )  # fmt: skip


def rk4_update(y, k1, k2, k3, k4, h: float, i: int) -> float:
    """State ``i`` of RK4's new state (:func:`rk4_combine`)."""
    return y[i] + h * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])

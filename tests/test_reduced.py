"""The analytic reduced model on its own: SPEC check values, structure and property tests."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import brentq

from tt_mujoco.vehicle import reduced
from tt_mujoco.vehicle.params import Params

PAPER = Params(eta="paper")


def test_spec_check_values():
    # docs/model.md Section 4: paper parameters, eta = 3, phi = 0.
    np.testing.assert_allclose(reduced.mass_matrix(0.0, PAPER), np.diag([133.0, 12.844]), atol=1e-3)
    _, g = reduced.dynamics(0.0, (0.0, 0.0), PAPER)
    np.testing.assert_allclose(g, [[0.3759, 0.3759], [0.3893, -0.3893]], atol=1e-4)


@pytest.mark.parametrize("eta", [3.0, -0.125, 0.0, -3.0])
def test_drift_is_quadratic_in_velocity(eta):
    # f(phi, 0) = 0 and f(phi, c V) = c^2 f(phi, V): no constant gamma4 (docs/model.md Section 4).
    p = Params(eta=eta)
    f0, _ = reduced.dynamics(0.2, (0.0, 0.0), p)
    assert np.all(f0 == 0.0)
    f1, _ = reduced.dynamics(0.2, (0.3, -0.7), p)
    f3, _ = reduced.dynamics(0.2, (0.9, -2.1), p)
    np.testing.assert_allclose(f3, 9.0 * f1, rtol=1e-12)


@pytest.mark.parametrize("eta", [3.0, -0.125, 0.0])
def test_velocity_forces_are_consistent_with_mass_matrix_derivative(eta):
    # V^T Cbar V = (phi_dot / 2) V^T dMbar/dphi V: the condition for energy conservation.
    p = Params(eta=eta)
    rng = np.random.default_rng(3)
    for _ in range(20):
        phi = rng.uniform(-0.4, 0.4) * min(p.phi_singular, 1.0)
        V = rng.normal(size=2)
        h = 1e-6
        dM = (reduced.mass_matrix(phi + h, p) - reduced.mass_matrix(phi - h, p)) / (2 * h)
        phi_dot = np.dot(reduced.phi_rate(phi, p), V)
        lhs = V @ reduced.coriolis_force(phi, V, p)
        rhs = 0.5 * phi_dot * V @ dM @ V
        assert lhs == pytest.approx(rhs, rel=1e-7, abs=1e-9)


def test_linearised_articulation_rate():
    # docs/model.md Section 3: phi_dot ~ (eta - 1) v phi / L0 at omega = 0.
    for eta in (3.0, -0.125):
        p = Params(eta=eta)
        phi = 1e-5
        s1, _ = reduced.phi_rate(phi, p)
        assert s1 * 1.0 == pytest.approx((eta - 1) * phi / p.L0, rel=1e-6)


def test_trailer_velocity_formula_against_pose_derivative():
    # v0 and theta0_dot (paper eq. 12) against finite differences of trailer_pose along S(q) V.
    p = Params()
    q = np.array([0.3, -0.2, 0.7, 0.25, 0.0, 0.0])
    V = np.array([0.6, -0.4])
    dt = 1e-7
    qd = reduced.kinematics(q, V, p)
    _, P0a, th0a = reduced.trailer_pose(*q[:4], p)
    qb = q + dt * qd
    _, P0b, th0b = reduced.trailer_pose(*qb[:4], p)
    vel = (P0b - P0a) / dt
    v0, th0_dot = reduced.trailer_velocity(q[3], V, p)
    alpha = th0a + p.eta * q[3]
    np.testing.assert_allclose(vel, v0 * np.array([math.cos(alpha), math.sin(alpha)]), atol=1e-6)
    assert (th0b - th0a) / dt == pytest.approx(th0_dot, abs=1e-6)


def test_steady_turn_offtracking_matches_spec():
    # docs/model.md Section 3, R = 1.5 m: P0 radius minus tractor radius for eta*, 0, -3.
    expected_mm = {-0.125: -2.9, 0.0: -23.5, -3.0: 114.0}
    R = 1.5
    for eta, mm in expected_mm.items():
        p = Params(eta=eta)
        # Steady state: phi_dot = 0 with omega = v / R.
        lim = 0.99 * min(p.phi_singular, 1.2)

        def phi_dot(ph, p=p):
            return np.dot(reduced.phi_rate(ph, p), (1.0, 1.0 / R))

        phi = brentq(phi_dot, -lim, lim)
        _, P0, _ = reduced.trailer_pose(0.0, -R, 0.0, phi, p)  # circle centred at the origin
        assert (np.hypot(*P0) - R) * 1e3 == pytest.approx(mm, abs=0.6)


angles = st.floats(-math.pi, math.pi, allow_nan=False)
etas = st.sampled_from([3.0, -0.125, 0.0, -3.0, 1.5])


@settings(max_examples=200, deadline=None)
@given(
    x=st.floats(-10, 10), y=st.floats(-10, 10), theta=angles, frac=st.floats(-0.95, 0.95), eta=etas
)
def test_constraints_annihilate_selection(x, y, theta, frac, eta):
    # Paper eq. 18: F(q) S(q) = 0 everywhere away from the singularity.
    p = Params(eta=eta)
    phi = frac * min(p.phi_singular, 1.5)
    q = np.array([x, y, theta, phi, 0.0, 0.0])
    FS = reduced.constraint_matrix(q, p) @ reduced.selection_matrix(q, p)
    assert np.abs(FS).max() < 1e-9 * max(1.0, np.abs(reduced.selection_matrix(q, p)).max())


@settings(max_examples=200, deadline=None)
@given(eta=st.sampled_from([3.0, -3.0, 2.0]), excess=st.floats(0.0, 0.2))
def test_singularity_guard(eta, excess):
    # At or beyond |eta phi| = pi/2 (within COS_BETA_MIN) every entry point refuses.
    p = Params(eta=eta)
    phi = math.copysign((math.pi / 2 + excess) / abs(eta), eta)
    with pytest.raises(reduced.SingularityError, match="jackknife"):
        reduced.dynamics(phi, (0.5, 0.0), p)
    with pytest.raises(reduced.SingularityError):
        reduced.kinematics([0, 0, 0, phi, 0, 0], (0.5, 0.0), p)


@settings(max_examples=100, deadline=None)
@given(frac=st.floats(-0.99, 0.99), eta=etas)
def test_mass_matrix_positive_definite(frac, eta):
    p = Params(eta=eta)
    phi = frac * min(p.phi_singular, 1.5)
    eig = np.linalg.eigvalsh(reduced.mass_matrix(phi, p))
    assert eig.min() > 0


def test_memoised_terms_follow_phi_and_params():
    # The one-entry memo must not hand out another angle's or another Params' terms.
    p, q = Params(), Params(eta="paper")
    first = reduced.mass_matrix(0.1, p)
    assert np.array_equal(reduced.mass_matrix(0.1, p), first)
    assert not np.array_equal(reduced.mass_matrix(0.2, p), first)
    assert not np.array_equal(reduced.mass_matrix(0.1, q), first)
    tau = reduced.matched_torque(0.1, 3.5, 1.0, p)
    _, g = reduced.dynamics(0.1, (0.0, 0.0), p)
    np.testing.assert_allclose(g @ tau, [3.5, 1.0], rtol=1e-12)


def _steady_offtrack(eta: float, R: float) -> float:
    """P0's turning radius minus the tractor's, analytic steady turn of radius R."""
    p = Params(eta=eta)
    lim = 0.99 * min(p.phi_singular, 1.2)

    def phi_dot(ph):
        return np.dot(reduced.phi_rate(ph, p), (1.0, 1.0 / R))

    phi = brentq(phi_dot, -lim, lim)
    _, P0, _ = reduced.trailer_pose(0.0, -R, 0.0, phi, p)
    return float(np.hypot(*P0) - R)


def test_the_half_difference_gain_is_not_the_small_curvature_limit():
    # The half-difference gain -(L0 - L)/(2 L0) = -0.125 (an earlier derivation's limit of the
    # same-path gain, docs/model.md Section 3). If it were the limit, the off-tracking would
    # vanish faster than the curvature. It does not: R x off-tracking tends to a constant
    # (measured -3.889e-3 m^2), i.e. the error is O(kappa). (L - L0)/(L + L0) = -1/7, the
    # project's same_path, gives O(kappa^3): R^3 x off-tracking tends to -9.38e-4 m^4.
    L, L0 = 0.3, 0.4
    spec = -(L0 - L) / (2.0 * L0)
    assert spec == pytest.approx(-0.125)
    for R in (10.0, 30.0, 100.0):
        assert R * _steady_offtrack(spec, R) == pytest.approx(-3.889e-3, rel=0.01)
    ours = Params().eta
    assert ours == pytest.approx(-1.0 / 7.0)
    for R in (10.0, 30.0, 100.0):
        assert R**3 * _steady_offtrack(ours, R) == pytest.approx(-9.38e-4, rel=0.01)
    # And at the paper's S-curve radius: -2.87 mm against -0.27 mm.
    assert _steady_offtrack(spec, 1.5) == pytest.approx(-2.87e-3, abs=0.02e-3)
    assert _steady_offtrack(ours, 1.5) == pytest.approx(-0.275e-3, abs=0.01e-3)

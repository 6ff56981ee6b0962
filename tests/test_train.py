"""The train's reduced model (tt_mujoco.vehicle.train) and its same-path gains (docs/model.md
Section 12): the general chain against the one-trailer closed form, and the gains' derivation."""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest

from tt_mujoco.vehicle import reduced, train
from tt_mujoco.vehicle.params import MAX_TRAILERS, Params, train_same_path_etas
from tt_mujoco.vehicle.steering import (
    exact_same_path_eta,
    exact_train_same_path_etas,
    steady_train,
)

PAPER_LENGTHS = [(0.3, 0.4)] * 3

# The chain sums ~20 bodies' products where the closed form sums 6 lumped terms; both are exact,
# so they differ by round-off: measured worst 7.1e-16 (Mbar, relative), 1.9e-15 (Cbar V relative
# to 1 + |Cbar V|), 8.9e-16 (rates) and 5.8e-16 (energy) over 4 gains x 50 states. 1e-13 leaves
# 50x and still catches any wrong term (the smallest body term is ~1e-5 of Mbar).
CHAIN_TOL = 1e-13


@pytest.mark.parametrize("eta", ["paper", "same_path", 0.0, 0.5])
def test_general_chain_equals_the_closed_form_for_one_trailer(eta):
    p = Params(eta=eta)
    rng = np.random.default_rng(7)
    for _ in range(50):
        phi = float(rng.uniform(-0.4, 0.4)) * min(1.0, p.phi_singular)
        v, w = rng.normal(size=2)
        (M11, M12, M22), (c1, c2) = train.mass_and_bias((phi,), v, w, p)
        (a, b, d), (e1, e2) = reduced._coriolis(phi, v, w, p)
        assert max(abs(M11 - a), abs(M12 - b)) / a < CHAIN_TOL
        assert abs(M22 - d) / d < CHAIN_TOL
        assert max(abs(c1 - e1), abs(c2 - e2)) / (1 + abs(e1) + abs(e2)) < CHAIN_TOL
        theta = float(rng.uniform(-3, 3))
        rates = train.rates(theta, (phi,), v, w, p)
        assert rates == pytest.approx(reduced.rolling_rates(theta, phi, v, w, p), abs=CHAIN_TOL)
        energy = train.kinetic_energy((phi,), (v, w), p)
        assert energy == pytest.approx(reduced.kinetic_energy(phi, (v, w), p), rel=CHAIN_TOL)


def test_train_energy_is_half_v_mbar_v_and_mbar_is_positive_definite():
    p = Params().with_trailers(3)
    rng = np.random.default_rng(3)
    for _ in range(20):
        phis = tuple(rng.uniform(-0.6, 0.6, 3))
        V = rng.normal(size=2)
        (M11, M12, M22), _ = train.mass_and_bias(phis, 0.0, 0.0, p)
        M = np.array([[M11, M12], [M12, M22]])
        assert np.all(np.linalg.eigvalsh(M) > 0)
        assert train.kinetic_energy(phis, V, p) == pytest.approx(0.5 * V @ M @ V, rel=1e-13)


def test_poses_follow_the_chain_geometry():
    p = Params().with_trailers(2)
    (o1x, o1y, p1x, p1y, th1), (o2x, o2y, p2x, p2y, th2) = train.poses(0, 0, 0, (0.3, -0.2), p)
    # O_1 L behind P along theta; P_1 L0 behind O_1 along theta_1 = -0.3; O_2 L behind P_1
    # along trailer 1's *body* heading; theta_2 = theta_1 + 0.2.
    assert (o1x, o1y) == pytest.approx((-0.3, 0.0))
    assert th1 == pytest.approx(-0.3) and th2 == pytest.approx(-0.1)
    assert (p1x, p1y) == pytest.approx((-0.3 - 0.4 * math.cos(0.3), 0.4 * math.sin(0.3)))
    assert math.hypot(o2x - p1x, o2y - p1y) == pytest.approx(0.3)
    assert math.atan2(p1y - o2y, p1x - o2x) == pytest.approx(th1)
    assert math.hypot(p2x - o2x, p2y - o2y) == pytest.approx(0.4)


def test_same_path_limits_are_the_derived_recursion():
    # b_k = (L^2 - L0^2)/(2 L0) - (L/L0) b_(k-1), eta_k = b_k / (L + L0 + b_k - b_(k-1)), in
    # exact fractions for the paper's lengths: -1/7, -1/35, -13/119.
    L, L0 = Fraction(3, 10), Fraction(2, 5)
    b_prev, expected = Fraction(0), []
    for _ in range(3):
        b = (L * L - L0 * L0) / (2 * L0) - (L / L0) * b_prev
        expected.append(b / (L + L0 + b - b_prev))
        b_prev = b
    assert expected == [Fraction(-1, 7), Fraction(-1, 35), Fraction(-13, 119)]
    assert train_same_path_etas(PAPER_LENGTHS) == pytest.approx([float(e) for e in expected])
    assert Params().with_trailers(3).etas == pytest.approx([float(e) for e in expected])


def test_exact_gains_put_every_axle_on_the_tractors_path():
    # Geometry (circle intersections) and kinematics (phi_k_dot = 0) are independent routes:
    # with the exact gains every steady axle lies on the path to round-off.
    for R in (1.5, 3.0):
        etas = exact_train_same_path_etas(1 / R, PAPER_LENGTHS)
        assert etas[0] == pytest.approx(exact_same_path_eta(1 / R, 0.3, 0.4), abs=1e-14)
        p = Params(eta=etas[0]).with_trailers(3, [{"eta": etas[1]}, {"eta": etas[2]}])
        _, offtracks = steady_train(1 / R, p)
        assert max(abs(o) for o in offtracks) < 1e-12


def test_exact_gains_tend_to_the_limits_like_kappa_squared():
    limits = np.array(train_same_path_etas(PAPER_LENGTHS))
    gaps = [
        np.abs(np.array(exact_train_same_path_etas(kappa, PAPER_LENGTHS)) - limits)
        for kappa in (0.02, 0.01)
    ]
    assert np.all(gaps[0] / gaps[1] == pytest.approx(4.0, rel=0.01))


def _offtracks(eta_spec, R: float, overrides=()) -> np.ndarray:
    p = Params(eta=eta_spec).with_trailers(3, overrides)
    return np.abs(steady_train(1 / R, p)[1])


def test_limit_gains_leave_offtracking_falling_like_the_cube_of_curvature():
    # Halving the curvature divides the same-path trailers' off-tracking by 8 (each trailer),
    # plain trailers' by 2; at R = 1.5 m the gains are 74x to 86x better than plain trailers.
    same = [_offtracks("same_path", R) for R in (3.0, 6.0)]
    plain = [_offtracks(0.0, R) for R in (3.0, 6.0)]
    assert same[0] / same[1] == pytest.approx([8.0] * 3, rel=0.02)
    assert plain[0] / plain[1] == pytest.approx([2.0] * 3, rel=0.01)
    assert np.all(_offtracks(0.0, 1.5) / _offtracks("same_path", 1.5) > 20)


def test_a_trailers_own_single_gain_is_not_its_same_path_gain():
    # (L - L0)/(L + L0) = -1/7 on trailer 2 ignores that its hitch rides on trailer 1's body,
    # whose axle is steered: the off-tracking then falls only like the curvature.
    own = -1 / 7
    wrong = [_offtracks("same_path", R, [{"eta": own}])[1] for R in (3.0, 6.0)]
    assert wrong[0] / wrong[1] == pytest.approx(2.0, rel=0.02)
    assert wrong[1] > 10 * _offtracks("same_path", 6.0)[1]


def test_with_trailers_copies_trailer_one_and_takes_overrides():
    p = Params(Mr=7.0, eta="paper").with_trailers(3, [{"L0": 0.5}, {"eta": 0.0}])
    assert p.n_trailers == 3
    assert [t.Mr for t in p.trailers] == [7.0, 7.0, 7.0]
    assert [t.L0 for t in p.trailers] == [0.4, 0.5, 0.4]
    assert p.etas == (3.0, 3.0, 0.0)
    assert p.total_mass == pytest.approx(Params(Mr=7.0).total_mass + 2 * (7.0 + 8.0 + 1.0 + 1.0))
    assert Params().with_trailers(1) == Params()
    assert "train" not in Params().to_dict()
    # A train's parameters survive their own dict form (metrics.json, re-rendering).
    again = Params(**{k: v for k, v in p.to_dict().items() if k != "steering"})
    assert again.etas == p.etas and again.trailers == p.trailers


def test_with_etas_changes_only_the_gains():
    p = Params(Mr=7.0).with_trailers(3, [{"L0": 0.5}])
    q = p.with_etas((0.5, -1.0, 2.0))
    assert q.etas == (0.5, -1.0, 2.0)
    assert [t.L0 for t in q.trailers] == [t.L0 for t in p.trailers]
    assert [t.Mr for t in q.trailers] == [7.0, 7.0, 7.0]
    assert p.etas == tuple(train_same_path_etas([(t.L, t.L0) for t in p.trailers]))
    with pytest.raises(ValueError, match=r"2 gains are not allowed: this vehicle has 3 trailer"):
        p.with_etas((0.1, 0.2))


@pytest.mark.parametrize(
    ("call", "fragment"),
    [
        (lambda: Params().with_trailers(0), "trailers=0 is not allowed"),
        (lambda: Params().with_trailers(MAX_TRAILERS + 1), "trailers=9 is not allowed"),
        (lambda: Params().with_trailers(2, [{}, {}]), "2 trailer tables are not allowed"),
        (lambda: Params().with_trailers(2, [{"Lx": 1}]), "trailer 2 field 'Lx' is not allowed"),
        (lambda: Params().with_trailers(2, [{"L0": -1}]), "trailer L0=-1 is not allowed"),
        (lambda: Params().with_trailers(2, [{"eta": "wild"}]), "trailer 2: eta='wild'"),
        (lambda: Params().with_trailers(2, [{"Mr": 0}]), "trailer Mr=0 is not allowed"),
    ],
)
def test_bad_trailers_name_the_value(call, fragment):
    with pytest.raises(ValueError, match=fragment.replace("(", r"\(")):
        call()


def test_train_ode_keeps_straight_driving_straight():
    p = Params().with_trailers(3)
    ode = train.TrainODE(p, state=[0, 0, 0, 0, 0, 0, 0, 0, 0.5, 0.0])
    for _ in range(500):
        ode.step((0.2, 0.2), 0.001)
    assert np.all(ode.state[3:6] == 0.0)
    assert ode.state[-2] > 0.5


def test_with_unit_fields_sets_the_tractor_s_and_each_trailer_s():
    """Unit 0 the tractor, 1 trailer 1 (Params' own fields), k trailer k; a gain stays."""
    p = Params().with_trailers(3)
    q = p.with_unit_fields({(0, "Mf"): 11.0, (1, "Mr"): 7.0, (3, "L0"): 0.5, (2, "Ird"): 0.04})
    assert (q.Mf, q.Mr, q.train[1].L0, q.train[0].Ird) == (11.0, 7.0, 0.5, 0.04)
    assert q.etas == p.etas and q.train[1].L == p.train[1].L
    with pytest.raises(ValueError):
        p.with_unit_fields({(2, "L0"): -1.0})

"""The path-frame error kinematics' analytic Jacobians against central finite differences."""

from __future__ import annotations

import numpy as np
import pytest

from tt_mujoco.vehicle.linearize import error_rates, hitch_rates_with_jacobian, jacobians
from tt_mujoco.vehicle.params import Params
from tt_mujoco.vehicle.rolling import hitch_rates
from tt_mujoco.vehicle.steering import steady_articulation

#: Central differences with this step: truncation ~h^2 * |f'''| ~ 1e-12 and rounding
#: ~1e-16 / h ~ 1e-10 against entries of order 1, both far below the 1e-6 required.
STEP = 1e-6


def _train(n):
    p = Params(eta=-1.0 / 7.0).with_trailers(n)
    return [(t.L, t.L0) for t in p.trailers], list(p.etas)


def _states(n, count=50, seed=0):
    rng = np.random.default_rng(seed + n)
    for _ in range(count):
        z = np.concatenate([rng.uniform(-0.2, 0.2, 1), rng.uniform(-0.5, 0.5, 1)])
        z = np.concatenate([z, rng.uniform(-0.7, 0.7, n)])
        u = np.array([rng.uniform(-1.5, 1.5), rng.uniform(-1.0, 1.0)])
        yield z, u, float(rng.uniform(-1.5, 1.5))


def _central(f, x):
    cols = []
    for i in range(x.size):
        step = np.zeros_like(x)
        step[i] = STEP
        cols.append((f(x + step) - f(x - step)) / (2.0 * STEP))
    return np.column_stack(cols)


@pytest.mark.parametrize("n", [1, 2, 3])
def test_jacobians_agree_with_central_differences(n):
    # Issue "baselines", must-show 3: 1e-6 relative at 50 random states for N = 1, 2, 3
    # (measured worst 4.1e-10).
    lengths, etas = _train(n)
    for z, u, kappa in _states(n):
        A, B = jacobians(z, u, kappa, lengths, etas)
        A_fd = _central(lambda x, u=u, k=kappa: error_rates(x, u, k, lengths, etas), z)
        B_fd = _central(lambda x, z=z, k=kappa: error_rates(z, x, k, lengths, etas), u)
        for exact, approx in ((A, A_fd), (B, B_fd)):
            scale = max(1.0, float(np.max(np.abs(exact))))
            assert np.max(np.abs(exact - approx)) <= 1e-6 * scale


@pytest.mark.parametrize("n", [1, 2, 3])
def test_the_rates_are_the_train_kinematics(n):
    lengths, etas = _train(n)
    for z, u, _ in _states(n, count=10, seed=5):
        rates, _ = hitch_rates_with_jacobian(z[2:], u[0], u[1], lengths, etas)
        expected = [row[0] for row in hitch_rates(z[2:], u[0], u[1], lengths, etas)]
        np.testing.assert_allclose(rates, expected, atol=1e-14)


def test_a_steady_arc_is_an_equilibrium_and_the_hitch_is_unstable_reversing():
    # One trailer on a steady arc: z_dot = 0. Section 3's sign: the hitch's own eigenvalue is
    # negative forward and positive reversing (eta < 1).
    lengths, etas = _train(1)
    kappa = 2.0 / 3.0
    phi = steady_articulation(kappa, Params(eta=etas[0]))
    for v in (0.8, -0.8):
        z, u = np.array([0.0, 0.0, phi]), np.array([v, kappa * v])
        np.testing.assert_allclose(error_rates(z, u, kappa, lengths, etas), 0.0, atol=1e-12)
        A, _ = jacobians(z, u, kappa, lengths, etas)
        assert np.sign(A[2, 2]) == -np.sign(v)

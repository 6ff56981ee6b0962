"""The quadratic program of one real-time iteration of a tracking MPC, solved by OSQP.

Over a horizon of ``H`` samples the program takes the states ``x_0..x_H``, the inputs
``u_0..u_(H-1)`` and a slack ``e_k >= 0`` for each bounded state at each stage, and minimises

    1/2 sum_(k=1..H) (x_k - r_k)' Q (x_k - r_k)                         tracking
  + 1/2 sum_(k=0..H-1) (r_du |u_k - u_(k-1)|^2 + r_u |u_k|^2)           input rate and size
  + sum_k (rho/2 |e_k|^2 + rho1 sum e_k)                                soft state bounds

subject to ``x_0 = x_measured``, the linearised dynamics ``x_(k+1) = A_k x_k + B_k u_k + c_k``,
``|u_k| <= u_max`` and ``|x_k[i]| <= bound_i + e_k`` for the bounded states. ``u_(-1)`` is the
input applied last. The sparsity pattern never changes, so OSQP (Stellato et al., "OSQP: an
operator splitting solver for quadratic programs", Math. Prog. Comp. 2020) is set up once and
each sample updates the dynamics' values, the bounds and the linear cost, warm-started from the
previous solution.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["MissingSolverError", "QpSolution", "QpWeights", "TrackingQP"]


class MissingSolverError(ImportError, ValueError):
    """The optional QP solver is not installed (a ValueError too: the run is refused as bad
    input, exit 2)."""


def _osqp():
    try:
        import osqp
    except ImportError:
        raise MissingSolverError(
            "controller 'nmpc' needs the optional package osqp, which is not installed: "
            "pip install 'tt-mujoco[mpc]'"
        ) from None
    return osqp


@dataclass(frozen=True)
class QpSolution:
    """One solve: ``states`` (H + 1, nx), ``inputs`` (H, nu), ``ok`` and the solver's own
    ``iterations``."""

    states: np.ndarray
    inputs: np.ndarray
    ok: bool
    iterations: int


@dataclass(frozen=True)
class QpWeights:
    """The program's weights: ``Q`` the diagonal state weights (shape (nx,)), ``r_du`` and
    ``r_u`` the input-rate and input-size weights, ``rho`` and ``rho1`` the quadratic and
    linear slack weights of the soft bounds."""

    Q: tuple
    r_du: float
    r_u: float
    rho: float
    rho1: float


class TrackingQP:
    """The program of the module docstring for fixed sizes and weights.

    Parameters
    ----------
    nx, nu, horizon : int
    weights : QpWeights
    u_max : float
        Bound on every input's magnitude.
    bounded : sequence of int
        Indices of the states with a soft bound.
    """

    def __init__(self, nx, nu, horizon, weights: QpWeights, u_max, bounded):
        self.nx, self.nu, self.H = nx, nu, horizon
        self.bounded = np.asarray(bounded, dtype=int)
        nb = self.bounded.size
        H = horizon
        self._ix = lambda k: k * nx  # x_k's first column
        self._iu = lambda k: (H + 1) * nx + k * nu
        self._ie = lambda k: (H + 1) * nx + H * nu + (k - 1) * nb  # k = 1..H
        self.n = (H + 1) * nx + H * nu + H * nb
        self.u_max, self.r_du, self.rho1 = float(u_max), float(weights.r_du), float(weights.rho1)
        self._Q = np.asarray(weights.Q, dtype=float)
        P = self._cost_hessian(weights)
        A = self._constraint_matrix()
        self.lower = np.full(self.m, -np.inf)
        self.upper = np.full(self.m, np.inf)
        lo, hi = self._dyn_rows[1], self._bound_rows
        self.lower[lo:hi], self.upper[lo:hi] = -self.u_max, self.u_max
        self.lower[-H * nb :] = 0.0
        self._q = np.zeros(self.n)
        self._q[self._ie(1) :] = weights.rho1
        self._solver = _osqp().OSQP()
        self._solver.setup(
            P, self._q, A, self.lower, self.upper, verbose=False, eps_abs=1e-5, eps_rel=1e-5,
            max_iter=4000, polishing=False, warm_starting=True,
        )  # fmt: skip

    def _cost_hessian(self, weights: QpWeights):
        """The cost's Hessian (its upper triangle, as OSQP takes it)."""
        from scipy import sparse

        nx, nu, H, r_du = self.nx, self.nu, self.H, weights.r_du
        diag = np.zeros(self.n)
        for k in range(1, H + 1):
            diag[self._ix(k) : self._ix(k) + nx] = self._Q
        rate = np.full(H, 2.0 * r_du)
        rate[-1] = r_du  # the last input has no successor
        for k in range(H):
            diag[self._iu(k) : self._iu(k) + nu] = rate[k] + weights.r_u
        diag[self._ie(1) :] = weights.rho
        rows, cols, vals = list(range(self.n)), list(range(self.n)), list(diag)
        for k in range(H - 1):
            for j in range(nu):
                rows.append(self._iu(k) + j)
                cols.append(self._iu(k + 1) + j)
                vals.append(-r_du)
        return sparse.csc_matrix((vals, (rows, cols)), shape=(self.n, self.n))

    def _constraint_matrix(self):
        """The constraints' matrix: initial state, dynamics (their values set per solve),
        input box, soft bounds, slack >= 0; with the slots and rows :meth:`solve` fills."""
        from scipy import sparse

        nx, nu, H, nb = self.nx, self.nu, self.H, self.bounded.size
        rows, cols, vals = [], [], []

        def put(r, c, v):
            rows.append(r)
            cols.append(c)
            vals.append(v)

        row = 0
        for i in range(nx):
            put(row + i, self._ix(0) + i, 1.0)
        row += nx
        self._dyn_slots = []  # per k: (slot of -A_k's first entry, slot of -B_k's first entry)
        for k in range(H):
            for i in range(nx):
                put(row + i, self._ix(k + 1) + i, 1.0)
            a_slot = len(vals)
            for i in range(nx):
                for j in range(nx):
                    put(row + i, self._ix(k) + j, 1.0)  # values set per solve
            b_slot = len(vals)
            for i in range(nx):
                for j in range(nu):
                    put(row + i, self._iu(k) + j, 1.0)
            self._dyn_slots.append((a_slot, b_slot))
            row += nx
        self._dyn_rows = (nx, row)
        for k in range(H):
            for j in range(nu):
                put(row, self._iu(k) + j, 1.0)
                row += 1
        self._bound_rows = row
        for k in range(1, H + 1):
            for b, i in enumerate(self.bounded):
                put(row, self._ix(k) + i, 1.0)
                put(row, self._ie(k) + b, -1.0)  # x - e <= bound
                put(row + 1, self._ix(k) + i, 1.0)
                put(row + 1, self._ie(k) + b, 1.0)  # x + e >= -bound
                row += 2
        for k in range(1, H + 1):
            for b in range(nb):
                put(row, self._ie(k) + b, 1.0)
                row += 1
        self.m = row
        self._values = np.array(vals)
        # The CSC order of the COO entries (all distinct), to update the values in place.
        order = sparse.csc_matrix(
            (np.arange(1, len(vals) + 1, dtype=float), (rows, cols)), shape=(self.m, self.n)
        )
        self._perm = order.data.astype(int) - 1
        return sparse.csc_matrix(
            (self._values[self._perm], order.indices, order.indptr), order.shape
        )

    def solve(self, x0, A_list, B_list, c_list, references, u_previous, bounds) -> QpSolution:
        """Solve for initial state ``x0``, stage models ``x_(k+1) = A_k x_k + B_k u_k + c_k``,
        state references ``r_1..r_H`` (shape (H, nx)), the last applied input and the soft
        bounds (one per bounded state)."""
        nx, nu, H = self.nx, self.nu, self.H
        values = self._values
        for k, (a_slot, b_slot) in enumerate(self._dyn_slots):
            values[a_slot : a_slot + nx * nx] = -np.asarray(A_list[k]).ravel()
            values[b_slot : b_slot + nx * nu] = -np.asarray(B_list[k]).ravel()
        self.lower[:nx] = self.upper[:nx] = x0
        lo, hi = self._dyn_rows
        self.lower[lo:hi] = self.upper[lo:hi] = np.concatenate(c_list)
        bounds = np.asarray(bounds, dtype=float)
        row = self._bound_rows
        per_stage = np.empty(2 * bounds.size)
        per_stage[0::2], per_stage[1::2] = bounds, -bounds
        soft = np.tile(per_stage, H)
        end = row + soft.size
        self.upper[row:end:2] = soft[0::2]
        self.lower[row + 1 : end : 2] = soft[1::2]
        q = self._q
        for k in range(1, H + 1):
            q[self._ix(k) : self._ix(k) + nx] = -self._Q * references[k - 1]
        q[self._iu(0) : self._iu(0) + nu] = -self.r_du * np.asarray(u_previous, dtype=float)
        self._solver.update(q=q, l=self.lower, u=self.upper, Ax=values[self._perm])
        result = self._solver.solve(raise_error=False)  # a failed solve is counted, not raised
        ok = result.info.status_val in (1, 2)  # solved, or solved to low accuracy
        x = result.x if ok else np.full(self.n, np.nan)
        states = x[: (H + 1) * nx].reshape(H + 1, nx)
        inputs = x[(H + 1) * nx : (H + 1) * nx + H * nu].reshape(H, nu)
        return QpSolution(states, inputs, ok, int(result.info.iter))

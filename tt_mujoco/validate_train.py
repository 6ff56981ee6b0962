"""Model-versus-analytic checks for a train of N trailers (docs/model.md Section 12).

``python -m tt_mujoco.validate --trailers N`` runs these; the rows have the keys of
:mod:`tt_mujoco.validate`'s single-trailer checks, so the same bounds judge them
(:data:`tt_mujoco.validate.BOUNDS`). Every check works for N = 1 too, where it tests the general
chain code against MuJoCo (``tests/test_validate_train.py``).

1. :func:`check_inertia` - ``Sfull^T M_mujoco Sfull`` against the chain's Mbar(phi_1..phi_N).
2. :func:`check_bias` - ``Sfull^T (qfrc_bias + M Sfull_dot V)`` against the chain's Cbar V.
3. :func:`check_kinematics` - a torque-driven MuJoCo run against the chain's kinematics fed
   with MuJoCo's (v, omega): every axle P_k, every hitch's |beta_k - eta_k phi_k|.
4. :func:`check_energy` - kinetic energy change against the torques' work (reduced train).
5. :func:`check_jackknife` - which gains jackknife forward, hitch by hitch, in both plants.
"""

from __future__ import annotations

import itertools
import math

import mujoco
import numpy as np
from scipy.integrate import solve_ivp

from tt_mujoco.sim.parts.physics import Vehicle
from tt_mujoco.vehicle import reduced, train
from tt_mujoco.vehicle.params import Params

__all__ = [
    "check_bias",
    "check_energy",
    "check_inertia",
    "check_jackknife",
    "check_kinematics",
    "damped_program",
    "run_train",
    "torque_program_dynamics",
    "train_params",
]


def damped_program(base: float, weave: float, yaw_damping: float):
    """Wheel torques (T_r, T_l): a constant drive ``base`` on both wheels, a slow weave
    ``+-weave sin(0.8 t)`` and a yaw-rate damping term. The damping (no model in it) keeps the
    yaw mode, which is open-loop unstable when reversing a loaded trailer, from running away."""

    def program(t: float, omega: float) -> tuple[float, float]:
        diff = weave * math.sin(0.8 * t) - yaw_damping * omega
        return base + diff, base - diff

    return program


def torque_program_dynamics(t: float) -> tuple[float, float]:
    """Open-loop torques for the dynamics comparison: within traction (< 1 N m per wheel)."""
    common = 0.4 + 0.3 * math.sin(2.0 * t)
    diff = 0.25 * math.sin(3.0 * t + 0.5)
    return common + diff, common - diff


def _drive_scale(p: Params) -> float:
    """The train's mass over the single trailer's: drives scaled by it cover the same ground."""
    return p.total_mass / Params(eta=p.eta).total_mass


def train_params(n: int, eta="same_path") -> Params:
    """The paper's vehicle with ``n`` trailers, each a copy of the first, steered by ``eta``."""
    return Params(eta=eta).with_trailers(n)


def _random_phis(rng: np.random.Generator, p: Params, fraction: float = 0.9) -> tuple:
    """Hitch angles inside every trailer's non-singular range (at most 60 deg)."""
    return tuple(
        float(rng.uniform(-1.0, 1.0)) * min(limit, math.radians(60.0)) * fraction
        for limit in p.phi_singulars
    )


def check_inertia(p: Params, samples: int = 100, seed: int = 0) -> dict:
    """Max relative error of MuJoCo's mass matrix projected on the rolling subspace against the
    chain's Mbar, over random poses (round-off: ~1e-14)."""
    rng = np.random.default_rng(seed)
    veh = Vehicle(p)
    worst = 0.0
    for _ in range(samples):
        phis = _random_phis(rng, p)
        theta = float(rng.uniform(-math.pi, math.pi))
        veh.set_state(x=float(rng.normal()), y=float(rng.normal()), theta=theta, phi=phis)
        S = veh.rolling_selection(phis, theta)
        projected = S.T @ veh.full_mass_matrix() @ S
        M11, M12, M22 = train.mass_and_bias(phis, 0.0, 0.0, p)[0]
        analytic = np.array([[M11, M12], [M12, M22]])
        worst = max(worst, float(np.abs(projected - analytic).max() / np.abs(analytic).max()))
    return {"eta": p.eta, "trailers": p.n_trailers, "samples": samples, "max_rel_error": worst}


def check_bias(p: Params, samples: int = 50, seed: int = 1) -> dict:
    """Max relative error of the chain's Cbar V against MuJoCo's velocity-product forces on the
    rolling subspace, ``Sfull^T (qfrc_bias + M dSfull/dt V)`` with gravity off; ``dSfull/dt V``
    by five-point central differences along (theta, phi_k) with step 1e-5 (agreement ~1e-9)."""
    rng = np.random.default_rng(seed)
    veh = Vehicle(p)
    veh.model.opt.gravity[:] = 0.0
    worst = 0.0
    h = 1e-5
    for _ in range(samples):
        phis = np.array(_random_phis(rng, p, 0.8))
        theta = float(rng.uniform(-math.pi, math.pi))
        V = rng.normal(size=2)
        veh.set_state(theta=theta, phi=tuple(phis), v=V[0], omega=V[1])
        M = veh.full_mass_matrix()
        S = veh.rolling_selection(tuple(phis), theta)
        phi_dots = np.array([row[0] for row in train.trailer_rates(tuple(phis), *V, p)])
        # Five-point central difference: O(h^4) truncation, so h can stay large enough for
        # round-off (near |beta| = 90 deg a two-point one at h = 1e-6 reaches 2.6e-7).
        at = [
            veh.rolling_selection(tuple(phis + step * phi_dots), theta + step * V[1])
            for step in (-2 * h, -h, h, 2 * h)
        ]
        dS = (at[0] - 8 * at[1] + 8 * at[2] - at[3]) / (12 * h)
        mujoco_c = S.T @ (veh.data.qfrc_bias + M @ (dS @ V))
        analytic_c = np.array(train.mass_and_bias(tuple(phis), V[0], V[1], p)[1])
        scale = max(float(np.abs(mujoco_c).max()), 1e-9)
        worst = max(worst, float(np.abs(mujoco_c - analytic_c).max() / scale))
    return {"eta": p.eta, "trailers": p.n_trailers, "samples": samples, "max_rel_error": worst}


def _mujoco_run(p: Params, duration: float, program, v0: float = 0.0, phi0: float = 0.0):
    """Step MuJoCo with a torque program ``(t, omega) -> (T_r, T_l)``; the measurement (with
    every trailer) after each step, and MuJoCo's hitch rates phi_k_dot, as two lists."""
    veh = Vehicle(p)
    veh.set_state(v=v0, phi=phi0)
    m, d = veh.model, veh.data
    hitches = [veh.layout.hitch_v] + [row[1] for row in veh.layout.train]
    n = int(round(duration / p.timestep))
    out, rates = [veh.measure()], [-d.qvel[hitches]]
    for _ in range(n):
        veh.set_torque(*program(d.time, out[-1].omega))
        mujoco.mj_step(m, d)
        out.append(veh.measure())
        rates.append(-d.qvel[hitches])
    return out, rates


def _axles(me) -> list[tuple[float, float]]:
    return [(me.x0, me.y0)] + [(row[0], row[1]) for row in getattr(me, "train", ())]


def check_kinematics(p: Params, direction: int = 1, duration: float = 10.0) -> dict:
    """MuJoCo against the chain's kinematics on a long weaving run.

    The pose ``(x, y, theta, phi_1..phi_N)`` is integrated (midpoint rule) with the (v, omega)
    MuJoCo produced, from the same start; the axles P_k follow from it. The drive torque grows
    with the train's mass so that it covers about the single trailer's distance. Reported:
    distance, the final error of P and the worst final error over the axles P_k
    (``final_P0_error_m``, with each trailer's in ``final_P_k_error_m``), and the largest
    ``|beta_k - eta_k phi_k|`` over all hitches.
    """
    n = p.n_trailers
    scale = _drive_scale(p)
    program = damped_program(0.2 * direction * scale, 0.1 * scale, 2.0 * scale)
    run, hitch_rates = _mujoco_run(p, duration, program)
    dt = p.timestep
    q = np.array([run[0].x, run[0].y, run[0].theta, *run[0].phis])
    for a, b in itertools.pairwise(run):
        v, w = 0.5 * (a.v + b.v), 0.5 * (a.omega + b.omega)
        half = q + 0.5 * dt * np.array(train.rates(q[2], tuple(q[3:]), v, w, p)[: 3 + n])
        q = q + dt * np.array(train.rates(half[2], tuple(half[3:]), v, w, p)[: 3 + n])
    places = train.poses(q[0], q[1], q[2], tuple(q[3:]), p)
    last = run[-1]
    errors = [
        math.hypot(px - mx, py - my)
        for (_, _, px, py, _), (mx, my) in zip(places, _axles(last), strict=True)
    ]
    violation = max(_violation(me, p) for me in run)
    formula = np.array(
        [[row[0] for row in train.trailer_rates(me.phis, me.v, me.omega, p)] for me in run]
    )
    rate_error = np.sqrt(np.mean((np.array(hitch_rates) - formula) ** 2)) / np.sqrt(
        np.mean(formula**2)
    )
    xy = np.array([(me.x, me.y) for me in run])
    out = {
        "eta": p.eta,
        "trailers": n,
        "direction": "forward" if direction > 0 else "reverse",
        "distance_m": float(np.sum(np.hypot(*np.diff(xy, axis=0).T))),
        "phi_max_abs_deg": float(max(math.degrees(max(abs(a) for a in me.phis)) for me in run)),
        "final_P_error_m": float(math.hypot(q[0] - last.x, q[1] - last.y)),
        "final_P0_error_m": float(max(errors)),
    }
    out.update({f"final_P_{k}_error_m": float(e) for k, e in enumerate(errors, start=1)})
    out["phi_dot_rel_rms_error"] = float(rate_error)
    out["eq_violation_max_rad"] = float(violation)
    return out


def _violation(me, p: Params) -> float:
    """The largest ``|beta_k - eta_k phi_k|`` over the hitches of one measurement."""
    rows = [(me.phi, me.beta, p.eta)]
    train_rows = zip(getattr(me, "train", ()), p.train, strict=True)
    rows += [(row[3], row[4], t.eta) for row, t in train_rows]
    return max(abs(beta - eta * phi) for phi, beta, eta in rows)


def check_energy(p: Params, forced: bool, duration: float = 2.0) -> dict:
    """Kinetic energy change against the torques' work for the reduced train, integrated with
    DOP853 at rtol = atol = 1e-12 (the balance then holds to ~1e-10)."""
    n = p.n_trailers
    B = reduced.input_matrix(p)

    def tau_fn(t):
        return np.array(torque_program_dynamics(t)) if forced else np.zeros(2)

    def rhs(t, y):
        phis, V = tuple(y[3 : 3 + n]), y[3 + n : 5 + n]
        (M11, M12, M22), bias = train.mass_and_bias(phis, V[0], V[1], p)
        tau = tau_fn(t)
        V_dot = np.linalg.solve([[M11, M12], [M12, M22]], B @ tau - np.array(bias))
        rates = train.rates(y[2], phis, V[0], V[1], p)[: 3 + n]
        return [*rates, *V_dot, float(V @ B @ tau)]

    y0 = np.array([0.0, 0.0, 0.0, *([math.radians(2.0)] * n), 0.4, 0.1, 0.0])
    sol = solve_ivp(rhs, (0, duration), y0, method="DOP853", rtol=1e-12, atol=1e-12)
    y1 = sol.y[:, -1]
    ke0 = train.kinetic_energy(tuple(y0[3 : 3 + n]), y0[3 + n : 5 + n], p)
    ke1 = train.kinetic_energy(tuple(y1[3 : 3 + n]), y1[3 + n : 5 + n], p)
    work = float(y1[-1])
    return {
        "eta": p.eta,
        "trailers": n,
        "forced": forced,
        "ke_start_J": ke0,
        "ke_end_J": ke1,
        "work_J": work,
        "rel_error": abs(ke1 - ke0 - work) / max(ke0, ke1, abs(work)),
    }


def check_jackknife(p: Params, direction: int = 1, duration: float = 4.0) -> dict:
    """Does the train hold its hitches straight? From 1 deg on every hitch at 0.5 m/s with a
    yaw-damped drive (as :func:`check_kinematics`), on both plants; each hitch's largest |phi_k|
    (deg) and whether any passed 45 deg or, on the reduced plant, reached the singularity
    |beta_k| = 90 deg (a jackknife)."""
    n = p.n_trailers
    phi0 = math.radians(1.0) * direction
    scale = _drive_scale(p)
    program = damped_program(0.3 * direction * scale, 0.0, 2.0 * scale)

    veh = Vehicle(p)
    veh.set_state(v=0.5 * direction, phi=(phi0,) * n)
    worst_mujoco = [0.0] * n
    for _ in range(int(round(duration / p.timestep))):
        veh.set_torque(*program(0.0, veh.data.qvel[veh.layout.root_v + 5]))
        mujoco.mj_step(veh.model, veh.data)
        me = veh.measure()
        worst_mujoco = [max(w, abs(a)) for w, a in zip(worst_mujoco, me.phis, strict=True)]
        if max(worst_mujoco) > math.radians(45.0) or veh.data.warning.number.any():
            break
    ode = train.TrainODE(p, state=[0.0, 0.0, 0.0, *([phi0] * n), 0.0, 0.0, 0.5 * direction, 0.0])
    worst_reduced = [0.0] * n
    singular = False
    try:
        while ode.time < duration - 1e-12:
            ode.step(program(0.0, ode.state[-1]), p.timestep)
            phis = ode.state[3 : 3 + n]
            worst_reduced = [max(w, abs(a)) for w, a in zip(worst_reduced, phis, strict=True)]
            if max(worst_reduced) > math.radians(45.0):
                break
    except reduced.SingularityError:
        singular = True  # |beta_k| reached 90 deg: the largest angles reached are reported
    out = {"etas": ", ".join(f"{e:.4g}" for e in p.etas), "trailers": n}
    out["direction"] = "forward" if direction > 0 else "reverse"
    for k in range(n):
        out[f"phi_{k + 1}_max_deg_mujoco"] = math.degrees(worst_mujoco[k])
        out[f"phi_{k + 1}_max_deg_reduced"] = math.degrees(worst_reduced[k])
    limit = math.radians(45.0)
    out["jackknife_mujoco"] = max(worst_mujoco) > limit
    out["jackknife_reduced"] = singular or max(worst_reduced) > limit
    return out


def run_train(n: int) -> dict:
    """Every check for a train of ``n`` same-path trailers (and plain and paper-steered ones
    where the steering matters), as one JSON-serialisable dict."""
    presets = {
        "same_path": train_params(n),
        "plain": train_params(n, 0.0),
        "paper": train_params(n, "paper"),
    }
    return {
        "inertia": [check_inertia(p) for p in presets.values()],
        "coriolis": [check_bias(p) for p in presets.values()],
        "kinematics": [check_kinematics(presets["same_path"], +1)],
        "train_jackknife": [
            check_jackknife(presets[name], direction)
            for name in ("same_path", "plain", "paper")
            for direction in (+1, -1)
        ],
        "energy": [
            check_energy(presets[name], forced)
            for name in ("same_path", "plain")
            for forced in (False, True)
        ],
    }

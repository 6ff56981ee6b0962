"""Model-versus-analytic checks: MuJoCo's multibody model against the reduced model.

``python -m tt_mujoco.validate`` runs every check and writes ``report.md`` and ``report.json``
(default folder ``renders/validation``). The tests in ``tests/test_validation.py`` call the same
functions and assert the thresholds given in each docstring.

Checks (docs/model.md Sections 2-5):

1. :func:`check_inertia` - ``Sfull^T M_mujoco Sfull`` against Mbar(phi) at random configurations.
2. :func:`check_coriolis` - ``Sfull^T (qfrc_bias + M Sfull_dot V)`` against Cbar V: catches a
   Coriolis term that does no work, which an energy balance cannot see (docs/model.md Section 4).
3. :func:`check_kinematics` - a long torque-driven MuJoCo run against the analytic kinematics
   fed with MuJoCo's measured (v, omega).
4. :func:`check_dynamics` - the same torque program on MuJoCo and on the reduced ODE.
5. :func:`check_energy` - kinetic energy change equals the wheel torques' work (reduced model).
6. :func:`check_jackknife` - forward driving with eta = 3 jackknifes; same_path does not.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Callable
from pathlib import Path

import mujoco
import numpy as np
from scipy.integrate import solve_ivp

from tt_mujoco import guard
from tt_mujoco.cliargs import Parser
from tt_mujoco.defaults import EXIT_BAD_INPUT, EXIT_OK
from tt_mujoco.outputs import (
    OutputError,
    atomic_write,
    claim_folder,
    release_folder,
    write_json,
)
from tt_mujoco.sim.parts.physics import Vehicle
from tt_mujoco.validate_train import damped_program, run_train, torque_program_dynamics
from tt_mujoco.vehicle import reduced
from tt_mujoco.vehicle.params import MAX_TRAILERS, Params

__all__ = [
    "check_coriolis",
    "check_dynamics",
    "check_energy",
    "check_inertia",
    "check_jackknife",
    "check_kinematics",
    "run_all",
]

DEFAULT_OUT = Path("renders/validation")


def _random_phi(rng: np.random.Generator, p: Params, fraction: float = 0.9) -> float:
    """An articulation angle inside the non-singular range (at most 80 deg for eta = 0)."""
    limit = min(p.phi_singular, math.radians(80.0)) * fraction
    return float(rng.uniform(-limit, limit))


def check_inertia(p: Params, samples: int = 100, seed: int = 0) -> dict:
    """Max relative error of ``Sfull^T M Sfull`` against ``Mbar(phi)`` over random poses.

    The MJCF uses docs/model.md Section 4's mass layout body for body, so the only remainder is
    round-off
    (measured ~1e-14; the massless steering axle's compensation is exact, see ``model.py``).
    """
    rng = np.random.default_rng(seed)
    veh = Vehicle(p)
    worst = 0.0
    for _ in range(samples):
        phi = _random_phi(rng, p)
        theta = float(rng.uniform(-math.pi, math.pi))
        veh.set_state(x=float(rng.normal()), y=float(rng.normal()), theta=theta, phi=phi)
        S = veh.full_selection(phi, theta)
        projected = S.T @ veh.full_mass_matrix() @ S
        analytic = reduced.mass_matrix(phi, p)
        worst = max(worst, float(np.abs(projected - analytic).max() / np.abs(analytic).max()))
    return {"eta": p.eta, "samples": samples, "max_rel_error": worst}


def check_coriolis(
    p: Params,
    samples: int = 50,
    seed: int = 1,
    coriolis: Callable[[float, np.ndarray, Params], np.ndarray] = reduced.coriolis_force,
) -> dict:
    """Max relative error of the reduced velocity-product forces against MuJoCo's.

    Under rolling, ``qvel = Sfull(q) V``, so the reduced generalized forces are
    ``Sfull^T (qfrc_bias + M dSfull/dt V)`` with gravity off; ``dSfull/dt V`` is taken by central
    differences along (theta, phi) with step 1e-6, which limits the agreement to ~1e-8.
    """
    rng = np.random.default_rng(seed)
    veh = Vehicle(p)
    veh.model.opt.gravity[:] = 0.0
    worst = 0.0
    h = 1e-6
    for _ in range(samples):
        phi = _random_phi(rng, p, 0.8)
        theta = float(rng.uniform(-math.pi, math.pi))
        V = rng.normal(size=2)
        veh.set_state(theta=theta, phi=phi, v=V[0], omega=V[1])
        M = veh.full_mass_matrix()
        S = veh.full_selection(phi, theta)
        s1, s2 = reduced.phi_rate(phi, p)
        phi_dot = s1 * V[0] + s2 * V[1]
        dS = (
            veh.full_selection(phi + h * phi_dot, theta + h * V[1])
            - veh.full_selection(phi - h * phi_dot, theta - h * V[1])
        ) / (2 * h)
        mujoco_c = S.T @ (veh.data.qfrc_bias + M @ (dS @ V))
        analytic_c = coriolis(phi, V, p)
        scale = max(float(np.abs(mujoco_c).max()), 1e-9)
        worst = max(worst, float(np.abs(mujoco_c - analytic_c).max() / scale))
    return {"eta": p.eta, "samples": samples, "max_rel_error": worst}


def _mujoco_run(p: Params, duration: float, program, v0: float = 0.0, phi0: float = 0.0):
    """Step MuJoCo with a torque program; returns a dict of per-step arrays (after each step)."""
    veh = Vehicle(p)
    veh.set_state(v=v0, phi=phi0)
    m, d = veh.model, veh.data
    n = int(round(duration / p.timestep))
    cols = ("t", "x", "y", "theta", "phi", "beta", "v", "omega", "x0", "y0", "phi_dot", "slip")
    out = np.empty((n + 1, len(cols)))

    def record(k: int) -> None:
        me = veh.measure()
        out[k] = (
            d.time,
            me.x,
            me.y,
            me.theta,
            me.phi,
            me.beta,
            me.v,
            me.omega,
            me.x0,
            me.y0,
            -d.qvel[veh.layout.hitch_v],
            max(abs(me.slip_lateral), abs(me.slip_lateral_trailer)),
        )

    record(0)
    for k in range(n):
        T_r, T_l = program(d.time, out[k, 7])
        veh.set_torque(T_r, T_l)
        mujoco.mj_step(m, d)
        record(k + 1)
    return {c: out[:, i] for i, c in enumerate(cols)}


def check_kinematics(p: Params, direction: int, duration: float = 10.0) -> dict:
    """MuJoCo against the analytic kinematics (docs/model.md Section 2) on a long weaving run.

    The analytic pose ``(x, y, theta, phi)`` is integrated (midpoint rule) with the (v, omega)
    that MuJoCo produced, from the same start; P0 follows from the pose. Reported: distance
    driven, final P and P0 errors, the RMS of MuJoCo's phi_dot minus the formula of docs/model.md
    Section 2 relative to
    the RMS of phi_dot, the max equality violation |beta - eta phi| and the max side slip.
    """
    program = damped_program(base=0.2 * direction, weave=0.1, yaw_damping=2.0)
    run = _mujoco_run(p, duration, program)
    dt = p.timestep
    q = np.array([run["x"][0], run["y"][0], run["theta"][0], run["phi"][0], 0.0, 0.0])
    for k in range(len(run["t"]) - 1):
        V = (0.5 * (run["v"][k] + run["v"][k + 1]), 0.5 * (run["omega"][k] + run["omega"][k + 1]))
        half = q + 0.5 * dt * reduced.kinematics(q, V, p)
        q = q + dt * reduced.kinematics(half, V, p)
    _, P0, _ = reduced.trailer_pose(q[0], q[1], q[2], q[3], p)
    formula = np.array(
        [
            np.dot(reduced.phi_rate(ph, p), (v, w))
            for ph, v, w in zip(run["phi"], run["v"], run["omega"], strict=True)
        ]
    )
    return {
        "eta": p.eta,
        "direction": "forward" if direction > 0 else "reverse",
        "timestep": dt,
        "distance_m": float(np.sum(np.hypot(np.diff(run["x"]), np.diff(run["y"])))),
        "phi_max_abs_deg": float(np.degrees(np.abs(run["phi"]).max())),
        "final_P_error_m": float(math.hypot(q[0] - run["x"][-1], q[1] - run["y"][-1])),
        "final_P0_error_m": float(math.hypot(P0[0] - run["x0"][-1], P0[1] - run["y0"][-1])),
        "phi_dot_rel_rms_error": float(
            np.sqrt(np.mean((run["phi_dot"] - formula) ** 2)) / np.sqrt(np.mean(formula**2))
        ),
        "eq_violation_max_rad": float(np.abs(run["beta"] - p.eta * run["phi"]).max()),
        "slip_lateral_max_m_s": float(run["slip"].max()),
    }


def check_dynamics(p: Params, duration: float = 2.0, v0: float = 0.3) -> dict:
    """(v, omega) of MuJoCo and of the reduced ODE under the same open-loop torques.

    Both start moving straight at ``v0`` (reversing, with the torques negated, for eta > 1,
    which jackknifes forward). Reports max |dv|, max |d omega| and the largest
    lateral slip. Differences come from contact softness: the tyres creep laterally by about
    ``|v omega| * tc / 2`` and longitudinally under torque, which the rolling model forbids.
    """
    sign = -1.0 if p.eta > 1 else 1.0
    v0 *= sign

    def program(t, _omega=0.0):
        T_r, T_l = torque_program_dynamics(t)
        return sign * T_r, sign * T_l

    run = _mujoco_run(p, duration, program, v0=v0)
    plant = reduced.ReducedPlant(p, state=[0, 0, 0, 0, 0, 0, v0, 0.0])
    n = len(run["t"]) - 1
    v_red = np.empty(n + 1)
    w_red = np.empty(n + 1)
    v_red[0], w_red[0] = v0, 0.0
    for k in range(n):
        plant.step(program(k * p.timestep), p.timestep)
        v_red[k + 1], w_red[k + 1] = plant.state[6], plant.state[7]
    return {
        "eta": p.eta,
        "duration_s": duration,
        "v_max_abs_diff": float(np.abs(run["v"] - v_red).max()),
        "omega_max_abs_diff": float(np.abs(run["omega"] - w_red).max()),
        "v_range": float(np.ptp(v_red)),
        "omega_range": float(np.ptp(w_red)),
        "slip_lateral_max_m_s": float(run["slip"].max()),
    }


def _energy_rhs(p: Params, tau_fn, coriolis):
    B = reduced.input_matrix(p)

    def rhs(t, y):
        phi, V = y[3], y[6:8]
        tau = np.asarray(tau_fn(t))
        M = reduced.mass_matrix(phi, p)
        V_dot = np.linalg.solve(M, B @ tau - coriolis(phi, V, p))
        work_rate = float(V @ B @ tau)
        return np.concatenate([reduced.kinematics(y[:6], V, p), V_dot, [work_rate]])

    return rhs


def check_energy(
    p: Params,
    forced: bool,
    duration: float = 2.0,
    coriolis: Callable[[float, np.ndarray, Params], np.ndarray] = reduced.coriolis_force,
) -> dict:
    """Kinetic energy change against the torques' work for the reduced model.

    Integrated with DOP853 at rtol = atol = 1e-12, so the balance holds to ~1e-10 when the
    model is consistent; the work is integrated as an extra state. For eta > 1 the vehicle
    reverses (forward it would jackknife before the end).
    """
    sign = -1.0 if p.eta > 1 else 1.0
    y0 = np.array([0, 0, 0, math.radians(2.0), 0, 0, 0.4 * sign, 0.1, 0.0])

    def tau_fn(t):
        if not forced:
            return (0.0, 0.0)
        T_r, T_l = torque_program_dynamics(t)
        return sign * T_r, sign * T_l

    sol = solve_ivp(
        _energy_rhs(p, tau_fn, coriolis), (0, duration), y0, method="DOP853", rtol=1e-12, atol=1e-12
    )
    y1 = sol.y[:, -1]
    ke0 = reduced.kinetic_energy(y0[3], y0[6:8], p)
    ke1 = reduced.kinetic_energy(y1[3], y1[6:8], p)
    work = float(y1[8])
    scale = max(ke0, ke1, abs(work))
    return {
        "eta": p.eta,
        "forced": forced,
        "ke_start_J": ke0,
        "ke_end_J": ke1,
        "work_J": work,
        "rel_error": abs(ke1 - ke0 - work) / scale,
        "phi_end_deg": math.degrees(y1[3]),
    }


def check_jackknife(
    p: Params, duration: float = 3.0, phi0_deg: float = 0.5, v0: float = 0.8, torque: float = 0.5
) -> dict:
    """Forward drive from a 0.5 deg articulation at 0.8 m/s with 0.5 N m on each wheel.

    Linearised at phi = 0, ``phi_dot ~ (eta - 1) v phi / L0`` (docs/model.md Section 3): eta = 3
    grows
    like exp(4 t) at first and jackknifes (the tractor's yaw response slows it later);
    eta < 1 decays. Returns the first time |phi| passed 20 deg
    (or None) in MuJoCo and in the reduced model, and the max |phi| of each.
    """
    phi0 = math.radians(phi0_deg)
    limit = math.radians(20.0)

    def program(_t, _w):
        return torque, torque

    run = _mujoco_run(p, duration, program, v0=v0, phi0=phi0)
    over = np.nonzero(np.abs(run["phi"]) > limit)[0]
    t_mujoco = float(run["t"][over[0]]) if over.size else None

    plant = reduced.ReducedPlant(p, state=[0, 0, 0, phi0, 0, 0, v0, 0.0])
    t_reduced = None
    phi_max_reduced = abs(phi0)
    try:
        while plant.time < duration - 1e-12:
            plant.step((torque, torque), p.timestep)
            phi_max_reduced = max(phi_max_reduced, abs(plant.state[3]))
            if t_reduced is None and abs(plant.state[3]) > limit:
                t_reduced = plant.time
    except reduced.SingularityError:
        phi_max_reduced = p.phi_singular
    return {
        "eta": p.eta,
        "t_over_20deg_mujoco_s": t_mujoco,
        "t_over_20deg_reduced_s": t_reduced,
        "phi_max_abs_deg_mujoco": float(np.degrees(np.abs(run["phi"]).max())),
        "phi_max_abs_deg_reduced": math.degrees(phi_max_reduced),
    }


def run_all() -> dict:
    """Every check at its default settings, as one JSON-serialisable dict."""
    presets = {"paper": Params(eta="paper"), "same_path": Params(), "plain": Params(eta=0.0)}
    return {
        "inertia": [check_inertia(p) for p in presets.values()],
        "coriolis": [check_coriolis(p) for p in presets.values()],
        "kinematics": [
            check_kinematics(presets["same_path"], +1),
            check_kinematics(presets["paper"], -1),
        ],
        "dynamics": [check_dynamics(p) for p in presets.values()],
        "energy": [
            check_energy(presets[name], forced) for name in presets for forced in (False, True)
        ],
        "jackknife": [check_jackknife(presets["paper"]), check_jackknife(presets["same_path"])],
    }


#: The bounds each check must meet (the same as ``tests/test_validation.py``): per section,
#: (quantity, bound, kind) with kind "<" (measured below the bound) or ">" (above it). A
#: jackknife row is judged by its steering: the paper's eta must jackknife (pass 20 deg within
#: 3 s on both plants), the same-path gain must not (stay below 1 deg).
BOUNDS = {
    "inertia": [("max_rel_error", 1e-12, "<")],
    "coriolis": [("max_rel_error", 1e-7, "<")],
    "kinematics": [
        ("distance_m", 6.0, ">"),
        ("final_P_error_m", 2e-3, "<"),
        ("final_P0_error_m", 2e-3, "<"),
        ("phi_dot_rel_rms_error", 0.02, "<"),
        ("eq_violation_max_rad", 1e-4, "<"),
    ],
    "dynamics": [("v_max_abs_diff", 5e-4, "<"), ("omega_max_abs_diff", 5e-3, "<")],
    "energy": [("rel_error", 1e-6, "<")],
}
_JACKKNIFE_PAPER = [("t_over_20deg_mujoco_s", 3.0, "<"), ("t_over_20deg_reduced_s", 3.0, "<")]
_JACKKNIFE_STABLE = [("phi_max_abs_deg_mujoco", 1.0, "<"), ("phi_max_abs_deg_reduced", 1.0, "<")]


def verdicts(results: dict) -> list[dict]:
    """Every bound of every check: section, row, quantity, bound, measured value, pass."""
    out = []
    for section, rows in results.items():
        for i, row in enumerate(rows):
            if section == "jackknife":
                rules = _JACKKNIFE_PAPER if row["eta"] > 1 else _JACKKNIFE_STABLE
            else:
                rules = BOUNDS.get(section, [])
            for quantity, bound, kind in rules:
                value = row.get(quantity)
                ok = value is not None and (value < bound if kind == "<" else value > bound)
                out.append(
                    {
                        "check": section,
                        "row": i,
                        "eta": row.get("eta"),
                        "quantity": quantity,
                        "bound": f"{kind} {bound:g}",
                        "measured": value,
                        "pass": bool(ok),
                    }
                )
    return out


def _cell(value) -> str:
    if value is None:
        return "never"  # e.g. a jackknife time that was never reached
    return f"{value:.4g}" if isinstance(value, float) else str(value)


def _failures(failed: list[dict]) -> str:
    return (
        ("; FAILED: " + ", ".join(f"{c['check']}.{c['quantity']}" for c in failed))
        if failed
        else "."
    )


def validation_markdown(results: dict, trailers: int = 1) -> str:
    checks = verdicts(results)
    failed = [c for c in checks if not c["pass"]]
    command, train = "`python -m tt_mujoco.validate`", ""
    if trailers > 1:
        command = f"`python -m tt_mujoco.validate --trailers {trailers}`"
        train = f" with {trailers} trailers, each a copy of the first"
    lines = [
        f"# Model validation: MuJoCo against the reduced model{train}",
        "",
        f"Produced by {command}. Parameters: the paper's (Section 6.1),",
        f"timestep {Params().timestep} s. See `tt_mujoco/validate.py` for each check's definition.",
        "",
        f"**Verdict: {len(checks) - len(failed)} of {len(checks)} bounds hold"
        + (
            f"; FAILED: {', '.join(c['check'] + '.' + c['quantity'] for c in failed)}**"
            if failed
            else ".**"
        ),
        "",
        "| check | eta | quantity | bound | measured | pass |",
        "|---|---|---|---|---|---|",
    ]
    for c in checks:
        lines.append(
            f"| {c['check']} | {_cell(c['eta'])} | {c['quantity']} | {c['bound']} | "
            f"{_cell(c['measured'])} | {'pass' if c['pass'] else 'FAIL'} |"
        )
    lines.append("")
    for section, rows in results.items():
        lines += [f"## {section}", ""]
        keys = list(rows[0])
        lines.append("| " + " | ".join(keys) + " |")
        lines.append("|" + "---|" * len(keys))
        for row in rows:
            lines.append("| " + " | ".join(_cell(row.get(k)) for k in keys) + " |")
        lines.append("")
    return "\n".join(lines)


@guard.command
def main(argv: list[str] | None = None) -> int:
    """Exit 0 written and every bound holds, 1 written but a bound does not hold, 2 a used or
    unwritable ``--out`` (refused before the checks run)."""
    parser = Parser(
        prog="python -m tt_mujoco.validate",
        description="Check the MuJoCo model against the analytic reduced model. Writes "
        "report.md and report.json into a new folder (never into one with files in it).",
    )
    parser.add_argument(
        "--out", type=Path, default=None, help=f"output folder (default: a new {DEFAULT_OUT}[-N])"
    )
    parser.add_argument(
        "--trailers",
        type=int,
        default=1,
        metavar="N",
        help="check a train of N trailers (1: the paper's vehicle, every check; 2 to "
        f"{MAX_TRAILERS}: the train's checks of tt_mujoco.validate_train)",
    )
    args = parser.parse_args(argv)
    if not 1 <= args.trailers <= MAX_TRAILERS:
        print(
            f"error: --trailers {args.trailers} is not allowed: use 1 to {MAX_TRAILERS}",
            file=sys.stderr,
        )
        return EXIT_BAD_INPUT
    try:
        out, _ = claim_folder(args.out, DEFAULT_OUT)
    except OutputError as err:
        print(f"error: {err}", file=sys.stderr)
        return EXIT_BAD_INPUT
    results = run_all() if args.trailers == 1 else run_train(args.trailers)
    write_json(out / "report.json", {**results, "verdicts": verdicts(results)}, strict=True)
    text = validation_markdown(results, args.trailers)
    atomic_write(out / "report.md", text + "\n")
    release_folder(out)
    print(text)
    print(f"\nwrote {out / 'report.md'} and {out / 'report.json'}")
    failed = [c for c in verdicts(results) if not c["pass"]]
    if failed:
        print(f"error: {len(failed)} validation bound(s) do not hold", file=sys.stderr)
        return 1
    return EXIT_OK


if __name__ == "__main__":
    guard.end(main())

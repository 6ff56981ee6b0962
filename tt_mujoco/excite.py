"""``python -m tt_mujoco.excite``: which run to log so that a fit tells the chosen parameters
apart (:mod:`tt_mujoco.identify`).

At small hitch angles the kinematics see only ``(eta - 1) / L0`` and ``L / L0``: a gentle log
cannot separate ``eta``, ``L`` and ``L0``. This command drives candidate runs on the reduced
plant (the built-in controller, no disturbance: as a logging run would go), paths and speeds of
:data:`CANDIDATES`, and for each predicts what a fit of its log would know: the Fisher
information of the fit's own residuals (:func:`tt_mujoco.identify.step_errors`, their Jacobian
by central differences at the vehicle's parameters) for hitch encoders of ``--encoder-noise-deg``
read at ``--rate``, hence each parameter's 95 % half width and the parameters' correlations.
Runs that come within :data:`JACKKNIFE_MARGIN` of the jackknife angle are left out. The best
candidate (the smallest largest relative half width) is written as ``excitation.toml`` into
``--out``: ``python -m tt_mujoco.run --config OUT/excitation.toml`` logs it.

With ``--fit`` naming masses and inertias (``Mr``, ``Ird``, ...), the candidates are runs whose
speed and turning swing, each logged with the sensors' noise and fitted as ``identify`` fits
it (:mod:`tt_mujoco.excite_inertia`); the best is written with its path.

Exit codes: 0 written; 2 bad input (a parameter not fittable, lengths and masses asked
together, an --out in use, no candidate).
"""

from __future__ import annotations

import dataclasses
import math
import sys
from pathlib import Path

import numpy as np

from tt_mujoco import guard
from tt_mujoco.cliargs import Parser, given
from tt_mujoco.defaults import EXIT_BAD_INPUT, EXIT_OK

__all__ = ["CANDIDATES", "JACKKNIFE_MARGIN", "Candidate", "main", "rank"]

#: The runs tried: a path, its options (``R`` the radius, m; ``cruise`` the speed, m/s) and
#: whether the run backs up (the trailer leading, steered by the hitch cascade).
CANDIDATES = tuple(
    (traj, {"R": radius, "cruise": cruise}, reverse)
    for traj in ("circle", "s_curve")
    for radius in (0.5, 0.75, 1.0, 1.5)
    for cruise in (0.4, 0.8)
    for reverse in (False, True)
)
#: A candidate's largest |hitch angle| stays below this fraction of the jackknife angle.
JACKKNIFE_MARGIN = 0.6


@dataclasses.dataclass(frozen=True)
class Candidate:
    """What a fit of one candidate run's log would know: the run (its path, the path's
    options, backing up or not, its largest hitch angle), and the fit's parameters, their
    values, 95 % half widths, correlations and scales."""

    traj: str
    options: dict
    reverse: bool
    phi_max_deg: float
    names: list
    values: np.ndarray
    half_widths: np.ndarray
    correlation: np.ndarray
    scales: np.ndarray

    @property
    def worst(self) -> float:
        """The largest half width relative to its parameter's scale (its value; the log's
        period for the hitch lag, whose value is 0)."""
        return float(np.max(self.half_widths / self.scales))

    @property
    def max_correlation(self) -> float:
        n = len(self.names)
        off = [abs(self.correlation[i, j]) for i in range(n) for j in range(i + 1, n)]
        return float(max(off, default=0.0))

    def label(self) -> str:
        shown = ", ".join(f"{k}={v:g}" for k, v in self.options.items())
        return f"{self.traj} ({shown}{', backing up' if self.reverse else ''})"


def _predicted(scenario, fit, rate_hz, noise_deg) -> Candidate | None:
    from tt_mujoco.identify import HITCH_LAG, fitted_values, step_errors
    from tt_mujoco.sim import simulate
    from tt_mujoco.vehicle.params import jackknife_phi_deg

    result = simulate(scenario)
    p = scenario.plant_params()
    ts = result.timeseries
    phi_names = ["phi", *(f"phi_{k}" for k in range(2, p.n_trailers + 1))]
    phis = np.column_stack([ts[n] for n in phi_names])
    phi_max = float(np.degrees(np.max(np.abs(phis))))
    limit = min(jackknife_phi_deg(eta) for eta in p.etas)
    if result.status != "ok" or phi_max > JACKKNIFE_MARGIN * limit:
        return None
    stride = max(1, round(1.0 / (rate_hz * scenario.control_dt)))
    rate_hz = 1.0 / (stride * scenario.control_dt)  # the rate of the rows taken: the noise's
    t, v, omega, phis = ts["t"][::stride], ts["v"][::stride], ts["omega"][::stride], phis[::stride]
    keys, names, x = fitted_values(p, fit)
    residuals = step_errors(p, keys, t, v, omega, phis)
    jac = np.empty((residuals(x).size, x.size))
    for j in range(x.size):
        dx = 1e-6 * max(abs(x[j]), 1e-3)
        up, down = x.copy(), x.copy()
        up[j] += dx
        down[j] -= dx
        jac[:, j] = (residuals(up) - residuals(down)) / (2.0 * dx)
    # an encoder's noise sigma on each angle: a step's residual (phi_k+1 - phi_k) / h carries
    # sigma sqrt(2) / h of it
    sigma = math.radians(noise_deg) * math.sqrt(2.0) * rate_hz
    try:
        cov = np.linalg.inv(jac.T @ jac) * sigma * sigma
    except np.linalg.LinAlgError:
        return None
    spread = np.sqrt(np.abs(np.diag(cov)))
    correlation = cov / np.outer(spread, spread)
    options = dict(scenario.path_options)
    scales = [1.0 / rate_hz if n == HITCH_LAG else abs(v) for n, v in zip(names, x, strict=True)]
    scales = np.array(scales)
    return Candidate(
        traj=scenario.traj,
        options=options,
        reverse=scenario.reverse,
        phi_max_deg=phi_max,
        names=names,
        values=x,
        half_widths=1.96 * spread,
        correlation=correlation,
        scales=scales,
    )


def rank(scenario, fit=("L", "L0", "eta"), rate_hz=50.0, noise_deg=0.05) -> list[Candidate]:
    """Every candidate of :data:`CANDIDATES` for ``scenario``'s vehicle (a
    :class:`~tt_mujoco.sim.Scenario`), best first (the smallest largest relative half width);
    those that come too close to a jackknife are left out."""

    out = []
    for traj, options, reverse in CANDIDATES:
        run = dataclasses.replace(
            scenario,
            traj=traj,
            path_options=options,
            reverse=reverse,
            plant="reduced",
            disturbance="none",
        )
        found = _predicted(run, fit, rate_hz, noise_deg)
        if found is not None:
            out.append(found)
    return sorted(out, key=lambda c: c.worst)


def _toml(best: Candidate, scenario) -> str:
    import tomli_w

    doc = {"traj": best.traj, "path_options": best.options, "disturbance": "none"}
    if best.reverse:
        doc["reverse"] = True
    if scenario.trailers > 1:
        doc["trailers"] = scenario.trailers
    return tomli_w.dumps(doc)


def _table(ranked: list[Candidate]) -> str:
    names = ranked[0].names
    head = "| run | max hitch (deg) | " + " | ".join(f"{n} +-" for n in names)
    lines = [head + " | max correlation |", "|" + "---|" * (len(names) + 3)]
    for c in ranked:
        widths = " | ".join(f"{w:.3g}" for w in c.half_widths)
        lines.append(f"| {c.label()} | {c.phi_max_deg:.1f} | {widths} | {c.max_correlation:.3f} |")
    return "\n".join(lines) + "\n"


@guard.command
def main(argv: list[str] | None = None) -> int:
    """``python -m tt_mujoco.excite``: see the module."""
    from tt_mujoco.identify import INERTIAL, KINEMATIC, LogError, fit_names
    from tt_mujoco.outputs import atomic_write, claim_folder, release_folder
    from tt_mujoco.sim import Scenario

    parser = Parser(
        prog="python -m tt_mujoco.excite",
        description="Which run to log so that a fit tells the chosen parameters apart.",
    )
    parser.add_argument(
        "--fit",
        default="L,L0,eta",
        help="of L, L0, eta and hitch_lag (the log's, judged against its period) "
        "(default L,L0,eta), or of the masses and inertias (Mr, Ird, ...: a run whose speed "
        "and turning swing, tt_mujoco.excite_inertia)",
    )
    parser.add_argument("--eta", default="same_path", help="the vehicle's eta")
    parser.add_argument("--trailers", type=int, default=1)
    parser.add_argument("--rate", type=float, default=50.0, help="the log's rate (Hz)")
    parser.add_argument(
        "--encoder-noise-deg", type=float, default=0.05, help="the hitch encoders' noise (deg)"
    )
    parser.add_argument(
        "--snr-db", type=float, default=20.0, help="masses: the sensors' noise (dB, default 20)"
    )
    parser.add_argument(
        "--duration", type=float, default=30.0, help="masses: the run's length (s, default 30)"
    )
    parser.add_argument("--out", type=Path, default=None, help="a new folder")
    args = parser.parse_args(argv)

    def fail(message: str) -> int:
        print(f"error: {message}", file=sys.stderr)
        return EXIT_BAD_INPUT

    try:
        fit = fit_names(args.fit, KINEMATIC + INERTIAL)
    except LogError as err:
        return fail(str(err))
    inertial = [name for name in fit if name in INERTIAL]
    if inertial and len(inertial) < len(fit):
        return fail(
            f"--fit {args.fit!r} is not allowed: plan the lengths ({', '.join(KINEMATIC)}) and "
            "the masses and inertias in two excitations"
        )
    idle = _idle_option(args, bool(inertial))
    if idle:
        return fail(idle)
    if inertial:
        return _main_inertial(args, tuple(fit), fail)
    for name, value in (("--rate", args.rate), ("--encoder-noise-deg", args.encoder_noise_deg)):
        if not (math.isfinite(value) and value > 0):
            return fail(f"{name} {value!r} is not allowed: give a positive number")
    try:
        scenario = Scenario(eta=args.eta, trailers=args.trailers)
        scenario.validate()
        if args.rate > 1.0 / scenario.control_dt:
            return fail(
                f"--rate {args.rate!r} is not allowed: a log is at most as fast as the "
                f"simulation's control rate, {1.0 / scenario.control_dt:g} Hz"
            )
        out, _ = claim_folder(args.out, Path("renders") / "excite")
    except ValueError as err:
        return fail(str(err))
    ranked = rank(scenario, fit, args.rate, args.encoder_noise_deg)
    if not ranked:
        release_folder(out)
        return fail("no candidate run keeps its hitches well short of a jackknife")
    best = ranked[0]
    atomic_write(out / "excitation.toml", _toml(best, scenario))
    atomic_write(out / "excitation.md", _table(ranked))
    release_folder(out)
    print(_table(ranked), end="")
    print(
        f"best: {best.label()}, every parameter within {100 * best.worst:.2g} % (95 %); "
        f"log it with: python -m tt_mujoco.run --config {out}/excitation.toml"
    )
    return EXIT_OK


def _idle_option(args, inertial: bool) -> str:
    """Why an option the command line gave does nothing for the excitation ``--fit`` asks
    (the other one's: ``--duration`` for the lengths, ``--rate`` for the masses), or ""."""
    said = given(args)
    other_plans = ("rate", "encoder_noise_deg") if inertial else ("snr_db", "duration")
    idle = [said[dest] for dest in other_plans if dest in said]
    if not idle:
        return ""
    planned = "masses and inertias" if inertial else "lengths"
    return f"{idle[0]} does nothing where --fit {args.fit!r} plans the {planned}: drop it"


def _main_inertial(args, fit: tuple, fail) -> int:
    """``excite --fit Mr,...``: the run whose log tells the masses and inertias best
    (:mod:`tt_mujoco.excite_inertia`), written with its path."""
    from tt_mujoco import excite_inertia
    from tt_mujoco.defaults import MAX_DURATION
    from tt_mujoco.outputs import atomic_write, claim_folder, release_folder
    from tt_mujoco.sim import Scenario

    if not (math.isfinite(args.snr_db) and 0.0 < args.snr_db <= 200.0):
        return fail(f"--snr-db {args.snr_db!r} is not allowed: give a number in (0, 200] dB")
    if not (math.isfinite(args.duration) and 5.0 <= args.duration <= MAX_DURATION):
        return fail(f"--duration {args.duration!r} is not allowed: give 5 to {MAX_DURATION:g} s")
    try:
        scenario = Scenario(eta=args.eta, trailers=args.trailers)
        scenario.validate()
        out, _ = claim_folder(args.out, Path("renders") / "excite")
    except ValueError as err:
        return fail(str(err))
    ranked = excite_inertia.rank_inertial(scenario, fit, args.snr_db, args.duration)
    if not ranked:
        release_folder(out)
        return fail("no candidate run could be logged and fitted")
    best = ranked[0]
    atomic_write(out / "excitation_path.csv", excite_inertia.path_csv(best, args.duration))
    atomic_write(out / "excitation.toml", excite_inertia.run_toml(scenario, args.duration))
    atomic_write(out / "excitation.md", excite_inertia.table(ranked))
    release_folder(out)
    print(excite_inertia.table(ranked), end="")
    print(
        f"best: {best.label()}, every parameter within {100 * best.worst:.2g} % (95 %); "
        f"log it with: python -m tt_mujoco.run --config {out}/excitation.toml"
    )
    return EXIT_OK


if __name__ == "__main__":
    guard.end(main())

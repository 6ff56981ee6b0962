"""``python -m tt_mujoco.identify LOG``: the trailers' geometry and steering gains fitted to a
log of the vehicle, with confidence intervals and what the log cannot tell apart.

A log is a CSV or Parquet file, or a run's folder (its time series), with the columns ``t`` (s,
strictly increasing), ``v`` (m/s) and ``omega`` (rad/s) of the tractor's axle, and ``phi``,
``phi_2``, ... (rad) of the hitches (``--columns phi=hitch_deg`` maps another name; a name
ending in ``_deg`` is read in degrees; without ``v`` and ``omega``, they come from the wheels'
rates ``wheel_rate_r``, ``wheel_rate_l`` and ``--wheel RADIUS,TRACK``, or from the axle's pose
``x``, ``y``, ``theta``); or an MCAP file of ROS 2 messages (the mcap extra): ``t``, ``v`` and
``omega`` from the odometry topic, the hitch angles from the joint states' ``hitch_1``,
``hitch_2``, ... (``--topics odom=/my/odom``, ``--columns phi=my_hitch_joint``), each topic at
its own rate (:func:`tt_mujoco.bag.read_bag_log`). Each hitch angle moves by the train's
kinematics (docs/model.md Section 2, paper eq. 13 for one trailer;
:func:`tt_mujoco.vehicle.train.trailer_rates_of` for N): its rate is a function of the hitch
angles, ``v`` and ``omega``, and of each trailer's ``L``, ``L0`` and ``eta``. The fit (scipy's
``least_squares``) makes each logged step of the hitch angles the one the kinematics predict
from the step before (RK4 under the logged inputs; not rates by differences, whose bias a log
at 25 Hz feels), over the parameters chosen with ``--fit`` (default ``L,L0``: each trailer's;
``eta`` too where the log can tell it; ``hitch_lag``, how late the hitch angles are logged
after the inputs they answer, an encoder's filter or a bus's latency, which left unfitted
biases the lengths). Then the fitted train is replayed open loop (its hitch angles integrated
from the first logged ones under the logged ``v``, ``omega``) and its hitch angles compared
with the log.

The masses and inertias ``--fit`` names (``Mr``, ``Ird``, ... of
:data:`tt_mujoco.identify_inertia.INERTIAL`) are fitted to the log's wheel torques ``T_r``,
``T_l`` after the lengths, and ``--payload K`` finds a load put on trailer K during the log
(:mod:`tt_mujoco.identify_inertia`); ``--config FILE`` gives the vehicle what is not fitted
is taken from, and the fit's first guess.

Written into ``--out`` (a new folder): ``identified.toml`` (the fitted vehicle, a scenario file
every command takes: ``python -m tt_mujoco.run --config identified.toml``), ``identify.json``
(estimates, 95 % confidence intervals, correlations, the replay's errors), ``identify.md`` and
the same page as ``identify.html`` with its figures inside (the replayed hitch angles against
the log's, the estimates' correlations; also written as PNG files,
:mod:`tt_mujoco.identify_report`).
Two parameters whose estimates correlate beyond :data:`CORRELATED` (0.95) are reported as not told
apart by this log, with the excitation that would tell them apart. Bad logs (a missing column,
time not increasing, a gap, a value that is not a finite number) are exit 2 naming the column
and the row.
"""

from __future__ import annotations

import dataclasses
import math
import sys
from pathlib import Path

import numpy as np

from tt_mujoco import guard
from tt_mujoco.cliargs import Parser
from tt_mujoco.defaults import EXIT_BAD_INPUT, EXIT_OK
from tt_mujoco.identify_inertia import INERTIAL, check_payload
from tt_mujoco.schema import name_value, table_of
from tt_mujoco.schema_values import number_text
from tt_mujoco.vehicle.params import Params
from tt_mujoco.vehicle_log import (
    CORRELATED,
    NOISY_DB,
    LogError,
    confounded,
    estimates_report,
    input_snr_db,
    read_log,
    smoothed,
)

__all__ = [
    "CORRELATED",
    "FITTABLE",
    "Fit",
    "LogError",
    "fit_names",
    "fit_train",
    "fitted_values",
    "main",
    "read_log",
    "step_errors",
]

#: The parameters the kinematic fit takes: each trailer's, and the log's own ``hitch_lag``.
KINEMATIC = ("L", "L0", "eta", "hitch_lag")
#: Every parameter a fit can take: :data:`KINEMATIC`, and the masses and inertias
#: (:data:`tt_mujoco.identify_inertia.INERTIAL`, fitted to the log's torques).
FITTABLE = (*KINEMATIC, *INERTIAL)
#: How late (s) the hitch angles are logged after the inputs they answer: an encoder's
#: filter or a bus's latency. The log's own, one for every hitch; fitted where asked.
HITCH_LAG = "hitch_lag"
#: The largest hitch lag a fit looks for (s); the rows within it of either end stay out.
LAG_MAX = 0.5
#: At most this many rows enter the fit (the log is thinned evenly beyond it).
FIT_ROWS = 4000
#: The window (s) a noisy log's ``v`` and ``omega`` are averaged over before the fit.
INPUT_WINDOW_S = 0.04


def _with(p: Params, values: dict[tuple[int, str], float]) -> Params:
    """``p`` with trailer k's field set for each ``(k, field)`` (k from 1; the log's hitch lag
    is not ``p``'s): :meth:`~tt_mujoco.vehicle.params.Params.with_unit_fields`."""
    try:
        return p.with_unit_fields({key: x for key, x in values.items() if key[1] != HITCH_LAG})
    except ValueError as err:  # the fit went where no vehicle is: said of the log
        raise LogError(
            f"the fit leads to no vehicle ({err}): a log in other units than the fit reads "
            "does this (t in s, v in m/s, omega in rad/s, the hitch angles in rad, or in "
            "degrees in a column named ..._deg)"
        ) from None


def _rates(p: Params, phis: np.ndarray, v: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """Every hitch's rate (rows, N) by the train's kinematics; NaN where singular."""
    from tt_mujoco.vehicle.train import trailer_rates_of, train_constants

    c = train_constants(p)
    out = [[0.0, 0.0, 0.0] for _ in range(p.n_trailers)]
    rates = np.full(phis.shape, np.nan)
    for i in range(len(v)):
        if trailer_rates_of(phis[i], float(v[i]), float(omega[i]), c, out):
            rates[i] = [row[0] for row in out]
    return rates


class Fit:
    """A fit's estimates, their 95 % intervals and correlations, and the replay's errors."""

    def __init__(
        self,
        names,
        estimates,
        half_widths,
        correlation,
        params,
        replay_rms,
        replay,
        inputs=(math.inf, 0.0),
    ):
        #: the inputs' estimated signal-to-noise ratio (dB) and the window they were averaged
        #: over (s; 0: not averaged)
        self.input_snr_db, self.inputs_smoothed_s = inputs
        #: the log's times and hitch angles (rows), and the fitted train's replayed (NaN
        #: where the replay has none): what the report draws
        self.t, self.logged, self.replayed = replay
        self.names = list(names)
        self.estimates = np.asarray(estimates)
        self.half_widths = np.asarray(half_widths)
        self.correlation = np.asarray(correlation)
        self.params = params
        self.replay_rms = list(replay_rms)
        self.phi_max = list(np.max(np.abs(self.logged), axis=0))

    def confounded(self) -> list[tuple[str, str, float]]:
        """The pairs this log does not tell apart: ``(a, b, correlation)``."""
        return confounded(self.names, self.correlation)

    def report(self) -> dict:
        return {
            **estimates_report(self.names, self.estimates, self.half_widths, self.correlation),
            "replay_phi_rms_deg": [math.degrees(r) for r in self.replay_rms],
            "inputs": {
                "snr_db_estimated": self.input_snr_db,
                "averaged_over_s": self.inputs_smoothed_s,
            },
            "phi_max_abs_deg": [math.degrees(m) for m in self.phi_max],
        }


def fit_names(text: str, allowed=FITTABLE) -> tuple[str, ...]:
    """The parameters a ``--fit`` text names, each of ``allowed`` (default :data:`FITTABLE`)
    once.

    Raises
    ------
    LogError
        Naming the text: empty, a name not fittable, or a name given twice.
    """
    names = tuple(name.strip() for name in str(text).split(","))
    twice = sorted({name for name in names if names.count(name) > 1})
    if not all(name in allowed for name in names) or twice:
        why = f"{twice[0]!r} is given twice" if twice else f"choose from {', '.join(allowed)}"
        raise LogError(f"--fit {text!r} is not allowed: {why}")
    return names


def fit_train(t, v, omega, phis, p: Params, fit=("L", "L0"), smooth_s: float | None = None) -> Fit:
    """Fit ``fit`` (of :data:`FITTABLE`, every trailer's) of train ``p`` (its initial guess)
    to a log's ``t, v, omega, phis`` (see the module).

    ``smooth_s``: the window (s) ``v`` and ``omega`` are averaged over before the fit. Noise
    on them biases the fit (errors in the variables: at 20 dB on a 1 kHz log, L comes out 10 %
    short); averaging over :data:`INPUT_WINDOW_S` takes that to about 0.3 %. None (the
    default): averaged where either looks noisier than :data:`NOISY_DB`, not otherwise.
    """
    from scipy.optimize import least_squares

    snr = min(input_snr_db(v), input_snr_db(omega))
    if smooth_s is None:
        smooth_s = INPUT_WINDOW_S if snr < NOISY_DB else 0.0
    if smooth_s > 0.0:
        v, omega = smoothed(v, t, smooth_s), smoothed(omega, t, smooth_s)

    n = phis.shape[1]
    if n != p.n_trailers:
        raise LogError(f"the log has {n} hitch angle column(s); the vehicle has {p.n_trailers}")
    fit = fit_names(",".join(fit), KINEMATIC)
    keys, names, x0 = fitted_values(p, fit)
    residuals = step_errors(p, keys, t, v, omega, phis)

    lower = [{"eta": -np.inf, HITCH_LAG: -LAG_MAX}.get(f, 1e-3) for _, f in keys]
    upper = [LAG_MAX if f == HITCH_LAG else np.inf for _, f in keys]
    result = least_squares(residuals, x0, bounds=(lower, upper), x_scale="jac")
    try:
        design = np.linalg.inv(result.jac.T @ result.jac)
    except np.linalg.LinAlgError:
        design = np.full((len(x0), len(x0)), np.inf)
    if not np.all(np.isfinite(np.diag(design))):  # a log with nothing to tell: refused
        turned = math.degrees(float(np.max(np.abs(phis))))
        dead = [n for n, column in zip(names, result.jac.T, strict=True) if not np.any(column)]
        raise LogError(
            f"the log tells nothing of {', '.join(dead or names)}: its hitch angles reach "
            f"{turned:.3g} deg at most, where the fit's parameters do not change them; log a run "
            "that turns (python -m tt_mujoco.excite plans one)"
        )
    dof = max(result.fun.size - len(x0), 1)
    plain = design * float(result.fun @ result.fun) / dof
    # the intervals: the wider of the plain and the time-correlated estimate; what the log
    # tells apart (the correlations): the design's alone
    robust = (
        _covariance(design, result.jac, result.fun, n) if np.all(np.isfinite(design)) else design
    )
    spread = np.sqrt(np.maximum(np.diag(plain), np.diag(robust)))
    cov = design
    with np.errstate(invalid="ignore", divide="ignore"):
        scale = np.sqrt(np.abs(np.diag(cov)))
        correlation = cov / np.outer(scale, scale)
    values = dict(zip(keys, result.x, strict=True))
    fitted = _with(p, values)
    v, omega = _met(t, v, omega, values.get((0, HITCH_LAG), 0.0))
    start = int(np.flatnonzero(np.isfinite(v))[0])
    errors = np.full_like(phis, np.nan)
    errors[start:] = replay(t[start:], v[start:], omega[start:], phis[start], fitted) - phis[start:]
    return Fit(
        names,
        result.x,
        1.96 * spread,
        correlation,
        fitted,
        np.sqrt(np.nanmean(errors**2, axis=0)),
        (t, phis, phis + errors),
        (snr, smooth_s),
    )


def _covariance(bread: np.ndarray, jac: np.ndarray, residuals: np.ndarray, n: int) -> np.ndarray:
    """The estimates' covariance, robust to residuals correlated in time (Newey-West): the
    residuals of a log are not independent where the model is not the vehicle (a tyre's creep)
    or the inputs were smoothed, and the plain ``sigma^2 (J^T J)^-1`` then gives intervals
    too narrow to hold the truth. ``bread`` is ``(J^T J)^-1``; ``n`` residuals per logged step
    (one per hitch)."""
    scores = (jac * residuals[:, None]).reshape(-1, n, jac.shape[1]).sum(axis=1)  # per step
    rows = scores.shape[0]
    lags = max(1, math.ceil(4.0 * (rows / 100.0) ** (2.0 / 9.0)))  # Newey and West's rule
    meat = scores.T @ scores
    for lag in range(1, lags + 1):
        weight = 1.0 - lag / (lags + 1.0)
        cross = scores[lag:].T @ scores[:-lag]
        meat += weight * (cross + cross.T)
    dof = rows / max(rows - jac.shape[1], 1)
    return bread @ meat @ bread * dof


def fitted_values(p: Params, fit) -> tuple[list, list[str], np.ndarray]:
    """What a fit of ``fit`` (of :data:`FITTABLE`) takes of train ``p``: the ``(trailer,
    field)`` keys, their names (``L``, or ``L_2`` in a train) and their values in ``p``; the
    log's :data:`HITCH_LAG` last, key ``(0, "hitch_lag")``, from 0."""
    n = p.n_trailers
    own = [field for field in fit if field != HITCH_LAG]
    keys = [(k, field) for k in range(1, n + 1) for field in own]
    names = [f"{field}_{k}" if n > 1 else field for k, field in keys]
    values = [getattr(p.trailers[k - 1], field) for k, field in keys]
    if HITCH_LAG in fit:
        keys, names, values = [*keys, (0, HITCH_LAG)], [*names, HITCH_LAG], [*values, 0.0]
    return keys, names, np.array(values, dtype=float)


def _met(t, v, omega, lag: float) -> tuple[np.ndarray, np.ndarray]:
    """The inputs that the hitch angles logged at each ``t`` answer, for a log whose hitch
    angles come ``lag`` (s) late: ``v`` and ``omega`` at ``t - lag``, a cubic spline between
    their samples (the inputs, not the hitch angles: interpolating a noisy encoder would
    average its noise between samples, and the fit would favour lags of half a sample); NaN
    where that is outside the log."""
    if lag == 0.0:
        return v, omega
    at = t - lag
    inside = (at >= t[0]) & (at <= t[-1])
    return tuple(np.where(inside, spline(at), np.nan) for spline in _input_splines(t, v, omega))


def _input_splines(t, v, omega):
    """``v`` and ``omega`` between their samples, for a lagged log: cubic splines of the
    inputs (see :func:`_met`)."""
    from scipy.interpolate import CubicSpline

    return CubicSpline(t, v), CubicSpline(t, omega)


def step_errors(p: Params, keys, t, v, omega, phis):
    """The fit's residuals as a function of the values ``x`` of ``keys`` (``(trailer,
    field)`` pairs of ``p``): each logged step of the hitch angles predicted from the one
    before (RK4, the inputs linear between samples), less the logged one, as a rate (rad/s),
    at most :data:`FIT_ROWS` steps. A derivative taken by differences instead would carry a
    bias of the third derivative times h^2 / 6, which a log at 25 Hz feels."""
    lagged = (0, HITCH_LAG) in keys
    rows = np.arange(len(t) - 1)
    if lagged:  # the rows whose hitch angles lie in the log for any lag the fit may take
        rows = rows[(t[rows] - LAG_MAX >= t[0]) & (t[rows + 1] + LAG_MAX <= t[-1])]
        if rows.size < 2:
            raise LogError(f"the log is too short to fit {HITCH_LAG} (up to {LAG_MAX} s)")
    keep = rows[np.unique(np.linspace(0, rows.size - 1, min(FIT_ROWS, rows.size)).astype(int))]
    h = (t[keep + 1] - t[keep])[:, None]
    ahead = v[keep], omega[keep], v[keep + 1], omega[keep + 1]
    if lagged:
        speeds, rates = _input_splines(t, v, omega)
        lag_index = keys.index((0, HITCH_LAG))

    def residuals(x):
        train = _with(p, dict(zip(keys, x, strict=True)))
        inputs = ahead
        if lagged:  # the inputs the logged hitch angles answer (:func:`_met`)
            at, after = t[keep] - x[lag_index], t[keep + 1] - x[lag_index]
            inputs = speeds(at), rates(at), speeds(after), rates(after)
        error = ((_steps(train, phis[keep], h, *inputs) - phis[keep + 1]) / h).ravel()
        return np.where(np.isfinite(error), error, 10.0)  # singular: far off

    return residuals


def _steps(p: Params, phis, h, v0, w0, v1, w1) -> np.ndarray:
    """One RK4 step of length ``h`` (rows, 1) from each row of ``phis``, the inputs going
    linearly from ``(v0, w0)`` to ``(v1, w1)``: the hitch angles one step on."""
    vm, wm = 0.5 * (v0 + v1), 0.5 * (w0 + w1)
    k1 = _rates(p, phis, v0, w0)
    k2 = _rates(p, phis + 0.5 * h * k1, vm, wm)
    k3 = _rates(p, phis + 0.5 * h * k2, vm, wm)
    k4 = _rates(p, phis + h * k3, v1, w1)
    return phis + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)


def replay(t, v, omega, phi0, p: Params) -> np.ndarray:
    """The hitch angles of train ``p`` from ``phi0`` under the logged ``v``, ``omega`` (RK4 at
    the log's steps, the inputs linear between samples); NaN from a singularity on."""
    phis = np.full((len(t), len(phi0)), np.nan)
    phis[0] = phi0
    for i in range(len(t) - 1):
        nxt = _steps(
            p, phis[i][None, :], t[i + 1] - t[i], v[i : i + 1], omega[i : i + 1],
            v[i + 1 : i + 2], omega[i + 1 : i + 2],
        )[0]  # fmt: skip
        if not np.all(np.isfinite(nxt)):
            break
        phis[i + 1] = nxt
    return phis


def identified_toml(p: Params, inertial=()) -> str:
    """The fitted vehicle as a scenario file every command takes: its trailers' geometry and
    gains, and the masses and inertias ``inertial`` names."""
    import tomli_w

    from tt_mujoco.identify_inertia import TRACTOR_INERTIAL, TRAILER_INERTIAL

    first = p.trailers[0]
    own = [name for name in inertial if name in TRAILER_INERTIAL]
    params = {"L": float(first.L), "L0": float(first.L0)}
    params.update({name: float(getattr(p, name)) for name in inertial if name in TRACTOR_INERTIAL})
    params.update({name: float(getattr(first, name)) for name in own})
    doc = {"eta": float(first.eta), "params": params}
    if p.n_trailers > 1:
        doc["trailers"] = p.n_trailers
        doc["train"] = [
            {"L": float(t.L), "L0": float(t.L0), "eta": float(t.eta)}
            | {name: float(getattr(t, name)) for name in own}
            for t in p.trailers[1:]
        ]
    return "# the vehicle python -m tt_mujoco.identify fitted\n" + tomli_w.dumps(doc)


def _markdown(fit: Fit, log: Path) -> str:
    lines = [
        f"# Identified from {log}",
        "",
        "| parameter | estimate | 95 % interval |",
        "|---|---|---|",
    ]
    for n, e, h in zip(fit.names, fit.estimates, fit.half_widths, strict=True):
        lines.append(f"| {n} | {e:.6g} | {e - h:.6g} .. {e + h:.6g} |")
    if HITCH_LAG in fit.names:
        lines += [
            "",
            f"{HITCH_LAG} (s) is the log's: how late its hitch angles come after the inputs "
            "they answer. It is not the vehicle's, and identified.toml does not carry it.",
        ]
    lines += ["", "Replayed open loop: hitch angle rms error "]
    lines[-1] += ", ".join(f"{math.degrees(r):.3g} deg" for r in fit.replay_rms) + "."
    if fit.inputs_smoothed_s > 0.0:
        lines.append(
            f"v and omega look noisy (about {fit.input_snr_db:.0f} dB): averaged over "
            f"{1000 * fit.inputs_smoothed_s:.0f} ms before the fit, whose noise would bias it."
        )
    for a, b, rho in fit.confounded():
        lines.append(
            f"- {a} and {b} are not told apart by this log (correlation {rho:+.3f}): its hitch "
            f"angles reach {max(math.degrees(m) for m in fit.phi_max):.1f} deg at most; the "
            "terms that separate them grow with the articulation, so drive tighter turns (or "
            "back up), or fix one of them (--fit)."
        )
    return "\n".join(lines) + "\n"


@guard.command
def main(argv: list[str] | None = None) -> int:
    """``python -m tt_mujoco.identify LOG``: see the module. Exit codes: 0 written; 2 bad
    input (a bad log, bad options, an output folder in use)."""
    from tt_mujoco.outputs import atomic_write, claim_folder, release_folder, write_json
    from tt_mujoco.runfolder import check_out

    args = _parser().parse_args(argv)

    def fail(message: str) -> int:
        print(f"error: {message}", file=sys.stderr)
        return EXIT_BAD_INPUT

    try:
        columns = (name_value(item, "--columns", "phi=hitch_deg") for item in args.columns)
        mapping = table_of(columns, "--columns")
        given = (name_value(item, "--topics", "odom=/tractor/odom") for item in args.topics)
        topics = table_of(given, "--topics")
    except ValueError as err:
        return fail(str(err))
    unknown = sorted(set(topics) - {"odom", "joints"})
    if unknown:
        return fail(f"--topics {unknown[0]}=... is not allowed: use odom=TOPIC or joints=TOPIC")
    try:
        if args.out is not None:
            check_out(args.out / "identified.toml")
        wheel = None
        if args.wheel is not None:
            wheel = tuple(number_text(x) for x in args.wheel.split(","))
            if len(wheel) != 2 or not all(
                x is not None and math.isfinite(x) and x > 0 for x in wheel
            ):
                return fail(f"--wheel {args.wheel!r} is not allowed: give RADIUS,TRACK in m")
        fit, inertia = _fits(args, mapping, topics, wheel)
        out, _ = claim_folder(args.out, Path("renders") / f"identify-{args.log.stem}")
    except ValueError as err:  # LogError, a bad --eta or --config, an --out in use
        return fail(str(err))
    fitted = (inertia or fit).params
    report = {} if fit is None else fit.report()
    text = "" if fit is None else _markdown(fit, args.log)
    if inertia is not None:
        report["inertia"] = inertia.report()
        text += inertia.markdown(args.log, fit is None)
    inertial = () if inertia is None else inertia.fields
    atomic_write(out / "identified.toml", identified_toml(fitted, inertial))
    write_json(out / "identify.json", report, strict=True)
    written = ["identified.toml", "identify.json", *_write_report(out, text, fit, inertia)]
    release_folder(out)
    print(text, end="")
    print(f"wrote {', '.join(written)} to {out}/")
    return EXIT_OK


def _write_report(out: Path, text: str, fit, inertia) -> list[str]:
    """The report's files written into ``out``: its figures, ``identify.md`` (showing them)
    and ``identify.html`` (:mod:`tt_mujoco.identify_report`); their names."""
    import io

    from tt_mujoco import identify_report
    from tt_mujoco.outputs import atomic_write

    images = {}
    for name, figure in identify_report.figures(fit, inertia).items():
        buffer = io.BytesIO()
        figure.savefig(buffer, format="png", dpi=identify_report.DPI)
        images[name] = buffer.getvalue()
        atomic_write(out / name, images[name])
    text += identify_report.image_lines(images)
    atomic_write(out / "identify.md", text)
    page = identify_report.html_page(text, images, f"Identified from {out.name}")
    atomic_write(out / "identify.html", page)
    return [*images, "identify.md", "identify.html"]


def _vehicle(config: Path | None, eta: str | None, trailers: int) -> Params:
    """The vehicle a fit starts from: ``--config``'s (its ``eta`` unless ``--eta`` is given)
    or the project's, with as many trailers as the log has hitch angles."""
    from tt_mujoco.sim import Scenario

    if config is None:
        return Scenario(eta="same_path" if eta is None else eta, trailers=trailers).plant_params()
    from tt_mujoco.run import scenario_from_argv

    scenario = scenario_from_argv(["--config", str(config)])
    if scenario.trailers != trailers:
        raise LogError(
            f"--config {str(config)!r} has {scenario.trailers} trailer(s); the log has "
            f"{trailers} hitch angle column(s)"
        )
    if eta is not None:
        scenario = dataclasses.replace(scenario, eta=eta)
    return scenario.plant_params()


def _parser() -> Parser:
    parser = Parser(
        prog="python -m tt_mujoco.identify",
        description="Fit the trailers' L, L0 and eta to a log (t, v, omega, phi, phi_2, ...).",
    )
    parser.add_argument("log", type=Path, metavar="LOG", help="a CSV or Parquet log, or a run")
    parser.add_argument(
        "--fit",
        default="L,L0",
        help="of L, L0, eta (each trailer's), hitch_lag (the log's), and the masses and inertias "
        f"{', '.join(INERTIAL)} (each trailer's; the log's torques T_r, T_l needed) (default L,L0)",
    )
    parser.add_argument(
        "--eta", default=None, help="the initial or fixed eta (default --config's, or same_path)"
    )
    parser.add_argument(
        "--config",
        type=Path,
        default=None,
        metavar="FILE",
        help="a scenario file of the vehicle: what is not fitted, and the fit's first guess",
    )
    parser.add_argument(
        "--payload",
        type=int,
        default=None,
        metavar="K",
        help="find a payload put on trailer K during the log: its time and mass",
    )
    parser.add_argument(
        "--columns", action="append", default=[], metavar="NAME=COLUMN", help="map a column"
    )
    parser.add_argument(
        "--topics",
        action="append",
        default=[],
        metavar="KIND=TOPIC",
        help="an MCAP log's topics: odom=/tractor/odom, joints=/joint_states (the defaults)",
    )
    parser.add_argument(
        "--wheel",
        default=None,
        metavar="RADIUS,TRACK",
        help="the tractor's wheel radius and track (m), for a log of wheel rates "
        "(default the project's vehicle's)",
    )
    parser.add_argument("--out", type=Path, default=None, help="a new folder")
    return parser


def _fits(args, mapping: dict, topics: dict, wheel):
    """The kinematic fit (None where ``--fit`` names no length, gain or lag) and the fit of
    the masses and inertias (None where it names none and no ``--payload``) of the log."""
    names = fit_names(args.fit)
    kinematic = tuple(name for name in names if name not in INERTIAL)
    inertial = tuple(name for name in names if name in INERTIAL)
    dynamic = bool(inertial) or args.payload is not None
    t, v, omega, phis, *torques = read_log(
        args.log, mapping, topics=topics, wheel=wheel, torques=dynamic
    )
    if args.payload is not None:
        check_payload(args.payload, phis.shape[1])
    p = _vehicle(args.config, args.eta, phis.shape[1])
    fit = fit_train(t, v, omega, phis, p, kinematic) if kinematic else None
    if not dynamic:
        return fit, None
    from tt_mujoco.identify_inertia import fit_inertia

    known = p if fit is None else fit.params
    return fit, fit_inertia(t, v, omega, phis, torques[0], known, inertial, args.payload)


if __name__ == "__main__":
    guard.end(main())

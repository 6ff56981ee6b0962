"""The closed loop: one controller against either plant, the MuJoCo model or the reduced ODE.

A :class:`Scenario` holds the whole configuration of a run; :func:`simulate` runs it and returns
a :class:`Result` with the time series (one row per control step), the metrics and the outcome.
The same controller object, target and disturbance drive both plants, so their results compare
like for like:

- the controller sees the measurement (plus optional noise) and the *nominal* reduced model;
- the plant is built from ``nominal.scaled(param_scale)``, times ``plant_scale`` per field
  (parameter uncertainty, SPEC Section 8);
- the paper's disturbance (Section 6.1) enters as matched wheel torques
  ``g_nominal(phi)^-1 Delta(t)`` added outside the actuators' saturation, on both plants; in
  ``wrench`` mode MuJoCo instead gets the equivalent force and yaw moment on the chassis, which
  must be transmitted by the tyres and can exceed traction (SPEC Section 8).

Divergence is detected, never hidden: a jackknife (|beta| or |phi| near 90 deg), a singular
nominal model, non-finite numbers or MuJoCo warnings stop the run, which keeps every sample up
to that point and reports the time and state.

Faults (:mod:`tt_mujoco.sim.faults`: a payload step, sensor dropout, an actuator losing torque)
hook into the loop only when ``Scenario.faults`` lists some; a run without faults takes none of
those branches.
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field

import numpy as np

from tt_mujoco.sim.measure import Measurement
from tt_mujoco.vehicle import reduced
from tt_mujoco.vehicle.params import Params

__all__ = [
    "COLUMNS",
    "Result",
    "Scenario",
    "disturbance",
    "simulate",
]

#: Time-series columns, one row per control step (SI units, radians). See ``metrics.py``.
COLUMNS = (
    "t",
    "x",
    "y",
    "theta",
    "phi",
    "beta",
    "v",
    "omega",
    "x0",
    "y0",
    "theta0",
    "v0",
    "theta_l",
    "theta_r",
    "s",
    "x_ref",
    "y_ref",
    "v_d",
    "omega_d",
    "v_d_dot",
    "omega_d_dot",
    "v_meas",
    "omega_meas",
    "T_r",
    "T_l",
    "T_r_cmd",
    "T_l_cmd",
    "dist_T_r",
    "dist_T_l",
    "slip_lateral",
    "slip_lateral_trailer",
    "slip_left",
    "slip_right",
    "eq_violation",
    "kappa_d",
)

PLANTS = ("mujoco", "reduced")
TARGETS = ("dynamic", "static")
DISTURBANCE_MODES = ("matched", "wrench", "none")
#: A run stops as a jackknife when |beta| or |phi| passes this (just short of the singularity
#: at 90 deg, where the reduced model is undefined and the controller's g blows up).
JACKKNIFE_DEG = 85.0
#: Speeds beyond this are a numerical blow-up, not driving.
MAX_SPEED = 20.0


def jackknife_phi_deg(eta: float) -> float:
    """|phi| (deg) at which a run stops as a jackknife: |beta| = |eta phi| reaches
    :data:`JACKKNIFE_DEG`, or |phi| reaches 90 deg (the trailer across the tractor)."""
    return min(JACKKNIFE_DEG / abs(eta), 90.0) if eta else 90.0


def disturbance(t: float) -> tuple[float, float]:
    """The paper's multi-frequency disturbance (Section 6.1), in (v_dot, omega_dot):
    ``Delta1 = 3.5 + sin(0.3 t) + 0.5 cos(2 t)`` m/s^2, ``Delta2 = 1.5 sin(0.3 t) + 0.5 cos(5 t)``
    rad/s^2 (bounds 5 and 2)."""
    return (
        3.5 + math.sin(0.3 * t) + 0.5 * math.cos(2.0 * t),
        1.5 * math.sin(0.3 * t) + 0.5 * math.cos(5.0 * t),
    )


@dataclass
class Scenario:
    """Everything that defines a run. Defaults are the project's main run."""

    traj: str = "s_curve"
    controller: str = "ismc_sta"
    gains: str | dict | None = None
    target: str = "dynamic"
    plant: str = "mujoco"
    eta: str | float = "same_path"
    disturbance: str = "matched"
    noise_snr_db: float | None = None
    param_scale: float = 1.0
    duration: float | None = None
    seed: int = 0
    timestep: float = 0.001
    control_dt: float = 0.001
    #: "on_path": start in the reference's initial state (pose and speed); "paper": the
    #: paper's initial condition, at rest (and, on the cycloid, at its pose (0, 0, pi/4)).
    start: str = "on_path"
    friction: float = 1.0
    params: dict = field(default_factory=dict)
    #: Per-field factors on the *plant's* masses and inertias only (e.g. ``{"Mr": 1.2}``), on
    #: top of ``param_scale``: a model mismatch the controller does not know about.
    plant_scale: dict = field(default_factory=dict)
    #: Initial articulation phi (deg), with beta = eta phi; must stay short of the jackknife.
    phi0_deg: float = 0.0
    #: Fault specs (dicts or ``KIND:key=value,...`` strings), see :mod:`tt_mujoco.sim.faults`.
    faults: list = field(default_factory=list)
    #: Outer path-feedback loop on omega_d (:mod:`tt_mujoco.reference.feedback`): None (off) or a dict
    #: of gains, ``{}`` for the defaults (k_y, k_psi, c_max).
    path_feedback: dict | None = None
    #: Curvature-scheduled steering (:class:`tt_mujoco.vehicle.steering.EtaScheduler`): the plant's eta
    #: follows the exact same-path gain of the target's curvature; the controller keeps ``eta``.
    eta_schedule: bool = False
    #: Drive the path backwards, trailer first (:class:`tt_mujoco.vehicle.steering.ReverseTarget`).
    reverse: bool = False

    def validate(self) -> None:
        """Raise ValueError naming the first bad field and what is allowed."""
        if self.plant not in PLANTS:
            raise ValueError(f"plant={self.plant!r} is not allowed: use one of {PLANTS}")
        if self.target not in TARGETS:
            raise ValueError(f"target={self.target!r} is not allowed: use one of {TARGETS}")
        if self.disturbance not in DISTURBANCE_MODES:
            raise ValueError(
                f"disturbance={self.disturbance!r} is not allowed: use one of {DISTURBANCE_MODES}"
            )
        if self.duration is not None and not (
            isinstance(self.duration, int | float) and 0 < self.duration <= 600
        ):
            raise ValueError(f"duration={self.duration!r} is not allowed: it must be in (0, 600] s")
        if self.noise_snr_db is not None and not (
            isinstance(self.noise_snr_db, int | float) and math.isfinite(self.noise_snr_db)
        ):
            raise ValueError(
                f"noise SNR={self.noise_snr_db!r} is not allowed: it must be a finite number (dB)"
            )
        if not (isinstance(self.control_dt, int | float) and 0 < self.control_dt <= 0.05):
            raise ValueError(
                f"control_dt={self.control_dt!r} is not allowed: it must be in (0, 0.05] s"
            )
        ratio = self.control_dt / self.timestep
        if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
            raise ValueError(
                f"control_dt={self.control_dt!r} is not allowed: it must be a whole multiple of "
                f"the physics timestep {self.timestep!r}"
            )
        if not isinstance(self.seed, int) or isinstance(self.seed, bool) or self.seed < 0:
            raise ValueError(f"seed={self.seed!r} is not allowed: it must be an integer >= 0")
        for name in ("eta_schedule", "reverse"):
            value = getattr(self, name)
            if not isinstance(value, bool):
                raise ValueError(f"{name}={value!r} is not allowed: use True or False")
        if self.path_feedback is not None:
            from tt_mujoco.reference.feedback import check_config

            check_config(self.path_feedback)
        from tt_mujoco.sim.faults import parse_faults

        parse_faults(self.faults)
        self._check_phi0()

    def _check_phi0(self) -> None:
        phi0 = self.phi0_deg
        if isinstance(phi0, bool) or not isinstance(phi0, int | float) or not math.isfinite(phi0):
            raise ValueError(f"phi0={phi0!r} deg is not allowed: it must be a finite number")
        eta = self.nominal_params().eta
        limit = jackknife_phi_deg(eta)
        if abs(phi0) >= limit:
            singular = math.inf if eta == 0 else 90.0 / abs(eta)
            raise ValueError(
                f"phi0={phi0!r} deg is not allowed: with eta={eta:g} the model is singular at "
                f"|phi| = {singular:.4g} deg (|beta| = |eta phi| = 90 deg) and a run stops as a "
                f"jackknife at |phi| = {limit:.4g} deg; use |phi0| < {limit:.4g} deg"
            )

    def nominal_params(self) -> Params:
        """The controller's model: paper values, this steering and timestep, plus overrides."""
        return Params(eta=self.eta, timestep=self.timestep, friction=self.friction, **self.params)

    def plant_params(self) -> Params:
        """The plant's parameters: nominal, times ``param_scale`` on every mass and inertia,
        times ``plant_scale[field]`` on single ones (SPEC Section 8)."""
        from tt_mujoco.vehicle.params import INERTIA_FIELDS, MASS_FIELDS

        p = self.nominal_params()
        if self.param_scale != 1.0:
            p = p.scaled(self.param_scale)
        if self.plant_scale:
            allowed = MASS_FIELDS + INERTIA_FIELDS
            for name, factor in self.plant_scale.items():
                if name not in allowed:
                    raise ValueError(
                        f"plant_scale field {name!r} is not allowed: use one of {allowed}"
                    )
                if not (isinstance(factor, int | float) and math.isfinite(factor) and factor > 0):
                    raise ValueError(
                        f"plant_scale[{name!r}]={factor!r} is not allowed: "
                        "it must be finite and > 0"
                    )
            p = p.replace(**{k: getattr(p, k) * f for k, f in self.plant_scale.items()})
        return p

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)


@dataclass
class Result:
    """A finished (or stopped) run."""

    scenario: Scenario
    timeseries: dict[str, np.ndarray]
    metrics: dict
    status: str  # "ok", "jackknife" or "diverged"
    message: str
    reference_polyline: np.ndarray
    wall_time_s: float
    config: dict

    @property
    def ok(self) -> bool:
        return self.status == "ok"


class _StopRunError(Exception):
    def __init__(self, status: str, message: str):
        super().__init__(message)
        self.status = status
        self.message = message


class _MujocoPlant:
    """MuJoCo behind the loop's small plant interface."""

    def __init__(self, params: Params, pose, v_init: float, wrench: bool, phi0: float = 0.0):
        import mujoco

        from tt_mujoco.sim.physics import Vehicle

        self._mujoco = mujoco
        self.vehicle = Vehicle(params)
        self.vehicle.set_state(x=pose[0], y=pose[1], theta=pose[2], phi=phi0, v=v_init)
        self.model, self.data = self.vehicle.model, self.vehicle.data
        lay = self.vehicle.layout
        self._wheel_r, self._wheel_l = lay.wheel_right_v, lay.wheel_left_v
        self._act_r, self._act_l = lay.act_right, lay.act_left
        self._tractor = self.model.body("tractor").id
        self._wrench = wrench
        self._steps = 0

    def measure(self):
        return self.vehicle.measure()

    def scale_trailer_mass(self, factor: float) -> None:
        """Payload step: trailer body mass and inertia times ``factor``. MuJoCo builds the
        mass matrix from ``body_mass``/``body_inertia`` every step, so this acts at once
        (only the solver's compile-time ``body_invweight0``, which scales contact softness,
        keeps its old value)."""
        body = self.model.body("trailer_body").id
        self.model.body_mass[body] *= factor
        self.model.body_inertia[body] *= factor

    def apply(self, T_r, T_l, dist_r, dist_l, wrench_force, wrench_torque, theta):
        d = self.data
        d.ctrl[self._act_r] = T_r
        d.ctrl[self._act_l] = T_l
        if self._wrench:
            d.xfrc_applied[self._tractor, 0] = wrench_force * math.cos(theta)
            d.xfrc_applied[self._tractor, 1] = wrench_force * math.sin(theta)
            d.xfrc_applied[self._tractor, 5] = wrench_torque
        else:
            d.qfrc_applied[self._wheel_r] = dist_r
            d.qfrc_applied[self._wheel_l] = dist_l

    def advance(self, substeps: int) -> None:
        self._mujoco.mj_step(self.model, self.data, nstep=substeps)
        self._steps += 1
        if self._steps % 64 == 0:  # warning counters are sticky: checking every step is waste
            self.check_warnings()

    def check_warnings(self) -> None:
        numbers = self.data.warning.number
        if numbers.any():
            i = int(np.flatnonzero(numbers)[0])
            name = self._mujoco.mjtWarning(i).name
            raise _StopRunError("diverged", f"MuJoCo warning {name} by t={self.data.time:.3f} s")


class _ReducedPlantAdapter:
    """The reduced ODE behind the same interface; measurements are exact (no slip)."""

    def __init__(self, params: Params, pose, v_init: float, timestep: float, phi0: float = 0.0):
        self.params = params
        state = [pose[0], pose[1], pose[2], phi0, 0.0, 0.0, v_init, 0.0]
        self.plant = reduced.ReducedPlant(params, state=state)
        self.timestep = timestep
        self._tau = (0.0, 0.0)
        self._accel = (0.0, 0.0)

    def measure(self):
        p = self.params
        x, y, theta, phi, th_l, th_r, v, omega = (float(c) for c in self.plant.state)
        _, P0, theta0 = reduced.trailer_pose(x, y, theta, phi, p)
        v0, _ = reduced.trailer_velocity(phi, (v, omega), p)
        return Measurement(
            x=x,
            y=y,
            theta=theta,
            phi=phi,
            beta=p.eta * phi,
            v=v,
            omega=omega,
            x0=float(P0[0]),
            y0=float(P0[1]),
            theta0=theta0,
            v0=v0,
            theta_l=th_l,
            theta_r=th_r,
            theta_l_dot=(v - 0.5 * p.d * omega) / p.r,
            theta_r_dot=(v + 0.5 * p.d * omega) / p.r,
            slip_lateral=0.0,
            slip_lateral_trailer=0.0,
            slip_left=0.0,
            slip_right=0.0,
        )

    def apply(self, T_r, T_l, dist_r, dist_l, wrench_force, wrench_torque, theta):
        self._tau = (T_r + dist_r, T_l + dist_l)

    def scale_trailer_mass(self, factor: float) -> None:
        """Payload step: the trailer body's ``Mr`` and ``Ird`` times ``factor``."""
        p = self.params
        self.params = p.replace(Mr=p.Mr * factor, Ird=p.Ird * factor)
        self.plant.params = self.params

    def advance(self, substeps: int) -> None:
        for _ in range(substeps):
            self.plant.step(self._tau, self.timestep)

    def check_warnings(self) -> None:
        pass


def _noise_std(target, duration: float, snr_db: float) -> tuple[float, float]:
    """Noise standard deviations for SNR ``snr_db`` per channel.

    Signal power is the mean square of the noise-free reference (v_ref, kappa(s_ref) v_ref) over
    the run, sampled every 10 ms: a property of the scenario, not of the particular run.
    """
    ts = np.arange(0.0, duration, 0.01)
    v = np.asarray(target.reference_speed(ts), dtype=float)
    w = np.asarray(target.reference_yaw_rate(ts), dtype=float)
    scale = 10.0 ** (-snr_db / 10.0)
    return math.sqrt(np.mean(v**2) * scale), math.sqrt(np.mean(w**2) * scale)


_LOOP_COLUMNS = (
    "t",
    "s",
    "v_d",
    "omega_d",
    "v_d_dot",
    "omega_d_dot",
    "v_meas",
    "omega_meas",
    "T_r",
    "T_l",
    "T_r_cmd",
    "T_l_cmd",
    "dist_T_r",
    "dist_T_l",
    "kappa_d",
)


def _assemble_columns(measured: list, logged: list, eta: float) -> dict[str, np.ndarray]:
    """The time series in :data:`COLUMNS` order from the per-step measurement tuples and the
    loop's own values (``x_ref``/``y_ref`` are left NaN for the caller to fill)."""
    n = len(logged)
    meas = np.array(measured, dtype=float).reshape(n, len(Measurement._fields))
    loop = np.array(logged, dtype=float).reshape(n, len(_LOOP_COLUMNS))
    cols = {name: meas[:, i] for i, name in enumerate(Measurement._fields)}
    cols.update({name: loop[:, i] for i, name in enumerate(_LOOP_COLUMNS)})
    cols["eq_violation"] = cols["beta"] - eta * cols["phi"]
    cols["x_ref"] = np.full(n, np.nan)
    cols["y_ref"] = np.full(n, np.nan)
    return {name: np.ascontiguousarray(cols[name]) for name in COLUMNS}


def simulate(scenario: Scenario, progress=None, on_step=None) -> Result:
    """Run one scenario. Never raises for a diverging run: see ``Result.status``.

    Parameters
    ----------
    scenario : Scenario
    progress : callable, optional
        Called as ``progress(steps_done, steps_total)`` about every 1 % of the run.
    on_step : callable, optional
        Called as ``on_step(t, plant)`` after every control step, ``t`` the new time and
        ``plant`` the loop's plant (``.model``/``.data`` on the MuJoCo plant); the live viewer
        uses it. An exception it raises ends the run and propagates.

    Raises
    ------
    ValueError
        For bad configuration values (before anything is simulated).
    """
    from tt_mujoco.analysis import metrics as metrics_mod
    from tt_mujoco.controllers import make_controller, reduced_model
    from tt_mujoco.reference.targets import make_target
    from tt_mujoco.sim import faults as faults_mod

    scenario.validate()
    nominal = scenario.nominal_params()
    plant_p = scenario.plant_params()
    path, target, pose = make_target(
        scenario.traj, kind=scenario.target, duration=scenario.duration, start=scenario.start
    )
    duration = float(target.duration)
    if scenario.reverse:
        from tt_mujoco.vehicle.steering import ReverseTarget

        target = ReverseTarget(target)
        pose = target.initial_pose
    feedback = None
    if scenario.path_feedback is not None:
        from tt_mujoco.reference.feedback import PathFeedback

        feedback = PathFeedback.from_config(target, scenario.path_feedback)
    faults = None
    if scenario.faults:
        faults = faults_mod.FaultSchedule(
            faults_mod.parse_faults(scenario.faults), scenario.control_dt, duration
        )
    # The controller is built before the plant so that bad gains fail before any work.
    ctrl = make_controller(
        scenario.controller,
        reduced_model(nominal),
        torque_limit=nominal.torque_limit,
        gains=scenario.gains,
    )
    rng = np.random.default_rng(scenario.seed)
    if scenario.noise_snr_db is not None:
        noise_v, noise_w = _noise_std(target, duration, float(scenario.noise_snr_db))
    else:
        noise_v = noise_w = 0.0

    # "on_path": the vehicle starts in the reference's initial state, pose *and* speed (paper
    # Section 6.3). The paper's static cycloid target starts at 0.765 m/s while its vehicle is
    # at rest; that step spins the wheels in contact physics. "paper" reproduces it.
    v_init = target.reference_speed(0.0) if scenario.start == "on_path" else 0.0
    phi0 = math.radians(scenario.phi0_deg)
    if scenario.plant == "mujoco":
        wrench_mode = scenario.disturbance == "wrench"
        plant = _MujocoPlant(plant_p, pose, v_init, wrench=wrench_mode, phi0=phi0)
    else:
        plant = _ReducedPlantAdapter(plant_p, pose, v_init, scenario.timestep, phi0=phi0)
    scheduler = None
    if scenario.eta_schedule:
        from tt_mujoco.vehicle.steering import EtaScheduler

        scheduler = EtaScheduler(plant, plant_p)

    dt = scenario.control_dt
    substeps = round(dt / scenario.timestep)
    n = round(duration / dt)
    measured: list = []
    logged: list[tuple] = []
    use_dist = scenario.disturbance != "none"
    wrench = scenario.disturbance == "wrench"
    eta = nominal.eta
    jk = math.radians(JACKKNIFE_DEG)
    jk_phi = min(jk / abs(eta), math.radians(90.0)) if eta else math.radians(90.0)
    # Standard normal draws for (v, omega) at every control step, drawn at once (a scalar
    # Generator call costs ~1.5 us); same stream order as per-step draws: v_k, omega_k, ...
    noise = rng.standard_normal(2 * (n + 1)).tolist() if (noise_v or noise_w) else None
    matched_torque = reduced.matched_torque
    mass_matrix = reduced.mass_matrix
    ctrl.reset()
    target.reset()
    status, message = "ok", f"completed {duration:.3f} s"
    report_every = max(1, n // 100)
    # Bound methods as locals: the loop runs 1000 times a simulated second.
    measure, apply, advance = plant.measure, plant.apply, plant.advance
    target_update, ctrl_step = target.update, ctrl.step
    log_measured, log_loop = measured.append, logged.append
    start_wall = time.perf_counter()
    k = 0
    try:
        for k in range(n + 1):
            t = k * dt
            me = measure()
            if (
                not (math.isfinite(me.x) and math.isfinite(me.v) and math.isfinite(me.omega))
                or abs(me.v) > MAX_SPEED
            ):
                raise _StopRunError("diverged", f"state blew up at t={t:.3f} s: v={me.v!r}")
            if abs(me.phi) >= jk_phi or abs(me.beta) >= jk:
                raise _StopRunError(
                    "jackknife",
                    f"jackknife at t={t:.3f} s: phi={math.degrees(me.phi):.1f} deg, "
                    f"beta={math.degrees(me.beta):.1f} deg (eta={eta:g}; singular at "
                    f"|beta| = 90 deg), x={me.x:.3f} m, y={me.y:.3f} m, v={me.v:.3f} m/s",
                )
            v_m = me.v + noise_v * noise[2 * k] if noise else me.v
            w_m = me.omega + noise_w * noise[2 * k + 1] if noise else me.omega
            phi_m = me.phi
            if faults is not None:
                phi_m, v_m, w_m = faults.sensor(k, phi_m, v_m, w_m)
            if feedback is None:
                v_d, w_d, v_d_dot, w_d_dot = target_update(t, dt, v_m)
            else:
                v_d, w_d, v_d_dot, w_d_dot = feedback.update(t, dt, v_m, me.x, me.y, me.theta)
            try:
                T_r, T_l = ctrl_step(dt, phi_m, v_m, w_m, v_d, w_d, v_d_dot, w_d_dot)
            except FloatingPointError as err:
                msg = f"controller failed at t={t:.3f} s: {err}"
                raise _StopRunError("diverged", msg) from None
            T_r_cmd, T_l_cmd = ctrl.command
            if faults is not None:
                T_r, T_l = faults.torque(k, T_r, T_l)
                factor = faults.payload_factor(k)
                if factor is not None:
                    plant.scale_trailer_mass(factor)
            dist_r = dist_l = force = torque = 0.0
            if use_dist:
                a_v, a_w = disturbance(t)
                if wrench:
                    # The generalized force Mbar Delta, as a force along the heading at P and
                    # a yaw moment: the same effect on (v, omega), but through the tyres.
                    M = mass_matrix(me.phi, nominal)
                    force = M[0, 0] * a_v + M[0, 1] * a_w
                    torque = M[1, 0] * a_v + M[1, 1] * a_w
                else:
                    dist_r, dist_l = matched_torque(me.phi, a_v, a_w, nominal)
            # Log the measurement tuple as it is and the loop's own values beside it:
            # columns are assembled once after the loop (per-step attribute access is costly).
            log_measured(me)
            log_loop(
                (
                    t,
                    target.arc_length,
                    v_d,
                    w_d,
                    v_d_dot,
                    w_d_dot,
                    v_m,
                    w_m,
                    T_r,
                    T_l,
                    T_r_cmd,
                    T_l_cmd,
                    dist_r,
                    dist_l,
                    target.curvature,
                )
            )
            if k == n:
                plant.check_warnings()
                break
            if scheduler is not None:
                scheduler.update(target.curvature, k)
            apply(T_r, T_l, dist_r, dist_l, force, torque, me.theta)
            try:
                advance(substeps)
            except reduced.SingularityError as err:
                raise _StopRunError("jackknife", f"jackknife at t={t + dt:.3f} s: {err}") from None
            if on_step is not None:
                on_step(t + dt, plant)
            if progress is not None and k % report_every == 0:
                progress(k, n)
    except _StopRunError as stop:
        status, message = stop.status, stop.message
    wall = time.perf_counter() - start_wall
    if progress is not None:
        progress(n, n)

    ts = _assemble_columns(measured, logged, eta)
    if scheduler is not None:
        ts["eq_violation"] = ts["beta"] - scheduler.eta_series(len(logged)) * ts["phi"]
    if len(logged):
        ref = target.reference_point(ts["t"])
        ts["x_ref"], ts["y_ref"] = (np.asarray(c, dtype=float) for c in ref)
    polyline = path.dense()
    metrics = metrics_mod.compute_metrics(ts, polyline, nominal.torque_limit)
    metrics["wall_time_s"] = wall
    metrics["status"] = status
    if faults is not None:
        metrics["faults"] = faults_mod.fault_report(faults, ts, polyline, nominal.torque_limit)
    config = {
        "scenario": scenario.to_dict(),
        "nominal_params": nominal.to_dict(),
        "plant_params": plant_p.to_dict(),
        "controller": {"name": ctrl.name, "gains": ctrl.gains},
        "target": {"kind": scenario.target, "duration_s": duration, "path": path.name},
        "noise_std": {"v": noise_v, "omega": noise_w},
        "substeps": substeps,
    }
    return Result(
        scenario=scenario,
        timeseries=ts,
        metrics=metrics,
        status=status,
        message=message,
        reference_polyline=polyline,
        wall_time_s=wall,
        config=config,
    )

"""The closed loop: one controller against either plant, the MuJoCo model or the reduced ODE.

A :class:`Scenario` holds the whole configuration of a run; :func:`simulate` runs it and returns
a :class:`Result` with the time series (one row per control step), the metrics and the outcome.
The same controller object, target and disturbance drive both plants, so their results compare
like for like:

- the controller sees the measurement (plus optional noise) and the *nominal* reduced model;
- the plant is built from ``nominal.scaled(param_scale)`` (parameter uncertainty, SPEC Section 8);
- the paper's disturbance (Section 6.1) enters as matched wheel torques
  ``g_nominal(phi)^-1 Delta(t)`` added outside the actuators' saturation, on both plants; in
  ``wrench`` mode MuJoCo instead gets the equivalent force and yaw moment on the chassis, which
  must be transmitted by the tyres and can exceed traction (SPEC Section 8).

Divergence is detected, never hidden: a jackknife (|beta| or |phi| near 90 deg), a singular
nominal model, non-finite numbers or MuJoCo warnings stop the run, which keeps every sample up
to that point and reports the time and state.
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field

import numpy as np

from tt_mujoco import reduced
from tt_mujoco.params import Params

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

    def nominal_params(self) -> Params:
        """The controller's model: paper values, this steering and timestep, plus overrides."""
        return Params(eta=self.eta, timestep=self.timestep, friction=self.friction, **self.params)

    def plant_params(self) -> Params:
        nominal = self.nominal_params()
        return nominal if self.param_scale == 1.0 else nominal.scaled(self.param_scale)

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

    def __init__(self, params: Params, pose, v_init: float, wrench: bool):
        import mujoco

        from tt_mujoco.physics import Vehicle

        self._mujoco = mujoco
        self.vehicle = Vehicle(params)
        self.vehicle.set_state(x=pose[0], y=pose[1], theta=pose[2], v=v_init)
        self.model, self.data = self.vehicle.model, self.vehicle.data
        lay = self.vehicle.layout
        self._wheel_r, self._wheel_l = lay.wheel_right_v, lay.wheel_left_v
        self._act_r, self._act_l = lay.act_right, lay.act_left
        self._tractor = self.model.body("tractor").id
        self._wrench = wrench
        self._steps = 0

    def measure(self):
        return self.vehicle.measure()

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

    def __init__(self, params: Params, pose, v_init: float, timestep: float):
        self.params = params
        state = [pose[0], pose[1], pose[2], 0.0, 0.0, 0.0, v_init, 0.0]
        self.plant = reduced.ReducedPlant(params, state=state)
        self.timestep = timestep
        self._tau = (0.0, 0.0)
        self._accel = (0.0, 0.0)

    def measure(self):
        from tt_mujoco.measure import Measurement

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
    v = np.array([target.reference_speed(t) for t in ts])
    w = np.array([target.reference_yaw_rate(t) for t in ts])
    scale = 10.0 ** (-snr_db / 10.0)
    return math.sqrt(np.mean(v**2) * scale), math.sqrt(np.mean(w**2) * scale)


def simulate(scenario: Scenario, progress=None) -> Result:
    """Run one scenario. Never raises for a diverging run: see ``Result.status``.

    Parameters
    ----------
    scenario : Scenario
    progress : callable, optional
        Called as ``progress(steps_done, steps_total)`` about every 1 % of the run.

    Raises
    ------
    ValueError
        For bad configuration values (before anything is simulated).
    """
    from controllers import make_controller, reduced_model
    from tt_mujoco import metrics as metrics_mod
    from tt_mujoco.targets import make_target

    scenario.validate()
    nominal = scenario.nominal_params()
    plant_p = scenario.plant_params()
    path, target, pose = make_target(
        scenario.traj, kind=scenario.target, duration=scenario.duration, start=scenario.start
    )
    duration = float(target.duration)
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
    if scenario.plant == "mujoco":
        plant = _MujocoPlant(plant_p, pose, v_init, wrench=scenario.disturbance == "wrench")
    else:
        plant = _ReducedPlantAdapter(plant_p, pose, v_init, scenario.timestep)

    dt = scenario.control_dt
    substeps = round(dt / scenario.timestep)
    n = round(duration / dt)
    log = np.full((n + 1, len(COLUMNS)), np.nan)
    use_dist = scenario.disturbance != "none"
    wrench = scenario.disturbance == "wrench"
    eta = nominal.eta
    jk = math.radians(JACKKNIFE_DEG)
    jk_phi = min(jk / abs(eta), math.radians(90.0)) if eta else math.radians(90.0)
    matched_torque = reduced.matched_torque
    mass_matrix = reduced.mass_matrix
    ctrl.reset()
    target.reset()
    status, message = "ok", f"completed {duration:.3f} s"
    report_every = max(1, n // 100)
    start_wall = time.perf_counter()
    k = 0
    try:
        for k in range(n + 1):
            t = k * dt
            me = plant.measure()
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
            v_m = me.v + (noise_v * rng.standard_normal() if noise_v else 0.0)
            w_m = me.omega + (noise_w * rng.standard_normal() if noise_w else 0.0)
            v_d, w_d, v_d_dot, w_d_dot = target.update(t, dt, v_m)
            try:
                T_r, T_l = ctrl.step(dt, me.phi, v_m, w_m, v_d, w_d, v_d_dot, w_d_dot)
            except FloatingPointError as err:
                msg = f"controller failed at t={t:.3f} s: {err}"
                raise _StopRunError("diverged", msg) from None
            T_r_cmd, T_l_cmd = ctrl.command
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
            ref_x, ref_y = target.reference_point(t)
            log[k] = (
                t,
                me.x,
                me.y,
                me.theta,
                me.phi,
                me.beta,
                me.v,
                me.omega,
                me.x0,
                me.y0,
                me.theta0,
                me.v0,
                me.theta_l,
                me.theta_r,
                target.arc_length,
                ref_x,
                ref_y,
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
                me.slip_lateral,
                me.slip_lateral_trailer,
                me.slip_left,
                me.slip_right,
                me.beta - eta * me.phi,
                target.curvature,
            )
            if k == n:
                plant.check_warnings()
                break
            plant.apply(T_r, T_l, dist_r, dist_l, force, torque, me.theta)
            try:
                plant.advance(substeps)
            except reduced.SingularityError as err:
                raise _StopRunError("jackknife", f"jackknife at t={t + dt:.3f} s: {err}") from None
            if progress is not None and k % report_every == 0:
                progress(k, n)
    except _StopRunError as stop:
        status, message = stop.status, stop.message
        log = log[: k + (1 if not np.isnan(log[k, 0]) else 0)]
    wall = time.perf_counter() - start_wall
    if progress is not None:
        progress(n, n)

    ts = {name: log[:, i].copy() for i, name in enumerate(COLUMNS)}
    polyline = path.dense()
    metrics = metrics_mod.compute_metrics(ts, polyline, nominal.torque_limit)
    metrics["wall_time_s"] = wall
    metrics["status"] = status
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

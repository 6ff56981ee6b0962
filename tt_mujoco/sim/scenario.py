"""The scenario: everything that defines a run, validated field by field.

Defaults live in :mod:`tt_mujoco.defaults`. A :class:`Scenario` is plain data (it pickles, and
``to_dict`` gives its TOML/JSON form); :func:`tt_mujoco.sim.build.build` turns it into the
objects of a run.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

from tt_mujoco.defaults import CONTROL_DT, MAX_DURATION, TIME_LIMIT_S, TIMESTEP
from tt_mujoco.reference.feedback import check_config
from tt_mujoco.sim.faults import parse_faults
from tt_mujoco.sim.ground import parse_patches
from tt_mujoco.sim.motors import ACTUATORS
from tt_mujoco.sim.terrain import parse_terrain
from tt_mujoco.sim.wind import parse_wind
from tt_mujoco.vehicle.params import INERTIA_FIELDS, MASS_FIELDS, Params, jackknife_phi_deg

__all__ = [
    "DISTURBANCE_MODES",
    "ETA_SCHEDULES",
    "PLANTS",
    "TARGETS",
    "Scenario",
    "jackknife_phi_deg",
]

PLANTS = ("mujoco", "reduced")
TARGETS = ("dynamic", "static")
DISTURBANCE_MODES = ("matched", "wrench", "none")
#: What ``Scenario.eta_schedule`` may name besides False / True.
ETA_SCHEDULES = ("curvature", "path")


@dataclass
class Scenario:
    """Everything that defines a run. Defaults are the project's main run."""

    traj: str = "s_curve"
    controller: str = "ismc_sta"
    gains: str | dict | None = None
    target: str = "dynamic"
    plant: str = "mujoco"
    eta: str | float = "same_path"
    #: How the disturbance enters: "matched" (wheel torques g^-1 Delta), "wrench" (a force and
    #: yaw moment on the chassis, MuJoCo only) or "none".
    disturbance: str = "matched"
    #: Which disturbance Delta(t): a name in :data:`tt_mujoco.sim.disturbances.DISTURBANCES`
    #: ("paper") or a hook ``module:Name`` / ``file.py:Name``.
    disturbance_model: str = "paper"
    #: Bound on each wheel's matched disturbance torque (N m): "actuator" (default: the
    #: nominal torque limit, what a motor-sized disturbance can apply), "none" (the paper's
    #: unbounded idealisation g^-1 Delta), or a number > 0.
    disturbance_limit: str | float = "actuator"
    noise_snr_db: float | None = None
    param_scale: float = 1.0
    duration: float | None = None
    seed: int = 0
    timestep: float = TIMESTEP
    control_dt: float = CONTROL_DT
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
    #: Outer path-feedback loop on omega_d (:mod:`tt_mujoco.reference.feedback`): None (off) or a
    #: dict
    #: of gains, ``{}`` for the defaults (k_y, k_psi, c_max).
    path_feedback: dict | None = None
    #: Reversing without path feedback: the hitch-angle cascade that backs the train along the
    #: path (:class:`tt_mujoco.controllers.backing.HitchCascade`): a dict of its gains, ``{}``
    #: for the defaults, or None (the hitches left to themselves). Ignored driving forward.
    hitch_feedback: dict | None = field(default_factory=dict)
    #: Scheduled passive steering (:mod:`tt_mujoco.sim.schedule`): False (the constant ``eta``),
    #: ``"curvature"`` (or True: the exact same-path gain of the target's curvature) or
    #: ``"path"`` (each trailer's gain eta_k(s) from the path's geometry at its own arc length,
    #: :mod:`tt_mujoco.vehicle.path_schedule`). The controller keeps ``eta``.
    eta_schedule: bool | str = False
    #: Drive the path backwards, trailer first
    #: (:class:`tt_mujoco.reference.reverse.ReverseTarget`).
    reverse: bool = False
    #: Shape options of the path (``R``, ``cruise``, ``ramp_time``, ... see
    #: :func:`tt_mujoco.reference.targets.make_target`; for a path hook, its keyword arguments).
    path_options: dict = field(default_factory=dict)
    #: Extra metrics: names in :data:`tt_mujoco.analysis.metrics.METRICS` or hooks
    #: ``module:function`` / ``file.py:function``, each added to ``metrics.json``.
    metrics: list = field(default_factory=list)
    #: Number of trailers N (1: the paper's vehicle). Trailers 2..N copy trailer 1 (lengths,
    #: masses, and ``eta``: a preset gives each trailer its own value) ...
    trailers: int = 1
    #: ... then take these overrides, one table of ``Trailer`` fields per trailer 2, 3, ...
    train: list = field(default_factory=list)
    #: Wall-clock limit of the run (s): a run still going then (a hung controller, say) stops
    #: with status "failed" and its rows so far kept. Enforced where the run is in a
    #: process's main thread (the CLI, a sweep's process workers), by SIGALRM.
    time_limit_s: float = TIME_LIMIT_S
    #: The ground (:mod:`tt_mujoco.sim.terrain`): ``"flat"`` or ``"slope:GRADE_DEG[:HEADING_DEG]"``,
    #: a constant grade rising along the heading (MuJoCo plant only).
    terrain: str = "flat"
    #: What turns the torque command into wheel torque (:mod:`tt_mujoco.sim.motors`):
    #: ``"ideal"`` (at once, the paper's) or ``"dc_motor"`` (a DC motor per wheel with its
    #: lag and its current and voltage limits, the ``motor_*`` fields of ``Params``).
    actuator: str = "ideal"
    #: The sensors' delay (s, a whole multiple of ``control_dt``): the controller and the outer
    #: loops see the readings of that long ago (the first reading until then).
    sensor_delay: float = 0.0
    #: Wind on the bodies (:mod:`tt_mujoco.sim.wind`): ``"none"`` or
    #: ``"SPEED[:DIRECTION_DEG[:GUST_STD]]"`` (m/s, deg, m/s). MuJoCo plant only.
    wind: str = "none"
    #: Patches of other friction (:mod:`tt_mujoco.sim.ground`): ``"band:S0:S1:MU"`` along the
    #: path, ``"rect:X0:Y0:X1:Y1:MU"`` on the floor. MuJoCo plant only.
    ground: list = field(default_factory=list)

    @property
    def backs_with_cascade(self) -> bool:
        """Reversing with the hitch cascade: reverse, hitch_feedback on, no path feedback, and
        some hitch unstable backwards (eta_k < 1; with every eta_k > 1, such as the paper's 3,
        the hitches are stable reversing by themselves, docs/model.md Section 3)."""
        if not (self.reverse and self.hitch_feedback is not None and self.path_feedback is None):
            return False
        return min(self.nominal_params().etas) < 1.0

    @property
    def eta_schedule_kind(self) -> str | None:
        """None (constant eta), ``"curvature"`` or ``"path"``."""
        if self.eta_schedule is True:
            return "curvature"
        return self.eta_schedule or None

    def validate(self) -> None:
        """Raise ValueError naming the first bad field and what is allowed."""
        limit = self.time_limit_s
        if (
            isinstance(limit, bool)
            or not isinstance(limit, int | float)
            or not (math.isfinite(limit) and limit > 0)
        ):
            raise ValueError(
                f"time_limit_s={limit!r} is not allowed: it must be a finite number of seconds > 0"
            )
        if self.plant not in PLANTS:
            raise ValueError(f"plant={self.plant!r} is not allowed: use one of {PLANTS}")

        if self.target not in TARGETS:
            raise ValueError(f"target={self.target!r} is not allowed: use one of {TARGETS}")
        limit = self.disturbance_limit
        if limit not in ("actuator", "none") and not (
            isinstance(limit, int | float)
            and not isinstance(limit, bool)
            and math.isfinite(limit)
            and limit > 0
        ):
            raise ValueError(
                f"disturbance_limit={limit!r} is not allowed: use 'actuator', 'none' or a number "
                "> 0 (N m)"
            )
        if self.disturbance not in DISTURBANCE_MODES:
            raise ValueError(
                f"disturbance={self.disturbance!r} is not allowed: use one of {DISTURBANCE_MODES}"
            )
        if self.duration is not None and not (
            isinstance(self.duration, int | float) and 0 < self.duration <= MAX_DURATION
        ):
            raise ValueError(
                f"duration={self.duration!r} is not allowed: it must be in (0, {MAX_DURATION:g}] s"
            )
        if (
            self.duration is not None
            and isinstance(self.control_dt, int | float)
            and self.duration < self.control_dt
        ):
            raise ValueError(
                f"duration={self.duration!r} is not allowed: it is shorter than one control "
                f"period ({self.control_dt!r} s)"
            )
        if self.noise_snr_db is not None and not (
            isinstance(self.noise_snr_db, int | float) and math.isfinite(self.noise_snr_db)
        ):
            raise ValueError(
                f"noise SNR={self.noise_snr_db!r} is not allowed: it must be a finite number (dB)"
            )
        if not (
            isinstance(self.timestep, int | float)
            and not isinstance(self.timestep, bool)
            and 1e-5 <= self.timestep <= 0.01
        ):
            raise ValueError(
                f"timestep={self.timestep!r} is not allowed: it must be in [1e-05, 0.01] s"
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
        if not isinstance(self.reverse, bool):
            raise ValueError(f"reverse={self.reverse!r} is not allowed: use True or False")
        if not isinstance(self.eta_schedule, bool) and self.eta_schedule not in ETA_SCHEDULES:
            raise ValueError(
                f"eta_schedule={self.eta_schedule!r} is not allowed: use False, True "
                f"(curvature) or one of {ETA_SCHEDULES}"
            )
        for name in ("params", "plant_scale", "path_options"):
            if not isinstance(getattr(self, name), dict):
                raise ValueError(f"{name}={getattr(self, name)!r} is not allowed: give a table")
        if not isinstance(self.metrics, list | tuple) or not all(
            isinstance(m, str) for m in self.metrics
        ):
            raise ValueError(f"metrics={self.metrics!r} is not allowed: give a list of names")
        if self.path_feedback is not None:
            check_config(self.path_feedback)
        if self.hitch_feedback is not None:
            from tt_mujoco.controllers.backing import check_config as check_hitch

            check_hitch(self.hitch_feedback)
        parse_faults(self.faults)
        delay = self.sensor_delay
        if (
            isinstance(delay, bool)
            or not isinstance(delay, int | float)
            or not (math.isfinite(delay) and delay >= 0)
        ):
            raise ValueError(
                f"sensor_delay={delay!r} is not allowed: it must be a finite number of seconds >= 0"
            )
        if self.actuator not in ACTUATORS:
            raise ValueError(f"actuator={self.actuator!r} is not allowed: use one of {ACTUATORS}")
        if parse_patches(self.ground) and self.plant != "mujoco":
            raise ValueError(
                f"ground={self.ground!r} with plant={self.plant!r} is not allowed: the reduced "
                "plant rolls without slip on any ground; use plant='mujoco'"
            )
        if not parse_wind(self.wind).calm and self.plant != "mujoco":
            raise ValueError(
                f"wind={self.wind!r} with plant={self.plant!r} is not allowed: the reduced plant "
                "has no aerodynamics; use plant='mujoco'"
            )
        if not parse_terrain(self.terrain).flat and self.plant != "mujoco":
            raise ValueError(
                f"terrain={self.terrain!r} with plant={self.plant!r} is not allowed: the reduced "
                "plant has flat ground only; use plant='mujoco'"
            )
        if not isinstance(self.train, list | tuple):
            raise ValueError(f"train={self.train!r} is not allowed: give a list of tables")
        self.nominal_params()  # the trailers' count and tables, checked by Params
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
        """The controller's model: paper values, this steering and timestep, plus overrides,
        and the train of :attr:`trailers`."""
        p = Params(eta=self.eta, timestep=self.timestep, friction=self.friction, **self.params)
        if self.trailers == 1 and not self.train:
            return p
        return p.with_trailers(self.trailers, self.train)

    def plant_params(self) -> Params:
        """The plant's parameters: nominal, times ``param_scale`` on every mass and inertia,
        times ``plant_scale[field]`` on single ones (docs/model.md Section 8)."""
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

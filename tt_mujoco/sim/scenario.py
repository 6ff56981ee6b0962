"""The scenario: everything that defines a run, each field declared once as an option.

Every field of :class:`Scenario` is an :func:`~tt_mujoco.schema.option`: its default, help,
unit and the one check of its values. :data:`SCHEMA`, read from these fields, is what the
command line, scenario files, sweeps and the Gym env are made from
(:mod:`tt_mujoco.schema`), so a new option is one field here. Project-wide defaults live in
:mod:`tt_mujoco.defaults`. A :class:`Scenario` is plain data (it pickles, and ``to_dict`` gives
its TOML/JSON form); :func:`tt_mujoco.sim.build.build` turns it into the objects of a run.
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass

from tt_mujoco.defaults import (
    CONTROLLER,
    DISTURBANCE_MODEL,
    DRIVEN_PATH_GAIN,
    MAX_DURATION,
    TIME_LIMIT_S,
    TIMESTEP,
)
from tt_mujoco.reference.feedback import check_config
from tt_mujoco.schema import (
    Schema,
    boolean,
    check_typed,
    choice,
    number,
    option,
    optional_table,
    spec_list,
    table,
    text,
)
from tt_mujoco.sim import scenario_values as values
from tt_mujoco.sim.parts.ground import parse_patches
from tt_mujoco.sim.parts.motors import ACTUATORS
from tt_mujoco.sim.parts.terrain import parse_terrain
from tt_mujoco.sim.parts.wind import parse_wind
from tt_mujoco.vehicle.params import (
    INERTIA_FIELDS,
    MASS_FIELDS,
    MAX_TRAILERS,
    Params,
    jackknife_phi_deg,
)

__all__ = [
    "DISTURBANCE_MODES",
    "ETA_SCHEDULES",
    "PLANTS",
    "SCHEMA",
    "TARGETS",
    "Scenario",
    "jackknife_phi_deg",
]

PLANTS = ("mujoco", "reduced")
TARGETS = ("dynamic", "static")
DISTURBANCE_MODES = ("matched", "wrench", "none")
STARTS = ("on_path", "paper")
ETA_SCHEDULES, ETA_WORDS = values.ETA_SCHEDULES, values.ETA_WORDS


# --gains is parsed here, beside its option: the walk from the command line to the law's
# use of a gain stays within scenario.py, build.py, controllers/base.py, controllers/gains.py
# and sim/loop/law.py.
def _gain(value, label):
    if label.endswith(".preset"):
        return text(value, label)
    return values.finite(value, label)


def _gains(value, label):
    """None (the default preset), a preset name, a JSON object text, or a table of gains (a
    ``preset`` entry names the preset they change)."""
    if value is None:
        return None
    if isinstance(value, str) and value.strip().startswith("{"):
        from tt_mujoco.outputs import parse_strict_json

        try:
            value = parse_strict_json(value)
        except ValueError as err:
            why = err.msg if isinstance(err, json.JSONDecodeError) else str(err)
            raise ValueError(f"{label} {value!r} is not valid JSON: {why}") from None
        if not isinstance(value, dict):
            raise ValueError(f"{label} {value!r} is not a JSON object")
        gains = table(_gain)(value, label)
        check_typed(value, gains, label)  # JSON is typed: {"k1_v": "5"} is a mistake
        return gains
    if isinstance(value, dict):
        return table(_gain)(value, label)
    return text(value, label)


@dataclass
class Scenario:
    """Everything that defines a run. Defaults are the project's main run."""

    traj: str = option(
        "s_curve",
        text,
        "reference path: cycloid, s_curve, circle, clothoid (or another registered one), plan "
        "(planned from the --world's start to "
        "its goal), a CSV file with header x,y[,v], or a hook package.module:NAME / "
        "path/to/file.py:NAME (a ReferencePath or a factory)",
        file=True,
        metavar=values.path_names,
    )
    controller: str = option(
        CONTROLLER,
        values.controller,
        "a registered controller (ismc_sta, pid, fbl, ...), or a hook package.module:Class / "
        "path/to/file.py:Class (a Controller subclass or a plain_law)",
        file=True,
        metavar=values.controller_names,
    )
    gains: str | dict | None = option(
        None,
        _gains,
        "controller gain preset (ismc_sta: paper_6_1 or paper_6_2) or JSON overrides, e.g. "
        "'{\"k1_v\": 12}'",
        entry="gain",
    )
    target: str = option(
        "dynamic",
        choice(*TARGETS),
        "dynamic: omega_d = kappa(s) v (paper eq. 34); static: fixed functions of time",
        choices=TARGETS,
    )
    plant: str = option(
        "mujoco", choice(*PLANTS), "the MuJoCo multibody model or the reduced model", choices=PLANTS
    )
    #: The passive steering gain: "paper" (3), "same_path" ((L-L0)/(L+L0)) or a number; the
    #: words "scheduled" and "path" keep "same_path" for the controller and set
    #: ``eta_schedule``.
    eta: str | float = option(
        "same_path",
        values.eta,
        "passive steering gain: paper (3, jackknifes forward), same_path ((L-L0)/(L+L0) = "
        "-1/7), scheduled (the exact same-path gain for the local curvature, every step), path "
        "(each trailer's gain eta_k(s) from the path's geometry at its own arc length; |eta| "
        "<= 3), or a number",
    )
    #: How the disturbance enters: "matched" (wheel torques g^-1 Delta), "wrench" (a force and
    #: yaw moment on the chassis, MuJoCo only) or "none".
    disturbance: str = option(
        "matched",
        choice(*DISTURBANCE_MODES),
        "matched: wheel torques g^-1 Delta; wrench: force and moment on the chassis (can "
        "exceed traction); none",
        flags=("--disturbance-mode",),
        consts=(("--no-disturbance", "none"),),
        choices=DISTURBANCE_MODES,
    )
    #: Which disturbance Delta(t): a name in :data:`tt_mujoco.sim.parts.disturbances.DISTURBANCES`
    #: ("paper") or a hook ``module:Name`` / ``file.py:Name``.
    disturbance_model: str = option(
        DISTURBANCE_MODEL,
        text,
        "the disturbance Delta(t): paper, rolling (the wheels' rolling resistance, c_rr = "
        "0.015), another registered one, or a hook package.module:Name / file.py:Name",
        file=True,
        needs=("disturbance", lambda mode: mode != "none"),
    )
    #: Bound on each wheel's matched disturbance torque (N m): "actuator" (the nominal torque
    #: limit, what a motor-sized disturbance can apply), "none" (the paper's unbounded
    #: idealisation g^-1 Delta), or a number > 0.
    disturbance_limit: str | float = option(
        "actuator",
        values.torque_bound,
        "bound on each wheel's matched disturbance torque: actuator (the torque limit), none "
        "(the paper's unbounded g^-1 Delta) or a number",
        unit="N m",
        needs=("disturbance", lambda mode: mode == "matched"),
    )
    noise_snr_db: float | None = option(
        None,
        values.snr_db,
        "Gaussian measurement noise on v and omega at this SNR; none by default",
        unit="dB",
        flags=("--noise-snr-db", "--noise-snr"),
        metavar="DB",
    )
    param_scale: float = option(
        1.0,
        values.scale_factor,
        "scale the plant's masses and inertias (the controller keeps the nominal model)",
        metavar="F",
    )
    duration: float | None = option(
        None,
        number(0, MAX_DURATION, low_open=True, optional=True, unit="s"),
        f"run length, at most {MAX_DURATION:g} (default: the path's own duration)",
        unit="s",
        metavar="S",
    )
    seed: int = option(0, number(0, integer=True), "seed for the measurement noise and gusts")
    timestep: float = option(
        TIMESTEP, number(1e-5, 0.01, unit="s"), "physics step, in [1e-5, 0.01]", unit="s"
    )
    #: The control period (s); None: the physics timestep.
    control_dt: float | None = option(
        None,
        number(0, 0.05, low_open=True, optional=True, unit="s"),
        "control period, a multiple of the timestep, at most 0.05; default: the timestep",
        unit="s",
    )
    #: "on_path": start in the reference's initial state (pose and speed); "paper": the
    #: paper's initial condition, at rest (and, on the cycloid, at its pose (0, 0, pi/4)).
    start: str = option(
        "on_path",
        choice(*STARTS),
        "on_path: start in the reference's initial state (pose and speed); paper: the paper's "
        "initial condition, at rest (on the cycloid at its pose (0, 0, pi/4))",
        choices=STARTS,
    )
    friction: float = option(1.0, values.friction, "tyre friction coefficient")
    #: Overrides of vehicle parameters, of the plant and the controller's model alike.
    params: dict = option(
        parse=values.params,
        help="override a vehicle parameter of both plant and controller model, e.g. Mr=7.5 "
        "(repeatable; see tt_mujoco.vehicle.params.Params)",
        default_factory=dict,
        flags=("--param",),
        form="table",
        entry="param",
        merge=True,
        axis=False,
    )
    #: Per-field factors on the *plant's* masses and inertias only (e.g. ``{"Mr": 1.2}``), on
    #: top of ``param_scale``: a model mismatch the controller does not know about.
    plant_scale: dict = option(
        parse=table(values.scale_factor, MASS_FIELDS + INERTIA_FIELDS),
        help="scale one of the plant's masses or inertias, e.g. Mr=1.2 (the controller keeps "
        "the nominal model; repeatable)",
        default_factory=dict,
        form="table",
        entry="scale",
        merge=True,
        metavar="FIELD=F",
        axis=False,
    )
    #: Initial articulation phi (deg), with beta = eta phi; must stay short of the jackknife.
    phi0_deg: float = option(
        0.0,
        values.articulation_deg,
        "initial articulation phi, short of the jackknife",
        unit="deg",
        flags=("--phi0-deg", "--phi0"),
        metavar="DEG",
    )
    #: Fault specs (dicts or ``KIND:key=value,...`` strings), see :mod:`tt_mujoco.sim.parts.faults`.
    faults: list = option(
        parse=spec_list(values.fault),
        help="inject a fault (repeatable; replaces a config file's faults): "
        "payload:t=S[,factor=1.5,trailer=K] | dropout:t=S[,duration=0.1] | "
        "actuator:t=S[,duration=1,scale=0.3,wheel=both|right|left]",
        default_factory=list,
        flags=("--fault",),
        form="repeat",
        metavar="KIND:K=V,...",
    )
    #: Outer path-feedback loop on omega_d (:mod:`tt_mujoco.reference.feedback`): None (off) or
    #: a dict of gains, ``{}`` for the defaults (k_y, k_psi, c_max).
    path_feedback: dict | None = option(
        None,
        optional_table(values.loop_gain),
        "outer loop: lateral and heading errors feed the yaw-rate target "
        "(tt_mujoco.reference.feedback; k_y = k_psi = 4)",
        form="switch",
        entry="path_feedback",
    )
    #: Reversing without path feedback: the hitch-angle cascade that backs the train along the
    #: path (:class:`tt_mujoco.controllers.backing.HitchCascade`): a dict of its gains, ``{}``
    #: for the defaults, or None (the hitches left to themselves). Ignored driving forward.
    hitch_feedback: dict | None = option(
        parse=optional_table(values.loop_gain),
        help="reversing without --path-feedback: the leading trailer's axle tracks the path "
        "and a cascade on the hitch angles sets the tractor's yaw rate "
        "(tt_mujoco.controllers.backing); --no-hitch-feedback leaves the hitches to themselves",
        default_factory=dict,
        form="switch",
        entry="hitch_feedback",
        needs=("reverse", bool),
    )
    #: Scheduled passive steering (:mod:`tt_mujoco.sim.parts.schedule`): False (the constant
    #: ``eta``),
    #: ``"curvature"`` (or True: the exact same-path gain of the target's curvature) or
    #: ``"path"`` (each trailer's gain eta_k(s) from the path's geometry at its own arc length,
    #: :mod:`tt_mujoco.vehicle.path_schedule`), which replace the constant ``eta``; the
    #: controllers' model follows the gains in force (``Controller.steering_changed``). On the
    #: command line it is ``--eta scheduled`` / ``--eta path``.
    eta_schedule: bool | str = option(
        False,
        values.eta_schedule,
        "schedule the plant's steering gain: false, curvature (or true) or path",
        cli=False,
    )
    #: With ``eta_schedule="path"``, driving forward: the gain (1/m) that steers each axle
    #: towards the path the tractor drove (``atan(gain e)`` for ``e`` m beside it; 0: the
    #: table's steering alone; docs/model.md Section 13).
    driven_path_gain: float = option(
        DRIVEN_PATH_GAIN,
        number(0, 1e4, unit="1/m"),
        "with --eta path, driving forward: how hard each axle is steered towards the path the "
        "tractor drove (0: the schedule's steering alone)",
        unit="1/m",
        metavar="K",
    )
    #: Drive the path backwards, trailer first
    #: (:class:`tt_mujoco.reference.reverse.ReverseTarget`).
    reverse: bool = option(
        False,
        boolean,
        "drive the path backwards, trailer first (where eta > 1 is stable)",
        form="switch",
    )
    #: Shape options of the path (``R``, ``cruise``, ``ramp_time``, ... see
    #: :func:`tt_mujoco.reference.targets.make_target`; for a path hook, its keyword arguments).
    path_options: dict = option(
        parse=table(values.path_option),
        help="a shape option of the path (s_curve/circle: R, cruise, ramp_time; clothoid: R, "
        "angle_deg, transition, straight, cruise, ramp_time; CSV: max_curvature, smoothing, "
        "cruise, ramp_time; a registered path: its factory's keywords; a hook: its keyword "
        "arguments); repeatable",
        default_factory=dict,
        flags=("--path-option",),
        form="table",
        entry="path_option",
        merge=True,
    )
    #: Extra metrics: names in :data:`tt_mujoco.analysis.metrics.METRICS` or hooks
    #: ``module:function`` / ``file.py:function``, each added to ``metrics.json``.
    metrics: list = option(
        parse=spec_list(text),
        help="an extra metric fn(timeseries, path) added to metrics.json: a registered name or "
        "a hook package.module:fn / path/to/file.py:fn (repeatable)",
        default_factory=list,
        flags=("--metric",),
        form="repeat",
        metavar="HOOK",
        file=True,
    )
    #: Number of trailers N (1: the paper's vehicle). Trailers 2..N copy trailer 1 (lengths,
    #: masses, and ``eta``: a preset gives each trailer its own value) ...
    trailers: int = option(
        1,
        values.trailers,
        f"number of trailers, 1 to {MAX_TRAILERS}: trailers 2..N copy trailer 1 and steer with "
        "their own gain of the --eta preset (a config file's [[train]] tables override them)",
        metavar="N",
    )
    #: ... then take these overrides, one table of ``Trailer`` fields per trailer 2, 3, ...
    train: list = option(
        parse=values.train,
        help="overrides of trailers 2, 3, ...: one table of Trailer fields each",
        default_factory=list,
        cli=False,
        axis=False,
    )
    #: Wall-clock limit of the run (s): a run still going then (a hung controller, say) stops
    #: with status "failed" and its rows so far kept. Enforced where the run is in a
    #: process's main thread (the CLI, a sweep's process workers), by SIGALRM.
    time_limit_s: float = option(
        TIME_LIMIT_S,
        values.wall_limit,
        "wall-clock limit of the run: a run still going then stops, its rows kept (exit code 3)",
        unit="s",
        flags=("--time-limit",),
    )
    #: The ground (:mod:`tt_mujoco.sim.parts.terrain`): ``"flat"``,
    #: ``"slope:GRADE_DEG[:HEADING_DEG]"``
    #: (a constant grade rising along the heading), ``"ramp:START_S_M:GRADE_DEG[:LENGTH_M]"``
    #: (flat, then rising along the path's direction at its arc length START_S_M) or
    #: ``"rough:AMPLITUDE_M:WAVELENGTH_M[:SEED]"`` (a heightfield); MuJoCo plant only.
    terrain: str = option(
        "flat",
        values.spec(parse_terrain),
        "the ground: flat; a constant grade rising along HEADING_DEG (default 0, +x); a ramp "
        "rising from the path's arc length START_S (for LENGTH m, then level); or a rough "
        "ground of bumps of AMPLITUDE and about WAVELENGTH from SEED; MuJoCo plant only",
        metavar="flat|slope:GRADE_DEG[:HEADING_DEG]|ramp:START_S:GRADE_DEG[:LENGTH]|"
        "rough:AMPLITUDE:WAVELENGTH[:SEED]",
    )
    #: What turns the torque command into wheel torque (:mod:`tt_mujoco.sim.parts.motors`):
    #: ``"ideal"`` (at once, the paper's) or ``"dc_motor"`` (a DC motor per wheel with its
    #: lag and its current and voltage limits, the ``motor_*`` fields of ``Params``).
    actuator: str = option(
        "ideal",
        choice(*ACTUATORS),
        "ideal: the wheels get the commanded torque; dc_motor: a DC motor per wheel with its "
        "lag and current and voltage limits (Params motor_*, set with --param)",
        choices=ACTUATORS,
    )
    #: The sensors' delay (s, a whole multiple of ``control_dt``): the controller and the outer
    #: loops see the readings of that long ago (the first reading until then).
    sensor_delay: float = option(
        0.0,
        number(0, MAX_DURATION, unit="s"),
        "the sensors' delay (a multiple of the control period, shorter than the run)",
        unit="s",
        metavar="S",
    )
    #: Wind on the bodies (:mod:`tt_mujoco.sim.parts.wind`): ``"none"`` or
    #: ``"SPEED[:DIRECTION_DEG[:GUST_STD]]"`` (m/s, deg, m/s). MuJoCo plant only.
    wind: str = option(
        "none",
        values.spec(parse_wind),
        "wind blowing toward DIRECTION_DEG (m/s, deg from +x, gusts' std in m/s); MuJoCo "
        "plant only",
        metavar="SPEED[:DIRECTION_DEG[:GUST_STD]]",
    )
    #: Patches of other friction (:mod:`tt_mujoco.sim.parts.ground`): ``"band:S0:S1:MU"`` along the
    #: path, ``"rect:X0:Y0:X1:Y1:MU"`` on the floor. MuJoCo plant only.
    ground: list = option(
        parse=spec_list(values.patch),
        help="a patch of other friction (repeatable): a stretch of the path or a rectangle of "
        "the floor; MuJoCo plant only",
        default_factory=list,
        form="repeat",
        metavar="band:S0:S1:MU|rect:X0:Y0:X1:Y1:MU",
    )

    #: The along-track loop's gain k_s (1/s): the speed target gains ``k_s (s_nominal(t) -
    #: s*)``, s* the tractor's nearest path point and s_nominal(t) where the speed profile
    #: puts it, so that the run ends where its path does (docs/worlds.md). 0: none, the
    #: paper's; None: :data:`tt_mujoco.defaults.DOCKING_GAIN` on a planned path, else 0.
    along_track_gain: float | None = option(
        None,
        number(0, 1e3, optional=True),
        "gain of the along-track loop (1/s): the speed target corrected toward where the "
        "speed profile puts the tractor on its path; default: on for --traj plan, else off",
        unit="1/s",
        metavar="K",
    )
    #: The obstacles and the goal (:mod:`tt_mujoco.world`): ``"none"``, a named world
    #: (:data:`tt_mujoco.world.builtin.WORLDS`) or a world file ``path/to/world.toml``. A
    #: unit that touches an obstacle stops the run (status "collision", exit code 3).
    world: str = option(
        "none",
        values.world,
        "obstacles and a goal: none, a named world (loading_bay, alley, yard) or a world file "
        "(TOML); a unit touching an obstacle stops the run (exit code 3)",
        metavar="none|NAME|FILE.toml",
        file=True,
    )

    def __post_init__(self):
        # The shorthands every interface accepts, written into the fields they stand for.
        if isinstance(self.eta, str) and self.eta.strip().lower() in ETA_WORDS:
            self.eta_schedule = ETA_WORDS[self.eta.strip().lower()]
            self.eta = "same_path"  # the nominal model's gain; the plant's follows the schedule
        if isinstance(self.trailers, list):
            self.train = [dict(t) for t in self.trailers]
            self.trailers = len(self.trailers) + 1
        if self.control_dt is None:
            self.control_dt = self.timestep

    @property
    def eta_schedule_kind(self) -> str | None:
        """None (constant eta), ``"curvature"`` or ``"path"``."""
        if self.eta_schedule is True:
            return "curvature"
        return self.eta_schedule or None

    def validate(self) -> None:
        """Check every field by its option, then how they combine; raise ValueError naming the
        first bad field and what is allowed. Values are kept in their checked form (``seed``
        3.0 becomes 3, a fault's text its table)."""
        for opt in SCHEMA.options:
            given = getattr(self, opt.name)
            parsed = opt.parse(given, opt.name)
            check_typed(given, parsed, opt.name)  # Scenario(duration="1") is a mistake
            setattr(self, opt.name, parsed)
        if self.duration is not None and self.duration < self.control_dt:
            raise ValueError(
                f"duration={self.duration!r} is not allowed: it is shorter than one control "
                f"period ({self.control_dt!r} s)"
            )
        if self.duration is not None:
            periods = self.duration / self.control_dt
            if abs(periods - round(periods)) > 1e-9 * max(1.0, periods):
                whole = round(periods) * self.control_dt
                raise ValueError(
                    f"duration={self.duration!r} is not allowed: it is not a whole number of "
                    f"control periods ({self.control_dt!r} s); the run would last {whole:g} s"
                )
        ratio = self.control_dt / self.timestep
        if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
            raise ValueError(
                f"control_dt={self.control_dt!r} is not allowed: it must be a whole multiple of "
                f"the physics timestep {self.timestep!r}"
            )
        if self.path_feedback is not None:
            check_config(self.path_feedback)
        if self.hitch_feedback is not None:
            from tt_mujoco.controllers.backing import check_config as check_hitch

            check_hitch(self.hitch_feedback)
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
        if self.world != "none" and not parse_terrain(self.terrain).flat:
            raise ValueError(
                f"world={self.world!r} with terrain={self.terrain!r} is not allowed: a world's "
                "obstacles stand on flat ground; use terrain='flat'"
            )
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
        """The fields as plain data (the form of ``metrics.json``'s configuration)."""
        return dataclasses.asdict(self)


#: The options of a run: the :class:`Scenario`'s fields (:mod:`tt_mujoco.schema`).
SCHEMA = Schema.of(Scenario)

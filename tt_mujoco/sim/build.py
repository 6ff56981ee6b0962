"""From a scenario to the objects of a run: the one setup and validation path.

:func:`build` checks everything a run needs before any work (fields, parameters, path, gains,
faults, plant capabilities, hooks) and returns a :class:`Build`; the CLI's preflight, the sweep's
validation, :func:`tt_mujoco.sim.simulate.simulate`, the Gymnasium environment and the viewer all
go through it, so an option means the same everywhere and bad input fails the same way.
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np

from tt_mujoco.analysis.metrics import resolve_metrics
from tt_mujoco.controllers import (
    CONTROLLERS,
    Controller,
    ControllerSetup,
    controller_class,
    reduced_model,
)
from tt_mujoco.controllers.backing import HitchCascade
from tt_mujoco.defaults import (
    DOCKING_GAIN,
    MAX_DURATION,
    MAX_PHYSICS_STEPS,
    MAX_SPEED,
)
from tt_mujoco.reference.feedback import PathFeedback
from tt_mujoco.reference.reverse import ReverseTarget
from tt_mujoco.reference.targets import make_target, target_on
from tt_mujoco.registry import call_hook, is_hook, shown
from tt_mujoco.sim.parts.disturbances import make_disturbance
from tt_mujoco.sim.parts.faults import FaultSchedule, parse_faults
from tt_mujoco.sim.parts.ground import GroundPatches, parse_patches
from tt_mujoco.sim.parts.plant import Plant
from tt_mujoco.sim.parts.plant_reduced import ReducedPlant
from tt_mujoco.sim.parts.relief import relief_of
from tt_mujoco.sim.parts.schedule import EtaScheduler, PathEtaScheduler
from tt_mujoco.sim.parts.terrain import parse_terrain
from tt_mujoco.sim.scenario import Scenario
from tt_mujoco.sim.usercode import users_setup
from tt_mujoco.vehicle.params import Params, jackknife_phi_deg
from tt_mujoco.vehicle.path_schedule import PathSchedule, axle_chain, path_schedule
from tt_mujoco.world.builtin import parse_world
from tt_mujoco.world.part import check_world
from tt_mujoco.world.plan import PLAN, StartError, planned

__all__ = [
    "PLAN_FORWARD_DRIVE",
    "REVERSING_DRIVES",
    "Build",
    "LegStart",
    "build",
    "noise_std",
    "reversing_drive",
]

#: What keeps the tractor on a planned leg it drives forward (without ``--path-feedback``):
#: a plan's place matters, and the paper's velocity tracking alone leaves the tractor up to
#: 3 cm off a Dubins word's curvature steps.
PLAN_FORWARD_DRIVE = (
    "driving a planned leg forward: the path feedback (tt_mujoco.reference.feedback, its "
    "default gains) sets the yaw-rate target from the tractor's errors to the plan"
)

#: What sets the tractor's yaw-rate target backing up (``--reverse``), by name; the run's
#: ``metrics.json`` says which under ``reversing``, and its notes in a sentence.
REVERSING_DRIVES = {
    "hitch_cascade": "the hitch cascade sets the tractor's yaw-rate target so that the last "
    "trailer's axle tracks the path (tt_mujoco.controllers.backing; --no-hitch-feedback turns "
    "it off)",
    "path_feedback": "the outer path feedback sets the yaw-rate target from the tractor's "
    "errors to the path (--path-feedback)",
    "controller": "the controller steers the train itself (it sets BACKS_UP_ITSELF): it is "
    "given the path's own reverse target, and the trailers start on the path as with the "
    "cascade",
    "hitches_free": "the path's own reverse target drives the tractor and the hitches are left "
    "to themselves",
}


def reversing_drive(scenario: Scenario, cls: type[Controller]) -> str | None:
    """What drives a run backing up (a key of :data:`REVERSING_DRIVES`), None driving
    forward: path feedback when asked for; the controller itself when its class says so
    (``BACKS_UP_ITSELF``); otherwise the hitch cascade while it is on and some hitch is
    unstable backwards (eta_k < 1; with every eta_k > 1, such as the paper's 3, the hitches
    are stable reversing by themselves, docs/model.md Section 3)."""
    if not scenario.reverse:
        return None
    if scenario.path_feedback is not None:
        return "path_feedback"
    if getattr(cls, "BACKS_UP_ITSELF", False):
        return "controller"
    if scenario.hitch_feedback is None or min(scenario.nominal_params().etas) >= 1.0:
        return "hitches_free"
    return "hitch_cascade"


def noise_std(target, duration: float, snr_db: float) -> tuple[float, float]:
    """Noise standard deviations for SNR ``snr_db`` per channel (docs/model.md Section 8).

    Signal power is the mean square of the noise-free reference (v_ref, kappa(s_ref) v_ref) over
    the run, sampled every 10 ms: a property of the scenario, not of the particular run.
    """
    ts = np.arange(0.0, duration, 0.01)
    v = np.asarray(target.reference_speed(ts), dtype=float)
    w = np.asarray(target.reference_yaw_rate(ts), dtype=float)
    scale = 10.0 ** (-snr_db / 10.0)
    return math.sqrt(np.mean(v**2) * scale), math.sqrt(np.mean(w**2) * scale)


def _plant_class(name: str) -> type[Plant]:
    if name == "mujoco":
        from tt_mujoco.sim.parts.plant_mujoco import MujocoPlant  # MuJoCo only when it is used

        return MujocoPlant
    return ReducedPlant


@dataclass
class Build:
    """Everything of one run but its state: the stepper makes a fresh plant, fault schedule
    and noise stream for every episode from it."""

    scenario: Scenario
    nominal: Params
    plant_params: Params
    path: Any
    target: Any
    initial_pose: tuple
    duration: float
    control_dt: float
    substeps: int
    steps: int
    v_init: float
    noise_std: tuple[float, float]
    disturbance: Any
    #: Bound on each wheel's matched disturbance torque (N m), None for unbounded.
    disturbance_limit: float | None
    controller_class: type[Controller]
    controller_setup: ControllerSetup
    extra_metrics: dict
    #: The tabulated path schedule (``eta_schedule="path"``), else None.
    path_schedule: PathSchedule | None = None
    #: The path's arc length where the tractor starts (its end when reversing).
    start_s: float = 0.0
    #: What drives the run backing up (:func:`reversing_drive`), None driving forward.
    reversing: str | None = None
    #: Hitch angles phi_1..phi_N (rad) at the start: zeros, or, backing up with the hitch
    #: cascade, those that put every axle on the path (phi0_deg, when set, replaces phi_1).
    initial_hitches: tuple = ()
    #: The sensor delay in control steps (``Scenario.sensor_delay / control_dt``).
    delay_steps: int = 0
    #: The ground's shape (a ramp, a rough ground: :mod:`tt_mujoco.sim.parts.relief`), else None.
    relief: Any = None
    #: The obstacles and the goal (:mod:`tt_mujoco.world`), else None.
    world: Any = None
    #: The planned path (``traj="plan"``: :class:`tt_mujoco.world.plan.Plan`), else None.
    plan: Any = None
    #: The index of the plan's leg this run drives.
    leg: int = 0
    #: The along-track loop's gain (1/s; ``Scenario.along_track_gain`` resolved).
    along_track_gain: float = 0.0

    @property
    def wall_limit(self) -> float:
        """How long the run may take, wall clock (s; ``Scenario.time_limit_s``)."""
        return self.scenario.time_limit_s

    def initial_phis(self, phi0_deg: float | None = None) -> tuple:
        """The hitch angles phi_1..phi_N the plant starts with (rad): the scenario's
        ``phi0_deg`` (or ``phi0_deg``) for hitch 1, the others 0; backing up with the hitch
        cascade, those that put every axle on the path."""
        s = self.scenario
        phi0 = math.radians(s.phi0_deg if phi0_deg is None else phi0_deg)
        if any(self.initial_hitches):  # backing up: the trailers start on the path ...
            if phi0_deg is None and s.phi0_deg == 0.0:
                return self.initial_hitches
            return (phi0, *self.initial_hitches[1:])  # ... but for hitch 1 when it is given
        return (phi0,) + (0.0,) * (self.plant_params.n_trailers - 1)

    def new_plant(self, phi0_deg: float | None = None) -> Plant:
        """A fresh plant in the initial state (``phi0_deg`` overrides the scenario's)."""
        s = self.scenario
        phi0 = self.initial_phis(phi0_deg)
        if s.plant == "mujoco":
            wrench = s.disturbance == "wrench"
            terrain = parse_terrain(s.terrain)
            gravity = None if terrain.flat else terrain.gravity
            plant = _plant_class("mujoco")(
                self.plant_params,
                self.initial_pose,
                self.v_init,
                wrench,
                phi0,
                gravity,
                self.relief,
                self.world,
            )
            patches = parse_patches(s.ground)
            if patches:
                plant.set_ground(GroundPatches(patches, self.path, self.plant_params.friction))
            return plant
        return ReducedPlant(self.plant_params, self.initial_pose, self.v_init, s.timestep, phi0)

    def new_faults(self) -> FaultSchedule | None:
        specs = parse_faults(self.scenario.faults)
        if not specs:
            return None
        n = self.plant_params.n_trailers
        return FaultSchedule(
            specs, self.control_dt, self.duration, n_trailers=n, path_length=self.path.length
        )

    def new_scheduler(self, plant: Plant) -> EtaScheduler | None:
        """The scheduler of the scenario's ``eta_schedule`` on ``plant``, or None."""
        kind = self.scenario.eta_schedule_kind
        if kind == "path":
            return PathEtaScheduler(
                plant,
                self.plant_params,
                self.path_schedule,
                self.start_s,
                steps=self.steps,
                reverse=bool(self.scenario.reverse),
                gain=self.scenario.driven_path_gain,
            )
        return EtaScheduler(plant, self.plant_params) if kind == "curvature" else None

    def new_controller(self) -> Controller:
        """A new controller of the scenario's; a user's class's construction is its code, so
        what it raises there is a :class:`~tt_mujoco.registry.HookError` (bad input)."""
        make = self.controller_class.from_setup
        if not is_hook(self.scenario.controller):
            return make(self.controller_setup, self.scenario.gains)
        who = f"controller {self.scenario.controller!r}"
        return call_hook(who, make, users_setup(self.controller_setup), self.scenario.gains)


def drawn_polyline(path, duration: float) -> np.ndarray:
    """The reference path as a run of ``duration`` can reach it (``(N, 2)``): sized by the
    distance it can cover (``MAX_SPEED`` for its duration), not by the path, so a circle of
    R = 1e4 m on a 1 s run is a 20 m arc, not 63 km of polyline. Every run keeps it (its
    ``reference_path.parquet``); the ground's shapes are placed along it."""
    return path.dense(length=min(path.length, MAX_SPEED * duration))


def _along_track_gain(scenario: Scenario) -> float:
    """``Scenario.along_track_gain``, its default resolved: on for a planned path."""
    if scenario.along_track_gain is not None:
        return float(scenario.along_track_gain)
    return DOCKING_GAIN if scenario.traj == PLAN else 0.0


def _delay_steps(scenario: Scenario, dt: float, duration: float) -> int:
    """``sensor_delay`` in whole control periods, shorter than the run."""
    delay = scenario.sensor_delay
    steps = round(delay / dt)
    if abs(delay - steps * dt) > 1e-9 * max(1.0, delay):
        raise ValueError(
            f"sensor_delay={delay!r} s is not allowed: it must be a whole multiple of the "
            f"control period {dt!r} s"
        )
    if delay >= duration:
        raise ValueError(
            f"sensor_delay={delay!r} s is not allowed: it must be shorter than the run "
            f"({duration:g} s)"
        )
    return steps


def _initial_hitches(
    scenario: Scenario, path, start_s: float, plant_p: Params, reversing: str | None
) -> tuple:
    """Backing up from the path's end ("on_path" start) with the cascade, or with a controller
    that steers the train itself: the hitch angles that put every axle on the path there (the
    trailers lead, so they start where they must go); otherwise straight (zeros)."""
    n = plant_p.n_trailers
    if not (reversing in ("hitch_cascade", "controller") and scenario.start == "on_path"):
        return (0.0,) * n
    chain = axle_chain(path, np.array([start_s]), [(t.L, t.L0) for t in plant_p.trailers])
    phis = tuple(float(axle["phi"][0]) for axle in chain)
    # Only where the plant's own gains can hold that pose well short of a jackknife (with the
    # paper's eta = 3 the axle would stand at beta = 3 phi, beyond 90 deg on an R = 1 m circle).
    for phi, eta in zip(phis, plant_p.etas, strict=True):
        if abs(math.degrees(phi)) > 0.5 * jackknife_phi_deg(eta):
            return (0.0,) * n
    return phis


def _disturbance_limit(scenario: Scenario, nominal: Params) -> float | None:
    limit = scenario.disturbance_limit
    if scenario.disturbance != "matched" or limit == "none":
        return None
    return nominal.torque_limit if limit == "actuator" else float(limit)


def _check_size(scenario: Scenario, duration: float) -> None:
    """Refuse runs too long to be meant, before any work: a path whose speed profile takes
    longer than the duration cap, or more physics steps than :data:`MAX_PHYSICS_STEPS`."""
    if duration > MAX_DURATION:
        raise ValueError(
            f"path {scenario.traj!r} takes {duration:.6g} s at its speed profile, more than the "
            f"{MAX_DURATION:g} s a run may last: use a shorter path, a higher speed (a v column, "
            "or --path-option cruise=...), or a --duration"
        )
    steps = duration / scenario.timestep
    if steps > MAX_PHYSICS_STEPS:
        raise ValueError(
            f"timestep={scenario.timestep!r} s over {duration:.6g} s is {steps:.4g} physics "
            f"steps: at most {MAX_PHYSICS_STEPS} are allowed (use a larger timestep or a shorter "
            "duration)"
        )


class LegStart(NamedTuple):
    """Where a leg of a planned maneuver starts: the plan, the leg's index, and the state the
    last leg stopped in (the tractor's pose, the hitch angles; None: the plan's start)."""

    plan: Any
    index: int
    pose: tuple | None = None
    phis: tuple | None = None


def build(scenario: Scenario, leg: LegStart | None = None) -> Build:
    """Validate ``scenario`` and build its run.

    A planned run (``traj="plan"``) is built for the plan's first leg, or for ``leg``: the
    run drives one leg, its ``scenario`` the given one with ``reverse`` the leg's (see
    :mod:`tt_mujoco.sim.maneuver`).

    Raises
    ------
    ValueError
        Naming the first bad option and what is allowed.
    TypeError
        ``scenario`` is not a :class:`~tt_mujoco.sim.scenario.Scenario`.
    """
    if not isinstance(scenario, Scenario):
        hint = f", e.g. Scenario(traj={scenario!r})" if isinstance(scenario, str) else ""
        raise TypeError(
            f"scenario={shown(scenario)} is not allowed: give a tt_mujoco.sim.Scenario{hint}"
        )
    scenario.validate()
    world = parse_world(scenario.world)
    backs_up = scenario.reverse  # a leg of a maneuver that backs up may not
    scenario, leg = _leg_of(scenario, world, leg)
    nominal = scenario.nominal_params()
    plant_p = scenario.plant_params()
    _plant_class(scenario.plant).check_supported(scenario.disturbance)
    cls = _controller_class(scenario.controller, backs_up)
    reversing = reversing_drive(scenario, cls)
    path, target, pose, start_s = _path_and_target(scenario, leg)
    duration = float(target.duration)
    _check_size(scenario, duration)
    plan = None if leg is None else leg.plan
    target = _outer_target(scenario, target, nominal, reversing, plan)
    dt = scenario.control_dt
    # "on_path": the vehicle starts in the reference's initial state, pose *and* speed (paper
    # Section 6.3). The paper's static cycloid target starts at 0.765 m/s while its vehicle is
    # at rest; that step spins the wheels in contact physics. "paper" reproduces it.
    v_init = target.reference_speed(0.0) if scenario.start == "on_path" else 0.0
    if scenario.noise_snr_db is not None:
        noise = noise_std(target, duration, float(scenario.noise_snr_db))
    else:
        noise = (0.0, 0.0)
    result = Build(
        scenario=scenario,
        nominal=nominal,
        plant_params=plant_p,
        path=path,
        target=target,
        initial_pose=tuple(pose),
        duration=duration,
        control_dt=dt,
        substeps=round(dt / scenario.timestep),
        steps=round(duration / dt),
        v_init=v_init,
        noise_std=noise,
        disturbance=(
            make_disturbance(scenario.disturbance_model) if scenario.disturbance != "none" else None
        ),
        disturbance_limit=_disturbance_limit(scenario, nominal),
        controller_class=cls,
        controller_setup=_controller_setup(scenario, nominal, path),
        extra_metrics=resolve_metrics(scenario.metrics),
        path_schedule=(
            path_schedule(path, [(t.L, t.L0) for t in plant_p.trailers])
            if scenario.eta_schedule_kind == "path"
            else None
        ),
        start_s=start_s,
        reversing=reversing,
        initial_hitches=(
            _initial_hitches(scenario, path, start_s, plant_p, reversing)
            if leg is None or leg.phis is None
            else tuple(leg.phis)
        ),
        delay_steps=_delay_steps(scenario, dt, duration),
        relief=relief_of(parse_terrain(scenario.terrain), drawn_polyline(path, duration), plant_p),
        world=world,
        plan=plan,
        leg=0 if leg is None else leg.index,
        along_track_gain=_along_track_gain(scenario),
    )
    check_world(result.world, plant_p, result.initial_pose, result.initial_phis())
    result.new_faults()  # a fault after the end of the run is refused now
    result.new_controller()  # bad gains, and a user's __init__ that fails, before any work
    return result


def _leg_of(scenario: Scenario, world, leg: LegStart | None):
    """``(scenario, leg)``: a planned run's first leg planned now (``traj="plan"``), and the
    scenario driving the leg's direction; a run without a plan as it is."""
    if scenario.traj == PLAN and leg is None:
        if world is None:
            raise ValueError("traj='plan' is not allowed without a world: give --world")
        deadline = time.monotonic() + scenario.time_limit_s
        plan = planned(
            world, scenario.plant_params(), scenario.seed, bool(scenario.reverse), deadline
        )
        leg = LegStart(plan, 0)
    if leg is None:
        return scenario, None
    if leg.plan.cusps and parse_faults(scenario.faults):
        raise StartError(
            f"faults={scenario.faults!r} is not allowed here: this start's plan has "
            f"{leg.plan.cusps} cusp(s), each leg a run from rest, and a fault is timed within "
            "one run (give a start the train backs in from directly, or no faults)"
        )
    return dataclasses.replace(scenario, reverse=leg.plan.legs[leg.index].reverse), leg


def _controller_class(spec: str, backs_up: bool) -> type:
    """The controller's class, refused for a run that backs up when it cannot."""
    cls = controller_class(spec)
    if backs_up and not getattr(cls, "REVERSE", True):
        backing = ", ".join(n for n in CONTROLLERS if getattr(CONTROLLERS[n], "REVERSE", True))
        raise ValueError(
            f"controller={spec!r} with reverse=True is not allowed: it tracks the "
            f"path driving forward only (these back up: {backing})"
        )
    return cls


def _path_and_target(scenario: Scenario, leg: LegStart | None):
    """``(path, target, initial pose, start arc length)``: the scenario's path (or the leg's,
    its share of the duration by its length) and its target, backing up when it does, from
    where the last leg stopped when there was one."""
    stop_s = 0.0  # where backing stops on the path (a planned leg's)
    if leg is not None:
        plan = leg.plan
        ramp = {k: v for k, v in scenario.path_options.items() if k in ("cruise", "ramp_time")}
        planned_leg = plan.legs[leg.index]
        stop_s = planned_leg.stop_s
        duration = scenario.duration
        if duration is not None and plan.cusps:  # each leg its share, by its length
            whole = sum(one.driven_length for one in plan.legs)
            steps = round(duration * planned_leg.driven_length / whole / scenario.control_dt)
            duration = max(steps, 1) * scenario.control_dt
        path, target, pose = target_on(
            planned_leg.path, scenario.target, duration, planned_leg.driven_length, **ramp
        )
    else:
        path, target, pose = make_target(
            scenario.traj,
            kind=scenario.target,
            duration=scenario.duration,
            start=scenario.start,
            **scenario.path_options,
        )
    start_s = 0.0
    if scenario.reverse:
        target = ReverseTarget(target, stop_s)
        pose = target.initial_pose
        start_s = target.s_end
    if leg is not None and leg.pose is not None:
        pose = leg.pose  # where the last leg stopped
    return path, target, pose, start_s


def _outer_target(scenario: Scenario, target, nominal, reversing: str, plan):
    """The target with what sets its yaw-rate target from the errors: path feedback, the
    hitch cascade backing up, or a plan's forward legs' feedback."""
    if scenario.path_feedback is not None:
        return PathFeedback.from_config(target, scenario.path_feedback)
    if reversing == "hitch_cascade":
        return HitchCascade.from_config(target, nominal, scenario.hitch_feedback)
    if plan is not None and not scenario.reverse:
        return PathFeedback.from_config(target, {})  # see PLAN_FORWARD_DRIVE
    return target


def _controller_setup(scenario: Scenario, nominal, path) -> ControllerSetup:
    """What the controller is built with: the nominal parameters and model, the limits, the
    control period, the path and the direction."""
    return ControllerSetup(
        params=nominal,
        model=reduced_model(nominal),
        torque_limit=nominal.torque_limit,
        control_dt=scenario.control_dt,
        path=path,
        reverse=bool(scenario.reverse),
        # the path schedule steers the axles by actuators (PathEtaScheduler)
        axle_slew_rate=(
            nominal.axle_slew_rate if scenario.eta_schedule_kind == "path" else math.inf
        ),
    )

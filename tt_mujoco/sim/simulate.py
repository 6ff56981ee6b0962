"""Run a scenario to the end with its controller: the stepper, a controller, the metrics."""

from __future__ import annotations

import contextlib
import signal
import threading
import time
from dataclasses import dataclass, field
from numbers import Integral

import numpy as np

from tt_mujoco.analysis.metrics import compute_metrics, run_error_signals
from tt_mujoco.defaults import MAX_SPEED
from tt_mujoco.guard import (
    control_signal,
    keeping_process_state,
    noting_interrupts,
    users_failure,
)
from tt_mujoco.registry import HookError, finite_number, real_number, shown
from tt_mujoco.registry import describe_failure as usercode_failure
from tt_mujoco.sim.build import (
    PLAN_FORWARD_DRIVE,
    REVERSING_DRIVES,
    Build,
    build,
    drawn_polyline,
)
from tt_mujoco.sim.loop import compiled
from tt_mujoco.sim.loop.stepper import Stepper
from tt_mujoco.sim.parts import faults as faults_mod
from tt_mujoco.sim.parts.ground import ground_report, parse_patches
from tt_mujoco.sim.parts.plant import StopRun
from tt_mujoco.sim.parts.relief import RampRelief
from tt_mujoco.sim.parts.terrain import parse_terrain
from tt_mujoco.sim.probe import check_user_code
from tt_mujoco.sim.scenario import SCHEMA, Scenario
from tt_mujoco.sim.usercode import CheckedProgress, users_copy
from tt_mujoco.watchdog import grace_for
from tt_mujoco.world.part import world_report

__all__ = ["Result", "checked_build", "simulate"]


@dataclass
class Result:
    """A finished (or stopped) run."""

    scenario: Scenario
    timeseries: dict[str, np.ndarray]
    metrics: dict
    status: str  # "ok", "jackknife", "diverged", "collision" or "failed" (the user's code)
    message: str
    reference_polyline: np.ndarray
    wall_time_s: float
    config: dict
    #: The traceback of the user code that stopped a "failed" run (None otherwise).
    details: str | None = None
    #: What the run says about how it ran, a sentence each (the command line prints them and
    #: writes them to ``metrics.json``'s ``notes``): why the Python loop ran instead of the
    #: compiled one, what drove the vehicle backing up.
    notes: list[str] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return self.status == "ok"


@control_signal
class TimeLimitExceeded(BaseException):
    """The run's wall-clock limit passed (raised by SIGALRM wherever the run then was;
    a BaseException, so that the guard around user code does not take it for the user's)."""


@contextlib.contextmanager
def wall_time_limit(seconds: float, told: float | None = None):
    """Raise :class:`TimeLimitExceeded` (of ``told``, the limit as the user gave it; default
    ``seconds``) in this thread after ``seconds`` of wall time; a no-op outside a process's
    main thread, where signals cannot be received."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def expired(signum, frame):
        raise TimeLimitExceeded(seconds if told is None else told)

    previous = signal.signal(signal.SIGALRM, expired)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, previous)


def checked_build(scenario: Scenario) -> Build:
    """What every route does before a run: :func:`~tt_mujoco.sim.build.build` ``scenario``
    and try its user code once (:func:`~tt_mujoco.sim.probe.check_user_code`), within the
    scenario's time limit (``time_limit_s``, and the grace
    :func:`tt_mujoco.watchdog.grace_for` adds to it).

    Raises
    ------
    ValueError
        A bad option, or a user's code that fails; a :class:`~tt_mujoco.registry.HookError`
        too for a set-up that passed the time limit (a user's import, constructor or path
        factory that does not return), naming where it was. Code stuck inside one call into C
        is stopped when that call returns: the in-process limit acts between bytecodes.
    """
    limit = None  # no limit to keep, or a bad one: build names it
    if isinstance(scenario, Scenario):
        with contextlib.suppress(ValueError):
            limit = SCHEMA["time_limit_s"].parse(scenario.time_limit_s, "time_limit_s")
    # after a grace (the watchdog's): a budget of the set-up's own that keeps the limit (the
    # planner's) ends first and says so itself; this catches only what does not return
    grace = None if limit is None else grace_for(limit)
    try:
        with (
            wall_time_limit(grace, limit) if grace is not None else contextlib.nullcontext(),
            keeping_process_state(),
        ):
            built = build(scenario)
            check_user_code(built)
    except TimeLimitExceeded as err:
        where = usercode_failure(err).split(": ")[0]
        where = f"in {where}" if ", line " in where else "in tt-mujoco's own set-up"
        raise HookError(
            f"the run's set-up passed its time limit of {err.args[0]:g} s (wall clock; "
            f"--time-limit) {where}, before anything was simulated (a user's import, "
            "constructor or path that did not return)"
        ) from None
    return built


def _time_limit_stop(stepper: Stepper, err: TimeLimitExceeded) -> tuple[str, str]:
    import traceback

    stepper.stop_details = "".join(traceback.format_exception(err))
    t = max(stepper.samples - 1, 0) * stepper.dt
    where = usercode_failure(err).split(": ")[0]
    return "failed", (
        f"the run passed its time limit of {err.args[0]:g} s (wall clock; --time-limit) at "
        f"t={t:.3f} s, in {where}"
    )


def run_episode(stepper: Stepper, controller, progress=None, on_step=None) -> tuple[str, str]:
    """Drive ``stepper`` (already reset) with ``controller`` to the end or a stop.

    Returns ``(status, message)``; see :func:`simulate` for ``progress`` and ``on_step``. The
    compiled loop runs the episode where it can; where it cannot, the Python loop runs it (the
    same numbers) and ``stepper.loop_note`` says why, the one place every fallback is told.
    """
    sooner = compiled.loading_pays(stepper.built)  # counts the process's episodes
    why = compiled.unsupported(stepper.built, controller, on_step)
    if why is None and sooner is not None:
        compiled.ask_for_cache()  # no cache to judge: the Python loop runs this one anyway
        stepper.loop_note = python_loop_note(sooner=sooner)
    else:
        why = why or compiled.not_ready()
        if why is None:
            try:
                return compiled.run_compiled(stepper, controller, progress)
            except compiled.Fallback as fallback:
                why = str(fallback)
        stepper.loop_note = python_loop_note(why)
    stepper.begin(controller)
    return stepper.run(progress=progress, on_step=on_step)


def python_loop_note(slower: str | None = None, sooner: str | None = None) -> str | None:
    """The run's note for an episode the Python loop ran instead of the compiled one: why the
    compiled loop could not run it (``slower``), or why the Python loop is the faster here
    (``sooner``)."""
    if sooner is not None:
        return f"the Python loop ran this episode (the same numbers, sooner): {sooner}"
    if slower is not None:
        return f"the Python loop ran this episode (the same numbers, slower): {slower}"
    return None


def simulate(
    scenario: Scenario | Build, progress=None, on_step=None, checkpoint=None, on_rows=None
) -> Result:
    """Run one scenario. Never raises for a diverging run: see ``Result.status``.

    Parameters
    ----------
    scenario : Scenario or Build
        A scenario, or the :class:`~tt_mujoco.sim.build.Build` of one (a caller that built it
        to check its input first, as the CLI does, need not build it again; such a caller
        also calls :func:`tt_mujoco.sim.probe.check_user_code` on it first).
    progress : callable, optional
        Called as ``progress(steps_done, steps_total)`` about every 1 % of the run.
    on_step : callable, optional
        Called as ``on_step(t, plant)`` after every control step, ``t`` the new time and
        ``plant`` the running :class:`~tt_mujoco.sim.parts.plant.Plant`; the live viewer uses it. An
        exception it raises ends the run and propagates.
    checkpoint : path, optional
        A file that receives the logged rows block by block while the run goes on (see
        :meth:`tt_mujoco.sim.loop.stepper.Stepper.reset`).
    on_rows : callable, optional
        Called as ``on_rows(timeseries, reference_polyline, signals)`` once the run is over,
        before its metrics are computed (those of ``Result``; the CLI's figures are drawn
        meanwhile), ``signals`` the run's
        :func:`~tt_mujoco.analysis.metrics.run_error_signals` that its metrics take (None for a
        maneuver's joined legs, each measured against its own path). It must change none of
        them.

    Raises
    ------
    ValueError
        For bad configuration values, and a user's controller or disturbance that fails
        before the run (:class:`tt_mujoco.registry.HookError`), before anything is simulated.
        User code that fails during the run stops it instead: status ``"failed"``, the
        traceback in ``Result.details``.
    """
    built = scenario if isinstance(scenario, Build) else checked_build(scenario)
    if progress is not None:  # a caller's code: its failure stops the run as "failed"
        progress = CheckedProgress(progress, built.scenario.control_dt)
    if built.plan is not None and built.plan.cusps:
        from tt_mujoco.sim.maneuver import drive  # a maneuver: its legs one after the other

        result = drive(built, progress, on_step, checkpoint)
        if on_rows is not None:
            on_rows(result.timeseries, result.reference_polyline, None)
        return result
    rng = np.random.default_rng(built.scenario.seed)
    leg = drive_leg(built, rng, built.scenario.time_limit_s, progress, on_step, checkpoint)
    return finish(built, *leg, on_rows=on_rows)


def drive_leg(built: Build, rng, time_limit: float, progress=None, on_step=None, checkpoint=None):
    """``(stepper, controller, status, message, wall)``: one episode of ``built`` (a run, or
    one leg of a maneuver) with the noise of ``rng``, stopped after ``time_limit`` s of wall
    time (what is left of the scenario's); the others as :func:`simulate`'s."""
    compiled.prepare()  # beside the set-up below
    stepper = Stepper(built)
    with keeping_process_state():  # the user's resets
        stepper.reset(rng, checkpoint=checkpoint)
        controller = built.new_controller()
        controller.reset()
    start_wall = time.perf_counter()
    try:
        with (
            wall_time_limit(time_limit, built.scenario.time_limit_s),
            noting_interrupts(),
            keeping_process_state(),
        ):
            status, message = run_episode(stepper, controller, progress, on_step)
    except TimeLimitExceeded as err:
        status, message = _time_limit_stop(stepper, err)
    finally:
        stepper.close()  # the checkpoint file, if any, then holds every row computed
    wall = time.perf_counter() - start_wall
    if progress is not None:
        try:
            progress(stepper.steps, stepper.steps)
        except StopRun as stop:  # the caller's progress failed at the end: the run's failure
            if status == "ok":
                status, message, stepper.stop_details = stop.status, stop.message, stop.details
    return stepper, controller, status, message, wall


def controller_report(controller) -> tuple[dict, str | None]:
    """``(report, error)``: the controller's :meth:`~tt_mujoco.controllers.Controller.report`,
    each value a finite number or None (strict JSON); a user's report that fails, or is not a
    dict of numbers, must not lose the run."""
    try:
        with keeping_process_state():
            report = controller.report()
        if not isinstance(report, dict):
            raise TypeError(f"report() returned {shown(report)}, not a dict")
        clean = {}
        for key, value in report.items():
            if value is not None and not real_number(value):
                raise TypeError(f"report() value {key}={shown(value)} is not a number or None")
            number = None if value is None else finite_number(value)  # NaN, inf: None
            if number is not None and isinstance(value, Integral):
                number = int(value)
            clean[str(key)] = number
        return clean, None
    except BaseException as err:  # the user's code: kept as an error, never raised
        if not users_failure(err):
            raise
        return {}, usercode_failure(err)


def user_metric(fn, ts: dict, path) -> tuple[float | None, str | None]:
    """``(value, error)`` of a user's metric on read-only views of the time series: a metric
    that fails, or returns something other than a number, must not lose the run (its value
    is then None and its error kept), nor change the series the run saves."""
    if not len(ts["t"]):
        return None, None
    views = {}
    for key, column in ts.items():
        views[key] = column.view()
        views[key].flags.writeable = False
    try:
        value = fn(views, path)
    except BaseException as err:
        if not users_failure(err):
            raise
        return None, usercode_failure(err)
    return metric_value(value)


def metric_value(value) -> tuple[float | int | None, str | None]:
    """``(value, error)`` of what a user's metric returned: a finite real number (a NumPy
    scalar made plain; an integer kept whole) or None; anything else (a bool, a string, a
    NaN or an infinity, an integer beyond a float) is None and the error says what it was,
    so that every ``metrics.json`` reads back as strict JSON."""
    if value is None:
        return None, None
    number = finite_number(value)
    if number is None:
        return None, f"it returned {shown(value, 60)}: a metric returns a number or None (finite)"
    return (int(value) if isinstance(value, int | np.integer) else number), None


def reference_polylines(built: Build) -> tuple[np.ndarray, np.ndarray]:
    """The reference path as the run can reach it (``(N, 2)``, to draw: :func:`drawn_polyline`),
    and as distances are measured to it: one period of a path that repeats itself (a circle's
    laps coincide, and projecting onto every lap would cost the run's length times its laps).
    """
    path = built.path
    drawn = drawn_polyline(path, built.duration)
    if path.period is None or path.period >= min(path.length, MAX_SPEED * built.duration):
        return drawn, drawn
    return drawn, path.dense(length=path.period)


def _relief_times(relief, ts) -> dict:
    """On a ramp: when the tractor's axle P reached its foot (None: never) and the mean torque
    it took from then on."""
    if not isinstance(relief, RampRelief):
        return {}
    up = relief.height(ts["x"], ts["y"]) > 0.0
    if not up.any():
        return {"t_ramp_reached": None, "torque_sum_mean_on_ramp": None}
    first = int(np.argmax(up))
    torque = ts["T_r"][first:] + ts["T_l"][first:]
    return {
        "t_ramp_reached": float(ts["t"][first]),
        "torque_sum_mean_on_ramp": float(torque.mean()),
    }


def driven_leg(leg: dict, reverse: bool, metrics: dict, t, status: str, offset=0.0) -> None:
    """Add to a plan's ``leg`` report how it was driven: when (``t_start_s``, ``t_end_s``,
    the maneuver's time), how it ended, and its leading point's rms off its path."""
    leg["t_start_s"] = offset
    leg["t_end_s"] = offset + float(t[-1]) if len(t) else offset
    leg["status"] = status
    leading = "leading_cross_track_rms" if reverse else "cross_track_rms"
    leg["leading_cross_track_rms"] = metrics.get(leading)


def finish(
    built: Build, stepper: Stepper, controller, status, message, wall, on_rows=None
) -> Result:
    """The :class:`Result` of an episode: time series, metrics (built-in and the scenario's
    extra ones) and the configuration; ``on_rows`` as :func:`simulate`'s."""
    scenario = built.scenario
    ts = stepper.timeseries(release=True)
    polyline, measured_against = reference_polylines(built)
    signals = run_error_signals(ts, measured_against, scenario.reverse) if len(ts["t"]) else None
    if on_rows is not None:
        on_rows(ts, polyline, signals)
    limit = built.nominal.torque_limit
    if len(ts["t"]):
        metrics = compute_metrics(ts, measured_against, limit, scenario.reverse, signals)
    else:  # stopped before its first sample was logged
        metrics = {"steps": 0, "finite_samples": 0, "sim_time_s": 0.0}
    for name, fn in built.extra_metrics.items():
        with keeping_process_state():
            metrics[name], error = user_metric(fn, ts, users_copy(built.path))
        if error is not None:
            metrics.setdefault("metric_errors", {})[name] = error
    terrain = parse_terrain(scenario.terrain)
    if not terrain.flat and len(ts["t"]):
        metrics["terrain"] = {
            **terrain.report(),
            **(built.relief.report() if built.relief is not None else {}),
            "torque_sum_mean": float(np.mean(ts["T_r"] + ts["T_l"])),
            **_relief_times(built.relief, ts),
        }
    if scenario.ground and len(ts["t"]):
        metrics["ground"] = ground_report(parse_patches(scenario.ground), stepper.ground_masks, ts)
    if built.world is not None:
        metrics["world"] = world_report(
            built.world, built.plant_params, ts, stepper.world_clearance, stepper.collision
        )
        if built.plan is not None:
            report = built.plan.report()
            driven_leg(report["legs"][built.leg], scenario.reverse, metrics, ts["t"], status)
            metrics["world"]["plan"] = report
    report, error = controller_report(controller)
    if report:
        metrics["controller"] = report
    if error is not None:
        metrics.setdefault("metric_errors", {})["controller.report"] = error
    if built.reversing is not None:
        metrics["reversing"] = built.reversing
    metrics["wall_time_s"] = wall
    metrics["status"] = status
    if stepper.faults is not None:
        record = stepper.records.loop.faults  # the faults' state as the episode left it
        metrics["faults"] = faults_mod.fault_report(
            stepper.faults, record, ts, measured_against, limit
        )
    notes = [stepper.loop_note] if stepper.loop_note else []
    if built.reversing is not None:
        notes.append(f"backing up: {REVERSING_DRIVES[built.reversing]}")
    elif built.plan is not None and scenario.path_feedback is None:
        notes.append(PLAN_FORWARD_DRIVE)
    config = {
        "scenario": scenario.to_dict(),
        "nominal_params": built.nominal.to_dict(),
        "plant_params": built.plant_params.to_dict(),
        "controller": {"name": controller.name, "gains": controller.gains},
        "target": {"kind": scenario.target, "duration_s": built.duration, "path": built.path.name},
        "noise_std": {"v": built.noise_std[0], "omega": built.noise_std[1]},
        "substeps": built.substeps,
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
        details=stepper.stop_details,
        notes=notes,
    )

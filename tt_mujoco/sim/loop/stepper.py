"""One episode of a built scenario: its objects, its records, its loop and its logged rows.

:func:`tt_mujoco.sim.simulate.simulate`, the Gymnasium environment and the live viewer all use
:class:`Stepper`; only who computes the torques differs (a built-in law, a user's law or
controller, an agent). Its step is :mod:`tt_mujoco.sim.loop.closed_loop`'s, the only one, over the
episode's records (:mod:`tt_mujoco.sim.loop.episode`):

- :meth:`Stepper.run` runs the episode to its end chunk by chunk, with the kernel's compiled
  loop (:mod:`tt_mujoco.sim.loop.compiled`) or CPython's over the same source
  (:func:`tt_mujoco.sim.loop.closed_loop.run_steps`), a controller's Python ``compute`` called
  between the halves of every step;
- :meth:`Stepper.sense` and :meth:`Stepper.actuate` run one step's halves
  (:func:`~tt_mujoco.sim.loop.closed_loop.sense_step`, :func:`~tt_mujoco.sim.loop.closed_loop.
  actuate_step`) for an agent that computes the torques in between.

A control step ``k`` (time ``t = k dt``) measures the plant, stops on a blow-up or jackknife,
adds measurement noise and sensor faults, updates the target; the law's torques are clipped at
the limit, actuator faults, payloads and the disturbance applied, the row logged, and (unless
``k`` is the last step) the scheduled eta updated and the plant advanced one control period.
"""

from __future__ import annotations

import math
import operator

import numpy as np

from tt_mujoco.controllers import Reference
from tt_mujoco.defaults import JACKKNIFE_DEG, MAX_SPEED
from tt_mujoco.guard import users_failure
from tt_mujoco.sim import usercode
from tt_mujoco.sim.build import Build
from tt_mujoco.sim.loop import closed_loop, episode, outcome, records, target_step
from tt_mujoco.sim.loop.checkpoint import Checkpoint
from tt_mujoco.sim.loop.python_law import PythonLaw, law_failure, reference_of, seen_measurement
from tt_mujoco.sim.loop.records import (
    Limits,
    LogRecord,
)
from tt_mujoco.sim.loop.step import COLLISION, FINISHED, PAYLOAD, RUNNING, SINGULAR, WARNING
from tt_mujoco.sim.loop.timeseries import LOOP_COLUMNS, assemble_columns, train_columns
from tt_mujoco.sim.parts.measure import TRAIN_FIELDS, Measurement, TrainMeasurement
from tt_mujoco.sim.parts.motors import DcMotors
from tt_mujoco.sim.parts.plant import StopRun
from tt_mujoco.sim.parts.schedule import eta_series_of
from tt_mujoco.sim.parts.wind import DragConstants, parse_wind
from tt_mujoco.sim.scenario import jackknife_phi_deg
from tt_mujoco.world.part import world_record

__all__ = ["CHECKPOINT_COLUMNS", "Stepper"]

#: Columns of a checkpoint file: the measurement and the loop's own values, as logged.
CHECKPOINT_COLUMNS = (*Measurement._fields, *LOOP_COLUMNS)

#: Rows of a chunk of steps, logged together and then kept as one block of float arrays.
CHUNK = 8192
#: The stops that log their step's row (a stop in the advance, a payload step, the end).
LOGGING_STOPS = (FINISHED, WARNING, SINGULAR, PAYLOAD)
_LOOP_VALUES = operator.attrgetter(*LOOP_COLUMNS)


def _called_back(stepper, made, kernel, by_address: bool = False):
    """The kernel's records with the Python they hold (a law, a path without closed form, a
    user's disturbance) as C functions it calls back (:class:`tt_mujoco.sim.loop._kernel.
    CalledBack`), each given the records it reads and writes; placeholders where there is
    none."""
    loop, plant, law, target, stop = made
    path, disturbance = target.path_hook, loop.disturbance_hook
    who = usercode.controller_label(stepper.built)

    def path_answer(what: float, s: float) -> tuple:
        if what == target_step.HOOK_CURVATURE:
            return path.curvature_and_rate(s)
        if what == target_step.HOOK_POSE:
            return path.pose_at(s)
        try:  # the reference pose of a plain-number law: its Python form asks the path itself
            return path.path.pose_at(s)
        except BaseException as err:
            if not users_failure(err):
                raise
            raise law_failure(who, float(law.reference[0]["t"]), err) from None

    target = target._replace(
        path_hook=kernel.no_hook
        if path is None
        else kernel.HookCallback(path_answer, target.hook_out)
    )
    loop = loop._replace(
        disturbance_hook=kernel.no_hook
        if disturbance is None
        else kernel.HookCallback(lambda what, t: disturbance(t), loop.hook_out)
    )
    hooks = (law.user, target.path_hook, loop.disturbance_hook)
    for hook in hooks:
        if isinstance(hook, kernel.CalledBack):
            hook.stop_record = stop
    stepper.hooks = hooks  # held while the kernel calls them
    if by_address:  # an agent's step, one call a step: the kernel takes integers at no cost
        law = law._replace(user=kernel.address_of(law.user))
        target = target._replace(path_hook=kernel.address_of(target.path_hook))
        loop = loop._replace(disturbance_hook=kernel.address_of(loop.disturbance_hook))
    if isinstance(hooks[0], kernel.PythonLawCallback):
        hooks[0].law_record = law
    return records.EpisodeRecords(loop, plant, law, target, stop)


class Stepper:
    """One episode of a built scenario.

    Parameters
    ----------
    built : Build
        From :func:`tt_mujoco.sim.build.build`.
    steps : int, optional
        The control steps its records, noise and log are made for (default the run's,
        ``built.steps``): a look at the first step alone needs one, not the episode's
        tables (:mod:`tt_mujoco.sim.probe`).
    """

    def __init__(self, built: Build, steps: int | None = None):
        self.built = built
        self.dt = built.control_dt
        self.steps = built.steps if steps is None else steps
        self.eta = built.nominal.eta
        bound = built.disturbance_limit
        self.limits = Limits(
            torque_limit=built.nominal.torque_limit,
            disturbance_bound=math.inf if bound is None else bound,
            jackknife_phi=math.radians(jackknife_phi_deg(self.eta)),
            jackknife_beta=math.radians(JACKKNIFE_DEG),
            max_speed=MAX_SPEED,
            noise_v=built.noise_std[0],
            noise_w=built.noise_std[1],
        )
        # Trailers 2..N: their hitch limits, and their logged columns after the usual ones.
        etas = built.plant_params.etas
        self.train_limits = [math.radians(jackknife_phi_deg(e)) for e in etas[1:]]
        self.train_columns = train_columns(len(etas))
        self.checkpoint_columns = (*CHECKPOINT_COLUMNS, *self.train_columns)
        self.plant = None
        self._checkpoint = None
        self._episode = None
        self._end_status = None
        self._log = None

    def reset(
        self, rng: np.random.Generator, phi0_deg: float | None = None, checkpoint=None
    ) -> None:
        """Start an episode: a fresh plant in the initial state, the target and faults reset,
        the noise of the whole episode drawn from ``rng`` (v_k, omega_k, ... in step order, the
        same numbers as drawing them step by step).

        ``checkpoint``, a file path, receives every block of logged rows as it is kept (an
        Arrow IPC stream of the raw logged columns, :class:`~tt_mujoco.sim.loop.checkpoint.
        Checkpoint`): a run killed after an hour keeps what it computed there. :meth:`close`
        writes the rows not yet kept.
        """
        b = self.built
        self.close()  # a previous episode's checkpoint
        self._checkpoint = (
            None if checkpoint is None else Checkpoint(checkpoint, self.checkpoint_columns)
        )
        self.plant = b.new_plant(phi0_deg)
        self.faults = b.new_faults()
        self.motors = (
            DcMotors(b.plant_params, b.control_dt) if b.scenario.actuator == "dc_motor" else None
        )
        self.world = world_record(b.world, b.plant_params, self.steps)
        self._end_status = None  # the stop code the episode ended with (None: not ended)
        self.scheduler = b.new_scheduler(self.plant)
        self._given_path = None  # a copy for the code sense() is for, made on first use
        self.k = 0
        self.finished = False
        self.stop_details = None  # the traceback of user code that stopped the episode
        self.loop_note = None  # why the Python loop ran it, as the run's note (run_episode)
        self._signals: dict[str, np.ndarray] = {}  # what the controller logged, by name
        noise_v, noise_w = b.noise_std
        self.noise = rng.standard_normal(2 * (self.steps + 1)) if noise_v or noise_w else None
        episode.prepare_profile(b, self.steps)  # the targets' table, with the noise
        wind = parse_wind(b.scenario.wind)
        # the gusts are drawn after the noise, so that a wind leaves the noise as it was
        self.wind_speeds = None if wind.calm else wind.speeds(rng, self.steps, self.dt)
        direction = math.radians(wind.direction_deg)
        self.wind_direction = (math.cos(direction), math.sin(direction))
        self.drag = DragConstants(*(getattr(b.plant_params, f) for f in DragConstants._fields))
        self._blocks: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
        self._episode = None  # the records: begin()
        #: The C functions the kernel's records name by address (the law, the path, the
        #: disturbance; begin()), held while it runs.
        self.hooks: tuple = ()
        self._log = None  # the log of the rows being computed, from step _log_k; _taken kept

    # --- the records ---------------------------------------------------------------------
    def begin(self, controller=None, compiled_law=None, kernel=None, by_address=False) -> tuple:
        """Make the (reset) episode's records for ``controller``: ``(loop, plant, law, target,
        stop)`` (:func:`tt_mujoco.sim.loop.episode.episode_records`).

        With the compiled ``kernel`` (:mod:`tt_mujoco.sim.loop._kernel`), the records are NumPy's,
        for its loop, with ``compiled_law`` a plain-number law compiled for it (its placeholder
        for a built-in law), or None for a controller whose Python ``compute`` the kernel calls
        back, as it calls back a path without closed form and a user's disturbance (C functions
        of the kernel's). Otherwise CPython runs the step on the records as plain objects
        (:func:`tt_mujoco.sim.loop.records.interpreted`): a built-in law's own function, or any
        other controller's Python ``compute`` between the halves (None: an agent's torques,
        :meth:`sense` and :meth:`actuate`). ``by_address``: the kernel's records name their C
        functions by address (an agent's step, :meth:`begin_agent`), else by object (the
        chunk loop's).
        """
        python = None
        if kernel is not None:
            callback = None
            if compiled_law is None:  # a controller's compute, called back from the kernel
                python = PythonLaw(self, controller)
                callback = kernel.PythonLawCallback(python)
            made = episode.episode_records(self, controller, compiled_law, callback)
            made = _called_back(self, made, kernel, by_address)
        else:
            self.hooks = ()
            if controller is None or not episode.runs_built_in(controller):
                python = PythonLaw(self, controller)
            made = records.listed(
                records.interpreted(episode.episode_records(self, controller, None, python))
            )
        if python is not None:
            python.steering = made.plant.steering
        self._episode, self._log = made, None
        self._controller = controller
        self._interpreted = kernel is None
        etas = tuple(np.asarray(made.plant.steering.etas).tolist())
        self._changes = [(0, etas)]  # (first row, gains) of each change
        if self.motors is not None:  # the motors' torques as the step delivers them
            self.motors.torques = made.loop.motor_torques
        return made

    def begin_agent(self, kernel=None) -> tuple:
        """Make the (reset) episode's records for an agent's steps
        (:mod:`tt_mujoco.sim.loop.agent_step`), for the compiled ``kernel`` or, without one,
        for CPython: ``(loop, plant, law, target, log, stop)``, the log of two rows (step ``k``
        in row ``k % 2``)."""
        loop, plant, law, target, stop = self.begin(None, None, kernel, by_address=True)
        self._start_log(self.k, 2)
        return loop, plant, law, target, self._log, stop

    def agent_after_payload(self, k: int, advance) -> tuple[int, tuple]:
        """An agent's step ``k`` that a payload on the reduced plant interrupted
        (:data:`~tt_mujoco.sim.loop.step.PAYLOAD`): the plant's constants changed and the step
        advanced (``advance``: the kernel's or CPython's
        :func:`~tt_mujoco.sim.loop.closed_loop.advance_after_payload`). ``(status, records)``:
        the records as :meth:`begin_agent` gives them, the plant's a new one."""
        status, _ = self._after_payloads(PAYLOAD, k, advance)
        loop, plant, law, target, stop = self._episode
        return status, (loop, plant, law, target, self._log, stop)

    def hook_failure(self) -> BaseException | None:
        """What Python code the kernel called back (a controller's ``compute``, a user's path
        or disturbance) raised in this episode, which its caller raises; None if nothing did."""
        for hook in self.hooks:
            if getattr(hook, "raised", None) is not None:
                return hook.raised
        return None

    @property
    def records(self):
        """The episode's records (:meth:`begin`): after it ran, the state it left, which
        what a run reports reads (the faults': :func:`~tt_mujoco.sim.parts.faults.
        fault_report`)."""
        return self._episode

    # --- the episode, run to its end ------------------------------------------------------
    def run(self, run_chunk=None, advance=None, progress=None, on_step=None) -> tuple[str, str]:
        """Run the begun episode (:meth:`begin`) from step :attr:`k` to its end or a stop;
        ``(status, message)`` (:func:`tt_mujoco.sim.simulate.run_episode`).

        Parameters
        ----------
        run_chunk, advance : callable, optional
            The kernel's chunk loop and payload advance (:mod:`tt_mujoco.sim.loop.compiled`);
            default: CPython's, :func:`~tt_mujoco.sim.loop.closed_loop.run_steps` and
            :func:`~tt_mujoco.sim.loop.closed_loop.advance_after_payload`.
        progress, on_step : callable, optional
            As for :func:`tt_mujoco.sim.simulate.simulate`.
        """
        if run_chunk is None:
            run_chunk, advance = closed_loop.run_steps, closed_loop.advance_after_payload
        steps, k, status = self.steps, self.k, RUNNING
        report_every = max(1, steps // 100)
        size = 1 if on_step is not None else report_every * max(1, CHUNK // report_every)
        size = min(size, CHUNK, steps - k + 1)
        try:
            while status == RUNNING:
                self._start_log(k, size)
                loop, plant, law, target, stop = self._episode
                k_end = min(steps, k + size - 1)
                status, k_next = run_chunk(k, k_end, loop, plant, law, target, self._log, stop)
                self._take(k_next - k + (1 if status in LOGGING_STOPS else 0))
                status, k_next = self._after_payloads(status, k_next, advance)
                if on_step is not None and status == RUNNING:
                    self._sync_plant(k_next)
                    on_step(k_next * self.dt, self.plant)
                if progress is not None and (size > 1 or k_next % report_every == 0):
                    progress(k_next, steps)
                k = k_next
        except StopRun as stop_run:  # a Python law's failure, a user's disturbance's
            self.stop_details = stop_run.details
            self._end(None, self._fold())
            return stop_run.status, stop_run.message
        except BaseException:  # the time limit, an interrupt, a viewer closed: rows kept
            self._end(None, self._fold())
            raise
        self._end(status, k)
        return outcome.outcome(status, self._episode.stop, self, self._controller, k)

    def _after_payloads(self, status, k, advance) -> tuple[int, int]:
        """The payload changes a step made to the reduced plant's constants, and the step
        they interrupted (:data:`~tt_mujoco.sim.loop.step.PAYLOAD`) advanced: ``(status, k)``."""
        loop, plant, stop = self._episode.loop, self._episode.plant, self._episode.stop
        if not records.value_of(stop, "payloads"):
            return status, k
        plant = episode.carry_payloads(self, plant, loop.faults, stop)
        self._episode = self._episode._replace(plant=plant)
        if status == PAYLOAD:
            status = advance(plant, loop.wind, stop)
            k += 1 if status == RUNNING else 0
        return status, k

    def _end(self, status, k: int) -> None:
        """The episode's state at step ``k`` back to its objects (``status``: FINISHED, or
        not)."""
        self._sync_plant(k)
        self._end_status = status
        episode.hand_back(self, self._controller, status, k, self._episode.law)

    @property
    def collision(self) -> tuple | None:
        """``(unit, obstacle, t, gap)`` of the contact that stopped the episode (the indices of
        the unit and the world's obstacle, the time in s, the gap in m, negative: how deep),
        from its stop record; None when no contact stopped it."""
        if self._end_status != COLLISION:
            return None
        stop = records.values_of(self._episode.stop)
        return int(stop["unit"]), int(stop["obstacle"]), self.k * self.dt, stop["gap"]

    def _sync_plant(self, k: int) -> None:
        """The reduced plant's ODE state at step ``k``, for an ``on_step`` hook or the end."""
        plant = self._episode.plant
        if not plant.mujoco:
            self.plant.ode.state = plant.ode_state.copy()
            self.plant.ode.time = k * self.dt

    # --- the log -------------------------------------------------------------------------
    def _start_log(self, k: int, size: int) -> None:
        """Log the rows from step ``k`` in a log of ``size`` rows (CPython's is reused)."""
        log = self._log
        if log is None or not self._interpreted or len(log.loop) != size:
            n, n_trailers = size, self.built.plant_params.n_trailers
            scheduled = self._episode.plant.steering.kind != 0
            log = LogRecord(
                measurement=np.empty((n, len(records.MEASUREMENT_DTYPE))),
                loop=np.empty(n, dtype=records.LOG_DTYPE),
                train=np.empty((n, n_trailers - 1, len(TRAIN_FIELDS))),
                etas=np.empty((n if scheduled else 0, n_trailers)),
            )
            log.loop["t"] = math.nan  # a row is whole once its time is logged
            if self._interpreted:  # rows of floats (read back every step), not of NumPy's
                log = records.interpreted(log)
                lists = {name: getattr(log, name).tolist() for name in ("measurement", "train")}
                log = log._replace(etas=log.etas.tolist(), **lists)
        self._log, self._log_k, self._taken = log, k, 0

    def _whole_rows(self) -> int:
        """How many rows of the log are whole: those whose time is logged."""
        log, k, dt, i = self._log, self._log_k, self.dt, self._taken
        if self._interpreted:
            rows = log.loop
            while i < len(rows) and rows[i].t == (k + i) * dt:
                i += 1
            return i
        times = log.loop["t"]
        while i < len(times) and times[i] == (k + i) * dt:
            i += 1
        return i

    def _take(self, rows: int) -> None:
        """Keep the log's rows ``_taken..rows - 1`` as a block (:meth:`add_block`)."""
        first, log = self._taken, self._log
        if rows <= first:
            return
        self._taken = rows
        etas = log.etas[first:rows]
        if self._interpreted:
            loop = np.array([_LOOP_VALUES(row) for row in log.loop[first:rows]], dtype=float)
            measured = np.array(log.measurement[first:rows], dtype=float)
            trains = np.array(log.train[first:rows], dtype=float).reshape(rows - first, -1)
            etas = np.array(etas, dtype=float).reshape(rows - first, -1)
        else:
            loop = log.loop[first:rows].view(np.float64).reshape(rows - first, -1)
            measured = log.measurement[first:rows]
            trains = log.train[first:rows].reshape(rows - first, -1)
        self.add_block(measured, loop, trains)
        if self._episode.plant.steering.kind:
            new = episode.changes_of(etas, self._changes, self.samples - rows + first)
            self._changes.extend(new)

    def _fold(self) -> int:
        """Keep the whole rows of the log; the step of the first row not whole."""
        if self._log is None:
            return self.k
        rows = self._whole_rows()
        self._take(rows)
        return self._log_k + rows

    # --- one step at a time, for an agent -------------------------------------------------
    @property
    def t(self) -> float:
        return self.k * self.dt

    def sense(self) -> tuple[Measurement, Reference]:
        """The measurement as the law sees it (noise, faults and the delay included) and the
        target, at the current step (:func:`~tt_mujoco.sim.loop.closed_loop.sense_step`).

        Raises
        ------
        StopRun
            The state blew up or jackknifed.
        """
        if self._episode is None:
            self.begin(None)
        k = self.k
        if self._log is None or k - self._log_k >= len(self._log.measurement):
            self._fold()
            self._start_log(k, min(CHUNK, self.steps - k + 1))
        loop, plant, law, target, stop = self._episode
        code = closed_loop.sense_step(
            k, k - self._log_k, loop, plant, law, target, self._log, stop[0]
        )
        if code != RUNNING:
            self._stop(code, k)
        return seen_measurement(law), reference_of(law, self.given_path)

    @property
    def given_path(self):
        """The path as the code that :meth:`sense` is for sees it (an agent, a check before
        the run): a copy for the episode, so that what it changes stays with it."""
        if self._given_path is None:
            self._given_path = usercode.users_copy(self.built.path)
        return self._given_path

    @property
    def measurement(self) -> Measurement:
        """The plant's measurement at the current step (no noise, no fault: what the metrics
        read), after :meth:`sense`."""
        row = self.k - self._log_k
        values = [float(value) for value in self._log.measurement[row]]
        if len(self.train_limits) == 0:
            return Measurement._make(values)
        out = TrainMeasurement._make(values)
        out.train = tuple(tuple(float(value) for value in r) for r in self._log.train[row])
        return out

    def actuate(self, T_r: float, T_l: float, command: tuple[float, float] | None = None) -> bool:
        """Apply the torques of the current step and advance; False when the episode is over
        (:func:`~tt_mujoco.sim.loop.closed_loop.actuate_step`).

        Parameters
        ----------
        T_r, T_l : float
            Wheel torques (N m); clipped at the torque limit.
        command : (float, float), optional
            The unsaturated request, for the log (default: the torques given).
        """
        loop, plant, law, target, stop = self._episode
        got, k = law.reading[0], self.k
        got.T_r, got.T_l = T_r, T_l
        got.u1, got.u2 = (T_r, T_l) if command is None else command
        row = k - self._log_k
        code = closed_loop.actuate_step(k, row, loop, plant, law, target, self._log, stop[0])
        advance = closed_loop.advance_after_payload
        code, k_next = self._after_payloads(code, k + 1 if code == RUNNING else k, advance)
        if code == FINISHED:
            self._fold()
            self._end(FINISHED, k)
            return False
        if code != RUNNING:
            self._stop(code, k)
        self.k = k_next
        return True

    def _stop(self, code: int, k: int) -> None:
        """End the episode at step ``k`` with the stop ``code``: raise its StopRun."""
        self._fold()
        self._end(code, k)
        status, message = outcome.outcome(code, self._episode.stop, self, self._controller, k)
        raise StopRun(status, message)

    # --- what the episode logged -----------------------------------------------------------
    @property
    def plant_etas(self) -> tuple:
        """The trailers' steering gains eta_1..eta_N in force (a scheduler's, else the plant's
        constant ones)."""
        if self._episode is not None and self._episode.plant.steering.kind:
            return tuple(np.asarray(self._episode.plant.steering.etas).tolist())
        if self.scheduler is not None:
            return self.scheduler.etas
        return self.built.plant_params.etas

    @property
    def world_clearance(self) -> np.ndarray:
        """Per control step, the least gap between a unit and the world's obstacles (m; inf
        for the steps not run, empty without obstacles)."""
        return self.world.clearance

    @property
    def ground_masks(self) -> list[int]:
        """Per advance of the episode, the bit mask of the friction patches some wheel stood
        on (from the ground record; empty without patches)."""
        if self._episode is None or not self.built.scenario.ground:
            return []
        return np.asarray(self._episode.loop.ground.masks)[: self.k].tolist()

    @property
    def signal_names(self):
        """The names the controller has logged so far (a view, not a copy)."""
        return self._signals.keys()

    def record_signals(self, signals: dict[str, float], k: int) -> None:
        """The controller's logged signals at step ``k``, columns ``ctrl_<name>`` of the time
        series, NaN where a step logged none."""
        for name, value in signals.items():
            column = self._signals.get(name)
            if column is None:
                column = self._signals[name] = np.full(self.steps + 1, np.nan)
            column[k] = value

    def add_block(self, meas: np.ndarray, loop: np.ndarray, trains: np.ndarray) -> None:
        """Append logged rows as float arrays (measurement, loop values, trailers 2..N), and
        to the checkpoint file if there is one."""
        self._blocks.append((meas, loop, trains))
        if self._checkpoint is not None:
            self._checkpoint.append(meas, loop, trains)

    def close(self) -> None:
        """Write every logged row to the checkpoint file, if there is one, and close it (an
        interrupted run calls this too, so the file then holds every row computed)."""
        checkpoint = self._checkpoint
        if checkpoint is not None:
            self._fold()
            self._checkpoint = None
            checkpoint.close()

    @property
    def samples(self) -> int:
        """Rows logged so far."""
        return sum(len(b[0]) for b in self._blocks)

    def timeseries(self, release: bool = False) -> dict[str, np.ndarray]:
        """The episode's time series so far, in :data:`tt_mujoco.sim.loop.timeseries.COLUMNS` order.

        ``release``: the episode is over and the caller takes the rows; the logged blocks are
        dropped as they are gathered, so that a long run's rows are held about once, not
        three times (blocks, their concatenation, the columns)."""
        if self._log is not None:
            self._fold()
        if self._blocks:
            blocks = self._blocks
            if release:
                self._blocks = []
            measured = np.concatenate([b[0] for b in blocks])
            logged = np.concatenate([b[1] for b in blocks])
            trains = np.concatenate([b[2] for b in blocks])
            del blocks
        else:
            measured = logged = []
            trains = np.empty((0, len(self.train_columns)))
        ts = assemble_columns(measured, logged, self.eta)
        ts.update({name: trains[:, i].copy() for i, name in enumerate(self.train_columns)})
        n_rows = len(ts["t"])
        ts.update(
            {f"ctrl_{name}": column[:n_rows].copy() for name, column in self._signals.items()}
        )
        n = len(logged)
        if self.scheduler is not None:
            ts["eq_violation"] = ts["beta"] - eta_series_of(self._changes, n) * ts["phi"]
        if n:
            ref = self.built.target.reference_pose(ts["t"])
            ts["x_ref"], ts["y_ref"], ts["theta_ref"] = (np.asarray(c, dtype=float) for c in ref)
        return ts

"""The closed loop's one step, shared by every route that drives a plant.

:func:`tt_mujoco.sim.simulate.simulate`, the Gymnasium environment and the live viewer all use
:class:`Stepper`; only who computes the torques differs (a controller, an agent). A control step
``k`` (time ``t = k dt``) is:

1. :meth:`Stepper.sense`: measure the plant, stop on a blow-up or jackknife, add measurement
   noise, apply sensor faults, update the target (or the path feedback around it); return the
   measurement as the controller sees it and the :class:`~tt_mujoco.controllers.Reference`;
2. :meth:`Stepper.actuate`: clip the torques at the limit, apply actuator faults and payload
   steps, add the disturbance, log the row, then (unless ``k`` is the last step) update the
   scheduled eta and advance the plant one control period.
"""

from __future__ import annotations

import collections
import math

import numpy as np

from tt_mujoco.controllers import Reference
from tt_mujoco.defaults import JACKKNIFE_DEG, MAX_SPEED
from tt_mujoco.sim import usercode
from tt_mujoco.sim.build import Build
from tt_mujoco.sim.checkpoint import Checkpoint
from tt_mujoco.sim.disturbances import injected
from tt_mujoco.sim.faults import HELD, PAYLOAD_ROW
from tt_mujoco.sim.measure import TRAIN_FIELDS, Measurement
from tt_mujoco.sim.motors import DcMotors, MotorConstants
from tt_mujoco.sim.plant import StopRun
from tt_mujoco.sim.records import (
    DelayRecord,
    FaultRecord,
    GroundRecord,
    Limits,
    LoopRecord,
    WindRecord,
)
from tt_mujoco.sim.scenario import jackknife_phi_deg
from tt_mujoco.sim.step import (
    BLEW_UP,
    JACKKNIFE,
    clip,
    clip_pair,
    hitch_stop,
    noisy,
    stop_code,
)
from tt_mujoco.sim.timeseries import LOOP_COLUMNS, assemble_columns, train_columns
from tt_mujoco.sim.wind import DragConstants, parse_wind, wind_wrenches_of
from tt_mujoco.vehicle.reduced import SingularityError

__all__ = ["CHECKPOINT_COLUMNS", "Stepper"]

#: Columns of a checkpoint file: the measurement and the loop's own values, as logged.
CHECKPOINT_COLUMNS = (*Measurement._fields, *LOOP_COLUMNS)

#: Rows kept as Python tuples before they are folded into float arrays: a long run's log then
#: costs 8 bytes a value (about 290 bytes a row) instead of a tuple's ~1.3 kB.
_LOG_BLOCK = 8192


def blew_up_message(t: float, v: float) -> str:
    return f"state blew up at t={t:.3f} s: v={v!r}"


def jackknife_message(t, phi, beta, eta, x, y, v, hitch: int = 1) -> str:
    """Which limit the hitch reached, and why it is one."""
    phi_deg, beta_deg = math.degrees(phi), math.degrees(beta)
    if abs(beta_deg) >= JACKKNIFE_DEG:
        why = (
            f"|beta| = {abs(beta_deg):.1f} deg reached {JACKKNIFE_DEG:g} deg: the steered axle "
            f"nears 90 deg, where it would roll across the trailer (phi={phi_deg:.1f} deg)"
        )
    else:
        limit = jackknife_phi_deg(eta)
        reason = (
            "the trailer stands across the tractor"
            if limit >= 90.0
            else f"with eta={eta:g} the axle's beta = eta phi would reach {JACKKNIFE_DEG:g} deg"
        )
        why = (
            f"|phi| = {abs(phi_deg):.1f} deg reached {limit:.4g} deg: {reason} "
            f"(beta={beta_deg:.1f} deg)"
        )
    return (
        f"jackknife at t={t:.3f} s, hitch {hitch}: {why}; x={x:.3f} m, y={y:.3f} m, v={v:.3f} m/s"
    )


class Stepper:
    """One episode of a built scenario, step by step.

    Parameters
    ----------
    built : Build
        From :func:`tt_mujoco.sim.build.build`.
    """

    def __init__(self, built: Build):
        self.built = built
        s = built.scenario
        self.dt = built.control_dt
        self.steps = built.steps
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
        self._mode = s.disturbance
        self._feedback = s.path_feedback is not None
        self._measured_target = getattr(built.target, "uses_measurement", False)
        self._dist_label = usercode.disturbance_label(built)
        # Trailers 2..N: their hitch limits, and their logged columns after the usual ones.
        etas = built.plant_params.etas
        self._train_limits = [math.radians(jackknife_phi_deg(e)) for e in etas[1:]]
        self.train_columns = train_columns(len(etas))
        self.checkpoint_columns = (*CHECKPOINT_COLUMNS, *self.train_columns)
        self.plant = None
        self._checkpoint = None

    def reset(
        self, rng: np.random.Generator, phi0_deg: float | None = None, checkpoint=None
    ) -> None:
        """Start an episode: a fresh plant in the initial state, the target and faults reset,
        the noise of the whole episode drawn from ``rng`` (v_k, omega_k, ... in step order, the
        same numbers as drawing them step by step).

        ``checkpoint``, a file path, receives every block of logged rows as it is folded (an
        Arrow IPC stream of the raw logged columns, :class:`~tt_mujoco.sim.checkpoint.
        Checkpoint`): a run killed after an hour keeps what it computed there. :meth:`close`
        writes the rows not yet folded.
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
        self._ground_masks = [] if b.scenario.ground else None  # the patches under the wheels
        steps = b.delay_steps
        # until `steps` readings exist, the first one is what the sensors have given
        self._delayed = None if not steps else collections.deque(maxlen=steps + 1)
        self.scheduler = b.new_scheduler(self.plant)
        b.target.reset()
        self.k = 0
        self.finished = False
        self.stop_details = None  # the traceback of user code that stopped the episode
        self._signals: dict[str, np.ndarray] = {}  # what the controller logged, by name
        noise_v, noise_w = b.noise_std
        self._noise = (
            rng.standard_normal(2 * (self.steps + 1)).tolist() if noise_v or noise_w else None
        )
        wind = parse_wind(b.scenario.wind)
        # the gusts are drawn after the noise, so that a wind leaves the noise as it was
        self._wind = None if wind.calm else wind.speeds(rng, self.steps, self.dt).tolist()
        direction = math.radians(wind.direction_deg)
        self._wind_direction = (math.cos(direction), math.sin(direction))
        self._drag = DragConstants(*(getattr(b.plant_params, f) for f in DragConstants._fields))
        self._measured: list = []
        self._logged: list = []
        self._train_logged: list = []
        self._blocks: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
        self.measurement = None

    def loop_record(self) -> LoopRecord:
        """The episode's constants and noise as the compiled loop reads them (after
        :meth:`reset`)."""
        dist = self.built.disturbance is not None
        noise, faults = self._noise, self.faults
        rows = faults.payload_rows if faults else []
        motors = self.motors
        depth = self.built.delay_steps + 1
        return LoopRecord(
            limits=self.limits,
            dt=self.dt,
            steps=self.steps,
            noise=np.zeros(0) if noise is None else np.array(noise),
            disturbed=dist and self._mode == "matched",
            wrench=dist and self._mode == "wrench",
            n_trailers=self.built.plant_params.n_trailers,
            hitch_limits=np.array(self._train_limits, dtype=float),
            faults=FaultRecord(
                dropouts=np.array(faults.dropouts if faults else [], dtype=float).reshape(-1, 2),
                actuators=np.array(faults.actuators if faults else [], dtype=float).reshape(-1, 4),
                held=np.array(faults.held if faults else [0.0] * len(HELD), dtype=float),
                payloads=np.array(rows, dtype=float).reshape(-1, len(PAYLOAD_ROW)),
                payload_state=np.array(faults.payload_state if faults else [0.0, 0.0]),
                payload_changes=np.zeros((len(rows), 2)),
            ),
            dc_motor=motors is not None,
            motor=motors.constants if motors else MotorConstants(*[0.0] * 6),
            motor_torques=np.array(motors.torques if motors else [0.0, 0.0]),
            wind=WindRecord(
                np.array(self._wind or [], dtype=float),
                self._wind_direction,
                self._drag,
                np.zeros(6),
            ),
            delay=DelayRecord(
                measurements=np.zeros((depth, len(Measurement._fields))),
                rows=np.zeros((depth, len(self._train_limits), len(TRAIN_FIELDS))),
                seen=np.zeros((depth, 3)),
            ),
            ground=self._ground_record(),
        )

    def _ground_record(self) -> GroundRecord:
        """The friction patches under the wheels, as the compiled loop reads them."""
        ground = getattr(self.plant, "ground", None)
        if ground is None:
            none, no_ints = np.zeros(0), np.zeros(0, dtype=np.int64)
            return GroundRecord(
                no_ints, np.zeros((1, 3)), np.zeros((1, 3)), no_ints, np.zeros((0, 4)), none,
                0.0, none, np.zeros((0, 2)), none, no_ints,
            )  # fmt: skip
        patches, geoms, xpos, friction = ground
        points = np.array(xpos[geoms, :2], dtype=float)
        return GroundRecord(
            geoms=np.array(geoms, dtype=np.int64),
            geom_xpos=xpos,
            geom_friction=friction,
            kinds=patches.kinds,
            bounds=patches.bounds,
            mus=patches.mus,
            base_mu=patches.base_mu,
            arcs=patches.start(points),
            points=points,
            frictions=np.zeros(len(geoms)),
            masks=np.zeros(self.steps + 1, dtype=np.int64),
        )

    def log_ground(self, masks, arc_lengths) -> None:
        """A compiled episode's patch masks (one per advance) and the wheels' last arc lengths
        (see :attr:`ground_masks`)."""
        self._ground_masks.extend(int(m) for m in masks)
        patches = self.plant.ground[0]
        if len(arc_lengths):
            patches.arc_lengths = [float(s) for s in arc_lengths]

    @property
    def plant_etas(self) -> tuple:
        """The trailers' steering gains eta_1..eta_N in force (a scheduler's, else the plant's
        constant ones)."""
        if self.scheduler is not None:
            return self.scheduler.etas
        return self.built.plant_params.etas

    @property
    def t(self) -> float:
        return self.k * self.dt

    def sense(self) -> tuple[Measurement, Reference]:
        """The measurement as the controller sees it and the target, at the current step.

        Raises
        ------
        StopRun
            The state blew up or jackknifed.
        """
        k, t = self.k, self.k * self.dt
        me = self.plant.measure()
        stop = stop_code(me.x, me.v, me.omega, me.phi, me.beta, self.limits)
        if stop == BLEW_UP:
            raise StopRun("diverged", blew_up_message(t, me.v))
        if stop == JACKKNIFE:
            raise StopRun(
                "jackknife", jackknife_message(t, me.phi, me.beta, self.eta, me.x, me.y, me.v)
            )
        if self._train_limits:
            self._check_train(me, t)
        noise = self._noise
        if noise is not None:
            lim = self.limits
            v_m = noisy(me.v, lim.noise_v, noise, 2 * k)
            w_m = noisy(me.omega, lim.noise_w, noise, 2 * k + 1)
        else:
            v_m, w_m = me.v, me.omega
        phi_m = me.phi
        if self.faults is not None:
            phi_m, v_m, w_m = self.faults.sensor(k, phi_m, v_m, w_m)
        seen = (
            me
            if (phi_m, v_m, w_m) == (me.phi, me.v, me.omega)
            else me._replace(phi=phi_m, v=v_m, omega=w_m)
        )
        sensed = me  # what the outer loops (path feedback, the hitch cascade) read
        delayed = self._delayed
        if delayed is not None:  # the loops see the readings of `delay` steps ago
            delayed.append((me, seen))
            sensed, seen = delayed[0]
            v_m, w_m = seen.v, seen.omega
        target = self.built.target
        if self._measured_target:
            v_d, w_d, v_d_dot, w_d_dot = target.update(t, self.dt, v_m, sensed)
            self._omega_ref = target.reference_omega_d
        elif self._feedback:
            x, y, theta = sensed.x, sensed.y, sensed.theta
            v_d, w_d, v_d_dot, w_d_dot = target.update(t, self.dt, v_m, x, y, theta)
            self._omega_ref = target.reference_omega_d
        else:
            v_d, w_d, v_d_dot, w_d_dot = target.update(t, self.dt, v_m)
            self._omega_ref = w_d
        self.measurement = me
        self._seen = (v_m, w_m)
        ref = Reference(
            t, target.arc_length, target.curvature, v_d, w_d, v_d_dot, w_d_dot, self.built.path
        )
        self._ref = ref
        return seen, ref

    @property
    def ground_masks(self) -> list[int]:
        """Per step, the bit mask of the friction patches some wheel stood on."""
        return self._ground_masks or []

    def _blow(self, k: int, me) -> None:
        """The wind's drag on the tractor and the trailer over step ``k`` (sim/wind.py)."""
        speed = self._wind[k]
        wind = (speed * self._wind_direction[0], speed * self._wind_direction[1])
        motion = (me.v, me.theta, me.v0, me.theta0, me.beta)
        wrenches = wind_wrenches_of(wind, motion, self._drag)
        self.plant.blow(wrenches[:3], wrenches[3:])

    def _check_train(self, me, t: float) -> None:
        """Stop when any hitch behind the first jackknifes."""
        i = hitch_stop(me.train, self._train_limits, self.limits.jackknife_beta)
        if i >= 0:
            phi, beta = me.train[i][3], me.train[i][4]
            eta = self.built.nominal.etas[i + 1]
            raise StopRun(
                "jackknife", jackknife_message(t, phi, beta, eta, me.x, me.y, me.v, hitch=i + 2)
            )

    def actuate(self, T_r: float, T_l: float, command: tuple[float, float] | None = None) -> bool:
        """Apply the torques of the current step and advance; False when the episode is over.

        Parameters
        ----------
        T_r, T_l : float
            Wheel torques (N m); clipped at the torque limit.
        command : (float, float), optional
            The unsaturated request, for the log (default: the torques given).
        """
        k, t, me, ref = self.k, self.k * self.dt, self.measurement, self._ref
        T_r_cmd, T_l_cmd = (T_r, T_l) if command is None else command
        limits = self.limits
        T_r = clip(T_r, limits.torque_limit)
        T_l = clip(T_l, limits.torque_limit)
        faults = self.faults
        if faults is not None:
            T_r, T_l = faults.torque(k, T_r, T_l)
            for trailer, factor in faults.payloads(k, ref.s):
                self.plant.scale_trailer_mass(factor, trailer)
        if self.motors is not None:  # what the motors deliver of the command, over this step
            T_r, T_l = self.motors.deliver(T_r, T_l, me.theta_r_dot, me.theta_l_dot)
        dist_r = dist_l = force = torque = 0.0
        clipped = 0.0
        dist = self.built.disturbance
        if dist is not None:
            try:
                out = dist(t)
            except (Exception, SystemExit) as err:
                raise usercode.failure(self._dist_label, t, err) from None
            a_v, a_w = usercode.checked_disturbance(out, self._dist_label, t)
            phi = me.phis if self._train_limits else me.phi
            dist_r, dist_l, force, torque = injected(self._mode, a_v, a_w, phi, self.built.nominal)
            # What a disturbance of motor size can apply, per wheel: beyond it the paper's
            # g^-1 Delta (unbounded as g nears singular) would itself drive a jackknife.
            dist_r, dist_l, clipped = clip_pair(dist_r, dist_l, limits.disturbance_bound)
        # Log the measurement tuple as it is and the loop's own values beside it, in the order
        # of LOOP_COLUMNS (records.LOG_DTYPE): columns are assembled once after the episode.
        self._measured.append(me)
        if self._train_limits:
            self._train_logged.append([value for row in me.train for value in row])
        v_m, w_m = self._seen
        self._logged.append(
            (
                t,
                ref.s,
                ref.v_d,
                self._omega_ref,
                ref.v_d_dot,
                ref.omega_d_dot,
                v_m,
                w_m,
                T_r,
                T_l,
                T_r_cmd,
                T_l_cmd,
                dist_r,
                dist_l,
                ref.kappa,
                ref.omega_d,
                clipped,
            )
        )
        if len(self._logged) >= _LOG_BLOCK:
            self._fold()
        if k == self.steps:
            self.finished = True
            return False
        if self.scheduler is not None:
            self.scheduler.update(ref.kappa, k, me)
        self.plant.apply(T_r, T_l, dist_r, dist_l, force, torque, me.theta)
        if self._wind is not None:
            self._blow(k, me)
        try:
            self.plant.advance(self.built.substeps)
            if self._ground_masks is not None:
                self._ground_masks.append(self.plant.ground_mask)
        except SingularityError as err:
            raise StopRun("jackknife", f"jackknife at t={t + self.dt:.3f} s: {err}") from None
        self.k = k + 1
        return True

    def record_signals(self, signals: dict[str, float]) -> None:
        """The controller's logged signals at the current step (columns ``ctrl_<name>`` of
        the time series, NaN where a step logged none)."""
        k = self.k
        for name, value in signals.items():
            column = self._signals.get(name)
            if column is None:
                column = self._signals[name] = np.full(self.steps + 1, np.nan)
            column[k] = value

    def _fold(self) -> None:
        """Move the rows logged as tuples into one block of float arrays.

        A row is complete once its loop values are logged (the last of its parts): an
        interruption between its parts leaves it out."""
        n = len(self._logged)
        if n:
            meas = np.array(self._measured[:n], dtype=float).reshape(n, len(Measurement._fields))
            loop = np.array(self._logged, dtype=float).reshape(n, -1)
            trains = np.array(self._train_logged[:n], dtype=float)
            trains = trains.reshape(n, len(self.train_columns))
            self.add_block(meas, loop, trains)
            self._measured.clear()
            self._logged.clear()
            self._train_logged.clear()

    def add_block(self, meas: np.ndarray, loop: np.ndarray, trains: np.ndarray) -> None:
        """Append logged rows as float arrays (measurement, loop values, trailers 2..N), and
        to the checkpoint file if there is one; the compiled episode logs this way."""
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
        return len(self._logged) + sum(len(b[0]) for b in self._blocks)

    def timeseries(self, release: bool = False) -> dict[str, np.ndarray]:
        """The episode's time series so far, in :data:`tt_mujoco.sim.timeseries.COLUMNS` order.

        ``release``: the episode is over and the caller takes the rows; the logged blocks are
        dropped as they are gathered, so that a long run's rows are held about once, not
        three times (blocks, their concatenation, the columns)."""
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
            ts["eq_violation"] = ts["beta"] - self.scheduler.eta_series(n) * ts["phi"]
        if n:
            ref = self.built.target.reference_pose(ts["t"])
            ts["x_ref"], ts["y_ref"], ts["theta_ref"] = (np.asarray(c, dtype=float) for c in ref)
        return ts

"""Fault injection for the closed loop: a payload step, sensor dropout, an actuator losing torque.

A fault is a small spec, given as a dict (a TOML ``[[faults]]`` table) or as the text of
``--fault KIND:key=value,...``:

- ``payload``: at time ``t``, or where the reference reaches the arc length ``s`` (m) along the
  path (forward or backing up), the body of trailer ``trailer`` (default 1) has its mass and
  yaw inertia (``Mr``, ``Ird``; the payload bed at P0) multiplied by ``factor`` (default 1.5,
  "+50 %"; below 1 it unloads) for the rest of the run: loading or unloading at a place. The
  controller keeps its nominal model, so it does not know.
- ``dropout``: from ``t`` for ``duration`` s (default 0.1) the controller's measurements
  (phi, v, omega, after any noise) hold the last value received before the dropout; the
  dynamic target integrates the held speed too, as it would on a vehicle.
- ``actuator``: from ``t`` for ``duration`` s (default 1) the ``wheel`` ("right", "left" or
  "both") delivers ``scale`` (default 0.3) of the torque the controller asked for.

Two further faults of the issue are ordinary scenario options, not specs: low friction is
``Scenario.friction`` (``--friction 0.3``) and the disturbance that exceeds traction is
``Scenario.disturbance = "wrench"`` (``--disturbance-mode wrench``, docs/model.md Section 8).

Timing is by control step: a fault starting at ``t`` acts from the first control step at or
after ``t``, and a ``duration`` covers ``round(duration / control_dt)`` steps, so runs are
exactly repeatable. A payload at ``s`` acts from the first control step whose reference arc
length has reached ``s``; the report gives the time that was. :func:`fault_report`
summarises each fault's effect for ``metrics.json``.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from tt_mujoco.analysis.metrics import distance_to_polyline
from tt_mujoco.schema_values import number_text
from tt_mujoco.vehicle.params import MAX_TRAILERS

__all__ = [
    "FAULT_KINDS",
    "RECOVERY_S",
    "Fault",
    "FaultSchedule",
    "acted_at_of",
    "dropped_of",
    "fault_report",
    "fault_torque_of",
    "held_steps_of",
    "parse_fault",
    "parse_faults",
    "payloads_of",
    "sensor_of",
    "window_errors",
]

#: Each kind's options and their defaults (``t`` is required for all).
FAULT_KINDS: dict[str, dict[str, float | str]] = {
    "payload": {"factor": 1.5, "trailer": 1},
    "dropout": {"duration": 0.1},
    "actuator": {"duration": 1.0, "scale": 0.3, "wheel": "both"},
}
WHEELS = ("right", "left", "both")
#: A fault's report window runs this long past its end: the controller's recovery.
RECOVERY_S = 1.0
#: Largest arc length a payload may be placed at (m): 600 s at the speed cap is far less.
MAX_ARC_LENGTH = 12_000.0


@dataclass(frozen=True)
class Fault:
    """One fault, validated. ``duration`` is ``inf`` for a payload step (it stays)."""

    kind: str
    #: The start time (s); None for a payload placed at an arc length instead.
    t: float | None
    duration: float = math.inf
    factor: float = 1.0
    scale: float = 1.0
    wheel: str = "both"
    trailer: int = 1
    #: The arc length (m) along the path where a payload acts; None: at ``t``.
    s: float | None = None

    def to_dict(self) -> dict:
        """The spec as it would be written in TOML: only the kind's own options."""
        full = asdict(self)
        when = {"t": self.t} if self.s is None else {"s": self.s}
        return {"kind": self.kind, **when, **{k: full[k] for k in FAULT_KINDS[self.kind]}}

    @property
    def label(self) -> str:
        opts = ", ".join(f"{k}={v}" for k, v in self.to_dict().items() if k != "kind")
        return f"{self.kind}({opts})"


def _number(kind: str, key: str, value, low: float, high: float, low_open: bool = False):
    text = value
    if isinstance(value, str):
        value = number_text(value)
        if value is None:
            raise ValueError(f"fault {kind}: {key}={text!r} is not a number")
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ValueError(f"fault {kind}: {key}={text!r} is not a number")
    value = float(value)
    ok = math.isfinite(value) and (value > low if low_open else value >= low) and value <= high
    if not ok:
        interval = f"{'(' if low_open else '['}{low:g}, {high:g}]"
        raise ValueError(f"fault {kind}: {key}={text!r} is not allowed: it must be in {interval}")
    return value


def _split_text(spec: str) -> dict:
    """``"actuator:t=2,scale=0.3"`` -> ``{"kind": "actuator", "t": "2", "scale": "0.3"}``."""
    kind, _, rest = spec.partition(":")
    out: dict = {"kind": kind.strip()}
    items = [part.strip() for part in rest.split(",")] if rest.strip() else []
    for item in items:
        if not item:  # "t=1,,scale=0.3" or "t=1,": a value lost, not a spelling
            raise ValueError(
                f"fault {spec!r}: an empty item between commas; write e.g. 'actuator:t=2,scale=0.3'"
            )
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            raise ValueError(
                f"fault {spec!r}: {item!r} is not key=value; write e.g. 'actuator:t=2,scale=0.3'"
            )
        if key.strip() in out:
            raise ValueError(f"fault {spec!r}: {key.strip()!r} is given twice; give it once")
        out[key.strip()] = value.strip()
    return out


def parse_fault(spec) -> Fault:
    """A :class:`Fault` from a dict, a ``KIND:key=value,...`` string or a Fault.

    Raises
    ------
    ValueError
        Unknown kind or option, a missing ``t``, or a value out of range; the message names it.
    """
    if isinstance(spec, Fault):
        return spec
    if isinstance(spec, str):
        spec = _split_text(spec)
    if not isinstance(spec, dict):
        raise ValueError(f"fault {spec!r} is not allowed: give a table or 'KIND:key=value,...'")
    kind = spec.get("kind")
    if kind not in FAULT_KINDS:
        raise ValueError(f"fault kind={kind!r} is not allowed: use one of {', '.join(FAULT_KINDS)}")
    when = ("t", "s") if kind == "payload" else ("t",)  # a payload may be placed instead
    allowed = ("kind", *when, *FAULT_KINDS[kind])
    unknown = [k for k in spec if k not in allowed]
    if unknown:
        raise ValueError(
            f"fault {kind}: option {unknown[0]!r} is not allowed: use {', '.join(allowed[1:])}"
        )
    given = [k for k in when if k in spec]
    if not given:
        what = (
            "the start time t (s) or the arc length s (m)"
            if kind == "payload"
            else ("the start time t (s)")
        )
        raise ValueError(f"fault {kind}: {what} is missing")
    if len(given) > 1:
        raise ValueError(
            f"fault {kind}: give the start time t or the arc length s, not both "
            f"(t={spec['t']!r}, s={spec['s']!r})"
        )
    options = {**FAULT_KINDS[kind], **{k: v for k, v in spec.items() if k != "kind"}}
    if kind == "payload":
        t = _number(kind, "t", options["t"], 0.0, 600.0) if "t" in options else None
        s = _number(kind, "s", options["s"], 0.0, MAX_ARC_LENGTH) if "s" in options else None
        factor = _number(kind, "factor", options["factor"], 0.0, 100.0, low_open=True)
        trailer = _number(kind, "trailer", options["trailer"], 1.0, MAX_TRAILERS)
        if trailer != int(trailer):
            raise ValueError(
                f"fault payload: trailer={options['trailer']!r} is not allowed: it must be a "
                f"whole number from 1 to {MAX_TRAILERS}"
            )
        return Fault(kind, t, factor=factor, trailer=int(trailer), s=s)
    t = _number(kind, "t", options["t"], 0.0, 600.0)
    duration = _number(kind, "duration", options["duration"], 0.0, 600.0, low_open=True)
    if kind == "dropout":
        return Fault(kind, t, duration=duration)
    scale = _number(kind, "scale", options["scale"], 0.0, 1.0)
    wheel = options["wheel"]
    if wheel not in WHEELS:
        raise ValueError(f"fault actuator: wheel={wheel!r} is not allowed: use one of {WHEELS}")
    return Fault(kind, t, duration=duration, scale=scale, wheel=wheel)


def parse_faults(specs) -> tuple[Fault, ...]:
    """Validate a list of specs (see :func:`parse_fault`)."""
    if specs is None:
        return ()
    if isinstance(specs, str | dict) or not hasattr(specs, "__iter__"):
        raise ValueError(f"faults={specs!r} is not allowed: give a list of fault specs")
    return tuple(parse_fault(s) for s in specs)


class FaultSchedule:
    """The faults of one run, applied by control-step index inside the loop.

    Parameters
    ----------
    faults : sequence of Fault
    control_dt : float
        Control period (s).
    duration : float
        Run length (s); a fault starting after it is refused.
    n_trailers : int
        The train's trailers; a payload on another is refused.
    path_length : float, optional
        The reference path's length (m); a payload placed beyond it is refused.
    """

    def __init__(
        self,
        faults,
        control_dt: float,
        duration: float,
        n_trailers: int = 1,
        path_length: float | None = None,
    ):
        self.faults = tuple(faults)
        for f in self.faults:
            if f.t is not None and f.t > duration:
                raise ValueError(
                    f"fault {f.label}: t={f.t!r} s is after the end of the run ({duration:.6g} s)"
                )
            if f.s is not None and path_length is not None and f.s > path_length:
                raise ValueError(
                    f"fault {f.label}: s={f.s!r} m is beyond the end of the path "
                    f"({path_length:.6g} m)"
                )
            if f.kind == "payload" and f.trailer > n_trailers:
                raise ValueError(
                    f"fault {f.label}: trailer={f.trailer} is not allowed: the train has "
                    f"{n_trailers} trailer(s)"
                )
        # First step at or after t (the 1e-9 forgives t = k dt written in decimal).
        self._windows = []
        for f in self.faults:
            if f.t is None:
                continue
            k0 = math.ceil(f.t / control_dt - 1e-9)
            k1 = math.inf if math.isinf(f.duration) else k0 + round(f.duration / control_dt)
            self._windows.append((f, k0, k1))
        #: The dropouts' step windows (k0, k1), and the actuator faults' (k0, k1, scale of the
        #: right wheel, of the left): the rows :func:`sensor_of` and :func:`fault_torque_of` read.
        self.dropouts = [(k0, k1) for f, k0, k1 in self._windows if f.kind == "dropout"]
        self.actuators = [
            (k0, k1, _scale(f, "right"), _scale(f, "left"))
            for f, k0, k1 in self._windows
            if f.kind == "actuator"
        ]
        #: :data:`PAYLOAD_ROW` of every payload, those at a time first, each group in the
        #: faults' order; and :data:`PAYLOAD_STATE` (the reference's last arc length, dt)
        timed = [(1.0, k0, math.nan, f.trailer, f.factor, math.nan, -1.0)
                 for f, k0, _ in self._windows if f.kind == "payload"]  # fmt: skip
        placed = [(0.0, -1.0, f.s, f.trailer, f.factor, math.nan, i)
                  for i, f in enumerate(self.faults) if f.s is not None]  # fmt: skip
        self.payload_rows = tuple(tuple(row) for row in (*timed, *placed))
        self.payload_state = (math.nan, float(control_dt))
        #: :data:`HELD`: the last sample the controller received, and the steps held so far
        self.held = (0.0,) * len(HELD)
        # These are the first values of the episode's fault record
        # (:class:`~tt_mujoco.sim.loop.records.FaultRecord`), whose state the step changes: what
        # a run reports is read from that record (:func:`fault_report`), never handed back here.


def held_steps_of(held) -> int:
    """Control steps whose measurement a dropout held, from a fault record's ``held``."""
    return int(held[HELD_STEPS])


def acted_at_of(payloads) -> dict[int, float]:
    """When each payload placed at an arc length acted (s), by its index among the faults,
    from a fault record's ``payloads`` rows (:data:`PAYLOAD_ROW`)."""
    acted = PAYLOAD_ROW.index("acted")
    return {
        int(row[-1]): row[acted]
        for row in np.asarray(payloads, dtype=float).tolist()
        if row[TIMED] == 0.0 and not math.isnan(row[acted])
    }


#: What a dropout holds: whether a sample was received, its (phi, v, omega), and the steps held.
HELD = ("received", "phi", "v", "omega", "steps")
RECEIVED, HELD_PHI, HELD_V, HELD_OMEGA, HELD_STEPS = range(len(HELD))
#: An actuator fault's row: its first and end step, and its torque scale on each wheel.
ACTUATOR_ROW = ("k0", "k1", "scale_right", "scale_left")
ACT_K0, ACT_K1, ACT_SCALE_R, ACT_SCALE_L = range(len(ACTUATOR_ROW))


def _scale(fault: Fault, wheel: str) -> float:
    """An actuator fault's torque scale on ``wheel`` (1 where it does not act)."""
    return fault.scale if fault.wheel in (wheel, "both") else 1.0


def dropped_of(k: int, dropouts) -> bool:
    """Whether step ``k`` lies in one of the ``dropouts`` windows (k0, k1) (the compiled
    episode shares it)."""
    for i in range(len(dropouts)):
        if dropouts[i][0] <= k < dropouts[i][1]:
            return True
    return False


def sensor_of(k: int, dropouts, held, phi: float, v: float, omega: float):
    """The controller's ``(phi, v, omega)`` at step ``k``: during a dropout the last sample
    received before it (the first one, for a dropout from the first step), else the sample,
    which ``held`` (:data:`HELD`) keeps (the compiled episode shares it)."""
    if dropped_of(k, dropouts):
        if held[RECEIVED] == 0.0:
            held[RECEIVED], held[HELD_PHI], held[HELD_V], held[HELD_OMEGA] = 1.0, phi, v, omega
        held[HELD_STEPS] += 1.0
        return held[HELD_PHI], held[HELD_V], held[HELD_OMEGA]
    held[RECEIVED], held[HELD_PHI], held[HELD_V], held[HELD_OMEGA] = 1.0, phi, v, omega
    return phi, v, omega


def fault_torque_of(k: int, actuators, T_r: float, T_l: float) -> tuple[float, float]:
    """The torques the wheels deliver at step ``k`` under the ``actuators`` faults (rows k0,
    k1, scale right, scale left), in their order (the compiled episode shares it)."""
    for i in range(len(actuators)):
        row = actuators[i]
        if row[ACT_K0] <= k < row[ACT_K1]:
            T_r *= row[ACT_SCALE_R]
            T_l *= row[ACT_SCALE_L]
    return T_r, T_l


#: A payload's row: at a time (1) or a place (0), its step, its arc length, the trailer, the
#: factor, when it acted (s; NaN before) and its index among the faults.
PAYLOAD_ROW = ("timed", "k0", "s", "trailer", "factor", "acted", "index")
TIMED, K0, AT_S, TRAILER, FACTOR, ACTED = range(len(PAYLOAD_ROW) - 1)
#: The payloads' state: the reference's arc length at the last step (NaN before the first) and
#: the control period (s).
PAYLOAD_STATE = ("last_s", "control_dt")
LAST_S, CONTROL_DT = range(len(PAYLOAD_STATE))
#: A payload change as :func:`payloads_of` gives it: the trailer (1..N) and the factor.
PAYLOAD_CHANGE = ("trailer", "factor")
CHANGE_TRAILER, CHANGE_FACTOR = range(len(PAYLOAD_CHANGE))


def payloads_of(k: int, s: float, rows, state, out) -> int:
    """The payload changes taking effect at step ``k`` with the reference at arc length ``s``,
    as :data:`PAYLOAD_CHANGE` rows of ``out``; how many. ``rows`` (:data:`PAYLOAD_ROW`) record
    when a placed one acted, ``state`` is :data:`PAYLOAD_STATE` (the compiled episode shares
    it)."""
    count, placed = 0, False
    for i in range(len(rows)):
        row = rows[i]
        if row[TIMED] == 1.0:
            if row[K0] == k:
                out[count][CHANGE_TRAILER], out[count][CHANGE_FACTOR] = row[TRAILER], row[FACTOR]
                count += 1
        else:
            placed = True
    if not placed:
        return count
    prev = state[LAST_S]
    state[LAST_S] = s
    for i in range(len(rows)):
        row = rows[i]
        if row[TIMED] == 1.0 or not math.isnan(row[ACTED]):
            continue
        at = row[AT_S]
        reached = s == at if math.isnan(prev) else min(prev, s) <= at <= max(prev, s)
        if reached:
            row[ACTED] = k * state[CONTROL_DT]
            out[count][CHANGE_TRAILER], out[count][CHANGE_FACTOR] = row[TRAILER], row[FACTOR]
            count += 1
    return count


def window_errors(ts, polyline, t_start: float, t_end: float) -> dict:
    """Tracking errors over ``t_start <= t <= t_end`` of a run's time series.

    Returns ``max_abs_v`` (m/s), ``max_abs_omega`` (rad/s), ``max_lateral`` (m, P to the
    reference polyline) and ``rmse_v``, ``rmse_omega`` over the finite samples in the window
    (NaN if there are none), and ``samples``.
    """

    t = np.asarray(ts["t"])
    sel = (t >= t_start - 1e-12) & (t <= t_end + 1e-12)
    e_v = (np.asarray(ts["v"]) - np.asarray(ts["v_d"]))[sel]
    e_w = (np.asarray(ts["omega"]) - np.asarray(ts["omega_d"]))[sel]
    finite = np.isfinite(e_v) & np.isfinite(e_w)
    e_v, e_w = e_v[finite], e_w[finite]
    if e_v.size == 0:
        nan = math.nan
        return {k: nan for k in ("max_abs_v", "max_abs_omega", "max_lateral", "rmse_v")} | {
            "rmse_omega": nan,
            "samples": 0,
        }
    points = np.column_stack([np.asarray(ts["x"])[sel], np.asarray(ts["y"])[sel]])[finite]
    lateral = distance_to_polyline(points, polyline)
    return {
        "max_abs_v": float(np.max(np.abs(e_v))),
        "max_abs_omega": float(np.max(np.abs(e_w))),
        "max_lateral": float(np.max(lateral)),
        "rmse_v": float(np.sqrt(np.mean(e_v**2))),
        "rmse_omega": float(np.sqrt(np.mean(e_w**2))),
        "samples": int(e_v.size),
    }


def fault_report(schedule: FaultSchedule, record, ts, polyline, torque_limit: float) -> list[dict]:
    """Per fault: its spec, the window it acted in and the tracking errors over that window
    plus :data:`RECOVERY_S` (payload: to the end of the run), for ``metrics.json``; ``window``
    is None for a fault the run never reached (``reached`` False). ``record`` is the episode's
    fault record as the run left it (:class:`~tt_mujoco.sim.loop.records.FaultRecord`): where
    the payloads acted and what the dropouts held.

    Kind-specific entries: dropout ``held_steps`` (all dropouts together: control steps whose
    measurement was held); actuator ``torque_shortfall_max`` (N m, largest torque asked for
    and not delivered); payload ``factor``.
    """
    t = np.asarray(ts["t"])
    t_last = float(t[-1]) if t.size else 0.0
    report, acted_at = [], acted_at_of(record.payloads)
    for i, f in enumerate(schedule.faults):
        start = f.t if f.s is None else acted_at.get(i)
        t_end = t_last if math.isinf(f.duration) else start + f.duration
        reached = bool(t.size and start is not None and t_last >= start)
        entry = {
            **f.to_dict(),
            "t_end": t_end,
            "reached": reached,
            # A fault the run never reached (it stopped before) has no window: None, not NaN.
            "window": (
                window_errors(ts, polyline, start, min(t_last, t_end + RECOVERY_S))
                if reached
                else None
            ),
        }
        if f.s is not None:
            entry["t_acted"] = start  # where the reference reached s; None if it never did
        if f.kind == "dropout":
            entry["held_steps"] = held_steps_of(record.held)
        elif f.kind == "actuator":
            sel = (t >= f.t - 1e-12) & (t < t_end - 1e-12)
            asked = np.clip(
                np.stack([ts["T_r_cmd"][sel], ts["T_l_cmd"][sel]]), -torque_limit, torque_limit
            )
            got = np.stack([ts["T_r"][sel], ts["T_l"][sel]])
            gap = np.abs(asked - got)
            gap = gap[np.isfinite(gap)]
            entry["torque_shortfall_max"] = float(gap.max()) if gap.size else 0.0
        report.append(entry)
    return report

"""An agent's control step over the named records: its torques applied, the next step sensed,
and what the agent observes written into a row of a batch, in one call.

The vector environment (:mod:`tt_mujoco.gym_vector`) steps each of its episodes with
:func:`act_then_sense`: the step's second half (:func:`~tt_mujoco.sim.loop.closed_loop.
actuate_step`) with the agent's torques, then the next step's first half (:func:`~tt_mujoco.sim.
loop.closed_loop.sense_step`) and :func:`observe_into`. The kernel compiles these from this
source (:mod:`tt_mujoco.sim.loop._kernel`), and CPython runs the same source where numba is
not there. The log is two rows: step ``k`` in row ``k % 2``.

The observation is :func:`tt_mujoco.gym_env.observation_names`' layout: the measurement as
the law sees it (noise, faults and the delay included), the train's rows 2..N as seen, every
unit's cross-track and heading error against the path (true poses), those of the unit that
leads the motion, then ``(v_d, omega_d)``; :data:`AUX_FIELDS` are what the reward and the
info read (:class:`AgentRecord`). Importing this module imports no numba.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from tt_mujoco.reference import feedback
from tt_mujoco.sim.loop.closed_loop import actuate_step, sense_step
from tt_mujoco.sim.loop.step import RAISED, RUNNING
from tt_mujoco.sim.parts.measure import (
    OMEGA,
    ROW_THETA0,
    ROW_X0,
    ROW_Y0,
    THETA,
    THETA0,
    X0,
    Y0,
    Measurement,
    V,
    X,
    Y,
)

__all__ = [
    "AUX_FIELDS",
    "AgentRecord",
    "act_then_sense",
    "observe_into",
    "sense_and_observe",
]

#: What a step writes beside the observation, in this order: the true speed and yaw rate,
#: the target and its derivatives, the wheels' longitudinal slips.
AUX_FIELDS = (
    "v",
    "omega",
    "v_d",
    "omega_d",
    "v_d_dot",
    "omega_d_dot",
    "slip_left",
    "slip_right",
)
(
    AUX_V,
    AUX_OMEGA,
    AUX_V_D,
    AUX_OMEGA_D,
    AUX_V_D_DOT,
    AUX_OMEGA_D_DOT,
    AUX_SLIP_LEFT,
    AUX_SLIP_RIGHT,
) = range(len(AUX_FIELDS))
_SLIP_LEFT = Measurement._fields.index("slip_left")
_SLIP_RIGHT = Measurement._fields.index("slip_right")


class AgentRecord(NamedTuple):
    """What an agent's step reads and writes besides the episode's records."""

    #: whether the train backs up (the last trailer leads)
    reverse: bool
    #: each unit's nearest arc length on the path, the warm start of the next
    unit_s: np.ndarray
    #: the observation (a row of the batch's)
    observation: np.ndarray
    #: :data:`AUX_FIELDS` (a row of the batch's)
    aux: np.ndarray


def observe_into(row, law, target, log, agent):
    """The observation at the log's ``row`` into ``agent.observation`` (see the module), each
    unit's nearest arc length warm-started from ``agent.unit_s`` and updated there;
    :data:`AUX_FIELDS` into ``agent.aux``."""
    out, aux, unit_s = agent.observation, agent.aux, agent.unit_s
    seen, seen_rows = law.measurement_values, law.measurement_rows
    measured, rows = log.measurement[row], log.train[row]
    i = 0
    for j in range(len(seen)):
        out[i] = seen[j]
        i += 1
    for r in range(len(seen_rows)):
        seen_row = seen_rows[r]
        for j in range(len(seen_row)):
            out[i] = seen_row[j]
            i += 1
    first = i
    for unit in range(len(unit_s)):
        if unit == 0:
            x, y, theta = measured[X], measured[Y], measured[THETA]
        elif unit == 1:
            x, y, theta = measured[X0], measured[Y0], measured[THETA0]
        else:
            train_row = rows[unit - 2]
            x, y, theta = train_row[ROW_X0], train_row[ROW_Y0], train_row[ROW_THETA0]
        s, e_y, e_psi = feedback.path_errors_of(target, unit_s[unit], x, y, theta)
        unit_s[unit] = s
        out[i], out[i + 1] = e_y, e_psi
        i += 2
    lead = i - 2 if agent.reverse else first
    out[i], out[i + 1] = out[lead], out[lead + 1]
    r = law.reference[0]
    out[i + 2], out[i + 3] = r.v_d, r.omega_d
    aux[AUX_V], aux[AUX_OMEGA] = measured[V], measured[OMEGA]
    aux[AUX_V_D], aux[AUX_OMEGA_D] = r.v_d, r.omega_d
    aux[AUX_V_D_DOT], aux[AUX_OMEGA_D_DOT] = r.v_d_dot, r.omega_d_dot
    aux[AUX_SLIP_LEFT], aux[AUX_SLIP_RIGHT] = measured[_SLIP_LEFT], measured[_SLIP_RIGHT]


def sense_and_observe(k, episode, agent):
    """Step ``k``'s first half (:func:`~tt_mujoco.sim.loop.closed_loop.sense_step`, into the
    log's row ``k % 2``) on the ``episode``'s records ``(loop, plant, law, target, log,
    stop_record)`` and, when it runs on, its observation (:func:`observe_into`); the stop
    code."""
    loop, plant, law, target, log, stop_record = episode
    stop = stop_record[0]
    row = k % 2
    code = sense_step(k, row, loop, plant, law, target, log, stop)
    if stop.raised:  # Python code called back by the kernel raised: its caller raises it
        return RAISED
    if code != RUNNING:
        return code
    observe_into(row, law, target, log, agent)
    if stop.raised:  # the path, called back for a unit's errors, raised
        return RAISED
    return RUNNING


def act_then_sense(k, T_r, T_l, episode, agent):
    """Step ``k``'s second half with the agent's torques ``(T_r, T_l)`` (N m, clipped at the
    limit), then step ``k + 1``'s first half and observation (:func:`sense_and_observe`); the
    stop code (RUNNING: the observation is step ``k + 1``'s)."""
    loop, plant, law, target, log, stop_record = episode
    reading = law.reading[0]
    reading.T_r, reading.T_l, reading.u1, reading.u2 = T_r, T_l, T_r, T_l
    code = actuate_step(k, k % 2, loop, plant, law, target, log, stop_record[0])
    if code != RUNNING:
        return code
    return sense_and_observe(k + 1, episode, agent)

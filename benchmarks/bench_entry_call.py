"""What calling the compiled step from Python costs per call: numba's unboxing of the records.

Run: ``python benchmarks/bench_entry_call.py``. The Python loop could call the kernel's step
halves (``sense_step``, ``actuate_step`` in :mod:`tt_mujoco.sim.loop.closed_loop`) once each per
step,
around a controller class; what such a call costs before any of the step runs is numba turning
its Python arguments into native ones. This builds the records of an S-curve episode as
:func:`tt_mujoco.sim.loop.compiled.run_compiled` does (one trailer, then three), compiles functions
that take them and do nothing, calls each through its typed entry point (as the chunk loop is
called) and prints the microseconds a call: with every record of the step, with the plant's
record alone, and with one array.
"""

import os
import time

os.environ.setdefault("TT_MUJOCO_COMPILE_NOW", "1")  # compile here, not in the background

import numpy as np
from numba import njit

from tt_mujoco.sim import Scenario
from tt_mujoco.sim.build import build
from tt_mujoco.sim.loop import compiled, episode, records
from tt_mujoco.sim.loop.stepper import Stepper
from tt_mujoco.sim.parts.measure import TRAIN_FIELDS

CALLS = 20000


@njit
def takes_the_step(k, row, loop, plant, law, target, log, stop):
    return k + row


@njit
def takes_the_plant(k, plant):
    return k


@njit
def takes_an_array(k, values):
    return k


def per_call_us(dispatcher, args) -> float:
    """Microseconds a call of ``dispatcher``'s entry point typed for ``args``, best of three."""
    entry = dispatcher.compile(tuple(dispatcher.typeof_pyval(a) for a in args))
    best = float("inf")
    for _ in range(3):
        start = time.perf_counter()
        for _ in range(CALLS):
            entry(*args)
        best = min(best, (time.perf_counter() - start) / CALLS)
    return 1e6 * best


def main() -> None:
    k_mod = compiled.kernel()
    for trailers in (1, 3):
        built = build(Scenario(traj="s_curve", duration=10.0, trailers=trailers))
        stepper = Stepper(built)
        stepper.reset(np.random.default_rng(0))
        controller = built.new_controller()
        user = compiled._user_law(k_mod, controller)
        loop, plant, law, target, stop = episode.episode_records(stepper, controller, user)
        log = records.LogRecord(
            measurement=np.empty((1, len(records.MEASUREMENT_DTYPE))),
            loop=np.empty(1, dtype=records.LOG_DTYPE),
            train=np.empty((1, trailers - 1, len(TRAIN_FIELDS))),
            etas=np.empty((0, trailers)),
        )
        step_args = (0, 0, loop, plant, law, target, log, stop)
        print(
            f"{trailers} trailer(s): a call with every record of the step "
            f"{per_call_us(takes_the_step, step_args):.2f} us, with the plant's record "
            f"{per_call_us(takes_the_plant, (0, plant)):.2f} us, with one array "
            f"{per_call_us(takes_an_array, (0, plant.ode_state)):.2f} us"
        )


if __name__ == "__main__":
    main()

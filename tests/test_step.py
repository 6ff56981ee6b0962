"""The step's shared checks and clips (tt_mujoco.sim.loop.step) and the records they read
(tt_mujoco.sim.loop.records), which the Python and the compiled loop both run."""

from __future__ import annotations

import bisect
import math

import numpy as np
import pytest

from tt_mujoco.reference.paths import arc_segment
from tt_mujoco.sim.loop import records, step

LIMITS = records.Limits(
    torque_limit=15.0,
    disturbance_bound=math.inf,
    jackknife_phi=math.radians(60.0),
    jackknife_beta=math.radians(80.0),
    max_speed=50.0,
    noise_v=0.0,
    noise_w=0.0,
)


@pytest.mark.parametrize(
    ("state", "code"),
    [
        ((0.0, 1.0, 0.0, 0.0, 0.0), step.RUNNING),
        ((math.nan, 1.0, 0.0, 0.0, 0.0), step.BLEW_UP),
        ((0.0, 1.0, math.inf, 0.0, 0.0), step.BLEW_UP),
        ((0.0, 50.1, 0.0, 0.0, 0.0), step.BLEW_UP),
        ((0.0, 1.0, 0.0, math.radians(60.0), 0.0), step.JACKKNIFE),
        ((0.0, 1.0, 0.0, 0.0, -math.radians(80.0)), step.JACKKNIFE),
        ((0.0, -50.0, 0.0, math.radians(59.9), math.radians(79.9)), step.RUNNING),
    ],
)
def test_stop_code(state, code):
    assert step.stop_code(*state, LIMITS) == code


def test_clips():
    assert step.clip(20.0, 15.0) == 15.0 and step.clip(-20.0, 15.0) == -15.0
    assert step.clip(3.0, 15.0) == 3.0
    assert step.clip_pair(1.0, -2.0, math.inf) == (1.0, -2.0, 0.0)
    assert step.clip_pair(1.0, -20.0, 15.0) == (1.0, -15.0, 1.0)
    assert step.noisy(1.0, 0.5, [0.0, 2.0], 1) == 2.0


def test_arc_segment_is_bisect_over_the_inner_bounds():
    rng = np.random.default_rng(0)
    for n in (1, 2, 3, 7):
        bounds = [0.0, *np.cumsum(rng.uniform(0.1, 2.0, n)).tolist()]
        for s in [-1.0, 0.0, *bounds, *rng.uniform(-1.0, bounds[-1] + 1.0, 50).tolist()]:
            assert arc_segment(s, bounds) == bisect.bisect_right(bounds[1:-1], s)


def test_a_record_is_read_and_written_by_name():
    record = records.new_record(records.TARGET_FIELDS, v_prev=math.nan, kappa=0.5)
    assert record.dtype.names == records.TARGET_FIELDS
    assert math.isnan(record[0]["v_prev"]) and record[0]["kappa"] == 0.5 and record[0]["s"] == 0.0
    log = np.zeros(3, dtype=records.LOG_DTYPE)
    assert log.view(np.float64).reshape(3, -1).shape == (3, len(records.LOG_DTYPE))


def _positional_counts(functions):
    """``name -> number of positional parameters`` of each plain-number function."""
    import inspect

    counts = {}
    for fn in functions:
        kinds = (inspect.Parameter.POSITIONAL_ONLY, inspect.Parameter.POSITIONAL_OR_KEYWORD)
        params = inspect.signature(fn).parameters.values()
        counts[f"{fn.__module__}.{fn.__name__}"] = sum(p.kind in kinds for p in params)
    return counts


def test_no_function_of_the_step_takes_more_than_eight_positional_arguments():
    # Named records carry what a long argument list would (Tracking, Nominal, Saturation, ...).
    import ast
    from pathlib import Path

    from tt_mujoco.sim.loop import kernel_sources

    counts = _positional_counts(kernel_sources.SHARED)
    for name in ("closed_loop.py", "_kernel.py", "stepper.py", "episode.py", "compiled.py"):
        source = Path(kernel_sources.__file__).with_name(name)
        for node in ast.walk(ast.parse(source.read_text())):
            if isinstance(node, ast.FunctionDef):
                arguments = len(node.args.posonlyargs) + len(node.args.args)
                method = bool(node.args.args) and node.args.args[0].arg == "self"
                counts[f"{name}:{node.name}"] = arguments - method
    assert "closed_loop.py:sense_step" in counts and "_kernel.py:run_chunk" in counts
    assert "closed_loop.py:run_steps" in counts and "stepper.py:run" in counts
    too_long = {name: n for name, n in counts.items() if n > 8}
    assert not too_long


def test_a_built_in_law_takes_named_records_and_returns_one():
    from tt_mujoco.controllers import base, fbl

    tracking = base.Tracking(v=1.0, omega=0.0, v_d=0.5, omega_d=0.0, v_d_dot=0.0, omega_d_dot=0.0)
    model = base.Nominal(f1=0.0, f2=0.0, g11=1.0, g12=0.0, g21=0.0, g22=1.0)
    saturation = base.Saturation(limit=15.0, saturated=False, anti_windup=True)
    gains = fbl.FblGains(k_v=8.0, k_omega=5.0)
    out = fbl.fbl_law(0.001, tracking, model, fbl.FblState(), gains, saturation)
    # u = g^-1 (v_d_dot - f - K e) with g = I: -8 * 0.5 on the first wheel
    assert out.status == base.LAW_OK and (out.T_r, out.T_l) == (-4.0, 0.0)
    assert not out.saturated and out.state == fbl.FblState()

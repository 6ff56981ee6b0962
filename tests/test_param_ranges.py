"""Every number a run takes has a stated range, and every value in it runs.

Generated from :data:`tt_mujoco.vehicle.param_ranges.RANGES` and the run's option schema: a
new parameter or option is covered by declaring it. At each end of a range a short run on
either plant ends in one of the documented statuses (or the plant's builder refuses the
vehicle, naming it); just beyond it, the value is refused, naming the field and the range.
"""

import dataclasses
import math
import re

import pytest

from tt_mujoco.sim import SCHEMA, Scenario, simulate
from tt_mujoco.vehicle.param_ranges import RANGES, in_range
from tt_mujoco.vehicle.params import SETTABLE_FIELDS, Params

STATUSES = {"ok", "jackknife", "diverged", "collision", "failed"}
#: Numeric fields with a check of their own (eta's presets and singularity, the timestep's
#: interval, the drag levers' 10 m) rather than a range here.
OWN_CHECKS = {"eta", "timestep", "drag_centre_tractor", "drag_centre_trailer"}
#: Extreme finite values tried on every option that takes a number.
EXTREMES = (1e300, -1e300, 1e-300, -1e-300, 1e15, -1e15)


def _short_run(plant: str, **options):
    """A run of 20 control steps: its status, or the ValueError that refused it."""
    try:
        return simulate(Scenario(plant=plant, duration=0.02, **options)).status
    except ValueError as err:
        return err


def test_every_numeric_parameter_declares_a_range():
    numeric = [f.name for f in dataclasses.fields(Params) if f.init and f.type in (float, "float")]
    assert numeric, "Params' fields not found"
    assert sorted(set(numeric) - OWN_CHECKS - set(RANGES)) == []
    assert all(low < high and math.isfinite(high) and low > 0 for low, high, _ in RANGES.values())


@pytest.mark.parametrize("name", sorted(RANGES))
def test_just_beyond_a_range_is_refused_naming_the_field_and_the_range(name):
    low, high, _ = RANGES[name]
    for value in (low * (1 - 1e-9), high * (1 + 1e-9), math.nan, math.inf):
        allowed = re.escape(f"[{low:g}, {high:g}]")
        with pytest.raises(ValueError, match=rf"^{name}=.* is not allowed: .*{allowed}"):
            in_range(name, value)
        with pytest.raises(ValueError, match=rf"{name}="):
            Params(**{name: value})


@pytest.mark.parametrize("plant", ["reduced", "mujoco"])
@pytest.mark.parametrize("name", sorted(RANGES))
def test_each_end_of_a_range_runs_to_a_documented_status(name, plant):
    for value in RANGES[name][:2]:
        # friction is a scenario option of its own, the rest are --param's
        given = {"params": {name: value}} if name in SETTABLE_FIELDS else {name: value}
        outcome = _short_run(plant, **given)
        if isinstance(outcome, ValueError):
            # refused by a rule that ties two fields (a wheel larger than its link) or by
            # MuJoCo's builder (a body too light for it): the message names the field
            assert name in str(outcome)
        else:
            assert outcome in STATUSES


def _numeric_options():
    """The run's options that take a number, and of its tables of numbers every entry."""
    for opt in SCHEMA.options:
        if opt.name == "params":
            continue  # the ranges above
        names = getattr(opt.parse, "names", None)
        if names is not None:
            for entry in names:
                yield opt.name, entry
            continue
        for probe in (1, 0.001):  # a number inside most ranges, or inside the timesteps'
            try:
                opt.parse(probe, opt.name)
            except (ValueError, TypeError):
                continue
            yield opt.name, None
            break


NUMERIC_OPTIONS = sorted(_numeric_options(), key=str)


def test_the_numeric_options_are_found():
    names = {name for name, _ in NUMERIC_OPTIONS}
    assert {"duration", "noise_snr_db", "time_limit_s", "plant_scale", "friction"} <= names


@pytest.mark.parametrize(("name", "entry"), NUMERIC_OPTIONS, ids=str)
def test_an_extreme_value_of_any_option_is_refused_or_runs(name, entry):
    # Before: noise_snr_db=-1e15 overflowed, time_limit_s=1e15 passed time_t, a clothoid of
    # R=1e15 asked for exabytes and L=1e300 overflowed its square: bugs (exit 70), not input.
    for value in EXTREMES:
        given = {name: value if entry is None else {entry: value}}
        try:
            Scenario(**given).validate()
        except ValueError as err:
            assert name in str(err)
            continue
        for plant in ("reduced", "mujoco"):
            outcome = _short_run(plant, **given)
            assert isinstance(outcome, ValueError) or outcome in STATUSES, (given, plant)

"""Built-in disturbances (tt_mujoco/sim/parts/disturbances.py): their forms, which the step computes
itself, and the rolling resistance."""

import math

import numpy as np
import pytest

from tt_mujoco.sim import Scenario, simulate
from tt_mujoco.sim.parts.disturbances import (
    DISTURBANCES,
    PaperDisturbance,
    RollingResistance,
    builtin_forms,
    form_of,
    paper_disturbance_of,
)
from tt_mujoco.sim.parts.terrain import GRAVITY


def test_every_registered_class_of_the_module_is_a_built_in_form():
    forms = builtin_forms()
    assert [form_of(DISTURBANCES[name]())[0] for name in DISTURBANCES] == list(range(len(forms)))
    assert forms[form_of(PaperDisturbance())[0]](1.3, 0.4, 0.2, ()) == paper_disturbance_of(1.3)


def test_a_subclass_or_a_callable_is_called_back():
    class Doubled(RollingResistance):
        def __call__(self, t, v=0.0, omega=0.0):
            return 2.0 * super().__call__(t, v, omega)[0], 0.0

    assert form_of(Doubled()) is None and form_of(lambda t: (0.0, 0.0)) is None


def test_the_rolling_resistance_opposes_the_motion_and_vanishes_at_rest():
    rolling = RollingResistance(c_rr=0.02, v_smooth=0.05)
    assert rolling(0.0, 0.0) == (0.0, 0.0)
    assert rolling(0.0, 1.0)[0] == pytest.approx(-0.02 * GRAVITY, rel=1e-8)
    assert rolling(0.0, -1.0)[0] == pytest.approx(0.02 * GRAVITY, rel=1e-8)


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"c_rr": -0.1}, r"c_rr=-0.1 is not allowed"),
        ({"c_rr": 1.5}, r"c_rr=1.5 is not allowed"),
        ({"c_rr": "a"}, r"c_rr='a' is not allowed"),
        ({"v_smooth": 0.0}, r"v_smooth=0.0 is not allowed"),
        ({"v_smooth": math.inf}, r"v_smooth=inf is not allowed"),
    ],
)
def test_bad_coefficients_are_refused(kw, match):
    with pytest.raises(ValueError, match=match):
        RollingResistance(**kw)


@pytest.mark.parametrize(("plant", "rtol"), [("reduced", 1e-6), ("mujoco", 2e-3)])
def test_a_proportional_speed_loop_lags_by_the_resistance_over_its_gain(plant, rtol):
    # Stanley's inner loop is e_v_dot = -k_v e_v + a_v: at cruise on the circle the lag is
    # c_rr g / k_v = 7.3575 mm/s. The reduced plant is the nominal model, so the matched
    # torques give it to rounding (measured 1e-9 relative); MuJoCo's tyres move it by 0.04 %.
    result = simulate(
        Scenario(controller="stanley", traj="circle", plant=plant, disturbance_model="rolling")
    )
    ts = result.timeseries
    cruise = (ts["t"] > 4.0) & (ts["t"] < 7.0)
    lag = float(np.mean(ts["v_d"][cruise] - ts["v"][cruise]))
    assert lag == pytest.approx(0.015 * GRAVITY / 20.0, rel=rtol)

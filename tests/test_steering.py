"""Passive steering: exact same-path gains, the scheduler, reverse driving."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest
from target_steps import SteppedTarget

from tt_mujoco.analysis.metrics import follower_offtrack, trailer_offtrack
from tt_mujoco.reference.reverse import ReverseTarget
from tt_mujoco.reference.targets import make_target
from tt_mujoco.sim import Scenario, simulate
from tt_mujoco.sim.parts.plant_reduced import ReducedPlant
from tt_mujoco.sim.parts.schedule import (
    EtaScheduler,
    curvature_gains_of,
    eta_series_of,
    gains_moved,
)
from tt_mujoco.vehicle import reduced
from tt_mujoco.vehicle.params import Params
from tt_mujoco.vehicle.steering import (
    exact_same_path_eta,
    exact_train_same_path_etas,
    same_path_eta_limit,
    steady_offtrack,
)

L, L0 = 0.3, 0.4


def test_exact_gain_tends_to_minus_one_seventh_not_spec_minus_one_eighth():
    # Linearised kinematics and geometry give 1 - eta = 2 L0 / (L + L0): -1/7 for the paper's
    # links. The closed form is exact; at kappa = 1e-4 the O(kappa^2) term is ~1e-10.
    assert same_path_eta_limit(L, L0) == pytest.approx(-1.0 / 7.0, abs=1e-15)
    assert exact_same_path_eta(1e-4, L, L0) == pytest.approx(-1.0 / 7.0, abs=1e-8)
    assert exact_same_path_eta(0.0, L, L0) == same_path_eta_limit(L, L0)
    assert abs(exact_same_path_eta(1e-4, L, L0) - (-0.125)) > 0.017


@pytest.mark.parametrize("kappa", [0.25, 0.653, 2.0 / 3.0, 1.0, 2.0])
def test_exact_gain_puts_p0_on_the_tractor_path(kappa):
    eta = exact_same_path_eta(kappa, L, L0)
    assert exact_same_path_eta(-kappa, L, L0) == eta  # even in kappa
    # The steady articulation of the kinematics (independent root finder) with this gain puts
    # P0 on the circle of radius 1/kappa: 1e-9 m covers the root finder's xtol = 1e-13 rad.
    assert abs(steady_offtrack(kappa, Params(eta=eta))) < 1e-9


def test_steady_offtracking_values_against_spec_section_3():
    # docs/model.md Section 3 (R = 1.5 m): same-path -0.125 gives -2.9 mm, plain -23.5 mm, eta = -3
    # +114 mm (R = 3 m: -1.3 / -11.7 / +58 mm). SPEC rounds to 0.1 mm (0.5 mm for the last).
    cases = [(1.5, -0.125, -2.9e-3), (1.5, 0.0, -23.5e-3), (1.5, -3.0, 114e-3)]
    cases += [(3.0, -0.125, -1.3e-3), (3.0, 0.0, -11.7e-3), (3.0, -3.0, 58e-3)]
    for R, eta, spec in cases:
        assert steady_offtrack(1.0 / R, Params(eta=eta)) == pytest.approx(spec, abs=5e-4)
    # The exact limit -1/7 is ten times closer than -0.125 at R = 1.5 m (measured -0.275 mm).
    assert steady_offtrack(1.0 / 1.5, Params(eta=-1.0 / 7.0)) == pytest.approx(-2.75e-4, abs=2e-6)
    # eta = 3: the steady turn exists (unstable forward, stable reversing) with P0 0.30 m
    # outside the unit circle, as the reversing runs of the steering study measure.
    assert steady_offtrack(1.0, Params(eta=3.0)) == pytest.approx(0.3036, abs=1e-4)


def test_exact_gain_checked_by_integrating_the_reduced_kinematics():
    # Independent of the geometry above: drive the reduced kinematics (paper eq. 13) round a
    # circle of R = 1.5 m for 24 m (67 articulation time constants L0 / (1 - eta) = 0.35 m)
    # and measure P0's radius. RK4 at 5 mm steps: error ~1e-12 m.
    R, v = 1.5, 0.8
    p = Params(eta=exact_same_path_eta(1.0 / R, L, L0))
    q = np.array([R, 0.0, math.pi / 2, 0.0, 0.0, 0.0])
    dt, V = 0.00625, (v, v / R)
    for _ in range(4800):
        k1 = reduced.kinematics(q, V, p)
        k2 = reduced.kinematics(q + dt / 2 * k1, V, p)
        k3 = reduced.kinematics(q + dt / 2 * k2, V, p)
        k4 = reduced.kinematics(q + dt * k3, V, p)
        q = q + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    _, P0, _ = reduced.trailer_pose(q[0], q[1], q[2], q[3], p)
    assert abs(math.hypot(P0[0], P0[1]) - R) < 1e-8


def test_exact_gain_rejects_impossible_curvatures():
    with pytest.raises(ValueError, match="kappa=20"):
        exact_same_path_eta(20.0, L, L0)
    with pytest.raises(ValueError, match="finite"):
        exact_same_path_eta(math.nan, L, L0)


def test_scheduler_on_the_reduced_plant_swaps_params_and_logs_eta():
    adapter = ReducedPlant(Params(), (0.0, 0.0, 0.0), 0.0, 0.001)
    sched = EtaScheduler(adapter, adapter.params)
    # the step's own schedule: the exact gain at kappa = 1, applied if it moved enough
    etas = [0.0]
    assert curvature_gains_of(1.0, sched.lengths, etas)
    assert etas[0] == pytest.approx(exact_same_path_eta(1.0, L, L0))
    assert gains_moved(etas, sched.etas, sched.tolerance)
    # A change below the tolerance (1e-5) is not applied.
    near = [0.0]
    assert curvature_gains_of(1.0 + 1e-3, sched.lengths, near)  # eta moves ~1e-6 here
    assert not gains_moved(near, etas, sched.tolerance)
    # the scheduler applies the first gains; what a run changes stays in its records, and the
    # time series reads the gain in force at each sample from the changes the run logged
    first = adapter.params.eta
    assert first == adapter.ode.params.eta == sched.eta == pytest.approx(-1.0 / 7.0)
    changes = [(0, (first,)), (1, tuple(etas)), (5, (first,))]
    series = eta_series_of(changes, 7)
    assert series[0] == first  # before the first change: the params' eta
    assert np.all(series[1:5] == exact_same_path_eta(1.0, L, L0))
    assert np.all(series[5:] == first)
    assert eta_series_of(changes, 3).tolist() == [first, etas[0], etas[0]]
    with pytest.raises(ValueError, match="plant"):
        EtaScheduler(object(), Params())


def test_scheduled_runs_hold_beta_at_the_exact_gain_on_both_plants():
    # Circle, 4 s: kappa = 1 all along. The MuJoCo equality follows eq_data (a soft
    # constraint: |beta - eta phi| measured 2.8e-5 rad at most, beta / phi within 4e-8 of the
    # gain at the end); the reduced plant holds it exactly.
    exact = exact_same_path_eta(1.0, L, L0)
    for plant, tol in (("reduced", 1e-12), ("mujoco", 1e-4)):
        sc = Scenario(plant=plant, traj="circle", duration=4.0, eta_schedule=True)
        res = simulate(sc)
        assert res.status == "ok"
        ts = res.timeseries
        assert res.metrics["eq_violation_max"] < tol
        assert ts["beta"][-1] / ts["phi"][-1] == pytest.approx(exact, abs=1e-6)
        assert abs(exact - (-1.0 / 7.0)) > 1e-3  # so the check above sees the schedule act


def test_scheduler_writes_the_steering_equality_polycoef():
    from tt_mujoco.sim.parts.plant_mujoco import MujocoPlant

    plant = MujocoPlant(Params(), (0.0, 0.0, 0.0), 0.0, wrench=False)
    vehicle = plant.vehicle
    sched = EtaScheduler(plant, vehicle.params)
    row = vehicle.model.eq_data[vehicle.model.equality("steering").id]
    assert row[1] == pytest.approx(1.0 / 7.0)  # polycoef = (0, -eta, 0, 0, 0)
    assert row[0] == row[2] == 0.0 and sched.etas == vehicle.params.etas


def _steering_jacobian(plant):
    """The steering equality's constraint row of ``efc_J`` (dense) after a forward pass."""
    import mujoco

    m, d = plant.model, plant.data
    mujoco.mj_forward(m, d)
    eq = m.equality("steering").id
    rows = [
        i
        for i in range(d.nefc)
        if d.efc_type[i] == mujoco.mjtConstraint.mjCNSTR_EQUALITY and d.efc_id[i] == eq
    ]
    assert len(rows) == 1
    if mujoco.mj_isSparse(m):
        J = np.zeros((d.nefc, m.nv))
        mujoco.mju_sparse2dense(J, d.efc_J, d.efc_J_rownnz, d.efc_J_rowadr, d.efc_J_colind)
    else:
        J = d.efc_J[: d.nefc * m.nv].reshape(d.nefc, m.nv)
    return J[rows[0]]


def _advance(plant, etas) -> None:
    """One physics step of a plant whose axles are actuated, as the loop takes it: each
    axle's target aimed from its hitch towards ``etas``, then MuJoCo's step."""
    from tt_mujoco.sim.parts.plant_mujoco import aim_steering_of

    eq_data, ids, hitches_q, actuated, max_turn = plant.steering
    assert actuated
    aim_steering_of(eq_data, ids, hitches_q, list(etas), plant.data.qpos, max_turn)
    mujoco.mj_step(plant.model, plant.data)


def test_an_actuated_axle_holds_beta_eta_phi_and_loads_the_hitch_with_nothing():
    from tt_mujoco.sim.parts.plant_mujoco import MujocoPlant

    linkage = MujocoPlant(Params(), (0.0, 0.0, 0.0), 0.5, wrench=False, phi0=0.2)
    lay = linkage.vehicle.layout
    linkage.set_etas((2.0,))
    # the linkage's row: dq_steer - (-eta) dq_hitch, so its force acts on the hitch times eta
    assert _steering_jacobian(linkage)[[lay.steer_v, lay.hitch_v]] == pytest.approx([1.0, 2.0])

    plant = MujocoPlant(Params(), (0.0, 0.0, 0.0), 0.8, wrench=False, phi0=0.2)
    plant.steer_by_actuator()
    plant.set_etas((2.0,))
    _advance(plant, (2.0,))
    assert _steering_jacobian(plant)[[lay.steer_v, lay.hitch_v]] == pytest.approx([1.0, 0.0])

    plant = MujocoPlant(Params(), (0.0, 0.0, 0.0), 0.8, wrench=False, phi0=0.2)
    plant.steer_by_actuator()
    eta0, worst = Params().eta, 0.0
    for step in range(300):  # the gain ramps at 1 1/s from -1/7 while the hitch settles
        eta = eta0 + 0.001 * step
        plant.set_etas((eta,))
        _advance(plant, (eta,))
        me = plant.measure()
        worst = max(worst, abs(me.beta - eta * me.phi))
    # a target moving at d(eta phi)/dt ~ 0.2 rad/s behind a coupling of time constant
    # tc = 2 steps lags by about 2 tc d(eta phi)/dt = 8e-4 rad: measured 7.6e-4 (the
    # linkage, 5.9e-4)
    assert worst < 1e-3
    with pytest.raises(ValueError, match="2 gains are not allowed: the plant has 1"):
        plant.set_etas((1.0, 1.0))


def test_an_actuated_axle_starts_where_it_stands_and_turns_at_its_slew_rate():
    from tt_mujoco.sim.parts.plant_mujoco import MujocoPlant, aim_steering_of

    # the pure update: at most max_turn a step, the target itself once within reach
    eq_data, qpos = np.zeros((1, 5)), np.array([-0.2])  # hitch angle -phi: phi = 0.2
    aim_steering_of(eq_data, [0], [0], [2.0], qpos, 0.05)
    assert eq_data[0, 0] == 0.05
    aim_steering_of(eq_data, [0], [0], [-0.5], qpos, 0.05)
    assert eq_data[0, 0] == 0.0
    aim_steering_of(eq_data, [0], [0], [-0.1], qpos, 0.05)
    assert eq_data[0, 0] == -0.1 * 0.2

    params = Params(axle_slew_rate=2.0)
    plant = MujocoPlant(params, (0.0, 0.0, 0.0), 0.8, wrench=False, phi0=0.2)
    plant.steer_by_actuator()
    row = plant.model.eq_data[plant.model.equality("steering").id]
    start = plant.measure().beta
    assert row[0] == start == pytest.approx(params.eta * 0.2)  # no step at the hand-over
    plant.set_etas((2.0,))  # asks beta = 0.4 rad at once
    targets = []
    for _ in range(50):
        _advance(plant, (2.0,))
        targets.append(row[0])
    # 2 rad/s at 1 ms a step: 2 mrad a step, far short of the 0.43 rad asked
    assert np.diff([start, *targets]) == pytest.approx(np.full(50, 2e-3), abs=1e-12)
    with pytest.raises(ValueError, match="axle_slew_rate=0 is not allowed"):
        Params(axle_slew_rate=0)


def test_reverse_target_runs_the_path_backwards():
    _, forward, _ = make_target("circle", "dynamic")
    rev = ReverseTarget(forward)
    assert rev.s_end == pytest.approx(forward.path.length)
    pose = rev.initial_pose
    assert (pose.x, pose.y) == pytest.approx(forward.path.pose_at(rev.s_end)[:2])
    # Feed the step v = -v_ref: s runs back by the profile's distance (trapezoid error < 1e-6 m).
    stepped = SteppedTarget(traj="circle", reverse=True, hitch_feedback=None)
    assert isinstance(stepped.target, ReverseTarget) and stepped.state.s == rev.s_end
    dt, t = 0.001, 0.0
    for k in range(5001):
        t = k * dt
        v_d, w_d, _, _ = stepped.step(t, dt, -forward.reference_speed(t))
        assert v_d == pytest.approx(-forward.reference_speed(t))
        assert w_d == pytest.approx(stepped.state.kappa * v_d)
    assert stepped.state.s == pytest.approx(rev.s_end - forward.profile.distance(t), abs=1e-6)
    ts = np.array([0.0, 2.5, 5.0])
    xs, ys = rev.reference_point(ts)
    for i, ti in enumerate(ts):
        assert (xs[i], ys[i]) == pytest.approx(rev.reference_point(float(ti)))
    assert rev.reference_speed(1.0) == pytest.approx(-forward.reference_speed(1.0))


def test_paper_eta_jackknifes_forward_and_tracks_reversing():
    # docs/model.md Section 3: phi_dot ~ (eta - 1) v phi / L0. Circle, no disturbance, reduced
    # plant:
    # forward jackknifes at ~1.0 s (measured), reversing tracks (lateral RMSE ~1e-6 m measured).
    fwd = simulate(Scenario(plant="reduced", traj="circle", eta="paper", disturbance="none"))
    assert fwd.status == "jackknife" and fwd.timeseries["t"][-1] < 1.5
    rev = simulate(
        Scenario(
            plant="reduced",
            traj="circle",
            eta="paper",
            disturbance="none",
            reverse=True,
            duration=5.0,
        )
    )
    assert rev.status == "ok"
    assert rev.metrics["rmse_lateral"] < 1e-3
    # Backwards all the way (the stop at the end overshoots by ~2e-6 m/s, measured).
    assert np.max(rev.timeseries["v"]) < 1e-4 and np.min(rev.timeseries["v"]) < -0.7
    # The leading trailer stays on the outside, short of the eta = 3 singularity at 30 deg.
    assert rev.metrics["phi_max_abs_deg"] < 20.0


def test_follower_offtrack_swaps_roles_when_reversing():
    t = np.linspace(0, 1, 50)
    p = np.column_stack([t, np.zeros_like(t)])
    p0 = np.column_stack([t - 0.5, 0.01 * np.ones_like(t)])
    ts = {"x": p[:, 0], "y": p[:, 1], "x0": p0[:, 0], "y0": p0[:, 1]}
    np.testing.assert_array_equal(follower_offtrack(ts), trailer_offtrack(p, p0))
    np.testing.assert_array_equal(follower_offtrack(ts, reverse=True), trailer_offtrack(p0, p))


@pytest.mark.parametrize("field", ["eta_schedule", "reverse"])
def test_scenario_rejects_non_bool_switches(field):
    with pytest.raises(ValueError, match=field):
        Scenario(**{field: "maybe"}).validate()


def test_the_curvature_schedule_keeps_the_gain_near_the_paper_linkage():
    # docs/model.md Section 13: for |kappa| <= 2 1/m the curvature schedule's gain stays within
    # [-0.159, -0.143], a linkage's range (the path schedule's sweeps [-3, 3]).
    p = Params()
    etas = [exact_same_path_eta(kappa, p.L, p.L0) for kappa in np.linspace(-2.0, 2.0, 401)]
    assert (round(min(etas), 3), round(max(etas), 3)) == (-0.159, -0.143)


def test_the_curvature_schedule_keeps_its_gains_where_no_axle_can_reach_the_path():
    # The scheduler's plain form: the public functions' gains where a pose exists, and False
    # (the gains in force kept) on a path tighter than the trailer can follow, where the
    # public functions raise.
    from tt_mujoco.sim.parts.schedule import curvature_gains_of

    one, train = [(0.3, 0.4)], [(0.3, 0.4), (0.3, 0.4)]
    for kappa in (0.0, 1e-7, 0.5, -1.5):
        out = [0.0]
        assert curvature_gains_of(kappa, one, out)
        assert out == [exact_same_path_eta(kappa, 0.3, 0.4)]
        out = [0.0, 0.0]
        assert curvature_gains_of(kappa, train, out)
        assert out == exact_train_same_path_etas(kappa, train)
    for lengths in (one, train):
        assert not curvature_gains_of(20.0, lengths, [0.0] * len(lengths))
        with pytest.raises(ValueError, match=r"kappa=20\.0 is not allowed"):
            if len(lengths) == 1:
                exact_same_path_eta(20.0, 0.3, 0.4)
            else:
                exact_train_same_path_etas(20.0, lengths)


def test_an_axle_follows_its_gain_up_to_its_slew_rate():
    from tt_mujoco.vehicle.steering import followed_gain_of

    assert followed_gain_of(-3.0, 0.2, 1.0) == -3.0  # 0.6 rad/s asked: followed whole
    assert followed_gain_of(-3.0, 0.5, 1.0) == pytest.approx(-2.0)  # 1.5 asked, 1 given
    assert followed_gain_of(2.0, -4.0, 1.0) == pytest.approx(0.25)
    assert followed_gain_of(0.5, 0.0, 1.0) == 0.5
    assert followed_gain_of(0.5, 1e3, math.inf) == 0.5  # a linkage
    from tt_mujoco.vehicle.steering import followed_gains_of

    out = [0.0, 0.0]
    followed_gains_of((-3.0, 2.0), [(0.5, 0.8, 0.1), (0.1, 0.7, 0.0)], 1.0, out)
    assert out == [pytest.approx(-2.0), 2.0]  # a train: each trailer at its own hitch rate

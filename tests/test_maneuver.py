"""A maneuver with a cusp (tt_mujoco.sim.maneuver): a forward leg, a stop, a backing leg, each
a run from where the last stopped; one result, the same on every route."""

import copy
import json
import math

import numpy as np
import pytest
import tomli_w

from tt_mujoco import run
from tt_mujoco.sim import Scenario, build, simulate
from tt_mujoco.world.builtin import WORLDS


@pytest.fixture
def facing_away(tmp_path):
    """The loading bay with the train starting in front of the building, facing away from
    it, too close to turn in: the plan drives forward first, stops, and backs in."""
    table = copy.deepcopy(WORLDS["loading_bay"])
    table["start"] = {"x": 5.8, "y": -0.8, "heading_deg": -90.0}
    path = tmp_path / "away.toml"
    path.write_text(tomli_w.dumps(table))
    return str(path)


def test_the_plan_has_a_cusp_and_the_first_leg_drives_forward(facing_away):
    built = build(Scenario(world=facing_away, traj="plan", reverse=True, plant="reduced"))
    assert built.plan.cusps == 1
    assert built.leg == 0 and not built.scenario.reverse
    assert built.reversing is None


@pytest.mark.parametrize(("plant", "trailers"), [("reduced", 1), ("reduced", 2), ("mujoco", 1)])
def test_a_maneuver_with_a_cusp_reaches_the_goal(facing_away, plant, trailers):
    """With 20 dB noise (one trailer; two trailers without: their controller saturates its
    torques under that noise driving forward, off the plan by 4 cm rms). Measured: the last
    axle 2.3, 0.6 and 2.3 mm off the goal, each leg's leading point at most 2.9 mm (one
    trailer) and 5.5 mm (two) rms off its path; the must-show bounds (1 cm, 0.05 rad, 2 cm
    rms) are asserted."""
    noise = 20.0 if trailers == 1 else None
    scenario = Scenario(
        world=facing_away,
        traj="plan",
        reverse=True,
        trailers=trailers,
        plant=plant,
        noise_snr_db=noise,
    )
    result = simulate(scenario)
    assert result.status == "ok", result.message
    assert result.scenario.reverse  # the maneuver is the one asked for, backing in
    world = result.metrics["world"]
    goal = world["goal"]
    assert goal["reached"]
    assert goal["position_error_m"] < 0.01
    assert abs(math.radians(goal["heading_error_deg"])) < 0.05
    assert world["min_clearance_m"] > 0.0 and world["collision"] is None
    plan = world["plan"]
    assert plan["cusps"] == 1
    forward, backing = plan["legs"]
    assert (forward["direction"], backing["direction"]) == ("forward", "reverse")
    assert forward["status"] == backing["status"] == "ok"
    for leg in plan["legs"]:
        assert leg["leading_cross_track_rms"] < 0.02, leg
    ts = result.timeseries
    assert np.all(np.diff(ts["t"]) > 0)
    assert forward["t_end_s"] < backing["t_start_s"] <= backing["t_end_s"]
    assert backing["t_end_s"] == pytest.approx(ts["t"][-1])
    # the backing leg starts where, and as, the forward leg stopped: at rest, the same pose
    cusp = int(np.searchsorted(ts["t"], backing["t_start_s"] - 1e-9))
    for column in ("x", "y", "theta", "phi"):
        assert ts[column][cusp] == pytest.approx(ts[column][cusp - 1], abs=1e-6), column
    # at rest: the speed target ends at zero, the speed within the band that the noise on the
    # measured speed leaves the inner loop (0.021 m/s at most over the last 0.1 s, measured)
    assert abs(ts["v_d"][cusp - 1]) < 0.005
    assert np.abs(ts["v"][cusp - 100 : cusp]).max() < 0.05
    assert result.metrics["steps"] == len(ts["t"])
    assert any("cusp" in note for note in result.notes)


@pytest.mark.parametrize("seed", [17, 24])
def test_two_trailers_stand_straight_at_the_cusp(seed):
    """After the forward leg's last turn passively steered trailers straighten only with the
    distance driven, and the backing leg starts from where they stand: the plan drives the
    train into its cusp along 2 D of straight where that is clear (plan.CUSP_STRAIGHTS).
    Two random starts of the loading bay that need a cusp, the reduced plant, no noise and
    no disturbance: measured 0.16 deg at most at the cusp, the backing leg's last axle 6.1 and
    5.4 mm rms off its path (the bound, 1 cm, is half the 2 cm a leg may be off); with the
    straight of one train length the second hitch stood 3.6 and 2.9 deg bent there and the
    last axle was 29.5 and 21.8 mm rms off."""
    scenario = Scenario(
        world="loading_bay", traj="plan", reverse=True, trailers=2, seed=seed, plant="reduced",
        disturbance="none",
    )  # fmt: skip
    result = simulate(scenario)
    assert result.status == "ok", result.message
    _, backing = result.metrics["world"]["plan"]["legs"]
    ts = result.timeseries
    cusp = int(np.searchsorted(ts["t"], backing["t_start_s"] - 1e-9))
    hitches = np.degrees([ts["phi"][cusp], ts["phi_2"][cusp]])
    assert np.abs(hitches).max() < 1.0, hitches
    assert backing["leading_cross_track_rms"] < 0.01, backing
    assert result.metrics["world"]["goal"]["reached"]


def test_a_maneuver_is_the_same_on_every_route(facing_away, tmp_path, monkeypatch):
    """The same seed, the same maneuver: the Python API, the command line, a scenario file and
    a sweep give the same plan and the same end (the Gym goal env's start: test_gym_goal.py)."""
    import csv

    from tt_mujoco import sweep

    monkeypatch.chdir(tmp_path)
    scenario = Scenario(world=facing_away, traj="plan", reverse=True, plant="reduced", seed=3)
    api = simulate(scenario).metrics["world"]
    options = ("--world", facing_away, "--traj", "plan", "--reverse", "--seed", "3")
    quiet = ("--plant", "reduced", "--no-video", "--quiet")
    assert run.main([*options, *quiet, "--out", "cli"]) == 0
    (tmp_path / "scenario.toml").write_text(
        tomli_w.dumps({"world": facing_away, "traj": "plan", "reverse": True, "seed": 3})
    )
    assert run.main(["--config", "scenario.toml", *quiet, "--no-plots", "--out", "toml"]) == 0
    items = [f"world={facing_away}", "traj=plan", "reverse=true", "plant=reduced", "seed=3"]
    assert sweep.main([*items, "--quiet", "--no-figures", "--out", "sweep"]) == 0
    for folder in ("cli", "toml"):
        doc = json.loads((tmp_path / folder / "metrics.json").read_text())
        assert doc["world"]["goal"] == api["goal"], folder
        assert doc["world"]["plan"]["legs"] == api["plan"]["legs"], folder
        assert doc["config"]["scenario"]["reverse"] is True
    (row,) = csv.DictReader((tmp_path / "sweep" / "runs.csv").open())
    assert int(row["world.plan.cusps"]) == api["plan"]["cusps"] == 1
    for key in ("position_error_m", "heading_error_deg"):
        assert float(row[f"world.goal.{key}"]) == api["goal"][key]
    assert float(row["world.plan.length_m"]) == api["plan"]["length_m"]
    assert (tmp_path / "cli" / "path.png").stat().st_size > 0


def test_faults_are_refused_on_a_maneuver_with_a_cusp(facing_away):
    with pytest.raises(ValueError, match="cusp"):
        build(
            Scenario(
                world=facing_away,
                traj="plan",
                reverse=True,
                plant="reduced",
                faults=["dropout:t=0.5,duration=0.2"],
            )
        )


def test_a_duration_is_shared_by_the_legs_by_their_length(facing_away):
    whole = Scenario(world=facing_away, traj="plan", reverse=True, plant="reduced", duration=30.0)
    result = simulate(whole)
    legs = result.metrics["world"]["plan"]["legs"]
    lengths = [leg["length_m"] for leg in legs]
    spans = [leg["t_end_s"] - leg["t_start_s"] + 0.001 for leg in legs]
    assert sum(spans) == pytest.approx(30.0, abs=0.01)
    assert spans[0] / spans[1] == pytest.approx(lengths[0] / lengths[1], rel=0.01)


def test_the_gym_env_drives_a_plan_with_a_cusp_and_fails_a_leg_that_cannot_start(
    facing_away, monkeypatch
):
    """The env steps the plan's legs one after the other (tests/test_gym_legs.py: as the run
    does); a leg that cannot start where the last stopped ends the episode as "failed", as it
    stops the maneuver, with the penalty of the steps left."""
    pytest.importorskip("gymnasium")
    from tt_mujoco import gym_legs
    from tt_mujoco.gym_env import TractorTrailerEnv

    env = TractorTrailerEnv(world=facing_away, traj="plan", reverse=True, plant="reduced")
    assert env.n_legs == 2

    def cannot(self, index, measurement):
        raise ValueError("leg 2 of 2 could not start: the trailer is outside the world")

    monkeypatch.setattr(gym_legs.Legs, "next", cannot)
    env.reset(seed=0)
    terminated = truncated = False
    while not (terminated or truncated):
        _, reward, terminated, truncated, info = env.step([0.0, 0.0])
    assert terminated and info["status"] == "failed" and "could not start" in info["message"]
    assert info["leg"] == 0 and reward == -(1.0 + env._legs.steps_after(0))  # leg 2's steps


def test_a_leg_that_cannot_start_keeps_what_was_driven(facing_away, monkeypatch):
    """After the first leg ran, a leg that cannot be built (a user's controller that fails
    to be made again, a unit outside the bounds) stops the maneuver as "failed", the rows
    driven kept: never bad input (exit 2) after the run began."""
    from tt_mujoco.sim import maneuver

    real = maneuver.build

    def second_fails(scenario, leg=None):
        if leg is not None and leg.index > 0:
            raise ValueError("controller 'mine.py:Law' failed: mine.py, line 3: RuntimeError")
        return real(scenario, leg)

    monkeypatch.setattr(maneuver, "build", second_fails)
    result = simulate(Scenario(world=facing_away, traj="plan", reverse=True, plant="reduced"))
    assert result.status == "failed"
    assert result.message.startswith("leg 2 of 2 could not start: controller 'mine.py:Law'")
    legs = result.metrics["world"]["plan"]["legs"]
    assert legs[0]["status"] == "ok" and "status" not in legs[1]
    assert result.timeseries["t"][-1] == pytest.approx(legs[0]["t_end_s"])
    assert not result.metrics["world"]["goal"]["reached"]


@pytest.mark.parametrize("world_seed", range(6))
def test_planned_runs_reach_the_goal_in_generated_worlds(world_seed, tmp_path):
    """Worlds no one drew (tests/generated_worlds.py), one trailer, the reduced plant: every
    start the planner plans from is driven to the goal, with or without a cusp."""
    from generated_worlds import random_world

    path = tmp_path / "generated.toml"
    path.write_text(tomli_w.dumps(random_world(np.random.default_rng(world_seed))))
    result = simulate(Scenario(world=str(path), traj="plan", reverse=True, plant="reduced"))
    assert result.status == "ok", result.message
    goal = result.metrics["world"]["goal"]
    assert goal["reached"], goal


def test_the_nmpc_drives_both_legs_to_the_goal(facing_away):
    """The NMPC (its schedule as the along-track reference: the static target) drives the
    forward leg and the backing leg into the bay; measured 6.7 mm and 0.87 deg off the goal."""
    pytest.importorskip("osqp")
    scenario = Scenario(
        world=facing_away,
        traj="plan",
        reverse=True,
        plant="reduced",
        controller="nmpc",
        target="static",
    )
    result = simulate(scenario)
    assert result.status == "ok", result.message
    world = result.metrics["world"]
    assert [leg["status"] for leg in world["plan"]["legs"]] == ["ok", "ok"]
    assert world["goal"]["reached"], world["goal"]


def test_a_maneuver_stopped_before_it_backs_up_still_says_what_backs_it_up(
    facing_away, tmp_path, monkeypatch
):
    """A maneuver whose forward leg stops (a collision, forced here) never drives a backing
    leg: metrics.json still says what drives its backing legs, and the command line ends as
    a stopped run does (exit 3, its rows kept), not as a bug of ours (its summary names the
    backing drive, and read it from the last leg driven: exit 70)."""
    from tt_mujoco.sim import maneuver

    real = maneuver.drive_leg

    def collides(built, *args):
        stepper, controller, _, _, wall = real(built, *args)
        return stepper, controller, "collision", "a collision (forced by the test)", wall

    monkeypatch.setattr(maneuver, "drive_leg", collides)
    monkeypatch.chdir(tmp_path)
    options = ["--world", facing_away, "--traj", "plan", "--reverse", "--plant", "reduced"]
    assert run.main([*options, "--no-video", "--no-plots", "--quiet", "--out", "out"]) == 3
    metrics = json.loads((tmp_path / "out" / "metrics.json").read_text())
    assert metrics["status"] == "collision"
    assert metrics["reversing"] == "hitch_cascade"
    legs = metrics["world"]["plan"]["legs"]
    assert legs[0]["direction"] == "forward" and legs[0]["status"] == "collision"
    assert "status" not in legs[1]

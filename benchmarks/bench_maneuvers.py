"""Planned maneuvers from seeded random starts: how often the train reaches its goal, how long
planning takes, how closely the leading point follows the plan.

    python benchmarks/bench_maneuvers.py [--world loading_bay] [--trailers 1 2 3] [--seeds 200]
        [--plant mujoco] [--noise-snr-db 20] [--direction reverse] [--workers 2]
        [--disturbance matched] [--generated dead_end]

Each run is ``python -m tt_mujoco.run --world WORLD --traj plan [--reverse] --trailers N
--seed SEED`` (one process per worker, the runs of a seed in order): the start drawn from the
world's start ranges with the seed, the path planned (``tt_mujoco/world/plan.py``) and driven by
ISMC-STA (backing up: with the hitch cascade; forward: with the path feedback), a plan with a
cusp leg by leg. Success: the run completes with no contact and no
jackknife and ends with the last axle within the goal's tolerances (1 cm, 0.05 rad by default).
A start the planner finds no path from counts as a failure ("no plan"). The leading point's
rms off the plan is the worst leg's, each against its own path (the runs whose worst leg
is more than :data:`LEG_RMS_BOUND` off are counted). Planning times are one
core's, the medians and 95th percentiles over the seeds planned. The disturbance is the
scenario's default (the paper's matched torque disturbance) unless ``--disturbance`` names
another; the runs that did not reach the goal are summed up by how much of the time their
wheel torques were saturated (the train's load and the disturbance against the motors' limit).
With ``--generated dead_end`` each seed runs in a world of its own that no one drew
(``tests/generated_worlds.py``: a dead-end corridor the train starts in, facing its end, and a
bay at a random pose in the yard), where plans back out first and may need several cusps.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import tempfile
from collections import Counter
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import tomli_w

from tt_mujoco.sim import Scenario, simulate
from tt_mujoco.world.plan import PlanError, train_length

#: How far (rms) the leading point may be off each leg's path: the runs whose worst leg is
#: further off are counted.
LEG_RMS_BOUND = 0.02


#: The generators of worlds no one drew (tests/generated_worlds.py) that ``--generated`` takes:
#: each seed's run is in a world of its own, drawn from ``(trailers, seed)``.
GENERATED = ("dead_end",)


def _generated_world(name: str, trailers: int, seed: int, folder: str) -> str:
    """The world file of run ``seed``: drawn by ``tests/generated_worlds.py``'s ``name``."""
    tests = str(Path(__file__).resolve().parents[1] / "tests")
    if tests not in sys.path:  # once per worker, not once per run
        sys.path.insert(0, tests)
    import generated_worlds

    p = Scenario(trailers=trailers).plant_params()
    rng = np.random.default_rng([trailers, seed])
    table = getattr(generated_worlds, name)(rng, train_length(p))
    path = Path(folder) / f"{name}-{trailers}-{seed}.toml"
    path.write_text(tomli_w.dumps({"name": f"{name} {trailers} {seed}", **table}))
    return str(path)


def one(args) -> dict:
    world, trailers, seed, plant, snr, reverse, disturbance, generated = args
    with tempfile.TemporaryDirectory() as folder:
        if generated is not None:
            world = _generated_world(generated, trailers, seed, folder)
        return _one(world, trailers, seed, plant, snr, reverse, disturbance)


def _one(world, trailers, seed, plant, snr, reverse, disturbance) -> dict:
    scenario = Scenario(
        world=world,
        traj="plan",
        reverse=reverse,
        trailers=trailers,
        seed=seed,
        plant=plant,
        noise_snr_db=snr,
        **({} if disturbance is None else {"disturbance": disturbance}),
    )
    try:
        result = simulate(scenario)
    except PlanError:
        return {"outcome": "no plan"}
    metrics = result.metrics
    report = metrics["world"]
    reached = result.status == "ok" and report["goal"]["reached"]
    legs = report["plan"]["legs"]
    return {
        "outcome": "reached" if reached else (result.status if result.status != "ok" else "missed"),
        "cusps": report["plan"]["cusps"],
        "planning_time_s": report["plan"]["planning_time_s"],
        "position_error_m": report["goal"]["position_error_m"],
        "heading_error_deg": report["goal"]["heading_error_deg"],
        # the worst leg's: each leg's leading point against its own path
        "leading_rms_m": max(
            (v for leg in legs if (v := leg.get("leading_cross_track_rms")) is not None),
            default=math.nan,
        ),
        "clearance_m": report["min_clearance_m"],
        "time_s": metrics["sim_time_s"],
        "saturation": metrics.get("torque_saturation_fraction", math.nan),
        "clipped": metrics.get("disturbance_clipped_fraction", 0.0),
    }


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--world", default="loading_bay")
    parser.add_argument("--trailers", type=int, nargs="+", default=[1, 2, 3])
    parser.add_argument("--seeds", type=int, default=200)
    parser.add_argument("--plant", default="mujoco")
    parser.add_argument("--noise-snr-db", type=float, default=20.0)
    parser.add_argument("--direction", choices=("reverse", "forward"), default="reverse")
    parser.add_argument("--workers", type=int, default=min(2, os.cpu_count() or 1))
    parser.add_argument("--disturbance", default=None, help="default: the scenario's")
    parser.add_argument(
        "--generated",
        choices=GENERATED,
        default=None,
        help="each seed in a world of its own, drawn by tests/generated_worlds.py (--world unused)",
    )
    args = parser.parse_args(argv)
    reverse = args.direction == "reverse"
    disturbance = args.disturbance or Scenario().disturbance
    world = args.world if args.generated is None else f"{args.generated} (generated, one per seed)"
    print(
        f"world {world}, {args.direction}, {args.plant} plant, "
        f"{args.noise_snr_db:g} dB noise, disturbance {disturbance}, seeds 0..{args.seeds - 1}, "
        f"{args.workers} workers"
    )
    with ProcessPoolExecutor(args.workers) as pool:
        for n in args.trailers:
            jobs = [
                (
                    args.world,
                    n,
                    seed,
                    args.plant,
                    args.noise_snr_db,
                    reverse,
                    args.disturbance,
                    args.generated,
                )
                for seed in range(args.seeds)
            ]
            rows = list(pool.map(one, jobs, chunksize=4))
            outcomes = Counter(r["outcome"] for r in rows)
            planned = [r for r in rows if r["outcome"] != "no plan"]
            reached = [r for r in rows if r["outcome"] == "reached"]
            times = np.array([r["planning_time_s"] for r in planned])
            rms = np.array([r["leading_rms_m"] for r in reached])
            errors = np.array([r["position_error_m"] for r in reached])
            print(
                f"N = {n}: reached {len(reached)} of {len(rows)} "
                f"({100 * len(reached) / len(rows):.1f} %); "
                + ", ".join(f"{k} {v}" for k, v in sorted(outcomes.items()) if k != "reached")
            )
            cusped = sum(1 for r in planned if r["cusps"])
            print(
                f"  with a cusp: {cusped} of {len(planned)} planned, "
                f"{sum(1 for r in reached if r['cusps'])} of them reached"
            )
            several = [r for r in planned if r["cusps"] > 1]
            if several:
                most = max(r["cusps"] for r in several)
                print(
                    f"  with more than one cusp: {len(several)} planned (at most {most}), "
                    f"{sum(1 for r in reached if r['cusps'] > 1)} of them reached"
                )
            if len(times):
                print(
                    f"  planning time: median {np.median(times):.3f} s, 95th percentile "
                    f"{np.percentile(times, 95):.3f} s, max {times.max():.3f} s"
                )
            missed = [r["saturation"] for r in rows if r["outcome"] not in ("reached", "no plan")]
            if missed:
                print(
                    f"  not reached: torques saturated a median {100 * np.median(missed):.1f} % "
                    f"of the time (max {100 * np.max(missed):.1f} %)"
                )
            outside = [r for r in rows if r["outcome"] == "missed"]  # ended, off the goal
            if outside:
                off = np.array([r["position_error_m"] for r in outside])
                turned = np.abs([r["heading_error_deg"] for r in outside])
                print(
                    f"  missed: final position error median {1000 * np.median(off):.2f} mm, max "
                    f"{1000 * off.max():.2f} mm; heading error median {np.median(turned):.2f} "
                    f"deg, max {turned.max():.2f} deg"
                )
            if len(reached):
                print(
                    f"  reached: final position error median {1000 * np.median(errors):.2f} mm, "
                    f"max {1000 * errors.max():.2f} mm; leading point off the plan, rms per run: "
                    f"median {1000 * np.median(rms):.1f} mm, max {1000 * rms.max():.1f} mm, "
                    f"over {1000 * LEG_RMS_BOUND:.0f} mm in {int(np.sum(rms > LEG_RMS_BOUND))} runs"
                )
                over = [r["clipped"] for r in reached if r["leading_rms_m"] > LEG_RMS_BOUND]
                if over:
                    print(
                        f"  over {1000 * LEG_RMS_BOUND:.0f} mm: the disturbance at the motors' "
                        f"limit (no torque left on that wheel) a median {100 * np.median(over):.1f}"
                        f" % of the time (max {100 * np.max(over):.1f} %)"
                    )
                driven = np.array([r["time_s"] for r in reached])
                print(
                    f"  time to the goal (simulated): median {np.median(driven):.1f} s, "
                    f"max {driven.max():.1f} s"
                )
    return 0


if __name__ == "__main__":
    sys.exit(main())

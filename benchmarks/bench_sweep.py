"""Sweep throughput: runs/s on 1 and 2 workers, the 1000-episode wall time, per-episode overhead.

Run: ``python benchmarks/bench_sweep.py`` (about 8 minutes on 2 cores; ``--episodes 0`` skips the
1000-episode sweep, ``--dask`` adds a Dask LocalCluster line). Episodes are 10 s S-curves on the
MuJoCo plant with 20 dB measurement noise (so every episode differs), ISMC-STA, no video, no
plots.

It prints:

1. Where one episode's time goes, in this process (median of ``--profile`` episodes of the sweep
   itself): setup (target, MuJoCo model, controller), the control loop (compiled, see
   :mod:`tt_mujoco.sim.loop.compiled`) and the metrics, beside the episode's physics floor: MuJoCo's
   C rollout (``mujoco.rollout``, one thread) of its own ``mj_step`` inputs (recorded with the
   Python loop, which gives the same numbers; the rollout's final state is checked against the
   run's). The same replays are then
   run on ``--workers`` forked processes at once, each replaying all of them: the floor of an
   episode when that many run side by side on the same cores, as the sweep's do.
2. Scaling: the same ``--scaling-runs`` episodes through :func:`tt_mujoco.sweep.run_sweep` on 1
   and 2 local worker processes: runs/s, and the executor's own overhead per run (wall time x
   workers minus the episodes' own time, over the runs: pool start, transfer, journal, table).
3. The ``--episodes`` sweep on ``--workers`` workers (``--trailers 3``: of a three-trailer
   train): wall time, runs/s, failures, and its ratio to the physics floor, the mean replay
   time of the profiled episodes times the episodes over the workers, taken both ways: with
   each replay alone, and with the replays on the workers at once (issue "one step"'s goals:
   <= 1.1 for one trailer, <= 1.25 for a train). The replays are timed before the sweep and
   again after it, and the floor is the mean of the two: a shared machine's speed drifts over
   the minutes a sweep takes. A figure the drift moves less is printed beside it: the sweep's
   wall time against the sum of its own episodes' control loops over the workers (timed in the
   same minutes), times the loop's ratio to its rollout timed in pairs in part 1.

Numbers depend on what else runs on the machine; the load average is printed with them.
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import os
import statistics
import tempfile
import time

os.environ.setdefault("TT_MUJOCO_COMPILE_NOW", "1")  # compile here, not in the background
from pathlib import Path

import mujoco
import numpy as np
from bench_closed_loop import closed_loop, python_loop, replay

from tt_mujoco import sweep
from tt_mujoco.analysis import metrics
from tt_mujoco.sim import Scenario, simulate
from tt_mujoco.sweep import runs as sweep_runs

ITEMS = ["traj=s_curve", "duration=10", "noise_snr_db=20"]


def episode_breakdown(spec, n: int) -> dict:
    """Median time per part of the sweep's first ``n`` episodes, in this process (seconds), and
    their physics floor: the C rollout of each episode's own ``mj_step`` inputs."""
    simulate(Scenario(duration=2.5))  # imports, caches and the compiled loop out of the way
    parts = {"episode": [], "setup": [], "loop": [], "metrics": [], "replay": []}
    recorded = []
    for run in sweep_runs.expand(spec)[:n]:
        scenario = sweep_runs.build_scenario(run["options"])
        t = time.perf_counter()
        result = simulate(scenario)
        episode = time.perf_counter() - t
        t = time.perf_counter()
        metrics.compute_metrics(result.timeseries, result.reference_polyline, 15.0)
        metrics_s = time.perf_counter() - t
        with python_loop():  # record the inputs (the compiled loop gives the same numbers)
            _, _, inputs, initial, final, plant, _ = closed_loop(scenario, record=True)
        replay_s, replay_final = replay(plant, inputs, initial)
        assert np.array_equal(replay_final, final)
        recorded.append((plant, inputs, initial, final))
        parts["episode"].append(episode)
        parts["loop"].append(result.wall_time_s)
        parts["metrics"].append(metrics_s)
        parts["setup"].append(episode - result.wall_time_s - metrics_s)
        parts["replay"].append(replay_s)
    out = {k: statistics.median(v) for k, v in parts.items()}
    out["replay_mean"] = statistics.mean(parts["replay"])
    out["steps"] = int(result.metrics["steps"])
    return out, recorded


def mean_replay(recorded) -> float:
    """Every recorded episode replayed, checked against its final state: the mean replay (s)."""
    spent = []
    for plant, inputs, initial, final in recorded:
        replay_s, replay_final = replay(plant, inputs, initial)
        assert np.array_equal(replay_final, final)
        spent.append(replay_s)
    return statistics.mean(spent)


def _replay_all(recorded, results) -> None:
    """One worker of :func:`replay_on_workers`: :func:`mean_replay` of every recorded episode."""
    results.put(mean_replay(recorded))


def replay_on_workers(recorded, workers: int) -> float:
    """The physics floor of an episode on ``workers`` processes at once: each forked process
    replays every recorded episode while the others do the same, as the sweep's workers run
    side by side on the same cores and memory; the mean replay time (s)."""
    context = multiprocessing.get_context("fork")
    results = context.Queue()
    procs = [context.Process(target=_replay_all, args=(recorded, results)) for _ in range(workers)]
    for proc in procs:
        proc.start()
    means = [results.get() for _ in procs]
    for proc in procs:
        proc.join()
        if proc.exitcode:
            raise RuntimeError(f"a replay worker failed (exit code {proc.exitcode})")
    return statistics.mean(means)


def sweep_rate(n_runs: int, workers: int, scheduler: str | None = None) -> dict:
    spec = sweep.parse_spec(ITEMS, repeats=n_runs, seed=0)
    with tempfile.TemporaryDirectory() as tmp:
        t = time.perf_counter()
        out = Path(tmp) / "s"
        result = sweep.run_sweep(spec, out, workers=workers, scheduler=scheduler, figures=False)
        wall = time.perf_counter() - t
    run_wall = [r["run_wall_s"] for r in result.rows]
    loop = [r["wall_time_s"] for r in result.rows if isinstance(r.get("wall_time_s"), float)]
    return {
        "runs": n_runs,
        "workers": workers,
        "scheduler": scheduler or "processes",
        "wall_s": wall,
        "runs_per_s": n_runs / wall,
        "failed": result.summary["failed"],
        "episode_median_s": statistics.median(run_wall),
        "loop_median_s": statistics.median(loop) if loop else float("nan"),
        "loop_sum_s": sum(loop),
        "executor_overhead_per_run_s": (wall * workers - sum(run_wall)) / n_runs,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument(
        "--profile", type=int, default=20, help="episodes for the breakdown and the floor"
    )
    ap.add_argument("--scaling-runs", type=int, default=24, help="episodes per scaling point")
    ap.add_argument("--episodes", type=int, default=1000, help="the big sweep (0: skip)")
    ap.add_argument("--workers", type=int, default=2, help="workers of the big sweep")
    ap.add_argument("--dask", action="store_true", help="also time a Dask LocalCluster")
    ap.add_argument("--json", type=Path, default=None, help="write the numbers here too")
    ap.add_argument(
        "--control-dt", type=float, default=0.001, help="control period of every episode (s)"
    )
    ap.add_argument("--trailers", type=int, default=1, help="trailers of every episode's train")
    args = ap.parse_args()
    if args.control_dt != 0.001:
        ITEMS.append(f"control_dt={args.control_dt}")
    if args.trailers != 1:
        ITEMS.append(f"trailers={args.trailers}")

    print(f"mujoco {mujoco.__version__}, {os.cpu_count()} CPUs, load {os.getloadavg()[0]:.2f}")
    trailers = f"{args.trailers} trailer" + ("s" if args.trailers > 1 else "")
    print(f"control period {1e3 * args.control_dt:g} ms, physics step 1 ms, {trailers}")
    spec = sweep.parse_spec(ITEMS, repeats=max(args.episodes, args.profile), seed=0)
    b, recorded = episode_breakdown(spec, args.profile)
    b["replay_on_workers"] = replay_on_workers(recorded, args.workers)
    ms = {k: 1e3 * v for k, v in b.items() if k != "steps"}
    print(
        f"one 10 s episode ({b['steps']} control steps), median of {args.profile}, in-process:\n"
        f"  total {ms['episode']:.0f} ms = setup {ms['setup']:.0f} + control loop "
        f"{ms['loop']:.0f} + metrics {ms['metrics']:.0f}\n"
        f"  the C rollout of its own mj_step inputs (the physics floor): {ms['replay']:.0f} ms; "
        f"control loop / floor {b['loop'] / b['replay']:.2f}, episode / floor "
        f"{b['episode'] / b['replay']:.2f}\n"
        f"  the same replays on {args.workers} workers at once: "
        f"{1e3 * b['replay_on_workers']:.0f} ms an episode "
        f"({b['replay_on_workers'] / b['replay_mean']:.3f} of the replay alone)"
    )
    results = {"breakdown_s": b, "scaling": [], "load_start": os.getloadavg()[0]}
    points = [(1, None), (2, None)] + ([(2, "local")] if args.dask else [])
    for workers, scheduler in points:
        r = sweep_rate(args.scaling_runs, workers, scheduler)
        results["scaling"].append(r)
        print(
            f"{r['scheduler']:>9} x {workers}: {r['runs']} episodes in {r['wall_s']:.1f} s = "
            f"{r['runs_per_s']:.2f} runs/s (episode median {r['episode_median_s']:.3f} s, "
            f"executor overhead {1e3 * r['executor_overhead_per_run_s']:.0f} ms/run)"
        )
    base = results["scaling"][0]["runs_per_s"]
    print(f"speed-up on 2 workers: {results['scaling'][1]['runs_per_s'] / base:.2f}x")
    if args.episodes:
        r = sweep_rate(args.episodes, args.workers)
        results["big"] = r
        # The floor again after the sweep: a shared machine's speed drifts over minutes, so the
        # sweep is held against the mean of the floor taken before it and after it.
        after = mean_replay(recorded)
        after_on_workers = replay_on_workers(recorded, args.workers)
        print(
            f"the replays again after the sweep: {1e3 * after:.0f} ms alone (before: "
            f"{1e3 * b['replay_mean']:.0f}), {1e3 * after_on_workers:.0f} ms on "
            f"{args.workers} workers at once (before: {1e3 * b['replay_on_workers']:.0f})"
        )
        floor = 0.5 * (b["replay_mean"] + after) * args.episodes / args.workers
        floor_on_workers = (
            0.5 * (b["replay_on_workers"] + after_on_workers) * args.episodes / args.workers
        )
        goal = 1.1 if args.trailers == 1 else 1.25
        r["floor_s"], r["ratio_to_floor"] = floor, r["wall_s"] / floor
        r["floor_on_workers_s"] = floor_on_workers
        r["ratio_to_floor_on_workers"] = r["wall_s"] / floor_on_workers
        print(
            f"{args.episodes} episodes on {args.workers} workers: {r['wall_s']:.1f} s "
            f"({r['wall_s'] / 60:.2f} min), {r['runs_per_s']:.2f} runs/s, {r['failed']} failed, "
            f"episode median {r['episode_median_s']:.3f} s (loop {r['loop_median_s']:.3f} s)\n"
            f"physics floor (mean replay of {args.profile} episodes alone, before and after, x "
            f"{args.episodes} / {args.workers} workers): {floor:.1f} s; ratio to the floor "
            f"{r['ratio_to_floor']:.3f} (goal <= {goal:g})\n"
            f"physics floor on {args.workers} workers (the same replays run on {args.workers} "
            f"workers at once): {floor_on_workers:.1f} s; ratio to it "
            f"{r['ratio_to_floor_on_workers']:.3f}"
        )
        # Timed in the same minutes, the sweep against its own episodes' loops drifts with
        # them; the loop against its rollout is timed in pairs, one episode after the other.
        r["ratio_to_own_loops"] = r["wall_s"] / (r["loop_sum_s"] / args.workers)
        r["ratio_paired"] = r["ratio_to_own_loops"] * b["loop"] / b["replay"]
        print(
            f"the sweep against its own episodes' control loops (the same minutes): "
            f"{r['ratio_to_own_loops']:.3f}; times the loop against its rollout in this "
            f"process ({b['loop'] / b['replay']:.3f}): {r['ratio_paired']:.3f} of the floor"
        )
    results["load_end"] = os.getloadavg()[0]
    print(f"load average now {results['load_end']:.2f}")
    if args.json:
        args.json.write_text(json.dumps(results, indent=2, default=float) + "\n")


if __name__ == "__main__":
    main()

"""Sweep throughput: runs/s on 1 and 2 workers, the 1000-episode wall time, per-episode overhead.

Run: ``python benchmarks/bench_sweep.py`` (about 8 minutes on 2 cores; ``--episodes 0`` skips the
1000-episode sweep, ``--dask`` adds a Dask LocalCluster line). Episodes are 10 s S-curves on the
MuJoCo plant with 20 dB measurement noise (so every episode differs), ISMC-STA, no video, no
plots.

It prints:

1. Where one episode's time goes, in this process (median of ``--profile`` episodes): setup
   (target, MuJoCo model compile, controller), the control loop split into MuJoCo's ``mj_step``
   (timed by wrapping it) and everything else per step (measurement, controller, target,
   logging), and the metrics. "Overhead outside the physics step" is the episode minus
   ``mj_step``.
2. Scaling: the same ``--scaling-runs`` episodes through :func:`tt_mujoco.sweep.run_sweep` on 1
   and 2 local worker processes: runs/s, and the executor's own overhead per run (wall time x
   workers minus the episodes' own time, over the runs: pool start, transfer, journal, table).
3. The ``--episodes`` sweep on ``--workers`` workers: wall time, runs/s, failures.

Numbers depend on what else runs on the machine; the load average is printed with them.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import tempfile
import time
from pathlib import Path

import mujoco

from tt_mujoco import sweep
from tt_mujoco.analysis import metrics
from tt_mujoco.sim import Scenario, simulate

ITEMS = ["traj=s_curve", "duration=10", "noise_snr_db=20"]


def episode_breakdown(n: int, control_dt: float = 0.001) -> dict:
    """Median time per part of one episode, in this process (seconds)."""
    real_step = mujoco.mj_step
    spent = [0.0]

    def timed_step(*args, **kwargs):
        t = time.perf_counter()
        real_step(*args, **kwargs)
        spent[0] += time.perf_counter() - t

    simulate(Scenario(duration=1.0))  # imports and caches out of the measurement
    parts = {"episode": [], "setup": [], "loop": [], "physics": [], "metrics": []}
    mujoco.mj_step = timed_step  # sim looks mj_step up on the module at each call
    try:
        for seed in range(n):
            spent[0] = 0.0
            t = time.perf_counter()
            result = simulate(
                Scenario(
                    traj="s_curve", duration=10.0, noise_snr_db=20, seed=seed, control_dt=control_dt
                )
            )
            episode = time.perf_counter() - t
            t = time.perf_counter()
            metrics.compute_metrics(result.timeseries, result.reference_polyline, 15.0)
            metrics_s = time.perf_counter() - t
            parts["episode"].append(episode)
            parts["loop"].append(result.wall_time_s)
            parts["physics"].append(spent[0])
            parts["metrics"].append(metrics_s)
            parts["setup"].append(episode - result.wall_time_s - metrics_s)
    finally:
        mujoco.mj_step = real_step
    out = {k: statistics.median(v) for k, v in parts.items()}
    out["loop_other"] = out["loop"] - out["physics"]
    out["outside_physics"] = out["episode"] - out["physics"]
    out["steps"] = int(result.metrics["steps"])
    return out


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
        "executor_overhead_per_run_s": (wall * workers - sum(run_wall)) / n_runs,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--profile", type=int, default=5, help="episodes for the breakdown")
    ap.add_argument("--scaling-runs", type=int, default=24, help="episodes per scaling point")
    ap.add_argument("--episodes", type=int, default=1000, help="the big sweep (0: skip)")
    ap.add_argument("--workers", type=int, default=2, help="workers of the big sweep")
    ap.add_argument("--dask", action="store_true", help="also time a Dask LocalCluster")
    ap.add_argument("--json", type=Path, default=None, help="write the numbers here too")
    ap.add_argument(
        "--control-dt", type=float, default=0.001, help="control period of every episode (s)"
    )
    args = ap.parse_args()
    if args.control_dt != 0.001:
        ITEMS.append(f"control_dt={args.control_dt}")

    print(f"mujoco {mujoco.__version__}, {os.cpu_count()} CPUs, load {os.getloadavg()[0]:.2f}")
    print(f"control period {1e3 * args.control_dt:g} ms, physics step 1 ms")
    b = episode_breakdown(args.profile, args.control_dt)
    ms = {k: 1e3 * v for k, v in b.items() if k != "steps"}
    print(
        f"one 10 s episode ({b['steps']} control steps), median of {args.profile}, in-process:\n"
        f"  total {ms['episode']:.0f} ms = setup {ms['setup']:.0f} + control loop "
        f"{ms['loop']:.0f} + metrics {ms['metrics']:.0f}\n"
        f"  control loop = mj_step {ms['physics']:.0f} + other per-step Python "
        f"{ms['loop_other']:.0f} ({1e3 * ms['loop_other'] / b['steps']:.1f} us/step)\n"
        f"  overhead outside the physics step: {ms['outside_physics']:.0f} ms per episode "
        f"({100 * b['outside_physics'] / b['episode']:.0f} % of the episode)"
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
        print(
            f"{args.episodes} episodes on {args.workers} workers: {r['wall_s']:.1f} s "
            f"({r['wall_s'] / 60:.2f} min), {r['runs_per_s']:.2f} runs/s, {r['failed']} failed, "
            f"episode median {r['episode_median_s']:.3f} s (loop {r['loop_median_s']:.3f} s)"
        )
    results["load_end"] = os.getloadavg()[0]
    print(f"load average now {results['load_end']:.2f}")
    if args.json:
        args.json.write_text(json.dumps(results, indent=2, default=float) + "\n")


if __name__ == "__main__":
    main()

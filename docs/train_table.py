"""The train table of docs/trains.md: steady-arc off-tracking of a 3-trailer train, same-path gains
against plain trailers, in MuJoCo under ISMC-STA.

    python docs/train_table.py [--trailers 3] [--plant mujoco]

For each path (the circle with R = 1.5 m driven 30 s, and the S-curve's two R = 1.5 m arcs) and
each steering (every trailer's own same-path gain; plain trailers, eta = 0), one closed-loop run
without disturbance (a steady turn is a kinematic property; the paper's disturbance needs most of
the torque of a 3-trailer train). A sample is on a *steady arc* when the tractor has driven at
least ``SETTLE_M`` metres along the current arc and is still on it; the table gives each trailer's
mean |off-tracking| (its axle to the path the tractor's axle drove) over those samples, and the
steady value the reduced kinematics predict (``steering.steady_train``).
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from tt_mujoco.analysis.offtrack import trailer_offtrack
from tt_mujoco.sim import Scenario, simulate
from tt_mujoco.vehicle.steering import steady_train

#: Distance (m) along an arc before its samples count as steady: three train lengths of the
#: paper's units (the same-path transient decays over about one drawbar length per trailer).
SETTLE_M = 3.0

PATHS = {
    "circle": {"traj": "circle", "duration": 30.0, "path_options": {"R": 1.5}},
    "s_curve": {"traj": "s_curve"},
}
STEERINGS = {"same_path": "same_path", "plain": 0.0}


def steady_offtracking(ts, n: int) -> tuple[list[float], int]:
    """Mean |off-tracking| (m) of trailers 1..n over the steady-arc samples, and their count."""
    kappa, s = ts["kappa_d"], ts["s"]
    starts = np.concatenate([[0], np.flatnonzero(np.diff(kappa) != 0) + 1])
    arc_start = s[starts[np.searchsorted(starts, np.arange(len(s)), side="right") - 1]]
    steady = (s - arc_start >= SETTLE_M) & (kappa != 0)
    leader = np.column_stack([ts["x"], ts["y"]])
    out = []
    for k in range(1, n + 1):
        sfx = "" if k == 1 else f"_{k}"
        follower = np.column_stack([ts[f"x0{sfx}"], ts[f"y0{sfx}"]])
        off = np.abs(trailer_offtrack(leader, follower))[steady]
        out.append(float(np.nanmean(off)))
    return out, int(steady.sum())


def table(trailers: int = 3, plant: str = "mujoco") -> str:
    lines = [
        "| path | trailer k | same-path eta_k | off-tracking, same-path (mm) | plain (mm) | "
        "plain / same-path | reduced kinematics: same-path / plain (mm) |",
        "|---|---|---|---|---|---|---|",
    ]
    for name, options in PATHS.items():
        results = {}
        for label, eta in STEERINGS.items():
            scenario = Scenario(
                controller="ismc_sta",
                plant=plant,
                eta=eta,
                trailers=trailers,
                disturbance="none",
                **options,
            )
            run = simulate(scenario)
            if run.status != "ok":
                raise RuntimeError(f"{name} {label}: {run.status} {run.message}")
            results[label] = (run, *steady_offtracking(run.timeseries, trailers))
        run, same, count = results["same_path"]
        _, plain, _ = results["plain"]
        params = run.scenario.nominal_params()
        R = options.get("path_options", {}).get("R", 1.5)
        analytic_same = np.abs(steady_train(1 / R, params)[1])
        plain_params = results["plain"][0].scenario.nominal_params()
        analytic_plain = np.abs(steady_train(1 / R, plain_params)[1])
        for k in range(trailers):
            lines.append(
                f"| {name} (R = {R:g} m, {count} steady samples) | {k + 1} | "
                f"{params.etas[k]:.4f} | {1e3 * same[k]:.3f} | {1e3 * plain[k]:.2f} | "
                f"{plain[k] / same[k]:.0f}x | {1e3 * analytic_same[k]:.3f} / "
                f"{1e3 * analytic_plain[k]:.2f} |"
            )
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trailers", type=int, default=3)
    parser.add_argument("--plant", default="mujoco", choices=("mujoco", "reduced"))
    args = parser.parse_args(argv)
    print(table(args.trailers, args.plant))
    return 0


if __name__ == "__main__":
    sys.exit(main())

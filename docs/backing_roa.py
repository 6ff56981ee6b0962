"""Backing up: from which initial hitch angle the cascade still recovers (docs/model.md Section 14).

    python docs/backing_roa.py [--traj s_curve] [--plant mujoco] [--trailers 1] [--step 5]
        [--figure docs/backing_roa.png]

Each run reverses the path from its end with the default cascade (``--reverse``, ISMC-STA, no
disturbance), the train starting at rest with trailer 1's hitch at phi0 instead of where it puts
its axle on the path (the other trailers on the path). Prints, per phi0, how the run ended and
the leading axle's cross-track rms and max over its last half (m), and draws outcome against
phi0.
"""

from __future__ import annotations

import argparse

import numpy as np

from tt_mujoco.analysis.geometry import Polyline
from tt_mujoco.sim import Scenario, simulate


def outcome(traj: str, plant: str, trailers: int, phi0_deg: float) -> tuple[str, float, float]:
    """``(status, rms, max)`` of the leading axle's cross-track over the run's second half."""
    result = simulate(
        Scenario(
            traj=traj,
            plant=plant,
            trailers=trailers,
            reverse=True,
            disturbance="none",
            phi0_deg=phi0_deg,
        )
    )
    ts = result.timeseries
    n = len(ts["t"])
    if result.status != "ok":
        return result.status, float("nan"), float("nan")
    sfx = "" if trailers == 1 else f"_{trailers}"
    lead = np.column_stack([ts[f"x0{sfx}"], ts[f"y0{sfx}"]])[n // 2 :]
    path = Polyline(result.reference_polyline)
    cross = path.project(lead, extend_ends=True).signed_distance
    return result.status, float(np.sqrt(np.mean(cross**2))), float(np.max(np.abs(cross)))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--traj", default="s_curve")
    parser.add_argument("--plant", default="mujoco")
    parser.add_argument("--trailers", type=int, default=1)
    parser.add_argument("--step", type=float, default=5.0)
    parser.add_argument("--figure", default=None)
    args = parser.parse_args(argv)
    angles = np.arange(-85.0, 85.0 + 1e-9, args.step)
    rows = []
    print("| phi0 (deg) | run | lead cross-track rms, 2nd half (m) | max (m) |")
    print("|---|---|---|---|")
    for phi0 in angles:
        status, rms, worst = outcome(args.traj, args.plant, args.trailers, float(phi0))
        rows.append((phi0, status, worst))
        print(f"| {phi0:g} | {status} | {rms:.4f} | {worst:.4f} |", flush=True)
    if args.figure:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(7, 3))
        for phi0, status, worst in rows:
            ok = status == "ok"
            ax.bar(
                phi0,
                worst * 1e3 if ok else 1.0,
                width=0.8 * args.step,
                color="tab:green" if ok else "tab:red",
            )
        ax.set_xlabel("initial hitch angle phi0 (deg)")
        ax.set_ylabel("lead cross-track max, 2nd half (mm)")
        ax.set_title(
            f"backing up {args.traj}, {args.plant}, N = {args.trailers}: green recovers,"
            " red jackknifes"
        )
        fig.tight_layout()
        fig.savefig(args.figure, dpi=120)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

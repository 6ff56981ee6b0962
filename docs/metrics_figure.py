"""Draw docs/metrics.png: the geometry behind the tracking metrics (docs/metrics.md).

python docs/metrics_figure.py
"""

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from tt_mujoco.outputs import save_figure

OUT = Path(__file__).resolve().parent / "metrics.png"


def main() -> Path:
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 5.5), layout="constrained")
    # Left: cross-track and along-track of P against the reference point R(t).
    s = np.linspace(0.0, 3.0, 200)
    path = np.column_stack([s, 0.6 * np.sin(s / 1.2)])
    left.plot(*path.T, color="0.3", lw=2, label="reference path")
    end = np.array([3.0, 0.6 * np.sin(3.0 / 1.2)])
    end_tangent = np.array([1.0, 0.5 * np.cos(3.0 / 1.2)])
    end_tangent /= np.linalg.norm(end_tangent)
    ray = np.column_stack([end, end + 0.8 * end_tangent])
    left.plot(*ray, "--", color="0.5", lw=1, label="continued along its end tangent")
    r = np.array([0.9, 0.6 * np.sin(0.9 / 1.2)])
    tangent = np.array([1.0, 0.5 * np.cos(0.9 / 1.2)])
    tangent /= np.linalg.norm(tangent)
    normal = np.array([-tangent[1], tangent[0]])
    p = r + 0.45 * tangent + 0.25 * normal
    left.plot(*r, "o", color="tab:green", label="reference point R(t)")
    left.plot(*p, "o", color="tab:orange", label="tractor axle P")
    foot = r + 0.45 * tangent
    left.annotate("", p, r, arrowprops={"arrowstyle": "-", "color": "tab:orange", "lw": 0.8})
    left.plot(*np.column_stack([r, foot]), color="tab:blue", lw=2.5, label="along-track (lead)")
    left.plot(*np.column_stack([foot, p]), color="tab:red", lw=2.5, label="cross-track")
    left.set_title("P against the path and the reference point")
    left.set_aspect("equal")
    left.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.02), ncol=2)
    # Right: off-tracking of the trailer against the tractor's recent driven path.
    a = np.linspace(0.0, 2.2, 300)
    tractor = np.column_stack([np.sin(a), 1.0 - np.cos(a)]) * 1.5
    lag = 0.45
    trailer = np.column_stack([np.sin(a - lag), 1.0 - np.cos(a - lag)]) * 1.44
    right.plot(*tractor.T, color="tab:orange", lw=2, label="path the tractor drove")
    right.plot(*trailer[a > lag].T, color="tab:blue", lw=2, label="trailer axle P0")
    right.plot(
        *trailer[a <= lag].T, color="tab:blue", lw=2, ls=":", label="P0 before it passed P's start"
    )
    window = a > a[-1] - 3.0 * lag
    right.plot(*tractor[window].T, color="k", lw=5, alpha=0.15, label="recent path (3 x spacing)")
    i = 220
    q = trailer[i]
    d = np.hypot(*(tractor - q).T)
    j = int(np.argmin(np.where(window, d, np.inf)))
    right.plot(*np.column_stack([q, tractor[j]]), color="tab:red", lw=2.5, label="off-tracking")
    right.set_title("The trailer against the tractor's own track")
    right.set_aspect("equal")
    right.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.02), ncol=2)
    for ax in (left, right):
        ax.set_xticks([])
        ax.set_yticks([])
    return save_figure(fig, OUT, 110)


if __name__ == "__main__":
    print(main())

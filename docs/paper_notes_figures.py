"""The figures of docs/paper-notes.md, computed from the paper's formulas and the project's paths.

    python docs/paper_notes_figures.py

Each line is one figure as the notes quote it, with what it is. The cycloid's come from the
paper's Section 6.1 formulas (with the sign of the curvature restored), the S-curve's and the
circle's from the project's own targets (``make_target``), the articulation table from
``steering.steady_articulation``.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq

from tt_mujoco.reference.path_base import DEFAULT_MAX_CURVATURE
from tt_mujoco.reference.targets import make_target
from tt_mujoco.vehicle import steering
from tt_mujoco.vehicle.params import Params


def cycloid() -> list[str]:
    c = math.cos(math.pi / 8)
    length = 8 * c
    end = 1.5 * math.pi

    def kappa(s):
        return -1.0 / math.sqrt(16 - (4 * c - s) ** 2)

    def dynamic_distance(t):
        return length * (1 - (1 + t / 2) * math.exp(-t / 2))

    start = (math.pi / 4 - math.sin(math.pi / 4), 1 - math.cos(math.pi / 4))
    return [
        f"cycloid length l = 8 cos(pi/8)          {length:.4f} m",
        f"curvature at the ends                    {kappa(0.0):.3f} 1/m",
        f"curvature at the apex                    {kappa(length / 2):.2f} 1/m",
        f"start r(pi/4)                            ({start[0]:.4f}, {start[1]:.4f})",
        f"start heading 3pi/8                      {math.degrees(3 * math.pi / 8):.1f} deg",
        f"the paper's pose off the path            {math.hypot(*start):.3f} m",
        f"... and off its heading                  {math.degrees(math.pi / 8):.1f} deg",
        f"static v_ref(0) = 2 sin(pi/8)            {2 * math.sin(math.pi / 8):.3f} m/s",
        f"dynamic peak speed at t = 2 s            {2 * c * 2 * math.exp(-1):.3f} m/s",
        f"dynamic peak acceleration at t = 0       {2 * c:.2f} m/s^2",
        f"static v_ref(3pi/2)                      {2 * math.sin((end + math.pi / 4) / 2):.3f} m/s",
        f"dynamic v_ref(3pi/2)                     {2 * c * end * math.exp(-end / 2):.3f} m/s",
        f"static distance by 3pi/2                 {length:.3f} m",
        f"dynamic distance by 3pi/2                {dynamic_distance(end):.3f} m",
        f"... of the path                          {100 * dynamic_distance(end) / length:.1f} %",
        f"dynamic distance at t = 15 s             {100 * dynamic_distance(15.0) / length:.1f} %",
        f"the paper's static yaw rate (as printed) {0.5:.1f} rad/s",
    ]


def s_curve_and_circle() -> list[str]:
    s_curve = make_target("s_curve")
    path, profile = s_curve.path, s_curve.target.profile
    cruise = float(np.max(profile.speed(np.linspace(0.0, profile.duration, 2001))))
    t = np.linspace(0.0, 2.0, 20001)
    ramp_accel = float(np.max(np.gradient(profile.speed(t), t)))
    ramp_length = float(profile.distance(2.0))
    short = make_target("s_curve", duration=10.0).target.profile
    circle = make_target("circle")
    lap = 2 * math.pi * circle.path.curvature_and_rate(0.0)[0] ** -1
    circle_profile = circle.target.profile
    times = np.linspace(0.0, circle_profile.duration, 2001)
    circle_cruise = float(np.max(circle_profile.speed(times)))
    driven = float(circle_profile.distance(circle_profile.duration))
    return [
        f"S-curve arc radius                       {1 / path.curvature_and_rate(0.0)[0]:.1f} m",
        f"S-curve cruise                           {cruise:.1f} m/s",
        f"S-curve length 2 pi R                    {path.length:.2f} m",
        f"... at cruise alone                      {path.length / cruise:.1f} s",
        f"ramp's peak acceleration                 {ramp_accel:.1f} m/s^2",
        f"each ramp covers                         {ramp_length:.1f} m",
        f"default duration                         {profile.duration:.2f} s",
        f"distance by t = 10 s with duration=10    {float(short.distance(10.0)):.1f} m",
        f"the S-curve's inflection                 {path.length / 2:.2f} m",
        f"circle cruise                            {circle_cruise:.1f} m/s",
        f"circle driven in 10 s                    {driven:.1f} m = {driven / lap:.2f} laps",
    ]


def articulation() -> list[str]:
    lines = []
    for kappa in (0.653, 1.0, 2.0):
        cells = []
        for eta in ("same_path", 0.0, "paper"):
            phi = steering.steady_articulation(kappa, Params(eta=eta))
            cells.append(f"{math.degrees(phi):.1f} deg")
        lines.append(f"steady articulation at kappa = {kappa}: " + " / ".join(cells))
    p = Params()

    def perpendicular(kappa):
        return math.degrees(steering.steady_articulation(kappa, p)) - 90.0

    at = brentq(perpendicular, 2.0, 3.5)
    lines.append(f"rod O-P0 perpendicular to the tractor at {at:.3f} 1/m")
    limit = DEFAULT_MAX_CURVATURE
    lines.append(f"the CSV paths' curvature bound {limit:g} 1/m: turn radius {1 / limit:.1f} m")
    return lines


def main() -> None:
    print("Written by `python docs/paper_notes_figures.py`: the figures of docs/paper-notes.md.")
    for line in (*cycloid(), *s_curve_and_circle(), *articulation()):
        print(line)


if __name__ == "__main__":
    main()

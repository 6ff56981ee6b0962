"""How often a mass fitted to a noisy log lands within 2 % of the truth, and how often its 95 %
interval holds the truth, over noise seeds (tt_mujoco.identify_inertia).

The logs: the MuJoCo plant on examples/weave_surge.csv for 60 s at 1 kHz, the trailer's mass
8 kg (the project's is 6), then 20 dB of noise on v, omega and the hitch angle (each sensor's
noise a tenth of its rms); the torques are the commands as sent. Then the same with a payload
of 4 kg put on at t = 21.3 s, found by ``--payload 1``.

    python benchmarks/identify_coverage.py [--seeds 20]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from test_identify_inertia import _fit, _log, _noisy


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=20)
    seeds = range(parser.parse_args().seeds)

    ts, p = _log("mujoco")
    errors, halves = [], []
    for seed in seeds:
        fit = _fit(_noisy(ts, 20.0, seed), p.replace(Mr=6.0))
        errors.append(fit.estimates[0] / 8.0 - 1.0)
        halves.append(fit.half_widths[0] / 8.0)
    errors, halves = np.array(errors), np.array(halves)
    print(f"trailer mass, {len(errors)} seeds, 20 dB:")
    print(f"  within 2 %: {np.mean(np.abs(errors) < 0.02):.2f}")
    print(f"  interval holds the truth: {np.mean(np.abs(errors) <= halves):.2f}")
    print(f"  error: max {100 * np.max(np.abs(errors)):.2f} %, rms {100 * np.std(errors):.2f} %")
    print(f"  half width: median {100 * np.median(halves):.2f} %")

    ts, p = _log("mujoco", faults="payload:t=21.3")
    masses, times, covered, held = [], [], [], []
    for seed in seeds:
        load = _fit(_noisy(ts, 20.0, seed), p.replace(Mr=6.0), payload=1).payload
        masses.append(load.mass / 4.0 - 1.0)
        times.append(load.time - 21.3)
        covered.append(abs(load.mass - 4.0) <= load.mass_half_width)
        held.append(load.time_interval[0] <= 21.3 <= load.time_interval[1])
    masses, times = np.array(masses), np.array(times)
    print(f"payload of 4 kg at 21.3 s, {len(masses)} seeds, 20 dB:")
    print(f"  mass within 5 %: {np.mean(np.abs(masses) < 0.05):.2f}")
    print(f"  time within 0.5 s: {np.mean(np.abs(times) < 0.5):.2f}")
    print(f"  interval holds the mass: {np.mean(covered):.2f}")
    print(f"  interval holds the time: {np.mean(held):.2f}")
    print(f"  mass error: max {100 * np.max(np.abs(masses)):.2f} %")
    print(f"  time error: max {np.max(np.abs(times)):.2f} s")


if __name__ == "__main__":
    main()

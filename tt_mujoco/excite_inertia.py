"""Which run to log so that a fit of the masses and inertias tells them
(``python -m tt_mujoco.excite --fit Mr,...``; the fit is :mod:`tt_mujoco.identify_inertia`'s).

A mass shows in a log only where the wheels' torques change the train's speed, a yaw inertia
only where they change its turning: a run at a steady speed on a steady curve tells neither.
The candidates here are paths whose speed swings (``v`` around :data:`MEAN_SPEED` by a swing,
over a period along the path) on a straight line or a weave (:data:`SURGES`), written as CSV
paths with a speed column. Each is driven on the reduced plant (the built-in controller, no
disturbance, as a logging run would go) for the run's duration; its log, with the sensors'
noise at the given signal-to-noise ratio (seeded), is fitted as ``identify`` would fit it, and
the fit's own 95 % half widths are the candidate's prediction. The best candidate (the smallest
largest relative half width) is written with its path.
"""

from __future__ import annotations

import dataclasses
import math
import tempfile
from pathlib import Path

import numpy as np

__all__ = [
    "MEAN_SPEED",
    "SURGES",
    "InertiaCandidate",
    "path_csv",
    "rank_inertial",
    "run_toml",
    "surge_rows",
    "table",
]

#: The speed the candidates swing around (m/s).
MEAN_SPEED = 0.7
#: The candidates: ``(weave amplitude m, its wavelength m, speed swing m/s, the swing's period
#: along the path m)``; a straight line, a gentle weave and a tight one.
SURGES = tuple(
    (weave, wavelength, swing, period)
    for weave, wavelength in ((0.0, 1.0), (0.4, 6.0), (0.3, 3.0))
    for swing in (0.15, 0.3)
    for period in (1.0, 2.0)
)
#: The sensors whose noise the prediction adds (the torques are the commands as sent).
SENSORS = ("v", "omega", "phi", "phi_2", "phi_3", "phi_4")


def surge_rows(surge, length: float, step: float = 0.05):
    """The waypoints ``(x, y, v)`` (rows) of the candidate path ``surge`` (one of
    :data:`SURGES`), ``length`` m long: ``y`` a weave of its amplitude and wavelength, ``v``
    swinging by its swing around :data:`MEAN_SPEED` with its period along ``x``."""
    weave, wavelength, swing, period = surge
    x = np.arange(0.0, length + step / 2, step)
    y = weave * np.sin(2.0 * math.pi * x / wavelength)
    v = MEAN_SPEED + swing * np.sin(2.0 * math.pi * x / period)
    return np.column_stack([x, y, v])


@dataclasses.dataclass(frozen=True)
class InertiaCandidate:
    """A candidate run (its path, one of :data:`SURGES`) and what a fit of its log would know:
    the fit's names, estimates and 95 % half widths."""

    surge: tuple
    names: tuple
    values: np.ndarray
    half_widths: np.ndarray

    @property
    def worst(self) -> float:
        """The largest half width relative to its estimate."""
        return float(np.max(self.half_widths / np.abs(self.values)))

    def label(self) -> str:
        weave, wavelength, swing, period = self.surge
        shape = "straight" if weave == 0.0 else f"weave {weave:g} m every {wavelength:g} m"
        return f"{shape}, speed {MEAN_SPEED:g} +- {swing:g} m/s every {period:g} m"


def rank_inertial(scenario, fit=("Mr",), snr_db=20.0, duration=30.0, candidates=SURGES, seed=0):
    """Every candidate of ``candidates`` for ``scenario``'s vehicle, best first; those whose
    run does not finish, or whose log the fit refuses, are left out.

    Parameters
    ----------
    scenario : tt_mujoco.sim.Scenario
        The vehicle (its parameters, trailers and steering).
    fit : sequence of str
        Masses and inertias of :data:`tt_mujoco.identify_inertia.INERTIAL`.
    snr_db : float
        The sensors' signal-to-noise ratio (dB).
    duration : float
        The logging run's length (s).
    candidates : sequence of (float, float, float, float)
        As :data:`SURGES`.
    seed : int
        The noise's.

    Returns
    -------
    list of InertiaCandidate
    """
    from tt_mujoco.identify_inertia import fit_inertia
    from tt_mujoco.outputs import atomic_write
    from tt_mujoco.sim import simulate
    from tt_mujoco.vehicle_log import LogError

    out = []
    with tempfile.TemporaryDirectory() as folder:
        for i, surge in enumerate(candidates):
            path = Path(folder) / f"surge-{i}.csv"
            atomic_write(path, _csv(surge, duration))
            run = dataclasses.replace(
                scenario,
                traj=str(path),
                plant="reduced",
                disturbance="none",
                duration=duration,
                noise_snr_db=None,
            )
            result = simulate(run)
            if result.status != "ok":
                continue
            ts = _noisy(result.timeseries, snr_db, np.random.default_rng([seed, i]))
            names = ["phi", *(f"phi_{k}" for k in range(2, run.trailers + 1))]
            phis = np.column_stack([ts[n] for n in names])
            torques = (ts["T_r"], ts["T_l"])
            try:
                got = fit_inertia(
                    ts["t"], ts["v"], ts["omega"], phis, torques, run.plant_params(), fit
                )
            except LogError:
                continue
            out.append(InertiaCandidate(surge, got.names, got.estimates, got.half_widths))
    return sorted(out, key=lambda c: c.worst)


def _noisy(ts, snr_db: float, rng) -> dict:
    """The log with each of its sensors at ``snr_db`` (:func:`tt_mujoco.vehicle_log.noisy`)."""
    from tt_mujoco.vehicle_log import noisy

    out = dict(ts)
    for name in SENSORS:  # in this order: the draws of a seed
        if name in ts:
            out[name] = noisy(ts[name], snr_db, rng)
    return out


def _length(surge, duration: float) -> float:
    """A candidate path's length (m): more than its run drives in ``duration``."""
    return (MEAN_SPEED + surge[2]) * duration + 5.0


def path_csv(best: InertiaCandidate, duration: float) -> str:
    """The best candidate's path as the CSV a run takes (``--traj FILE``): the very file its
    prediction drove."""
    return _csv(best.surge, duration)


def _csv(surge, duration: float) -> str:
    from tt_mujoco.outputs import timeseries_csv

    rows = surge_rows(surge, _length(surge, duration))
    return timeseries_csv(dict(zip("xyv", rows.T, strict=True)), ["x", "y", "v"])


def run_toml(scenario, duration: float) -> str:
    """The logging run's scenario file, its path the CSV beside it (``excitation_path.csv``,
    relative to the file's folder)."""
    import tomli_w

    doc = {"traj": "excitation_path.csv", "disturbance": "none", "duration": duration}
    if scenario.trailers > 1:
        doc["trailers"] = scenario.trailers
    return tomli_w.dumps(doc)


def table(ranked) -> str:
    """The candidates as a Markdown table, best first."""
    names = ranked[0].names
    lines = [
        "| run | " + " | ".join(f"{n} +- (%)" for n in names) + " |",
        "|" + "---|" * (len(names) + 1),
    ]
    for c in ranked:
        pairs = zip(c.half_widths, c.values, strict=True)
        widths = " | ".join(f"{100 * w / abs(v):.3g}" for w, v in pairs)
        lines.append(f"| {c.label()} | {widths} |")
    return "\n".join(lines) + "\n"

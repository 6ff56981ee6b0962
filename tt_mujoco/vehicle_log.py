"""A log of a real vehicle read and checked (``python -m tt_mujoco.identify``, ``excite``).

A log is a CSV or Parquet file, or a run's folder (its time series), or an MCAP file of ROS 2
messages: :func:`read_log` gives its time, the tractor's speed and yaw rate and the hitch
angles, from the columns (or topics) the log has, and refuses what a fit cannot use (a missing
column, time not increasing, a gap, a value that is not a finite number) with a
:class:`LogError` naming the column and the row.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from tt_mujoco.vehicle.params import Params

__all__ = [
    "CORRELATED",
    "GAP",
    "NOISY_DB",
    "POSE",
    "TORQUES",
    "WHEEL_RATES",
    "LogError",
    "confounded",
    "estimates_report",
    "input_snr_db",
    "noise_std",
    "noisy",
    "read_log",
    "smoothed",
]

#: A step in ``t`` longer than this many times the median is a gap in the log.
GAP = 5.0
#: A log's columns of the tractor's wheels' rates (rad/s), right and left, where it has no
#: ``v`` and ``omega``.
WHEEL_RATES = ("wheel_rate_r", "wheel_rate_l")
#: A log's columns of the tractor axle's pose (m, m, rad), where it has neither.
POSE = ("x", "y", "theta")
#: A log's columns of the tractor's wheels' torques (N m), right and left, each row's held until
#: the next: what a fit of the masses and inertias needs.
TORQUES = ("T_r", "T_l")


#: Below this estimated signal-to-noise ratio (dB) a logged signal counts as noisy.
NOISY_DB = 40.0
#: Above this |correlation| two estimates are not told apart by the log.
CORRELATED = 0.95


class LogError(ValueError):
    """A log that cannot be used: the message names the column and the row."""


def read_log(
    path: Path,
    columns: dict[str, str] | None = None,
    trailers: int | None = None,
    topics: dict[str, str] | None = None,
    wheel: tuple[float, float] | None = None,
    torques: bool = False,
):
    """``(t, v, omega, phis)`` of a log (see the module), and ``(T_r, T_l)`` after them where
    ``torques`` (:data:`TORQUES`; an MCAP log's wheel joints' efforts). ``phis`` is ``(rows,
    N)``, N the number of ``phi`` columns found (or ``trailers``); ``topics`` names an MCAP
    log's odometry and joint-state topics (:data:`tt_mujoco.bag.LOG_TOPICS`). A log without
    ``v`` and ``omega`` gives them from its wheels' rates (:data:`WHEEL_RATES`, with ``wheel``
    the wheels' radius and track, m; default the project's vehicle's) or from the axle's pose
    (:data:`POSE`). Raises :class:`LogError`."""
    from tt_mujoco.outputs import read_timeseries

    file = _log_file(Path(path))
    if topics and file.suffix != ".mcap":
        raise LogError(f"--topics is for an MCAP log's topics; {file} is a table of columns")
    mapping = dict(columns or {})
    if file.suffix == ".mcap":  # ROS 2 messages: the joints are named, hitch_k for phi_k
        from tt_mujoco.bag import read_bag_log

        try:
            table = read_bag_log(file, topics)
        except ValueError as err:
            raise LogError(str(err)) from None
        except ImportError:
            raise LogError(
                f"{file} is MCAP: reading it needs the mcap extra (pip install 'tt-mujoco[mcap]')"
            ) from None
        mapping = {
            "phi": "hitch_1",
            **{f"phi_{k}": f"hitch_{k}" for k in range(2, 10)},
            "T_r": "wheel_right_effort",
            "T_l": "wheel_left_effort",
            **mapping,
        }
        if trailers is None:  # as many trailers as hitch joints with positions
            trailers = sum(1 for k in range(1, 10) if f"hitch_{k}" in table)
    else:
        try:
            table = read_timeseries(file)
        except (OSError, ValueError) as err:
            said = str(err)  # named once: the reader's messages may name the file already
            raise LogError(said if said.startswith(str(file)) else f"{file}: {said}") from None
    count = trailers or 1
    while trailers is None and (f"phi_{count + 1}" in table or f"phi_{count + 1}" in mapping):
        count += 1

    def has(*names) -> bool:
        return all(mapping.get(n, n) in table for n in names)

    # the tractor's speed and yaw rate, from what the log has: themselves, the wheels' rates,
    # or the pose of the tractor's axle
    speeds = ["v", "omega"]
    if not has(*speeds) and has(*WHEEL_RATES):
        speeds = list(WHEEL_RATES)
    elif not has(*speeds) and has(*POSE):
        speeds = list(POSE)
    names = ["t", *speeds, "phi", *(f"phi_{k}" for k in range(2, count + 1))]
    names += list(TORQUES) if torques else []
    data = {name: _log_column(file, table, mapping.get(name, name), name) for name in names}
    t = data["t"]
    _check_times(file, t)
    hitches = names[len(speeds) + 1 : len(names) - (len(TORQUES) if torques else 0)]
    for name in hitches:
        beyond = np.flatnonzero(np.abs(data[name]) > math.pi)
        if beyond.size:
            column = mapping.get(name, name)
            raise LogError(
                f"{file}: column {column!r} row {int(beyond[0]) + 2} is "
                f"{float(data[name][beyond[0]]):.6g} rad, beyond the +-pi of a hitch angle (a "
                "column in degrees has a name ending in _deg)"
            )
    phis = np.column_stack([data[n] for n in hitches])
    v, omega = _speeds(data, t, wheel, file)
    if torques:
        return t, v, omega, phis, tuple(data[name] for name in TORQUES)
    return t, v, omega, phis


def _log_column(file: Path, table, column: str, name: str) -> np.ndarray:
    """The log's ``column`` (for ``name``) as finite floats, in radians where it is in
    degrees; a :class:`LogError` naming the column and the row otherwise."""
    if column not in table:
        raise LogError(f"{file} has no column {column!r} (for {name}); it has {sorted(table)}")
    values = np.asarray(table[column], dtype=float)
    if column.endswith("_deg"):
        values = np.radians(values)
    bad = np.flatnonzero(~np.isfinite(values))
    if bad.size:
        raise LogError(
            f"{file}: column {column!r} row {int(bad[0]) + 2} is {float(values[bad[0]])!r}, not a "
            "finite number"
        )
    return values


def _check_times(file: Path, t: np.ndarray) -> None:
    """At least 10 rows, the time increasing, no gap of more than :data:`GAP` periods."""
    if t.size < 10:
        raise LogError(f"{file} has {t.size} rows: a fit needs at least 10")
    steps = np.diff(t)
    if np.any(steps <= 0):
        i = int(np.flatnonzero(steps <= 0)[0]) + 1
        raise LogError(
            f"{file}: column 't' does not increase at row {i + 2} ({float(t[i])!r} after "
            f"{float(t[i - 1])!r})"
        )
    median = float(np.median(steps))
    if np.any(steps > GAP * median):
        i = int(np.flatnonzero(steps > GAP * median)[0]) + 1
        raise LogError(
            f"{file}: a gap in column 't' at row {i + 2}: {steps[i - 1]:.6g} s after "
            f"{float(t[i - 1])!r}, more than {GAP:g} times the log's period ({median:.6g} s)"
        )


def _speeds(data: dict, t: np.ndarray, wheel: tuple[float, float] | None, file: Path):
    """``(v, omega)`` of the tractor's axle from what ``data`` (of ``file``) has: themselves;
    the wheels' rates (rad/s) with ``wheel = (radius, track)`` in m (docs/model.md Section 2;
    None: the project's vehicle's); or the axle's pose, by central differences (its heading
    unwrapped). A ``wheel`` given for a log that has no use for it is a LogError."""
    if wheel is not None and ("v" in data or WHEEL_RATES[0] not in data):
        raise LogError(  # a radius and a track read nowhere
            f"--wheel is for a log of the wheels' rates ({', '.join(WHEEL_RATES)}) without v "
            f"and omega; {file} has {'v and omega' if 'v' in data else 'no wheel rates'}"
        )
    if "v" in data:
        return data["v"], data["omega"]
    if WHEEL_RATES[0] in data:
        r, d = wheel if wheel is not None else _default_wheel()
        right, left = data[WHEEL_RATES[0]], data[WHEEL_RATES[1]]
        return r * (right + left) / 2.0, r * (right - left) / d
    x, y, theta = data["x"], data["y"], np.unwrap(data["theta"])
    vx, vy = np.gradient(x, t), np.gradient(y, t)
    return vx * np.cos(theta) + vy * np.sin(theta), np.gradient(theta, t)


def _default_wheel() -> tuple[float, float]:
    """The project's vehicle's wheel radius and track (m)."""
    default = Params()
    return default.r, default.d


def _log_file(path: Path) -> Path:
    """The file of the log ``path`` names (a run's folder: its time series), or a LogError:
    missing, a folder, a device, a name the file system refuses
    (:func:`tt_mujoco.registry.existing_file`)."""
    from tt_mujoco.outputs import run_timeseries_file
    from tt_mujoco.registry import existing_file

    try:
        try:
            given = run_timeseries_file(path) if path.is_dir() else path
        except OSError as err:  # a name the file system refuses (too long)
            raise ValueError(f"log {str(path)!r}: {err.strerror}") from None
        return existing_file(given, "log")
    except ValueError as err:
        raise LogError(f"{err}: give a CSV, Parquet or MCAP log, or a run's folder") from None


def noisy(x, snr_db: float, rng: np.random.Generator) -> np.ndarray:
    """``x`` as a sensor at ``snr_db`` logs it: white noise of a standard deviation of its rms
    times ``10^(-snr_db / 20)`` added (20 dB: a tenth), drawn from ``rng``."""
    x = np.asarray(x, dtype=float)
    return x + np.sqrt(np.mean(x**2)) * 10 ** (-snr_db / 20) * rng.standard_normal(x.shape)


def noise_std(x: np.ndarray) -> float:
    """A logged signal's noise (its standard deviation) from its second differences (a
    robust spread, so that the few jumps of a signal that steps do not count as noise); 0 for
    a clean log."""
    # second differences: a smooth signal's are its curvature times the step squared, small;
    # white noise's have six times its variance
    bends = np.diff(np.asarray(x, dtype=float), n=2)
    if bends.size < 3:
        return 0.0
    return 1.4826 * float(np.median(np.abs(bends - np.median(bends)))) / math.sqrt(6.0)


def input_snr_db(x: np.ndarray) -> float:
    """An estimate of a logged signal's signal-to-noise ratio (dB): its rms over its
    :func:`noise_std`; infinite for a clean log."""
    noise = noise_std(x)
    power = float(np.sqrt(np.mean(np.square(x))))
    return math.inf if noise == 0.0 or power == 0.0 else 20.0 * math.log10(power / noise)


def smoothed(x: np.ndarray, t: np.ndarray, seconds: float) -> np.ndarray:
    """``x`` averaged over a centred window of about ``seconds`` (an odd number of samples;
    the ends held)."""
    period = float(np.median(np.diff(t)))
    width = 2 * int(seconds / period / 2.0) + 1
    if width <= 1:
        return x
    padded = np.pad(np.asarray(x, dtype=float), width // 2, mode="edge")
    return np.convolve(padded, np.ones(width) / width, mode="valid")


def confounded(names, correlation) -> list[tuple[str, str, float]]:
    """The pairs of a fit's estimates its log does not tell apart: ``(a, b, correlation)``
    beyond :data:`CORRELATED`."""
    pairs = [(i, j) for i in range(len(names)) for j in range(i + 1, len(names))]
    return [
        (names[i], names[j], float(correlation[i, j]))
        for i, j in pairs
        if abs(correlation[i, j]) > CORRELATED
    ]


def estimates_report(names, estimates, half_widths, correlation) -> dict:
    """A fit's estimates with their 95 % intervals, their correlations and the pairs not told
    apart, as strict-JSON-ready numbers (``identify.json``)."""
    return {
        "estimates": {
            n: {"value": float(e), "ci95": [float(e - h), float(e + h)]}
            for n, e, h in zip(names, estimates, half_widths, strict=True)
        },
        "correlation": {
            a: {b: float(correlation[i, j]) for j, b in enumerate(names)}
            for i, a in enumerate(names)
        },
        "not_told_apart": [
            {"parameters": [a, b], "correlation": rho}
            for a, b, rho in confounded(names, correlation)
        ],
    }

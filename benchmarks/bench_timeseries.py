"""Size and write time of a 600 s run's time series, Parquet against CSV (no assertions).

    python benchmarks/bench_timeseries.py

The 600 s series is a real 60 s MuJoCo run on the circle with 20 dB noise (noise makes the
columns realistic to compress), repeated ten times with its time shifted: 600,001 rows of every
column of the time series. Write times are the median of 3, in this one process, so their ratio
is what to quote.
"""

import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from tt_mujoco.outputs import read_timeseries, write_timeseries
from tt_mujoco.sim import COLUMNS, Scenario, simulate
from tt_mujoco.sim.loop.timeseries import UNITS


def six_hundred_seconds() -> dict[str, np.ndarray]:
    ts = simulate(Scenario(traj="circle", duration=60.0, noise_snr_db=20.0)).timeseries
    n = len(ts["t"]) - 1  # drop the last sample of each copy: the next one starts there
    out = {}
    for name in COLUMNS:
        copies = [ts[name][:n] + (k * 60.0 if name == "t" else 0.0) for k in range(10)]
        out[name] = np.concatenate([*copies, [ts[name][-1] + (540.0 if name == "t" else 0.0)]])
    return out


def main() -> None:
    ts = six_hundred_seconds()
    rows = len(ts["t"])
    with tempfile.TemporaryDirectory() as folder:
        sizes, times = {}, {}
        for fmt in ("parquet", "csv"):
            path = Path(folder) / f"timeseries.{fmt}"
            runs = []
            for _ in range(3):
                path.unlink(missing_ok=True)
                start = time.perf_counter()
                write_timeseries(path, ts, COLUMNS, UNITS)
                runs.append(time.perf_counter() - start)
            times[fmt] = statistics.median(runs)
            sizes[fmt] = path.stat().st_size
            back = read_timeseries(path)
            assert all(np.array_equal(back[c], ts[c]) for c in COLUMNS)  # lossless
    print(f"600 s run: {rows} rows x {len(COLUMNS)} columns (float64)")
    for fmt in ("parquet", "csv"):
        print(f"  {fmt:8s} {sizes[fmt] / 1e6:8.1f} MB   write {times[fmt]:6.2f} s")
    print(
        f"  parquet / csv: size {sizes['parquet'] / sizes['csv']:.3f}, "
        f"write time {times['parquet'] / times['csv']:.3f}"
    )


if __name__ == "__main__":
    main()

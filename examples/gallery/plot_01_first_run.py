"""
# A first run from Python

One scenario through the Python API: the S-curve with the paper's ISMC-STA on the reduced
plant, its metrics, and the path the tractor and the trailer drove.
"""

import matplotlib.pyplot as plt

import tt_mujoco

run = tt_mujoco.simulate(tt_mujoco.Scenario(traj="s_curve", plant="reduced", duration=8.0))
print(run.status, f"cross-track rms {1e3 * run.metrics['cross_track_rms']:.1f} mm")

frame = run.to_pandas()
fig, ax = plt.subplots(figsize=(6, 4.5))
ax.plot(frame["x_ref"], frame["y_ref"], "k--", lw=1, label="reference")
ax.plot(frame["x"], frame["y"], label="tractor P")
ax.plot(frame["x0"], frame["y0"], label="trailer axle P0")
ax.set(xlabel="x (m)", ylabel="y (m)", aspect="equal", title="S-curve, ISMC-STA, reduced plant")
ax.legend()
plt.show()

"""
# Six controllers on the S-curve

The paper's ISMC-STA, PID and FBL and the baselines Stanley, LQR and NMPC on the S-curve
without disturbance (reduced plant): the tractor's cross-track error over time. The NMPC needs
the optional extra `mpc`.
"""

import matplotlib.pyplot as plt
import numpy as np

import tt_mujoco

fig, ax = plt.subplots(figsize=(7, 4))
for name in ("ismc_sta", "pid", "fbl", "stanley", "lqr", "nmpc"):
    scenario = tt_mujoco.Scenario(
        traj="s_curve", controller=name, plant="reduced", disturbance="none", duration=8.0
    )
    run = tt_mujoco.simulate(scenario)
    ts = run.timeseries
    # signed distance of P from the reference point, across the path's heading
    error = (ts["y"] - ts["y_ref"]) * np.cos(ts["theta_ref"]) - (ts["x"] - ts["x_ref"]) * np.sin(
        ts["theta_ref"]
    )
    ax.plot(ts["t"], 1e3 * error, label=name)
    print(f"{name:9s} cross-track rms {1e3 * run.metrics['cross_track_rms']:6.1f} mm")
ax.set(xlabel="t (s)", ylabel="lateral error (mm)", title="S-curve, no disturbance")
ax.legend(ncol=3)
plt.show()

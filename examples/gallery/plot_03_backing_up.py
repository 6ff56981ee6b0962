"""
# Backing a trailer along the S-curve

Reversing, the trailer leads and its hitch is unstable. The NMPC predicts it and keeps the
hitch angle within its bound; the paper's ISMC-STA backs up through the hitch cascade
(`controllers/backing.py`). Both on the reduced plant, without disturbance.
"""

import matplotlib.pyplot as plt
import numpy as np

import tt_mujoco

fig, (left, right) = plt.subplots(1, 2, figsize=(9, 4))
for name in ("ismc_sta", "nmpc"):
    scenario = tt_mujoco.Scenario(
        traj="s_curve", controller=name, plant="reduced", disturbance="none", reverse=True
    )
    run = tt_mujoco.simulate(scenario)
    ts = run.timeseries
    print(
        f"{name:9s} {run.status}: trailer axle cross-track rms "
        f"{1e3 * run.metrics['leading_cross_track_rms']:.1f} mm"
    )
    left.plot(ts["x0"], ts["y0"], label=f"{name}: trailer axle")
    right.plot(ts["t"], np.degrees(ts["phi"]), label=name)
left.plot(ts["x_ref"], ts["y_ref"], "k--", lw=1, label="reference (tractor)")
left.set(xlabel="x (m)", ylabel="y (m)", aspect="equal")
left.legend(fontsize=8)
right.set(xlabel="t (s)", ylabel="hitch angle phi (deg)")
right.legend()
plt.show()

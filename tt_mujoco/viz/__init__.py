"""Seeing runs: video, figures, the live viewer."""

#: The figure files a run writes (:func:`tt_mujoco.viz.plots.plot_run`), in order; named here,
#: where the run's process reads them without importing matplotlib.
FIGURES = ("path.png", "errors.png", "torques.png", "articulation.png")

"""The run's figures, drawn by a worker forked before its simulation.

A single run's figures took longer than its simulation: importing matplotlib and drawing four
figures one after the other, after the run. :class:`RunFigures` forks its worker as the command
starts (:class:`tt_mujoco.background.Worker`); the worker imports matplotlib (and the search
its errors figure projects with) and draws a first small figure while the simulation runs on
its own core. Handed the time series as soon as the episode ends (with its error signals, which
the run measures for its metrics anyway), it forks a second worker
from that warmed state, and the two draw their halves of the figures at once, while the run
computes its metrics, writes its files and renders its video; the figures come back as PNG
bytes, which the run writes into its folder.
This module imports no matplotlib itself: the run's own process never pays for it.
"""

from __future__ import annotations

from collections.abc import Mapping

from tt_mujoco.background import Worker
from tt_mujoco.viz import FIGURES

__all__ = ["GROUPS", "RunFigures"]

#: The run's figures (:data:`~tt_mujoco.viz.FIGURES`) in groups of about equal drawing
#: time, one per process: the errors figure (four panels) and the articulation's take about
#: as long as the path's and the torques'.
GROUPS = (("errors.png", "articulation.png"), ("path.png", "torques.png"))


def _prepare() -> None:
    from tt_mujoco.viz import plots

    plots.warm_up()


def _prepare_with_search() -> None:
    from tt_mujoco.analysis import geometry

    _prepare()
    geometry.prepare_search()


def _draw(names, ts, reference_polyline, params, world, errors, reverse) -> dict[str, bytes]:
    from tt_mujoco.viz import plots

    return plots.run_pngs(ts, reference_polyline, params, world, names, errors, reverse)


def _draw_groups(*args) -> dict[str, bytes]:
    """In the warmed worker: the other groups in workers forked from it, the first here; the
    arguments are :func:`_draw`'s after ``names``."""
    others = [Worker() for _ in GROUPS[1:]]
    try:
        for worker, names in zip(others, GROUPS[1:], strict=True):
            worker.call(_draw, names, *args)
        pngs = _draw(GROUPS[0], *args)
        for worker in others:
            pngs.update(worker.result())
        return pngs
    finally:
        for worker in others:
            worker.cancel()


class RunFigures:
    """The worker for one run's figures, forked now.

    Parameters
    ----------
    forked : bool, optional
        As :class:`~tt_mujoco.background.Worker`'s (default: forked where a core is spare).
    projects : bool, optional
        Whether the figures will measure the run against its path themselves (its error
        signals not handed over): the worker imports the nearest-point search ahead.
    """

    def __init__(self, forked: bool | None = None, projects: bool = False):
        self._worker = Worker(_prepare_with_search if projects else _prepare, forked=forked)

    @property
    def asked(self) -> bool:
        """Whether the worker has been handed a time series."""
        return self._worker.called

    def draw(
        self,
        ts: Mapping,
        reference_polyline,
        params=None,
        world=None,
        errors: Mapping | None = None,
        reverse: bool = False,
    ) -> None:
        """Hand the worker this time series (once); returns at once. The arguments are
        :func:`tt_mujoco.viz.plots.run_pngs`'."""
        self._worker.call(_draw_groups, ts, reference_polyline, params, world, errors, reverse)

    def result(self) -> dict[str, bytes]:
        """The figures as PNG files' bytes by file name, in :data:`~tt_mujoco.viz.FIGURES`
        order."""
        try:
            pngs = self._worker.result()
        finally:
            self.cancel()
        return {name: pngs[name] for name in FIGURES if name in pngs}

    def cancel(self) -> None:
        """End the worker if it still runs (the run gave up, or the figures are done)."""
        self._worker.cancel()

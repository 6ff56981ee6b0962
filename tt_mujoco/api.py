"""The Python API: one run from a notebook or a script.

:func:`simulate` is :func:`tt_mujoco.sim.simulate` (the same numbers as the command line for
the same scenario and seed) with the result wrapped in a :class:`Run`, whose helpers draw the
figures and the video the command line writes. :func:`load_scenario` reads a TOML scenario file
as ``python -m tt_mujoco.run --config FILE`` does.

Examples
--------
>>> import tt_mujoco
>>> run = tt_mujoco.simulate(tt_mujoco.Scenario(traj="circle", plant="reduced", duration=1.0))
>>> run.status
'ok'
>>> frame = run.to_pandas()  # the time series, one column per signal
>>> frame.attrs["units"]["v"]
'm/s'
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from tt_mujoco.sim import COLUMNS, Result, Scenario
from tt_mujoco.sim import simulate as _simulate
from tt_mujoco.sim.loop.timeseries import UNITS, unit_of

__all__ = ["Run", "load_scenario", "simulate"]


@dataclass(frozen=True)
class Run:
    """A finished run: the :class:`~tt_mujoco.sim.simulate.Result` and helpers around it.

    Attributes
    ----------
    result : tt_mujoco.sim.simulate.Result
    """

    result: Result

    @property
    def scenario(self) -> Scenario:
        return self.result.scenario

    @property
    def status(self) -> str:
        """``"ok"``, ``"jackknife"``, ``"diverged"``, ``"collision"`` or ``"failed"``."""
        return self.result.status

    @property
    def metrics(self) -> dict:
        """The figures ``metrics.json`` carries (docs/metrics.md)."""
        return self.result.metrics

    @property
    def timeseries(self) -> dict:
        """Column name -> array, one row per control step."""
        return self.result.timeseries

    def to_pandas(self):
        """The time series as a :class:`pandas.DataFrame` (pandas is needed), its units in
        ``frame.attrs["units"]`` (column -> unit, "" for a pure number).

        Returns
        -------
        pandas.DataFrame
        """
        import pandas as pd

        ts = self.result.timeseries
        order = [c for c in COLUMNS if c in ts] + [c for c in ts if c not in COLUMNS]
        frame = pd.DataFrame({name: ts[name] for name in order})
        frame.attrs["units"] = {name: UNITS.get(name, unit_of(name) or "") for name in order}
        frame.attrs["status"] = self.result.status
        return frame

    def plot(self, out_dir) -> list[Path]:
        """Write the run's four figures (as the command line does) into the folder
        ``out_dir``, made first when it does not exist; returns their paths.

        Raises
        ------
        ValueError
            ``out_dir`` is a file or a symbolic link, lies inside another run's or command's
            outputs, or holds one of the figures already (they are never overwritten).
        """
        from tt_mujoco.outputs import refuse_link_or_enclosed
        from tt_mujoco.viz import FIGURES, plots
        from tt_mujoco.world.builtin import parse_world

        out = Path(out_dir)
        if out.exists() and not out.is_dir():
            raise ValueError(f"out_dir={str(out_dir)!r} is not allowed: it is a file, not a folder")
        refuse_link_or_enclosed(out, "out_dir")
        taken = [name for name in FIGURES if (out / name).exists() or (out / name).is_symlink()]
        if taken:
            raise ValueError(
                f"out_dir={str(out_dir)!r} is not allowed: it holds {taken[0]} already, and "
                "figures are never overwritten; name a new folder"
            )
        out.mkdir(parents=True, exist_ok=True)
        made = plots.plot_run(
            self.result.timeseries,
            self.result.reference_polyline,
            out,
            params=self.scenario.plant_params(),
            world=parse_world(self.scenario.world),
            reverse=self.scenario.reverse,
        )
        return [Path(f) for f in made]

    def video(self, path, camera: str = "follow", fps: float = 30) -> Path:
        """Render the run to the MP4 ``path`` (never overwritten), as the command line does."""
        from tt_mujoco.viz import render

        info, outcome = render.run_labels(
            self.result.config["scenario"], self.result.status, self.result.message
        )
        return Path(
            render.render_video(
                self.result.timeseries,
                render.RunScene(
                    self.scenario.plant_params(),
                    self.result.reference_polyline,
                    info=info,
                    terrain=self.scenario.terrain,
                    world=self.scenario.world,
                ),
                path,
                render.VideoFormat(fps=fps, camera=camera),
                outcome,
                progress=False,
            )
        )


def simulate(scenario: Scenario, progress=None) -> Run:
    """Run one scenario to its end (never raises for a diverging run: see ``Run.status``).

    Parameters
    ----------
    scenario : Scenario
        What to run; its fields are the command line's options (docs: the scenario).
    progress : callable, optional
        ``progress(steps_done, steps_total)``, about every 1 % of the run.

    Returns
    -------
    Run

    Raises
    ------
    ValueError
        A bad scenario value, or a user's controller or disturbance that fails before the run.
    TypeError
        ``scenario`` is not a :class:`Scenario`, or ``progress`` is not callable.
    """
    if not isinstance(scenario, Scenario):
        raise TypeError(
            f"scenario={scenario!r} is not allowed: simulate takes a tt_mujoco.Scenario, e.g. "
            "tt_mujoco.Scenario(traj='s_curve'), or tt_mujoco.load_scenario(FILE)"
        )
    return Run(_simulate(scenario, progress=progress))


def load_scenario(path, *options: str) -> Scenario:
    """The scenario of a TOML file, as ``python -m tt_mujoco.run --config FILE`` reads it.

    Parameters
    ----------
    path : str or Path
        The TOML scenario file.
    *options : str
        Command-line options that override the file's, e.g. ``"--duration", "2"``.

    Returns
    -------
    Scenario
    """
    from tt_mujoco.run import scenario_from_argv

    return scenario_from_argv(["--config", str(path), *options])

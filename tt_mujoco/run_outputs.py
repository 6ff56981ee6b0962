"""What one run writes: its output options, its files and figures, its video.

:func:`write_outputs` writes a finished run's folder (``python -m tt_mujoco.run``, and callers
of the Python API that want the same folder); :data:`OUTPUTS` are the command's options besides
the scenario.
"""

from __future__ import annotations

import shutil
import tempfile
from collections.abc import Mapping
from pathlib import Path

from tt_mujoco.config import CONFIG_FILE
from tt_mujoco.defaults import CAMERAS
from tt_mujoco.outputs import (
    METRICS_FILE,
    REFERENCE_FILE,
    atomic_write,
    publish_new,
    write_json,
    write_timeseries,
)
from tt_mujoco.schema import Option, Schema, boolean, choice, number
from tt_mujoco.sim import COLUMNS
from tt_mujoco.sim.loop.timeseries import UNITS, train_columns, unit_of

__all__ = [
    "CHECKPOINT_FILE",
    "ERROR_LOG",
    "OUTPUTS",
    "STAGING",
    "TIMESERIES_FORMATS",
    "figure_rows",
    "figure_worker",
    "write_outputs",
]

#: Prefix of the hidden folder, private to one run, where figures and video are made before
#: they are moved into the output folder.
STAGING = ".partial-"
#: Formats of the time-series file (``timeseries.<format>``).
TIMESERIES_FORMATS = ("parquet", "csv")
#: The command's options besides the scenario: what it writes and how the run is watched.
OUTPUTS = Schema(
    (
        Option("video", True, "write video.mp4", boolean, form="switch"),
        Option("plots", True, "write PNG figures", boolean, form="switch"),
        Option(
            "camera",
            "follow",
            "video camera",
            choice(*CAMERAS),
            choices=CAMERAS,
            needs=("video", bool),
        ),
        Option(
            "fps",
            30.0,
            "video frame rate",
            number(0, 240, low_open=True),
            unit="1/s",
            needs=("video", bool),
        ),
        Option(
            "timeseries_format",
            "parquet",
            "timeseries.parquet (compact, columnar; pandas and polars read it) or "
            "timeseries.csv (text, full precision)",
            choice(*TIMESERIES_FORMATS),
            choices=TIMESERIES_FORMATS,
        ),
        Option(
            "mcap",
            False,
            "also write run.mcap: the run as ROS 2 messages for Foxglove and ROS 2's bag tools "
            "(the mcap extra; python -m tt_mujoco.bag converts a finished run)",
            boolean,
            form="switch",
        ),
        Option(
            "live",
            0,
            "serve the run live to Foxglove at ws://localhost:PORT (0: no; the mcap extra)",
            number(0, 65535, integer=True),
            metavar="PORT",
        ),
        Option(
            "live_realtime",
            True,
            "with --live: pace the run to real time (else as fast as it runs)",
            boolean,
            form="switch",
            needs=("live", bool),
        ),
        Option("quiet", False, "no progress bar", boolean, form="switch"),
        Option(
            "viewer",
            False,
            "show the run live in MuJoCo's viewer (needs a display; MuJoCo plant only)",
            boolean,
            form="switch",
        ),
    )
)
#: The rows of a run in progress (raw logged columns), removed once the time series is written.
CHECKPOINT_FILE = "timeseries.partial.arrows"
#: The traceback of the user's code that stopped a run (status "failed").
ERROR_LOG = "error.log"


def write_outputs(
    result,
    out: Path,
    shown: Mapping | None = None,
    config_toml: str | None = None,
    figures=None,
):
    """Write ``config.toml`` (if given), the time series, figures, video and, last,
    ``metrics.json`` into ``out``.

    Every file appears complete or not at all: text files through a temporary file and a
    rename; figures and video are made in a hidden staging folder and renamed into ``out``.
    An interruption therefore leaves complete files and no ``metrics.json``.

    Parameters
    ----------
    result : Result
        The run's (:func:`tt_mujoco.sim.simulate`).
    out : Path
        Its folder, claimed.
    shown : mapping, optional
        The output options by name (:data:`OUTPUTS`: ``video``, ``plots``, ``camera``, ...);
        those not given take their defaults.
    config_toml : str, optional
        The run's ``config.toml``.
    figures : RunFigures, optional
        Workers forked for the figures when the run started
        (:class:`tt_mujoco.viz.run_figures.RunFigures`); made here if not given.

    Returns
    -------
    (list of Path, list of str)
        The files written and the run's notes.
    """
    shown = {**OUTPUTS.defaults(), **(shown or {})}
    notes = list(result.notes)  # how the run ran (the loop, backing up), then the outputs'
    written, world = _write_data_files(result, out, shown, config_toml)
    plots, video = shown["plots"], shown["video"]
    if len(result.timeseries["t"]) < 2 and (plots or video):
        # A run that stopped at its first step has one sample: nothing to draw.
        notes.append("figures and video skipped: the run has fewer than 2 samples")
        plots = video = False
    if not plots and figures is not None:
        figures.cancel()
        figures = None
    staging = Path(tempfile.mkdtemp(dir=out, prefix=STAGING))  # this run's own
    try:
        if plots:  # drawn by a forked worker while the video renders here
            if figures is None:
                from tt_mujoco.viz.run_figures import RunFigures

                figures = RunFigures()
            if not figures.asked:
                params = result.scenario.plant_params()
                figures.draw(result.timeseries, result.reference_polyline, params, world)
        if video:
            made, note = _render_video(result, staging, shown, world)
            written += [publish_new(made, out / "video.mp4")] if made is not None else []
            notes += [note] if note is not None else []
        if figures is not None:
            pngs = figures.result()
            figures = None
            for name, png in pngs.items():
                (staging / name).write_bytes(png)
                written.append(publish_new(staging / name, out / name))
    finally:
        if figures is not None:
            figures.cancel()
        shutil.rmtree(staging, ignore_errors=True)
    doc = {
        **result.metrics,
        "message": result.message,
        "notes": notes,
        "config": result.config,
    }
    write_json(out / METRICS_FILE, doc, strict=True)
    written.append(out / METRICS_FILE)
    return written, notes


def _write_data_files(result, out: Path, shown: Mapping, config_toml: str | None):
    """``config.toml``, the error log, the reference path, the time series, the world and the
    MCAP file: ``(written, world)``."""
    written = []
    if config_toml is not None:
        atomic_write(out / CONFIG_FILE, config_toml)
        written.append(out / CONFIG_FILE)
    if result.details is not None:  # the traceback of the user code that stopped the run
        atomic_write(out / ERROR_LOG, result.details)
        written.append(out / ERROR_LOG)
    # The run's own reference path: render and compare read it, not a file that may change.
    line = result.reference_polyline
    write_timeseries(out / REFERENCE_FILE, {"x": line[:, 0], "y": line[:, 1]}, ("x", "y"), UNITS)
    written.append(out / REFERENCE_FILE)
    ts_file = out / f"timeseries.{shown['timeseries_format']}"
    extra = train_columns(result.scenario.plant_params().n_trailers)
    extra += tuple(name for name in result.timeseries if name.startswith("ctrl_"))
    units = {**UNITS, **{name: unit_of(name) or "" for name in extra}}
    write_timeseries(ts_file, result.timeseries, (*COLUMNS, *extra), units)
    (out / CHECKPOINT_FILE).unlink(missing_ok=True)  # the complete file replaces it
    written.append(ts_file)
    world = None
    if result.scenario.world != "none":  # its copy: re-rendering reads it, not the file
        from tt_mujoco.world.builtin import KEPT_WORLD, kept_world_toml, parse_world

        world = parse_world(result.scenario.world)
        atomic_write(out / KEPT_WORLD, kept_world_toml(world))
        written.append(out / KEPT_WORLD)
    if shown["mcap"]:
        from tt_mujoco.bag import BAG_FILE, write_bag

        scenario = result.scenario
        written.append(
            write_bag(
                result.timeseries,
                result.reference_polyline,
                scenario.plant_params(),
                out / BAG_FILE,
                bool(scenario.reverse),
                world,
            )
        )
    return written, world


def _render_video(result, staging: Path, shown: Mapping, world):
    """The run's video into ``staging``: ``(path, None)``, or ``(None, note)`` where no
    OpenGL renders it (the results are not lost for it)."""
    from tt_mujoco.viz import render

    try:
        info, outcome = render.run_labels(result.config["scenario"], result.status, result.message)
        scene = render.RunScene(
            result.scenario.plant_params(),
            result.reference_polyline,
            info=info,
            terrain=result.scenario.terrain,
            world=world,
        )
        video = render.VideoFormat(fps=shown["fps"], camera=shown["camera"])
        path = render.render_video(
            result.timeseries, scene, staging / "video.mp4", video, outcome, not shown["quiet"]
        )
    except render.RenderUnavailable as err:
        return None, f"video skipped: {err}"
    return Path(path), None


def figure_worker(scenario, shown: dict):
    """The run's figure worker (:class:`tt_mujoco.viz.run_figures.RunFigures`), forked as soon
    as the command line is read, before the set-up, so that matplotlib loads on the other core
    while the run is built and simulated; None when the run draws no figures (``--no-plots``,
    or a live view, which the figures would slow)."""
    if not shown["plots"] or shown["live"] or shown["viewer"]:
        return None
    from tt_mujoco.viz.run_figures import RunFigures

    # A maneuver's joined legs come without their error signals: the figures measure them.
    return RunFigures(projects=scenario.traj == "plan")


def figure_rows(figures, built):
    """The ``on_rows`` of :func:`tt_mujoco.sim.simulate` that hands ``figures`` (of
    :func:`figure_worker`) the time series as the run ends (a run of fewer than 2 samples has
    none to draw)."""
    reverse = built.scenario.reverse

    def on_rows(ts, reference_polyline, signals=None) -> None:
        if len(ts["t"]) >= 2:
            figures.draw(ts, reference_polyline, built.plant_params, built.world, signals, reverse)

    return on_rows

"""What a run's video is: its format (:class:`VideoFormat`) and what it shows besides the time
series (:class:`RunScene`), each checked when it is made; and the labels a run's outcome puts
on it (:func:`run_labels`)."""

from __future__ import annotations

import dataclasses
import textwrap
from collections.abc import Mapping

import numpy as np

from tt_mujoco.defaults import CAMERAS
from tt_mujoco.vehicle.params import Params

__all__ = ["RunScene", "VideoFormat", "run_labels"]


@dataclasses.dataclass(frozen=True)
class VideoFormat:
    """A video's frames: ``width`` x ``height`` pixels, even (H.264's 4:2:0 chroma), 16 to
    4096; ``fps`` frames per second, in (0, 240]; the ``camera``, one of
    :data:`~tt_mujoco.defaults.CAMERAS`.

    Raises
    ------
    ValueError
        A value outside those, naming it.
    """

    width: int = 640
    height: int = 480
    fps: float = 30.0
    camera: str = "follow"

    def __post_init__(self):
        for name, value in (("width", self.width), ("height", self.height)):
            if isinstance(value, bool) or not isinstance(value, int | np.integer):
                raise ValueError(f"{name}={value!r} is not allowed: it must be an even integer")
            if not (16 <= value <= 4096 and value % 2 == 0):
                raise ValueError(
                    f"{name}={value!r} is not allowed: it must be even (H.264 4:2:0) and in "
                    "[16, 4096]"
                )
        fps = self.fps
        if isinstance(fps, bool) or not isinstance(fps, int | float) or not 0 < fps <= 240:
            raise ValueError(f"fps={fps!r} is not allowed: it must be a number in (0, 240]")
        if self.camera not in CAMERAS:
            raise ValueError(
                f"camera={self.camera!r} is not allowed: use one of {', '.join(CAMERAS)}"
            )


@dataclasses.dataclass(frozen=True)
class RunScene:
    """What a run's video shows besides its time series.

    Parameters
    ----------
    params : Params
        The vehicle's parameters, which it is built from.
    reference_polyline : array_like, shape (M, 2)
        The reference path (m); may be empty (shape (0, 2)).
    info : str
        Shown in the top-right corner (e.g. "ismc_sta | mujoco plant | dynamic target").
    terrain : str
        The run's ground (``Scenario.terrain``): a grade is drawn as a slope, the whole scene
        turned from the plane's frame, where the run is computed, into the world's; a ramp or
        a rough ground is placed along ``reference_polyline`` as the run placed it.
    world : str or World
        The run's obstacles (``Scenario.world``, or the :class:`~tt_mujoco.world.World` a run
        kept: :mod:`tt_mujoco.world`).

    Raises
    ------
    ValueError
        A reference path with non-finite values.
    """

    params: Params
    reference_polyline: np.ndarray
    info: str = ""
    terrain: str = "flat"
    world: object = "none"

    def __post_init__(self):
        polyline = np.asarray(self.reference_polyline, dtype=float).reshape(-1, 2)
        if not np.all(np.isfinite(polyline)):
            raise ValueError("reference_polyline has non-finite values")
        object.__setattr__(self, "reference_polyline", polyline)


_TITLES = {"ok": "COMPLETED", "jackknife": "JACKKNIFE", "diverged": "DIVERGED"}


def run_labels(scenario: Mapping, status: str | None, message: str) -> tuple[str, tuple | None]:
    """The top-right line and the end card of a run's video, from its scenario and outcome."""
    info = " | ".join(
        f"{scenario.get(k, '?')}{suffix}"
        for k, suffix in (("controller", ""), ("plant", " plant"), ("target", " target"))
    )
    terrain = scenario.get("terrain", "flat")
    if terrain.startswith("slope:"):  # drawn as a slope too; the line says how steep, which way
        grade, _, heading = terrain.removeprefix("slope:").partition(":")
        info += f" | grade {grade}@{heading or 0} deg"
    elif terrain != "flat":
        info += f" | {terrain}"
    if status is None:
        return info, None
    return info, (_TITLES.get(status, status.upper()), textwrap.wrap(message, 58))

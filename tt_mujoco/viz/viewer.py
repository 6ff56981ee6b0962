"""Live viewing of a run in MuJoCo's passive viewer (``python -m tt_mujoco.run --viewer``).

The viewer watches the very loop that produces the outputs: :class:`LiveViewer` is the
``on_step`` hook of :func:`tt_mujoco.sim.simulate`, which syncs the window about 60 times a
simulated second and paces the loop to real time. The camera follows the tractor and the
reference path is drawn on the floor. Closing the window abandons the run
(:class:`ViewerClosed`); after a complete run the window stays open until it is closed.

MuJoCo's viewer needs a desktop session. Without one, MuJoCo's GLFW start-up ends the whole
process, so :func:`check_display` looks first: no ``DISPLAY``/``WAYLAND_DISPLAY`` (Linux), a
display GLFW cannot open (probed in a child process), or macOS outside ``mjpython`` raise
:class:`ViewerUnavailable`, which the CLI reports with exit code 2.
"""

from __future__ import annotations

import itertools
import os
import subprocess
import sys
import time

import numpy as np

__all__ = ["LiveViewer", "ViewerClosed", "ViewerUnavailable", "check_display"]

#: Window refreshes per simulated second.
VIEWER_FPS = 60.0
#: At most this many line segments of the reference path are drawn.
MAX_PATH_SEGMENTS = 400
#: Seconds the GLFW probe may take before the display counts as unusable.
PROBE_TIMEOUT_S = 30.0

_GLFW_PROBE = """
import sys, warnings
import glfw
messages = []
glfw.set_error_callback(lambda code, text: messages.append(text.decode(errors="replace")))
with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    ok = glfw.init()
if ok:
    glfw.terminate()
    sys.exit(0)
print("; ".join(messages) or "glfw.init() failed", file=sys.stderr)
sys.exit(1)
"""


class ViewerUnavailable(RuntimeError):  # noqa: N818 (a condition, like render.RenderUnavailable)
    """No window can be opened here; the message says why and what to do instead."""


class ViewerClosed(Exception):  # noqa: N818 (an event, not a fault)
    """The user closed the viewer window before the run ended."""


def check_display() -> None:
    """Raise :class:`ViewerUnavailable` unless MuJoCo's viewer can open a window here."""
    advice = "run without --viewer (the video and plots show the run afterwards)"
    if sys.platform.startswith("linux") or sys.platform.startswith("freebsd"):
        if not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
            raise ViewerUnavailable(
                "--viewer needs a display, and there is none (neither DISPLAY nor "
                f"WAYLAND_DISPLAY is set); {advice}"
            )
    if sys.platform == "darwin":
        try:
            from mujoco import viewer as mj_viewer

            under_mjpython = mj_viewer._MJPYTHON is not None  # set only by mjpython
        except (ImportError, AttributeError):
            under_mjpython = False
        if not under_mjpython:
            raise ViewerUnavailable(
                "--viewer on macOS needs MuJoCo's launcher: run `mjpython -m tt_mujoco.run "
                f"--viewer ...` instead of `python -m ...`; or {advice}"
            )
        return
    _probe_display(advice)


def _probe_display(advice: str) -> None:
    """Open GLFW in a child process: a failure there cannot take this process down."""
    try:
        proc = subprocess.run(
            [sys.executable, "-c", _GLFW_PROBE],
            capture_output=True,
            text=True,
            timeout=PROBE_TIMEOUT_S,
        )
    except subprocess.TimeoutExpired:
        raise ViewerUnavailable(
            f"--viewer: the display did not answer within {PROBE_TIMEOUT_S:g} s; {advice}"
        ) from None
    if proc.returncode != 0:
        reason = proc.stderr.strip().splitlines()[-1] if proc.stderr.strip() else "unknown"
        raise ViewerUnavailable(f"--viewer cannot open a window here ({reason}); {advice}")


class LiveViewer:
    """``on_step`` hook that shows a MuJoCo run live.

    Parameters
    ----------
    reference : array_like, shape (M, 2), optional
        Reference path drawn on the floor.
    fps : float
        Window refreshes per simulated second.
    realtime : bool
        Pace the loop so that simulated time runs at wall-clock speed.
    launch : callable, optional
        Stand-in for ``mujoco.viewer.launch_passive`` (tests).
    """

    def __init__(self, reference=None, fps: float = VIEWER_FPS, realtime: bool = True, launch=None):
        self.reference = None if reference is None else np.asarray(reference, dtype=float)
        self.period = 1.0 / fps
        self.realtime = realtime
        self._launch = launch
        self.handle = None
        self.frames = 0
        self._next_frame = 0.0
        self._wall_start = 0.0

    def __call__(self, t: float, plant) -> None:
        if self.handle is None:
            self._open(plant)
        if t + 1e-12 < self._next_frame:
            return
        self._next_frame += self.period
        if not self.handle.is_running():
            raise ViewerClosed(f"viewer closed at t={t:.3f} s")
        self.handle.sync()
        self.frames += 1
        if self.realtime:
            lag = self._wall_start + t - time.perf_counter()
            if lag > 0:
                time.sleep(lag)

    def _open(self, plant) -> None:
        import mujoco

        model, data = getattr(plant, "model", None), getattr(plant, "data", None)
        if model is None or data is None:
            raise ViewerUnavailable("--viewer shows the MuJoCo plant only")
        launch = self._launch
        if launch is None:
            from mujoco import viewer as mj_viewer

            launch = mj_viewer.launch_passive
        try:
            self.handle = launch(model, data, show_left_ui=False, show_right_ui=False)
        except Exception as err:  # any failure to open a window is the same fact for the user
            raise ViewerUnavailable(f"--viewer could not open a window: {err}") from None
        with self.handle.lock():
            cam = self.handle.cam
            cam.type = mujoco.mjtCamera.mjCAMERA_TRACKING
            cam.trackbodyid = model.body("tractor").id
            cam.distance = 2.5
            cam.elevation = -30.0
            if self.reference is not None:
                self._draw_reference(mujoco, self.handle.user_scn)
        self._wall_start = time.perf_counter() - float(data.time)
        self._next_frame = float(data.time)

    def _draw_reference(self, mujoco, scene) -> None:
        last = len(self.reference) - 1
        step = max(1, int(np.ceil(last / MAX_PATH_SEGMENTS)))
        points = self.reference[np.unique(np.r_[np.arange(0, last, step), last])]
        scene.ngeom = 0
        for a, b in itertools.pairwise(points):
            if scene.ngeom >= scene.maxgeom:
                break
            geom = scene.geoms[scene.ngeom]
            mujoco.mjv_initGeom(
                geom,
                mujoco.mjtGeom.mjGEOM_LINE,
                np.zeros(3),
                np.zeros(3),
                np.eye(3).ravel(),
                np.array([0.1, 0.9, 0.2, 1.0], dtype=np.float32),
            )
            mujoco.mjv_connector(
                geom,
                mujoco.mjtGeom.mjGEOM_LINE,
                3.0,
                np.array([a[0], a[1], 0.002]),
                np.array([b[0], b[1], 0.002]),
            )
            scene.ngeom += 1

    def wait_closed(self) -> None:
        """After the run: keep the window until the user closes it (or presses Ctrl-C)."""
        if self.handle is None:
            return
        print("viewer: the run is over; close the window to exit", file=sys.stderr)
        try:
            while self.handle.is_running():
                time.sleep(0.1)
        except KeyboardInterrupt:
            pass
        self.close()

    def close(self) -> None:
        if self.handle is not None:
            self.handle.close()
            self.handle = None

"""Headless H.264 videos of a finished run, rendered offscreen with MuJoCo.

A run is replayed, not re-simulated: for every video frame the vehicle is posed from the time
series (:func:`pose_vehicle`), MuJoCo computes the kinematics and renders the scene offscreen,
with the reference path, the growing traces of P and P0 and a text overlay added as user geoms
of the :class:`mujoco.MjvScene`. Frames stream into ``ffmpeg`` (the binary shipped by
``imageio-ffmpeg``, no system ffmpeg) through :class:`mediapy.VideoWriter`; the file is written
under a temporary name in the target folder and published atomically, never over an existing file.

The OpenGL backend is chosen by :mod:`tt_mujoco.viz.gl`; posing the vehicle from a time series
and the cameras are in :mod:`tt_mujoco.viz.scene`. ``python -m tt_mujoco.render RUN_DIR``
re-renders a finished run.
"""

from __future__ import annotations

import contextlib
import errno
import math
import os
from collections.abc import Mapping
from pathlib import Path

import mujoco
import numpy as np

from tt_mujoco.analysis.geometry import Polyline
from tt_mujoco.outputs import publish_new, temporary_beside
from tt_mujoco.progress import progress_bar
from tt_mujoco.sim.loop.timeseries import train_columns
from tt_mujoco.sim.parts.physics import Vehicle
from tt_mujoco.sim.parts.relief import relief_of
from tt_mujoco.sim.parts.terrain import Terrain, parse_terrain
from tt_mujoco.vehicle.params import Params
from tt_mujoco.viz.annotate import END_CARD_S, Legend, end_card
from tt_mujoco.viz.gl import GL_BACKENDS, RenderUnavailable, select_gl_backend
from tt_mujoco.viz.offscreen import Offscreen
from tt_mujoco.viz.scene import (
    CAMERAS,
    FOLLOW_AZIMUTH,
    FOLLOW_DISTANCE,
    FOLLOW_ELEVATION,
    MUJOCO_OVERLAY_MIN_HEIGHT,
    VIDEO_COLUMNS,
    CompactOverlay,
    decimate,
    frame_schedule,
    overview_camera,
    pose_vehicle,
    project_to_pixel,
    simplified,
    trailer_wheel_angles,
    validated_columns,
)
from tt_mujoco.viz.video_spec import RunScene, VideoFormat, run_labels
from tt_mujoco.world.builtin import parse_world

__all__ = [
    "CAMERAS",
    "GL_BACKENDS",
    "MAX_TRACE_POINTS",
    "PATH_RGBA",
    "TRACTOR_TRACE_RGBA",
    "TRAILER_TRACE_RGBA",
    "VIDEO_COLUMNS",
    "RenderUnavailable",
    "RunRenderer",
    "RunScene",
    "VideoFormat",
    "frame_schedule",
    "overview_camera",
    "pose_vehicle",
    "project_to_pixel",
    "render_video",
    "run_labels",
    "select_gl_backend",
    "trailer_wheel_angles",
]


# Each drawn line segment is one user geom, and on a software renderer the geoms, not the
# pixels, set a frame's cost. The reference path and the traces are drawn as chords within
# DRAW_TOLERANCE of the curve (a fraction of a pixel: the follow camera's 640 pixels span about
# 2.5 m), then decimated to at most these many segments, so a long run costs the same per frame
# as a short one.
DRAW_TOLERANCE = 1e-3  # m
MAX_PATH_SEGMENTS = 400


MAX_TRACE_POINTS = 600


# Heights (m) of the drawn lines above the floor: high enough to avoid depth fighting with the
# plane at the overview distance, low enough to look painted on the ground.
PATH_Z = 0.002


TRACE_Z = 0.004


PATH_RGBA = np.array([1.0, 1.0, 1.0, 1.0], dtype=np.float32)


TRACTOR_TRACE_RGBA = np.array([1.0, 0.45, 0.05, 1.0], dtype=np.float32)  # tractor orange


TRAILER_TRACE_RGBA = np.array([0.2, 0.6, 1.0, 1.0], dtype=np.float32)  # trailer blue

#: Traces of trailers 2, 3, ... of a train (cycled): violet, teal, pink, yellow-green.
TRAIN_TRACE_RGBA = tuple(
    np.array(rgba, dtype=np.float32)
    for rgba in (
        (0.65, 0.35, 1.0, 1.0),
        (0.1, 0.85, 0.7, 1.0),
        (1.0, 0.4, 0.7, 1.0),
        (0.7, 0.9, 0.2, 1.0),
    )
)


REFERENCE_POINT_RGBA = np.array([0.1, 0.9, 0.2, 1.0], dtype=np.float32)


REFERENCE_POINT_RADIUS = 0.015  # m


#: The encoder's constant quantiser (mediapy's own default for frames up to 640x480) and x264's
#: preset: "veryfast" encodes with half the CPU of the default "medium" at the same quantiser,
#: the picture within 0.3 dB and the file within 6 % (``benchmarks/bench_render.py``); the
#: encoder runs beside the renderer, on the same two cores.
H264_QP, H264_PRESET = 20, "veryfast"

_ZERO3 = np.zeros(3)


_EYE9 = np.eye(3).ravel()


class RunRenderer:
    """Frames of one run: the vehicle posed from the time series, the reference path, the
    traces of P (orange) and P0 (blue), the reference point (green) and a text overlay.

    Frames are fastest in increasing order (each adds a few geoms to those of the previous
    frame); any order is correct. Use as a context manager, or call :meth:`close`.

    Parameters
    ----------
    ts : mapping of str to 1-D arrays
        The run's time series; needs :data:`VIDEO_COLUMNS`; ``x_ref``/``y_ref`` are optional.
        Only the samples before the first non-finite value are shown.
    scene : RunScene
        The vehicle's parameters, the reference path, the corner's text, the ground and the
        obstacles (:class:`~tt_mujoco.viz.video_spec.RunScene`); a ramp or a rough ground is
        placed along the path as the run placed it, the vehicle resting on it in every frame.
    video : VideoFormat, optional
        Frame size, frames per second (see :func:`frame_schedule`) and camera
        (:class:`~tt_mujoco.viz.video_spec.VideoFormat`).
    """

    def __init__(self, ts: Mapping, scene: RunScene, video: VideoFormat | None = None):
        video = VideoFormat() if video is None else video
        params, polyline = scene.params, scene.reference_polyline
        self.info = scene.info
        ground = parse_terrain(scene.terrain)
        #: Plane frame to world (None: no grade, nothing to turn).
        graded = isinstance(ground, Terrain) and not ground.flat
        self.tilt = np.array(ground.world_rotation) if graded else None
        self.has_reference_point = "x_ref" in ts and "y_ref" in ts
        extra = ("x_ref", "y_ref") if self.has_reference_point else ()
        extra += train_columns(params.n_trailers)
        self.cols = validated_columns(ts, VIDEO_COLUMNS + extra)
        if len(polyline) > 1:
            polyline_drawn = polyline[simplified(polyline, DRAW_TOLERANCE)]
            self.path = decimate(polyline_drawn, MAX_PATH_SEGMENTS)
        else:
            self.path = polyline
        self.width, self.height, self.fps = video.width, video.height, video.fps
        self.camera_mode = video.camera
        self.params = params
        #: A ramp or a rough ground, placed along the run's reference as the run placed it.
        self.relief = relief_of(ground, polyline, params) if len(polyline) > 1 else None
        world = scene.world
        self.vehicle = Vehicle(
            params, self.relief, parse_world(world) if isinstance(world, str) else world
        )
        self.model = self.vehicle.model
        self.times, self.index = frame_schedule(self.cols["t"], video.fps)
        self.n_frames = len(self.times)
        self._pose_columns(params)
        self._traces(params, polyline)
        self._place_camera(params)
        self._mjv_camera = mujoco.MjvCamera()
        self._mjv_camera.type = mujoco.mjtCamera.mjCAMERA_FREE
        self._mjv_camera.distance = self.camera["distance"]
        self._mjv_camera.azimuth = self.camera["azimuth"]
        self._mjv_camera.elevation = self.camera["elevation"]
        self._option = mujoco.MjvOption()
        # The wheels' collision spheres (group 3) stay hidden: their visual tyres are drawn.
        self._option.geomgroup[3] = 0
        self._perturb = mujoco.MjvPerturb()
        self._line_px = max(1.0, round(video.height / 200))
        self._compact = (
            CompactOverlay(video.height) if video.height < MUJOCO_OVERLAY_MIN_HEIGHT else None
        )
        self._legend = (
            Legend(self._legend_entries(), video.height) if self._compact is None else None
        )
        # Room for the model's geoms twice over (mjv_updateScene may add decor) plus ours.
        n_user = self._n_fixed + 1 + len(self._units) * (len(self.trace_frames) + 1)
        maxgeom = 2 * self.model.ngeom + 100 + n_user
        self._off = Offscreen(self.model, video.width, video.height, maxgeom)
        self._geoms = self._off.scene.geoms  # the tuple is rebuilt on each attribute access
        self._base = -1  # geoms mjv_updateScene wrote in the previous frame
        self._committed = 0  # trace points already in the scene after the fixed geoms

    def _pose_columns(self, params: Params) -> None:
        """The wheels' angles and trailers 2..N's ``(phi_k, beta_k)`` at every sample."""
        trailers = range(1, params.n_trailers + 1)
        self._wheels = np.column_stack(
            [
                self.cols["theta_l"],
                self.cols["theta_r"],
                *(a for k in trailers for a in trailer_wheel_angles(self.cols, params, k)),
            ]
        )
        self._train = np.zeros((len(self.cols["t"]), params.n_trailers - 1, 2))
        for j, k in enumerate(trailers[1:]):
            self._train[:, j, 0] = self.cols[f"phi_{k}"]
            self._train[:, j, 1] = self.cols[f"beta_{k}"]

    def _traces(self, params: Params, polyline: np.ndarray) -> None:
        """Every axle's trace at the frames, their colours, the frames that commit a trace
        point, and P's cross-track error at each frame."""
        self._tractor_xy = np.column_stack([self.cols["x"], self.cols["y"]])[self.index]
        # P's cross-track error at each frame, against the full path (docs/metrics.md).
        self._cross = (
            Polyline(polyline).project(self._tractor_xy, extend_ends=True).signed_distance
            if len(polyline) > 1
            else np.full(self.n_frames, np.nan)
        )
        # Every axle's trace: P, P0, then P0_k of trailers k = 2..N.
        sfx = ["" if k == 1 else f"_{k}" for k in range(1, params.n_trailers + 1)]
        self._units = [self._tractor_xy] + [
            np.column_stack([self.cols[f"x0{s}"], self.cols[f"y0{s}"]])[self.index] for s in sfx
        ]
        self._unit_rgba = [TRACTOR_TRACE_RGBA, TRAILER_TRACE_RGBA] + [
            TRAIN_TRACE_RGBA[j % len(TRAIN_TRACE_RGBA)] for j in range(params.n_trailers - 1)
        ]
        self._last = f"x0{sfx[-1]}", f"y0{sfx[-1]}"  # the last axle, for the follow camera
        # Traces: one point a frame; the frames where some axle's trace leaves the chord by
        # more than DRAW_TOLERANCE are committed, and a live segment runs to "now".
        kept = np.unique(np.concatenate([simplified(xy, DRAW_TOLERANCE) for xy in self._units]))
        self.trace_frames = decimate(kept[:, None], MAX_TRACE_POINTS - 1)[:, 0].astype(int)
        self._n_fixed = max(len(self.path) - 1, 0)

    def _place_camera(self, params: Params) -> None:
        """The camera (over the whole run, or following the vehicle), and a far clipping plane
        beyond everything drawn."""
        fovy = float(self.model.vis.global_.fovy)
        drawn = np.vstack([*self._units, self.path])
        if self.camera_mode == "overview":
            # The bodies reach past P and P0 (the tractor's chassis 0.75 L ahead of P).
            pad = 0.75 * params.L + 0.5 * params.d
            self.camera = overview_camera(drawn, fovy, self.width / self.height, pad)
        else:
            # A train is longer than the paper's vehicle: back off by the extra length.
            extra_length = sum(t.L + t.L0 for t in params.train)
            self.camera = {
                "lookat": np.zeros(3),
                "distance": FOLLOW_DISTANCE + extra_length,
                "azimuth": FOLLOW_AZIMUTH,
                "elevation": FOLLOW_ELEVATION,
            }
        # MuJoCo's zfar is relative to the model's extent.
        far = 2.0 * (self.camera["distance"] + np.ptp(drawn, axis=0).max())
        extent = float(self.model.stat.extent)
        self.model.vis.map.zfar = max(float(self.model.vis.map.zfar), far / extent)

    def _legend_entries(self) -> list:
        entries = [
            ("tractor trace (axle P)", TRACTOR_TRACE_RGBA),
            ("trailer trace (axle P0)", TRAILER_TRACE_RGBA),
            *(
                (f"trailer {k} trace (axle P0_{k})", rgba)
                for k, rgba in enumerate(self._unit_rgba[2:], start=2)
            ),
            ("reference path", PATH_RGBA),
        ]
        if self.has_reference_point:
            entries.append(("reference point", REFERENCE_POINT_RGBA))
        entries.append(("hitch rods, hinges O and P0", np.array([0.95, 0.8, 0.15, 1.0])))
        return entries

    # --- context management -----------------------------------------------------------------------
    def __enter__(self) -> RunRenderer:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        self._off.close()

    # --- geoms ------------------------------------------------------------------------------------
    def _world(self, point) -> np.ndarray:
        """A point of the plane's frame in the world the picture shows (on a relief: lifted
        by the ground's height under it)."""
        point = np.asarray(point, dtype=float)
        if self.relief is not None:
            point = point + np.array([0.0, 0.0, float(self.relief.height(point[0], point[1]))])
        return point if self.tilt is None else self.tilt @ point

    def _tilt_model_geoms(self) -> None:
        """Turn the geoms ``mjv_updateScene`` just wrote into the world (a grade's slope)."""
        tilt = self.tilt
        for g in self._geoms[: self._off.scene.ngeom]:
            g.pos[:] = tilt @ g.pos
            g.mat[:] = (tilt @ g.mat.reshape(3, 3)).reshape(g.mat.shape)

    def _segment(self, slot: int, a, b, z: float, rgba: np.ndarray) -> None:
        g = self._geoms[slot]
        mujoco.mjv_initGeom(g, mujoco.mjtGeom.mjGEOM_LINE, _ZERO3, _ZERO3, _EYE9, rgba)
        mujoco.mjv_connector(
            g,
            mujoco.mjtGeom.mjGEOM_LINE,
            self._line_px,
            self._world([a[0], a[1], z]),
            self._world([b[0], b[1], z]),
        )

    def _user_geoms(self, frame: int, rewrite: bool) -> None:
        """Append the path, the reference point and the traces after the model's geoms.

        Layout: path segments, reference point (if recorded), committed trace segments (P and
        P0 pairs), then the live pair from the last committed point to "now". The user geoms
        lie beyond the ones ``mjv_updateScene`` writes, which it leaves alone, so the path and
        the pairs committed for earlier frames are still in place: a frame writes only the
        newly committed pairs, the reference point and the live pair.
        """
        scn = self._off.scene
        base = scn.ngeom
        committed = int(np.searchsorted(self.trace_frames, frame, side="right"))
        if rewrite or base != self._base or committed < self._committed:
            for i in range(self._n_fixed):
                self._segment(base + i, self.path[i], self.path[i + 1], PATH_Z, PATH_RGBA)
            self._committed = 1
            self._base = base
        slot = base + self._n_fixed
        if self.has_reference_point:
            i = self.index[frame]
            pos = self._world([self.cols["x_ref"][i], self.cols["y_ref"][i], TRACE_Z])
            mujoco.mjv_initGeom(
                self._geoms[slot],
                mujoco.mjtGeom.mjGEOM_SPHERE,
                np.full(3, REFERENCE_POINT_RADIUS),
                pos,
                _EYE9,
                REFERENCE_POINT_RGBA,
            )
            slot += 1
        trace0 = slot
        kept = self.trace_frames
        units = len(self._units)
        for j in range(self._committed, committed):
            self._trace_group(trace0 + units * (j - 1), kept[j - 1], kept[j])
        self._committed = committed
        slot = trace0 + units * (committed - 1)
        last = kept[committed - 1]
        if frame > last:  # a zero-length line would take its direction from stale memory
            self._trace_group(slot, last, frame)
            slot += units
        scn.ngeom = slot

    def _trace_group(self, slot: int, a: int, b: int) -> None:
        """Trace segments from frame ``a`` to frame ``b``: P at ``slot``, P0 at ``slot + 1``,
        then the axles of trailers 2..N."""
        for j, (xy, rgba) in enumerate(zip(self._units, self._unit_rgba, strict=True)):
            self._segment(slot + j, xy[a], xy[b], TRACE_Z, rgba)

    # --- frames -----------------------------------------------------------------------------------
    def overlay_text(self, frame: int) -> tuple[str, str]:
        """Labels and values of the text overlay for ``frame``."""
        i = self.index[frame]
        c = self.cols
        labels = "t\nv\nomega\nphi\nbeta\neta\ncross-track"
        values = (
            f"{self.times[frame]:6.2f} s\n{c['v'][i]:+.3f} m/s\n{c['omega'][i]:+.3f} rad/s\n"
            f"{math.degrees(c['phi'][i]):+.2f} deg\n{math.degrees(c['beta'][i]):+.2f} deg\n"
            f"{self.params.eta:+.4g}\n{1000.0 * self._cross[frame]:+.1f} mm"
        )
        # A train: every further hitch angle and its gain.
        for k, t in enumerate(self.params.train, start=2):
            labels += f"\nphi_{k} (eta_{k})"
            values += f"\n{math.degrees(c[f'phi_{k}'][i]):+.2f} deg ({t.eta:+.3g})"
        return labels, values

    def compact_text(self, frame: int) -> str:
        """The two-line overlay of small frames (see :data:`MUJOCO_OVERLAY_MIN_HEIGHT`)."""
        i = self.index[frame]
        c = self.cols
        return (
            f"t {self.times[frame]:.2f} s  phi {math.degrees(c['phi'][i]):+.1f} deg\n"
            f"v {c['v'][i]:+.2f} m/s  w {c['omega'][i]:+.2f} rad/s"
        )

    def render_frame(self, frame: int, *, rewrite: bool = False) -> np.ndarray:
        """The RGB image (height, width, 3) of video frame ``frame``.

        ``rewrite=True`` rebuilds every user geom instead of reusing those already in the
        scene (the result is the same; the tests use it to check that reuse is exact).
        """
        if not 0 <= frame < self.n_frames:
            raise ValueError(f"frame={frame!r} is not allowed: it must be in [0, {self.n_frames})")
        i = self.index[frame]
        c = self.cols
        pose_vehicle(
            self.vehicle,
            c["x"][i],
            c["y"][i],
            c["theta"][i],
            c["phi"][i],
            c["beta"][i],
            self._wheels[i],
            self._train[i],
        )
        if self.camera_mode == "follow":
            self._mjv_camera.lookat[:] = self._world(self.camera_at(frame)["lookat"])
        else:
            self._mjv_camera.lookat[:] = self._world(self.camera["lookat"])
        mujoco.mjv_updateScene(
            self.model,
            self.vehicle.data,
            self._option,
            self._perturb,
            self._mjv_camera,
            mujoco.mjtCatBit.mjCAT_ALL,
            self._off.scene,
        )
        if self.tilt is not None:
            self._tilt_model_geoms()
        self._user_geoms(frame, rewrite)
        if self._compact is None:
            image = self._off.render(*self.overlay_text(frame), info=self.info)
            return self._legend.apply(image)
        return self._compact.draw(self._off.render(), self.compact_text(frame))

    def camera_at(self, frame: int) -> dict:
        """The free camera (as in :func:`overview_camera`) used for ``frame``."""
        cam = dict(self.camera)
        if self.camera_mode == "follow":
            # The middle of the vehicle (between P and the last axle), so every unit stays framed.
            i = self.index[frame]
            c = self.cols
            lx, ly = self._last
            cam["lookat"] = np.array(
                [0.5 * (c["x"][i] + c[lx][i]), 0.5 * (c["y"][i] + c[ly][i]), 0.05]
            )
        return cam


@contextlib.contextmanager
def _encoder_failure_is_oserror(out: Path):
    """The encoder that cannot finish the file (a full disk, a quota: mediapy raises
    ffmpeg's words as a RuntimeError when the writer closes) as the OSError it is, naming
    ``out``: what the file system refused is said as such, not taken for a bug."""
    try:
        yield
    except RuntimeError as err:
        text = str(err)
        if not text.startswith("Error writing"):
            raise
        known = {"No space left": errno.ENOSPC, "quota": errno.EDQUOT, "Read-only": errno.EROFS}
        code = next((c for words, c in known.items() if words in text), errno.EIO)
        raise OSError(code, os.strerror(code), str(out)) from err


def render_video(
    ts: Mapping,
    scene: RunScene,
    out_path,
    video: VideoFormat | None = None,
    outcome: tuple[str, list[str]] | None = None,
    progress: bool = True,
) -> Path:
    """Render a run to an H.264 MP4 (see :class:`RunRenderer` for what is drawn).

    The number of frames is ``floor(duration * fps) + 1`` (:func:`frame_schedule`). The video
    is encoded while it is rendered (ffmpeg runs in its own process), written to a temporary
    file in the target folder and moved into place at the end.

    Parameters
    ----------
    ts, scene, video
        As for :class:`RunRenderer` (``video`` default ``VideoFormat()``).
    out_path : str or Path
        The ``.mp4`` to write, in an existing folder; never overwritten.
    outcome : (title, lines), optional
        How the run ended ("COMPLETED", "JACKKNIFE", ...: :func:`run_labels`): an end card
        over the last frame, held for :data:`~tt_mujoco.viz.annotate.END_CARD_S` after the
        run's frames.
    progress : bool
        Show a tqdm progress bar (on stderr).

    Returns
    -------
    Path
        ``out_path``.

    Raises
    ------
    ValueError
        Bad arguments or time series.
    FileExistsError
        ``out_path`` exists.
    RenderUnavailable
        No OpenGL backend works here.
    """
    # The encoder's imports (ffmpeg binary lookup, mediapy) load only when a video is made.
    import imageio_ffmpeg
    import mediapy

    out = Path(out_path)
    if out.suffix.lower() != ".mp4":
        raise ValueError(f"out_path={str(out)!r} is not allowed: it must end in .mp4")
    if not out.parent.is_dir():
        raise ValueError(
            f"out_path={str(out)!r} is not allowed: folder {out.parent} does not exist"
        )
    if out.exists():
        raise FileExistsError(f"{out} exists; it is not overwritten")
    video = VideoFormat() if video is None else video
    mediapy.set_ffmpeg(imageio_ffmpeg.get_ffmpeg_exe())

    with (
        RunRenderer(ts, scene, video) as renderer,
        temporary_beside(out, suffix=".tmp.mp4") as tmp,
    ):
        with (
            _encoder_failure_is_oserror(out),
            mediapy.VideoWriter(
                tmp,
                shape=(video.height, video.width),
                fps=video.fps,
                codec="h264",
                qp=H264_QP,
                ffmpeg_args=["-preset", H264_PRESET],
            ) as writer,
        ):
            bar = progress_bar(renderer.n_frames, f"video {out.name}", "frame", progress)
            with bar:
                for k in range(renderer.n_frames):
                    image = renderer.render_frame(k)
                    writer.add_image(image)
                    bar.update()
            if outcome is not None:
                card = end_card(image, *outcome)
                for _ in range(round(END_CARD_S * video.fps)):
                    writer.add_image(card)
        publish_new(tmp, out)
    return out

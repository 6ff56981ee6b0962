"""What a video frame shows: the vehicle posed from a time series, cameras, decimated traces,
the text overlay.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import mujoco
import numpy as np

from tt_mujoco.defaults import CAMERAS
from tt_mujoco.sim.loop.timeseries import COLUMNS
from tt_mujoco.vehicle.params import Params

__all__ = [
    "CAMERAS",
    "FOLLOW_AZIMUTH",
    "FOLLOW_DISTANCE",
    "FOLLOW_ELEVATION",
    "MUJOCO_OVERLAY_MIN_HEIGHT",
    "OVERVIEW_AZIMUTH",
    "OVERVIEW_ELEVATION",
    "OVERVIEW_MARGIN",
    "VIDEO_COLUMNS",
    "frame_schedule",
    "overview_camera",
    "pose_vehicle",
    "project_to_pixel",
    "trailer_wheel_angles",
]

#: Camera modes of :func:`render_video`.


#: Columns a video needs (SI units, radians): the time series' first 14, t to theta_r.
VIDEO_COLUMNS = COLUMNS[: COLUMNS.index("theta_r") + 1]


# Follow camera: fixed azimuth/elevation/distance, so the vehicle's turning shows as rotation.
FOLLOW_DISTANCE = 1.6


FOLLOW_AZIMUTH = 45.0  # looking towards +x+y: from behind for the built-in paths' travel


FOLLOW_ELEVATION = -40.0


# Overview camera: from -y looking towards +y (world x to the right, y up the image), steep.
OVERVIEW_AZIMUTH = 90.0


OVERVIEW_ELEVATION = -65.0


OVERVIEW_MARGIN = 1.08


# --- time series ----------------------------------------------------------------------------------
def _column(ts: Mapping, name: str) -> np.ndarray:
    if name not in ts:
        raise ValueError(f"time series has no column {name!r}; it needs {', '.join(VIDEO_COLUMNS)}")
    return np.asarray(ts[name], dtype=float)


def validated_columns(ts: Mapping, names) -> dict[str, np.ndarray]:
    """The columns ``names`` up to the first non-finite value in any of them.

    A run that diverged is written up to where it stopped, possibly with NaN rows at the end
    (docs/model.md Section 11): the video shows what was computed.
    """
    cols = {name: _column(ts, name) for name in names}
    n = len(cols["t"])
    for name, col in cols.items():
        if col.ndim != 1 or len(col) != n:
            raise ValueError(
                f"time series column {name!r} has shape {col.shape}: every column must be "
                f"1-D with the {n} samples of 't'"
            )
    finite = np.logical_and.reduce([np.isfinite(col) for col in cols.values()])
    n = n if finite.all() else int(np.argmin(finite))
    cols = {name: col[:n] for name, col in cols.items()}
    if n < 2 or not np.all(np.diff(cols["t"]) > 0):
        raise ValueError(
            "time series column 't' must have >= 2 strictly increasing samples (before the "
            "first non-finite value)"
        )
    return cols


def frame_schedule(t, fps: float) -> tuple[np.ndarray, np.ndarray]:
    """Video frame times and the time-series sample shown in each.

    Frame ``k`` is at ``t[0] + k / fps`` for ``k = 0 .. floor(duration * fps)``, so a run of
    duration ``D = t[-1] - t[0]`` gives ``floor(D * fps) + 1`` frames (both ends shown; 1e-9
    absorbs round-off in ``D * fps``). Each frame shows the sample nearest in time.

    Returns
    -------
    times : ndarray, shape (n,)
    index : ndarray of int, shape (n,)
    """
    t = np.asarray(t, dtype=float)
    n = math.floor((t[-1] - t[0]) * fps + 1e-9) + 1
    times = t[0] + np.arange(n) / fps
    right = np.clip(np.searchsorted(t, times), 1, len(t) - 1)
    left = right - 1
    index = np.where(times - t[left] <= t[right] - times, left, right)
    return times, index


def cumulative_trapezoid(y: np.ndarray, t: np.ndarray) -> np.ndarray:
    out = np.zeros_like(y)
    out[1:] = np.cumsum(0.5 * (y[1:] + y[:-1]) * np.diff(t))
    return out


def trailer_wheel_angles(ts: Mapping, params: Params, k: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """Trailer wheel spin angles (left, right) by integrating their rolling rates.

    The wheels at P0 +- (d/2) n(alpha) roll at ``(v0 -+ (d/2) alpha_dot) / r`` with
    ``alpha = theta0 + beta`` (docs/model.md Section 4), so the angles are
    ``(integral(v0) -+ (d/2) (alpha - alpha(0))) / r``. Trailer ``k`` >= 2 uses its own
    columns (``v0_k``, ``theta0_k``, ``beta_k``).
    """
    sfx = "" if k == 1 else f"_{k}"
    names = ("v0", "theta0", "beta")
    cols = validated_columns(ts, ("t", *(name + sfx for name in names)))
    v0, theta0, beta = (cols[name + sfx] for name in names)
    rolled = cumulative_trapezoid(v0, cols["t"])
    alpha = theta0 + beta
    turned = 0.5 * params.d * (alpha - alpha[0])
    return (rolled - turned) / params.r, (rolled + turned) / params.r


def pose_vehicle(vehicle, x, y, theta, phi, beta, wheels, train=()) -> None:
    """Put a :class:`~tt_mujoco.sim.parts.physics.Vehicle` in a planar pose and compute its
    kinematics.

    Free joint at (x, y, r) with yaw ``theta`` (resting on the vehicle's relief if it has
    one); ``q_hitch = -phi``; ``q_steer = beta`` (the recorded angle, so an equality-constraint
    violation shows); ``wheels`` are the spin angles
    (tractor left, tractor right, trailer left, trailer right, then trailer k's left and
    right for k = 2..N); ``train`` holds ``(phi_k, beta_k)`` of trailers 2..N.
    """
    lay, d, p = vehicle.layout, vehicle.data, vehicle.params
    i = lay.root_q
    d.qpos[i : i + 7] = [x, y, p.r, math.cos(theta / 2), 0.0, 0.0, math.sin(theta / 2)]
    d.qpos[lay.hitch_q] = -phi
    d.qpos[lay.steer_q] = beta
    for (hitch_q, _, steer_q, _, _), (phi_k, beta_k) in zip(lay.train, train, strict=True):
        d.qpos[hitch_q] = -phi_k
        d.qpos[steer_q] = beta_k
    for address, angle in zip(_wheel_qpos(vehicle), wheels, strict=True):
        d.qpos[address] = angle
    mujoco.mj_kinematics(vehicle.model, d)
    if vehicle.relief is not None:  # a ramp or a rough ground: resting on it, as at the start
        vehicle.rest_on_relief()
    mujoco.mj_camlight(vehicle.model, d)


def _wheel_qpos(vehicle) -> tuple[int, ...]:
    m = vehicle.model
    names = ["tractor_wheel_left", "tractor_wheel_right", "trailer_wheel_left"]
    names += ["trailer_wheel_right"]
    for k in range(2, vehicle.params.n_trailers + 1):
        names += [f"trailer_wheel_left_{k}", f"trailer_wheel_right_{k}"]
    return tuple(int(m.jnt_qposadr[m.joint(name).id]) for name in names)


def decimate(points: np.ndarray, max_segments: int) -> np.ndarray:
    """Every k-th point, keeping the last, so that at most ``max_segments`` segments remain."""
    stride = max(1, math.ceil((len(points) - 1) / max_segments))
    kept = points[::stride]
    if (len(points) - 1) % stride:
        kept = np.vstack([kept, points[-1]])
    return kept


def simplified(points: np.ndarray, tolerance: float) -> np.ndarray:
    """Indices of the points of a polyline that keep every other point within ``tolerance`` of
    the segment between the kept points around it (Ramer-Douglas-Peucker); the first and the
    last are kept.

    A drawn line costs the renderer one geom whatever its length, and a chord within a
    fraction of a pixel of the curve draws the same pixels: on an arc of radius R a chord of
    length c is ``c^2 / (8 R)`` off at its middle. The distance is to the segment, not its line,
    so that a trace that doubles back (a stop, a reversal) keeps its turning point.
    """
    n = len(points)
    keep = np.zeros(n, dtype=bool)
    keep[[0, n - 1]] = True
    spans = [(0, n - 1)]
    while spans:
        a, b = spans.pop()
        if b - a < 2:
            continue
        chord = points[b] - points[a]
        inner = points[a + 1 : b] - points[a]
        length2 = float(chord @ chord)
        t = np.clip(inner @ chord / length2, 0.0, 1.0) if length2 > 0.0 else np.zeros(len(inner))
        off = np.hypot(*(inner - t[:, None] * chord).T)
        i = int(np.argmax(off))
        if off[i] > tolerance:
            keep[a + 1 + i] = True
            spans += [(a, a + 1 + i), (a + 1 + i, b)]
    return np.flatnonzero(keep)


# --- offscreen rendering --------------------------------------------------------------------------
def _camera_axes(azimuth: float, elevation: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Forward, up and right unit vectors of a MuJoCo free camera (as in mjv_updateCamera)."""
    az, el = math.radians(azimuth), math.radians(elevation)
    forward = np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)])
    up = np.array([-math.sin(el) * math.cos(az), -math.sin(el) * math.sin(az), math.cos(el)])
    return forward, up, np.cross(forward, up)


def overview_camera(
    points_xy: np.ndarray, fovy_deg: float, aspect: float, pad: float = 0.0
) -> dict:
    """Free-camera settings that frame all ``points_xy``, widened by ``pad`` (m) on every side,
    and 0.1 m of height above them.

    For a point at offset ``q`` from the look-at point and a camera at distance ``D``, the
    point is inside the frustum when ``|q.right| <= tan(fovx/2) (D + q.forward)`` and likewise
    with ``up``/``fovy``; the smallest such ``D`` over the bounding-box corners, times a margin.
    """
    lo, hi = points_xy.min(axis=0) - pad, points_xy.max(axis=0) + pad
    centre = np.array([(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, 0.0])
    forward, up, right = _camera_axes(OVERVIEW_AZIMUTH, OVERVIEW_ELEVATION)
    ty = math.tan(math.radians(fovy_deg) / 2)
    tx = ty * aspect
    distance = 0.5  # at least this close a view, even for a vehicle that stood still
    for cx in (lo[0], hi[0]):
        for cy in (lo[1], hi[1]):
            for cz in (0.0, 0.1):
                q = np.array([cx, cy, cz]) - centre
                need = max(abs(q @ right) / tx, abs(q @ up) / ty) - q @ forward
                distance = max(distance, need)
    return {
        "lookat": centre,
        "distance": OVERVIEW_MARGIN * distance,
        "azimuth": OVERVIEW_AZIMUTH,
        "elevation": OVERVIEW_ELEVATION,
    }


def project_to_pixel(point, camera: dict, fovy_deg: float, width: int, height: int):
    """Pixel (column, row) of a world point seen by a free camera described as in
    :func:`overview_camera` (row 0 at the top). Used by the tests and for overlays."""
    forward, up, right = _camera_axes(camera["azimuth"], camera["elevation"])
    eye = np.asarray(camera["lookat"], dtype=float) - camera["distance"] * forward
    q = np.asarray(point, dtype=float) - eye
    depth = q @ forward
    ty = math.tan(math.radians(fovy_deg) / 2)
    tx = ty * width / height
    col = (0.5 + 0.5 * (q @ right) / (depth * tx)) * width
    row = (0.5 - 0.5 * (q @ up) / (depth * ty)) * height
    return col, row


# MuJoCo's overlay text is at least 18 px a line (it raises font scale 50 to 100), so its
# four-line box would cover a third of a small frame: below this height a compact two-line
# overlay is drawn with Pillow instead.
MUJOCO_OVERLAY_MIN_HEIGHT = 360


def font_scale(height: int) -> int:
    if height < 720:
        return int(mujoco.mjtFontScale.mjFONTSCALE_100)
    return int(mujoco.mjtFontScale.mjFONTSCALE_150)


class CompactOverlay:
    """Two lines of white text on a black box in the top-left corner, drawn with Pillow."""

    def __init__(self, height: int):
        from PIL import ImageFont

        self.font = ImageFont.load_default(size=max(7, height // 12))

    def draw(self, image: np.ndarray, text: str) -> np.ndarray:
        from PIL import Image, ImageDraw

        im = Image.fromarray(image)
        draw = ImageDraw.Draw(im)
        _, _, right, bottom = draw.multiline_textbbox((2, 1), text, font=self.font)
        draw.rectangle((0, 0, right + 2, bottom + 2), fill=(0, 0, 0))
        draw.multiline_text((2, 1), text, fill=(255, 255, 255), font=self.font)
        return np.asarray(im).copy()

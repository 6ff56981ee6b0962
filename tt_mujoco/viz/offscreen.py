"""An offscreen MuJoCo renderer: an OpenGL context (:mod:`tt_mujoco.viz.gl` chooses the
backend), MuJoCo's render context and a scene; the run's video and the Gym env's frames."""

from __future__ import annotations

import mujoco
import numpy as np

from tt_mujoco.viz.gl import RenderUnavailable, gl_context
from tt_mujoco.viz.scene import font_scale

__all__ = ["OFFSCREEN_SAMPLES", "Offscreen"]

# Multisample anti-aliasing of the offscreen buffer. On Mesa's llvmpipe, 4 samples make
# mjr_readPixels resolve the buffer in software, several times the cost of the frame itself.
OFFSCREEN_SAMPLES = 0


class Offscreen:
    """An OpenGL context, MuJoCo's render context (offscreen buffer) and a scene."""

    def __init__(self, model: mujoco.MjModel, width: int, height: int, maxgeom: int):
        backend, cls = gl_context()
        # The model belongs to our own Vehicle, so its visual settings are ours to change.
        model.vis.global_.offwidth = max(model.vis.global_.offwidth, width)
        model.vis.global_.offheight = max(model.vis.global_.offheight, height)
        model.vis.quality.offsamples = OFFSCREEN_SAMPLES
        self._gl = None
        self.context = None
        try:
            self._gl = cls(width, height)
            self._gl.make_current()
            self.context = mujoco.MjrContext(model, font_scale(height))
        except Exception as exc:
            self.close()
            raise RenderUnavailable(
                f"the {backend} OpenGL backend could not create a {width}x{height} render "
                f"context: {type(exc).__name__}: {exc}"
            ) from exc
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN, self.context)
        self.scene = mujoco.MjvScene(model, maxgeom=maxgeom)
        # Shadows and reflections off: together they cost more than the rest of a frame. The
        # skybox too: both cameras look down steeply enough never to see the sky.
        self.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = False
        self.scene.flags[mujoco.mjtRndFlag.mjRND_REFLECTION] = False
        self.scene.flags[mujoco.mjtRndFlag.mjRND_SKYBOX] = False
        self.rect = mujoco.MjrRect(0, 0, width, height)
        self._pixels = np.empty((height, width, 3), dtype=np.uint8)

    def render(self, labels: str = "", values: str = "", info: str = "") -> np.ndarray:
        """Render the scene, with MuJoCo's top-left text overlay if ``labels`` is not empty
        and ``info`` in the top-right corner; a new (H, W, 3) uint8 image."""
        self._gl.make_current()
        mujoco.mjr_render(self.rect, self.scene, self.context)
        if info:
            mujoco.mjr_overlay(
                mujoco.mjtFont.mjFONT_NORMAL,
                mujoco.mjtGridPos.mjGRID_TOPRIGHT,
                self.rect,
                info,
                "",
                self.context,
            )
        if labels:
            mujoco.mjr_overlay(
                mujoco.mjtFont.mjFONT_NORMAL,
                mujoco.mjtGridPos.mjGRID_TOPLEFT,
                self.rect,
                labels,
                values,
                self.context,
            )
        mujoco.mjr_readPixels(self._pixels, None, self.rect, self.context)
        return np.flipud(self._pixels).copy()  # OpenGL's rows run bottom-up

    def close(self) -> None:
        if self.context is not None:
            self.context.free()
            self.context = None
        if self._gl is not None:
            self._gl.free()
            self._gl = None

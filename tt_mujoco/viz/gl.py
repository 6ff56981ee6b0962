"""The OpenGL backend of offscreen rendering, chosen once per process.

The OpenGL platform of a process is fixed when PyOpenGL first loads one (``OpenGL.platform``),
not when MuJoCo is imported: ``import mujoco`` with ``MUJOCO_GL`` unset only loads GLFW, and this
module creates its own context instead of using :class:`mujoco.Renderer` (whose context class
was chosen at MuJoCo's import). So the choice is made at the first render by
:func:`select_gl_backend`:

- ``MUJOCO_GL`` set by the user: that backend (``egl``, ``osmesa`` or ``glfw``) and no other.
- unset: EGL (headless, through Mesa's llvmpipe on a CPU-only machine), else OSMesa. EGL is
  tried in a child interpreter first, because a failed EGL attempt in this process would leave
  PyOpenGL committed to EGL and make the OSMesa fallback impossible (and a broken driver may
  crash the process instead of raising).
- nothing works: :class:`RenderUnavailable`, with each backend's reason.
"""

from __future__ import annotations

import ctypes.util
import os
import subprocess
import sys

__all__ = [
    "GL_BACKENDS",
    "USER_GL_BACKENDS",
    "RenderUnavailable",
    "gl_context",
    "select_gl_backend",
]

#: Backends tried, in order, when ``MUJOCO_GL`` is unset.
GL_BACKENDS = ("egl", "osmesa")


#: Backends accepted from ``MUJOCO_GL`` (glfw needs a display).
USER_GL_BACKENDS = ("egl", "osmesa", "glfw")


_PROBE_TIMEOUT_S = 60.0


class RenderUnavailable(RuntimeError):  # noqa: N818 (name fixed by the CLI contract)
    """No OpenGL backend can render offscreen here; the message says what was tried and why."""


# --- OpenGL backend -------------------------------------------------------------------------------
_selected_backend: tuple[str, type] | None = None


# A child interpreter that creates a context and a MuJoCo render context (the fonts and the
# offscreen buffer are the first things to fail on a broken driver), then exits 0.
_PROBE = """
import sys
backend = sys.argv[1]
if backend == "egl":
    from mujoco.egl import GLContext
elif backend == "osmesa":
    from mujoco.osmesa import GLContext
else:
    from mujoco.glfw import GLContext
import mujoco
ctx = GLContext(32, 32)
ctx.make_current()
model = mujoco.MjModel.from_xml_string("<mujoco><worldbody><geom size='1'/></worldbody></mujoco>")
con = mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_100)
con.free()
ctx.free()
"""


def _import_gl_context(backend: str) -> type:
    if backend == "egl":
        from mujoco.egl import GLContext
    elif backend == "osmesa":
        from mujoco.osmesa import GLContext
    else:
        from mujoco.glfw import GLContext
    return GLContext


def _committed_platform() -> str | None:
    """The backend PyOpenGL has already loaded its platform for (it cannot change), or None."""
    platform = sys.modules.get("OpenGL.platform")
    if platform is None or getattr(platform, "PLATFORM", None) is None:
        return None
    name = type(platform.PLATFORM).__name__.lower()
    for backend in ("egl", "osmesa"):
        if backend in name:
            return backend
    return "glfw"  # GLX and the other window-system platforms serve GLFW contexts


#: Shared library each backend loads, and the Debian package that provides it.
_GL_LIBRARIES = {"egl": ("EGL", "libegl1 and libegl-mesa0"), "osmesa": ("OSMesa", "libosmesa6")}


def _missing_library(backend: str) -> str | None:
    """Why ``backend`` cannot load, if its shared library is not installed (else None)."""
    if backend not in _GL_LIBRARIES:
        return None
    name, package = _GL_LIBRARIES[backend]
    if ctypes.util.find_library(name) is None:
        return f"lib{name} is not installed (Debian: {package})"
    return None


def _probe(backend: str) -> str | None:
    """Try ``backend`` in a fresh interpreter: None if it works, else the reason."""
    env = dict(os.environ, MUJOCO_GL=backend)
    if backend in ("egl", "osmesa"):
        env["PYOPENGL_PLATFORM"] = backend
    else:
        env.pop("PYOPENGL_PLATFORM", None)
    try:
        proc = subprocess.run(
            [sys.executable, "-c", _PROBE, backend],
            env=env,
            capture_output=True,
            text=True,
            timeout=_PROBE_TIMEOUT_S,
            check=False,
        )
    except (OSError, subprocess.TimeoutExpired) as exc:
        return f"probe failed: {exc}"
    if proc.returncode == 0:
        return None
    lines = (proc.stderr or proc.stdout).strip().splitlines()
    return lines[-1] if lines else f"probe exited with code {proc.returncode}"


def _check_in_process(backend: str) -> type:
    cls = _import_gl_context(backend)
    ctx = cls(32, 32)
    try:
        ctx.make_current()
    finally:
        ctx.free()
    return cls


def select_gl_backend() -> str:
    """Choose, check and cache the OpenGL backend for offscreen rendering (see module doc).

    Returns
    -------
    str
        ``"egl"``, ``"osmesa"`` or ``"glfw"``.

    Raises
    ------
    RenderUnavailable
        If no backend can create a context; the message lists each backend's failure.
    """
    global _selected_backend
    if _selected_backend is not None:
        return _selected_backend[0]
    requested = os.environ.get("MUJOCO_GL", "").strip().lower()
    if requested:
        if requested not in USER_GL_BACKENDS:
            raise RenderUnavailable(
                f"MUJOCO_GL={requested!r} cannot render offscreen here: use one of "
                f"{', '.join(USER_GL_BACKENDS)} (or unset it to try {' then '.join(GL_BACKENDS)})"
            )
        candidates = [requested]
    else:
        candidates = list(GL_BACKENDS)
    committed = _committed_platform()
    if committed is not None:
        if committed not in candidates:
            raise RenderUnavailable(
                f"PyOpenGL already loaded its {committed!r} platform in this process, so "
                f"{'/'.join(candidates)} cannot be used: set MUJOCO_GL before starting Python"
            )
        candidates = [committed]
    reasons = []
    for i, backend in enumerate(candidates):
        missing = _missing_library(backend)
        if missing is not None:
            reasons.append(f"{backend}: {missing}")
            continue
        if i < len(candidates) - 1:
            # Not the last resort: check in a child so that a failure leaves PyOpenGL free.
            reason = _probe(backend)
            if reason is not None:
                reasons.append(f"{backend}: {reason}")
                continue
        try:
            cls = _check_in_process(backend)
        except Exception as exc:  # any failure of a GL stack means "not here"
            reasons.append(f"{backend}: {type(exc).__name__}: {exc}")
            break
        _selected_backend = (backend, cls)
        return backend
    raise RenderUnavailable(
        "no OpenGL backend can render offscreen here (" + "; ".join(reasons) + "). "
        "EGL needs libegl1 and libegl-mesa0 (Debian), OSMesa needs libosmesa6; "
        "set MUJOCO_GL to choose a backend"
    )


def gl_context() -> tuple[str, type]:
    """The selected backend's name and its OpenGL context class (selecting it first)."""
    select_gl_backend()
    return _selected_backend

"""The one visible form of a substitution: a function the compiled kernel replaces.

The closed loop's step is plain Python that CPython runs and numba compiles from the same
source (:mod:`tt_mujoco.sim.loop.kernel_sources` discovers what it calls). A few functions cannot be
compiled as written: MuJoCo's C step is called by its symbol, Python's code is called back
through C functions, Python's own ``math.hypot`` must be ported to give its last bit. Each is
marked here, beside its Python form, with why; :mod:`tt_mujoco.sim.loop._kernel` gives each its
compiled form, and ``tests/test_kernel_sources.py`` fails when a marked function has none or a
compiled form stands for an unmarked one. Importing this module imports nothing.
"""

from __future__ import annotations

__all__ = ["compiled_form", "compiled_form_reason"]

_MARK = "__compiled_form__"


def compiled_form(reason: str):
    """Mark a function whose compiled form differs from its Python source.

    Parameters
    ----------
    reason : str
        Why the kernel compiles another form, and what that form does.

    Returns
    -------
    callable
        A decorator that returns the function itself, marked.
    """

    def mark(fn):
        setattr(fn, _MARK, reason)
        return fn

    return mark


def compiled_form_reason(fn) -> str | None:
    """Why ``fn``'s compiled form differs (:func:`compiled_form`), None for an unmarked one."""
    return getattr(fn, _MARK, None)

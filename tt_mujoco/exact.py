"""Float functions whose compiled form must give Python's numbers to the last bit.

The shared step functions (:mod:`tt_mujoco.sim.loop.kernel_sources`) call these instead of their
:mod:`math` namesakes where numba's version differs from Python's: the compiled kernel
(:mod:`tt_mujoco.sim.loop._kernel`) overloads each with an exact port of CPython's algorithm, so the
compiled and the Python loop stay bit for bit the same.
"""

from __future__ import annotations

import math

from tt_mujoco.compiled_form import compiled_form

__all__ = ["hypot_of"]


@compiled_form("CPython's hypot algorithm ported, exact to the last bit (numba's differs)")
def hypot_of(x: float, y: float) -> float:
    """``math.hypot(x, y)``. Numba's own hypot (the C library's) differs from CPython's in the
    last bit for about 0.6 % of pairs; the kernel's overload is CPython's algorithm."""
    return math.hypot(x, y)

"""tt_mujoco.exact: the float functions whose compiled form gives Python's numbers."""

from __future__ import annotations

import numpy as np
import pytest

from tt_mujoco.sim.loop import compiled


@pytest.fixture(autouse=True)
def compile_now(monkeypatch):
    """Compile in the test process instead of in the background."""
    monkeypatch.setenv("TT_MUJOCO_COMPILE_NOW", "1")


def test_the_shared_hypot_compiles_to_pythons_to_the_last_bit():
    # Numba's math.hypot differs from CPython's in the last bit for about 0.6 % of pairs; the
    # shared functions call exact.hypot_of, which the kernel overloads with CPython's algorithm.
    import math

    from numba import njit

    from tt_mujoco.exact import hypot_of

    compiled.kernel()  # registers the overload
    hypot = njit(lambda x, y: hypot_of(x, y))
    rng = np.random.default_rng(7)
    scales = 10.0 ** rng.uniform(-300.0, 300.0, size=(20000, 1))
    pairs = (rng.normal(size=(20000, 2)) * scales).tolist()
    huge = 1.7e308
    special = [(0.0, 0.0), (-0.0, 3.0), (2.3e-308, 1e-300), (huge, huge), (huge, -huge),
               (math.inf, math.nan), (math.nan, 1.0), (-math.inf, 2.0)]  # fmt: skip
    for x, y in [*pairs, *special]:
        want, got = math.hypot(x, y), hypot(x, y)
        assert got == want or (math.isnan(want) and math.isnan(got)), (x, y, got, want)
    numba_hypot = njit(lambda x, y: math.hypot(x, y))  # what the overload is there for
    assert sum(numba_hypot(x, y) != math.hypot(x, y) for x, y in pairs) > 0

"""The registries of named parts (tt_mujoco/registry.py): a name is one part. Generated from
every Registry the package holds: each built-in name refuses another part, takes the same part
again, and is replaced only on purpose."""

from __future__ import annotations

import importlib
import pkgutil

import pytest

import tt_mujoco
from tt_mujoco.registry import Registry


def _registries() -> dict[str, Registry]:
    """Every Registry at the top of a module of the package, by where it lives."""
    found = {}
    for info in pkgutil.walk_packages(tt_mujoco.__path__, "tt_mujoco."):
        if info.name.endswith("__main__") or ".paper." in info.name:
            continue
        try:
            module = importlib.import_module(info.name)
        except ImportError:  # an optional extra's module
            continue
        for name, value in vars(module).items():
            if isinstance(value, Registry):
                found.setdefault(id(value), (f"{info.name}.{name}", value))
    return {label: registry for label, registry in found.values()}


REGISTRIES = _registries()


def test_the_registries_are_found():
    kinds = {registry.what for registry in REGISTRIES.values()}
    assert {"controller", "path", "metric", "disturbance"} <= kinds, kinds


@pytest.fixture
def restored():
    saved = {label: dict(r._items) for label, r in REGISTRIES.items()}
    yield
    for label, registry in REGISTRIES.items():
        registry._items.clear()
        registry._items.update(saved[label])


def _stranger():
    def stranger(*args, **kwargs):  # another part, defined here
        return None

    return stranger


CASES = [(label, name) for label, r in REGISTRIES.items() for name in r.names()]


@pytest.mark.parametrize(("label", "name"), CASES)
def test_a_built_in_name_refuses_another_part(restored, label, name):
    registry = REGISTRIES[label]
    built_in = registry[name]
    with pytest.raises(ValueError, match=f"name '{name}' is taken by the built-in"):
        registry.register(name, _stranger())
    assert registry[name] is built_in
    registry.register(name, built_in)  # the same part again
    replacement = _stranger()
    registry.register(name, replacement, replace=True)  # on purpose
    assert registry[name] is replacement


@pytest.mark.parametrize("label", list(REGISTRIES))
def test_a_users_name_takes_its_part_again_and_refuses_another(restored, label):
    registry = REGISTRIES[label]
    first = _stranger()
    registry.register("users_part", first)
    registry.register("users_part", _stranger())  # the same definition run again
    other = lambda *args: None  # noqa: E731 - a part defined elsewhere
    with pytest.raises(ValueError, match="is taken by"):
        registry.register("users-part", other)  # the same name, spelled otherwise


def test_finite_number_is_the_one_test_of_a_number():
    import math

    import numpy as np

    from tt_mujoco.registry import finite_number

    for good in (0, -3, 2.5, np.float32(1.5), np.int64(7), 1e308):
        assert finite_number(good) == float(good)
    for bad in (True, np.bool_(False), math.nan, -math.inf, 10**400, "1", 1j, None, [1.0], b"1"):
        assert finite_number(bad) is None, bad

"""A controller's gains: a preset, a table of overrides, checked once."""

from __future__ import annotations

import math
from collections.abc import Mapping
from numbers import Real

__all__ = ["resolve_gains"]


def _check_positive(key: str, value) -> float:
    if isinstance(value, bool) or not isinstance(value, Real):
        raise ValueError(f"gain {key}={value!r} is not allowed: it must be a finite number > 0")
    value = float(value)
    if not (math.isfinite(value) and value > 0.0):
        raise ValueError(f"gain {key}={value!r} is not allowed: it must be a finite number > 0")
    return value


def resolve_gains(
    controller: str,
    presets: Mapping[str, Mapping[str, float]],
    default_preset: str,
    gains: str | Mapping | None,
) -> tuple[dict[str, float], str]:
    """Turn a ``gains`` argument into a full, validated gain dict.

    Parameters
    ----------
    controller : str
        Controller name, for error messages.
    presets : mapping
        Preset name -> complete gain dict.
    default_preset : str
        Preset used when ``gains`` is None or a dict without a ``"preset"`` key.
    gains : str, dict or None
        A preset name; or a dict overriding individual gains of a preset (the dict may name its
        base preset under the key ``"preset"``); or None for the default preset.

    Returns
    -------
    values : dict
        Gain name -> float, every key of the preset.
    preset : str
        The base preset's name.
    """
    allowed_presets = ", ".join(repr(k) for k in presets)
    overrides: Mapping = {}
    preset = default_preset
    if gains is None:
        pass
    elif isinstance(gains, str):
        preset = gains
    elif isinstance(gains, Mapping):
        overrides = dict(gains)
        preset = overrides.pop("preset", default_preset)
        if not isinstance(preset, str):
            raise ValueError(
                f"gains preset={preset!r} for {controller} is not allowed: use one of "
                f"{allowed_presets}"
            )
    else:
        raise ValueError(
            f"gains={gains!r} for {controller} is not allowed: use a preset name "
            f"({allowed_presets}), a dict of gains or None"
        )
    if preset not in presets:
        raise ValueError(
            f"gains preset={preset!r} for {controller} is not allowed: use one of {allowed_presets}"
        )
    values = dict(presets[preset])
    for key, value in overrides.items():
        if key not in values:
            allowed_keys = ", ".join(repr(k) for k in values)
            raise ValueError(
                f"gain {key!r} (value {value!r}) is not a gain of {controller}: allowed keys are "
                f"{allowed_keys} and 'preset'"
            )
        values[key] = _check_positive(key, value)
    return values, preset

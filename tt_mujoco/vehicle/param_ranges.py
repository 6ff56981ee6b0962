"""What each vehicle parameter may be: one declared range per field of
:class:`~tt_mujoco.vehicle.params.Params` and :class:`~tt_mujoco.vehicle.params.Trailer`.

Every route (``--param``, a TOML ``[params]`` table, a trailer's table, ``Params(...)`` in
Python, an identified vehicle's ``config.toml``) builds a :class:`Params`, which checks each
field here: a value outside its range is refused, naming the field, the value and the range.

The ranges span any vehicle from a bench robot (the paper's: 6-9 kg bodies, 0.3-0.4 m links)
to a road train (100 t, 50 m), and stop well short of where the model's arithmetic breaks (the
square of a length or a ratio of inertias overflowing or underflowing a float): a value beyond
them is a typo or a unit slip, not a vehicle.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["INERTIA_FIELDS", "MASS_FIELDS", "RANGES", "in_range"]

# Fields that scale with --param-scale (plant parameter uncertainty, docs/model.md Section 8).
MASS_FIELDS = ("Mf", "Mr", "Mw", "Mc1", "Mc2")
INERTIA_FIELDS = ("Ifd", "Ird", "Iwd", "Ic1", "Ic2", "Iw")

_MASS = (1e-4, 1e6, "kg")
_INERTIA = (1e-9, 1e8, "kg m^2")
_LENGTH = (1e-3, 100.0, "m")

#: Field name -> (lowest, highest, unit), both ends allowed.
RANGES: dict[str, tuple[float, float, str]] = {
    **{name: _MASS for name in MASS_FIELDS},
    **{name: _INERTIA for name in INERTIA_FIELDS},
    "L": _LENGTH,
    "L0": _LENGTH,
    "r": (1e-3, 10.0, "m"),
    "d": (1e-3, 50.0, "m"),
    "torque_limit": (1e-6, 1e7, "N m"),
    "axle_slew_rate": (1e-6, 1e8, "rad/s"),  # 1e6: a study's "unbounded"
    "friction": (1e-6, 100.0, ""),
    "impratio": (1e-3, 1e4, ""),
    # a flat plate has 0.5: less breaks the triangle inequality of the body inertias
    "body_tilt_inertia_ratio": (0.5, 1e3, ""),
    "motor_kt": (1e-6, 1e4, "N m/A"),
    "motor_resistance": (1e-6, 1e6, "ohm"),
    "motor_voltage": (1e-6, 1e6, "V"),
    "motor_current_limit": (1e-6, 1e6, "A"),
    "motor_gear": (1e-3, 1e4, ""),
    "motor_lag": (1e-6, 1e3, "s"),
    "drag_area_tractor": (1e-9, 1e4, "m^2"),
    "drag_area_trailer": (1e-9, 1e4, "m^2"),
}


def in_range(name: str, value, label: str = "") -> float:
    """``value`` as a float, if it is a real number in ``name``'s range (:data:`RANGES`).

    Parameters
    ----------
    name : str
        The field, a key of :data:`RANGES`.
    value : object
        What was given.
    label : str, optional
        Put before the name in the message (``"trailer "``).

    Raises
    ------
    ValueError
        Not a real number, not finite, or outside the range; the message names the field,
        the value and the range.
    """
    low, high, unit = RANGES[name]
    if isinstance(value, np.integer | np.floating):  # a NumPy scalar: its value
        value = value.item()
    allowed = f"it must be a finite number in [{low:g}, {high:g}]" + (f" {unit}" if unit else "")
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ValueError(f"{label}{name}={value!r} is not allowed: {allowed}")
    if not (math.isfinite(value) and low <= value <= high):
        raise ValueError(f"{label}{name}={value!r} is not allowed: {allowed}")
    return float(value)

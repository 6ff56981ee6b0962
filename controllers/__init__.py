"""Velocity controllers for the tractor-trailer (SPEC Section 9): ISMC-STA, PID, FBL.

They track ``z = (v, omega)`` with wheel torques ``(T_r, T_l)`` using the *nominal* reduced model
``z_dot = f + g tau`` given as a plain-float callable (:func:`reduced_model`). Nothing here
imports MuJoCo.

>>> from tt_mujoco.vehicle.params import Params
>>> ctrl = make_controller("ismc_sta", reduced_model(Params()))
>>> T_r, T_l = ctrl.step(0.001, 0.0, 0.0, 0.0, 0.5, 0.0, 0.0, 0.0)
"""

from __future__ import annotations

from collections.abc import Mapping

from tt_mujoco.controllers.base import Controller, ModelFn, reduced_model
from tt_mujoco.controllers.fbl import FblController
from tt_mujoco.controllers.ismc_sta import IsmcStaController
from tt_mujoco.controllers.pid import PidController

__all__ = [
    "CONTROLLERS",
    "Controller",
    "FblController",
    "IsmcStaController",
    "ModelFn",
    "PidController",
    "make_controller",
    "reduced_model",
]

#: Controller name -> class, in the order the paper introduces them.
CONTROLLERS: dict[str, type[Controller]] = {
    "ismc_sta": IsmcStaController,
    "pid": PidController,
    "fbl": FblController,
}


def make_controller(
    name: str,
    model: ModelFn,
    torque_limit: float = 15.0,
    gains: str | Mapping | None = None,
    anti_windup: bool = True,
) -> Controller:
    """Build a controller by name.

    Parameters
    ----------
    name : str
        ``"ismc_sta"``, ``"pid"`` or ``"fbl"`` (case and ``-``/``_`` are not significant).
    model : callable
        Nominal model ``(phi, v, omega) -> (f1, f2, g11, g12, g21, g22)``, e.g.
        ``reduced_model(params)``.
    torque_limit : float
        Wheel torque saturation, N m (paper Section 6.2: 15).
    gains : str, dict or None
        A preset name (ISMC-STA: ``"paper_6_1"`` (default), ``"paper_6_2"``; PID and FBL:
        ``"paper_6_2"``), a dict overriding individual gains (optionally with a ``"preset"``
        key naming the base), or None for the default.
    anti_windup : bool
        Conditional integration under saturation (see :mod:`controllers.base`).

    Returns
    -------
    Controller
    """
    key = name.strip().lower().replace("-", "_") if isinstance(name, str) else None
    if key not in CONTROLLERS:
        allowed = ", ".join(repr(k) for k in CONTROLLERS)
        raise ValueError(f"controller name={name!r} is not allowed: use one of {allowed}")
    return CONTROLLERS[key](model, torque_limit=torque_limit, gains=gains, anti_windup=anti_windup)

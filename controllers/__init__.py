"""Controllers for the tractor-trailer: the protocol, the registry, and ISMC-STA, PID and FBL.

Every controller implements :class:`Controller` (``compute(t, measurement, reference) ->
(T_r, T_l)``, built from a :class:`ControllerSetup`). The built-in laws track ``z = (v, omega)``
with the *nominal* reduced model ``z_dot = f + g tau`` (docs/model.md Section 9). Nothing here
imports MuJoCo.

A controller is chosen by name from :data:`CONTROLLERS` or by hook
(``package.module:Class`` or ``path/to/file.py:Class``); :func:`controller_class` resolves
either, :func:`build_controller` builds it for a run.

>>> from tt_mujoco.vehicle.params import Params
>>> ctrl = make_controller("ismc_sta", reduced_model(Params()))
>>> T_r, T_l = ctrl.step(0.001, 0.0, 0.0, 0.0, 0.5, 0.0, 0.0, 0.0)
"""

from __future__ import annotations

from collections.abc import Mapping

from tt_mujoco.controllers.base import (
    Controller,
    ControllerSetup,
    ModelFn,
    Reference,
    VelocityController,
    reduced_model,
)
from tt_mujoco.controllers.fbl import FblController
from tt_mujoco.controllers.ismc_sta import IsmcStaController
from tt_mujoco.controllers.lqr import LqrController
from tt_mujoco.controllers.nmpc import NmpcController
from tt_mujoco.controllers.pid import PidController
from tt_mujoco.controllers.plain import PlainLawController, plain_law
from tt_mujoco.controllers.pure_pursuit import pure_pursuit
from tt_mujoco.controllers.smc import SmcController
from tt_mujoco.controllers.stanley import StanleyController

from tt_mujoco.defaults import TORQUE_LIMIT
from tt_mujoco.registry import Registry

__all__ = [
    "CONTROLLERS",
    "Controller",
    "ControllerSetup",
    "FblController",
    "IsmcStaController",
    "LqrController",
    "ModelFn",
    "NmpcController",
    "PidController",
    "PlainLawController",
    "Reference",
    "SmcController",
    "StanleyController",
    "VelocityController",
    "build_controller",
    "compiled_laws",
    "controller_class",
    "make_controller",
    "plain_law",
    "reduced_model",
]

#: Controller name -> class, in the order the paper introduces them. ``CONTROLLERS.register``
#: adds one; a hook ``module:Class`` or ``file.py:Class`` needs no registration.
CONTROLLERS = Registry("controller")
CONTROLLERS.register("ismc_sta", IsmcStaController)
CONTROLLERS.register("pid", PidController)
CONTROLLERS.register("fbl", FblController)
CONTROLLERS.register("smc", SmcController)
CONTROLLERS.register("stanley", StanleyController)
CONTROLLERS.register("pure_pursuit", pure_pursuit)
CONTROLLERS.register("lqr", LqrController)
CONTROLLERS.register("nmpc", NmpcController)


def compiled_laws() -> dict[str, type[VelocityController]]:
    """The built-in velocity laws, by registered name, in registration order: the registered
    classes of this package whose :attr:`~VelocityController.LAW` is a plain-number function of
    their own module. The compiled loop runs each (:mod:`tt_mujoco.sim.loop.kernel_sources`); adding
    one is its module and its line in :data:`CONTROLLERS`."""
    return {
        name: cls
        for name, cls in ((name, CONTROLLERS[name]) for name in CONTROLLERS)
        if isinstance(cls, type)
        and issubclass(cls, VelocityController)
        and cls.__module__.startswith("tt_mujoco.controllers.")
        and getattr(getattr(cls, "LAW", None), "__module__", None) == cls.__module__
    }


def controller_class(spec: str) -> type[Controller]:
    """The controller class a name or hook stands for.

    Raises
    ------
    ValueError
        Unknown name, a hook that does not load, or an object that is not a
        :class:`Controller` subclass.
    """
    cls = CONTROLLERS.resolve(spec)
    if not (isinstance(cls, type) and issubclass(cls, Controller)):
        raise ValueError(
            f"controller {spec!r} is not allowed: {cls!r} is not a subclass of "
            "tt_mujoco.controllers.Controller"
        )
    return cls


def build_controller(
    spec: str, setup: ControllerSetup, gains: str | Mapping | None = None
) -> Controller:
    """Build the controller named ``spec`` (name or hook) for a run."""
    return controller_class(spec).from_setup(setup, gains)


def make_controller(
    name: str,
    model: ModelFn,
    torque_limit: float = TORQUE_LIMIT,
    gains: str | Mapping | None = None,
    anti_windup: bool = True,
) -> VelocityController:
    """Build a built-in velocity controller by name, outside a run.

    Parameters
    ----------
    name : str
        A built-in velocity law's name (:func:`compiled_laws`: ``"ismc_sta"``, ``"pid"``,
        ``"fbl"``, ...; case and ``-``/``_`` are not significant).
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
        Conditional integration under saturation (see :mod:`tt_mujoco.controllers.base`).

    Returns
    -------
    VelocityController
    """
    builtin = tuple(compiled_laws())
    key = name.strip().lower().replace("-", "_") if isinstance(name, str) else None
    if key not in builtin:
        allowed = ", ".join(repr(k) for k in builtin)
        raise ValueError(f"controller name={name!r} is not allowed: use one of {allowed}")
    return CONTROLLERS[key](model, torque_limit=torque_limit, gains=gains, anti_windup=anti_windup)

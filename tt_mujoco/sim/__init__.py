"""The simulation: scenario -> build -> stepper -> time series, on either plant.

A :class:`Scenario` holds the whole configuration of a run; :func:`build` validates it and makes
its parts; a :class:`Stepper` runs the closed loop step by step on a :class:`Plant` (MuJoCo or
the reduced ODE); :func:`simulate` drives it with the scenario's controller to a :class:`Result`
(time series, metrics, outcome). The same controller, target and disturbance drive both plants,
so their results compare like for like:

- the controller sees the measurement (plus optional noise) and the *nominal* reduced model;
- the plant is built from ``nominal.scaled(param_scale)``, times ``plant_scale`` per field
  (parameter uncertainty, docs/model.md Section 8);
- the disturbance Delta(t) (default the paper's, Section 6.1) enters as matched wheel torques
  ``g_nominal(phi)^-1 Delta(t)`` added outside the actuators' saturation, on both plants; in
  ``wrench`` mode MuJoCo instead gets the equivalent force and yaw moment on the chassis, which
  must be transmitted by the tyres and can exceed traction.

Divergence is detected, never hidden: a jackknife (|beta| or |phi| near 90 deg), a singular
nominal model, non-finite numbers or MuJoCo warnings stop the run, which keeps every sample up
to that point and reports the time and state.
"""

import sys
import types

from tt_mujoco.defaults import JACKKNIFE_DEG, MAX_SPEED

#: Where each name of the package's API is defined: loaded on first use (PEP 562), so that a
#: command that needs only the options (``--help``, a scenario file's check) does not import
#: the simulation, MuJoCo included.
_WHERE = {
    "Build": "build",
    "build": "build",
    "disturbance": "parts.disturbances",
    "Plant": "parts.plant",
    "StopRun": "parts.plant",
    "DISTURBANCE_MODES": "scenario",
    "PLANTS": "scenario",
    "SCHEMA": "scenario",
    "TARGETS": "scenario",
    "Scenario": "scenario",
    "jackknife_phi_deg": "scenario",
    "Result": "simulate",
    "simulate": "simulate",
    "Stepper": "loop.stepper",
    "COLUMNS": "loop.timeseries",
}


def __getattr__(name: str):
    if name in _WHERE:
        import importlib

        return getattr(importlib.import_module(f"tt_mujoco.sim.{_WHERE[name]}"), name)
    raise AttributeError(f"module 'tt_mujoco.sim' has no attribute {name!r}")


class _Package(types.ModuleType):
    """This package: ``build`` and ``simulate`` stay the functions when their modules of the
    same names are imported (the import system binds a submodule to its package's name)."""

    def __setattr__(self, name: str, value) -> None:
        if name in _WHERE and isinstance(value, types.ModuleType):
            return  # the name is the API's: __getattr__ gives the function
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package


__all__ = [
    "COLUMNS",
    "DISTURBANCE_MODES",
    "JACKKNIFE_DEG",
    "MAX_SPEED",
    "PLANTS",
    "SCHEMA",
    "TARGETS",
    "Build",
    "Plant",
    "Result",
    "Scenario",
    "Stepper",
    "StopRun",
    "build",
    "disturbance",
    "jackknife_phi_deg",
    "simulate",
]

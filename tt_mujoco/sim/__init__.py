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

from tt_mujoco.defaults import JACKKNIFE_DEG, MAX_SPEED
from tt_mujoco.sim.build import Build, build
from tt_mujoco.sim.disturbances import disturbance
from tt_mujoco.sim.plant import Plant, StopRun
from tt_mujoco.sim.scenario import (
    DISTURBANCE_MODES,
    PLANTS,
    SCHEMA,
    TARGETS,
    Scenario,
    jackknife_phi_deg,
)
from tt_mujoco.sim.simulate import Result, simulate
from tt_mujoco.sim.stepper import Stepper
from tt_mujoco.sim.timeseries import COLUMNS

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

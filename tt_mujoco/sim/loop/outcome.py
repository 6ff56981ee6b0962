"""Why an episode ended, in words: the status and message :func:`outcome` makes from the stop
record, as :func:`tt_mujoco.sim.simulate.run_episode` reports it, whichever loop ran it (a
compiled plain-number law that failed is replayed in Python for its own message:
:func:`raised_again`)."""

from __future__ import annotations

import math

import numpy as np

from tt_mujoco.defaults import JACKKNIFE_DEG
from tt_mujoco.sim.loop import law as law_part
from tt_mujoco.sim.loop import records, step
from tt_mujoco.sim.scenario import jackknife_phi_deg

__all__ = ["NOMINAL_SINGULAR", "blew_up_message", "jackknife_message", "outcome", "raised_again"]


def blew_up_message(t: float, v: float) -> str:
    return f"state blew up at t={t:.3f} s: v={v!r}"


def jackknife_message(t, phi, beta, eta, x, y, v, hitch: int = 1) -> str:
    """Which limit the hitch reached, and why it is one."""
    phi_deg, beta_deg = math.degrees(phi), math.degrees(beta)
    if abs(beta_deg) >= JACKKNIFE_DEG:
        why = (
            f"|beta| = {abs(beta_deg):.1f} deg reached {JACKKNIFE_DEG:g} deg: the steered axle "
            f"nears 90 deg, where it would roll across the trailer (phi={phi_deg:.1f} deg)"
        )
    else:
        limit = jackknife_phi_deg(eta)
        reason = (
            "the trailer stands across the tractor"
            if limit >= 90.0
            else f"with eta={eta:g} the axle's beta = eta phi would reach {JACKKNIFE_DEG:g} deg"
        )
        why = (
            f"|phi| = {abs(phi_deg):.1f} deg reached {limit:.4g} deg: {reason} "
            f"(beta={beta_deg:.1f} deg)"
        )
    return (
        f"jackknife at t={t:.3f} s, hitch {hitch}: {why}; x={x:.3f} m, y={y:.3f} m, v={v:.3f} m/s"
    )


def outcome(status, stop_record, stepper, controller, k) -> tuple[str, str]:
    """``(status, message)`` of an episode that ended at step ``k`` with ``status`` (a stop
    code of :mod:`tt_mujoco.sim.loop.step`), from the ``stop`` record."""
    from tt_mujoco.controllers.base import LAW_NOT_FINITE, LAW_RAISED, LAW_SINGULAR
    from tt_mujoco.controllers.plain import PlainLawController
    from tt_mujoco.sim import usercode
    from tt_mujoco.sim.parts.plant import StopRun
    from tt_mujoco.vehicle.reduced import SingularityError

    t = k * stepper.dt
    value = records.values_of(stop_record)
    if status == step.FINISHED:
        return "ok", f"completed {stepper.built.duration:.3f} s"
    if status == step.BLEW_UP:
        return "diverged", blew_up_message(t, value["v"])
    if status == step.JACKKNIFE:
        phi, beta, x, y, v = (value[name] for name in ("phi", "beta", "x", "y", "v"))
        hitch = int(value["hitch"])
        eta = stepper.eta if hitch == 1 else value["eta"]
        return "jackknife", jackknife_message(t, phi, beta, eta, x, y, v, hitch=hitch)
    if status == step.COLLISION:
        from tt_mujoco.vehicle.footprint import unit_names

        unit = unit_names(stepper.built.plant_params.n_trailers)[int(value["unit"])]
        obstacle = stepper.built.world.all_obstacles[int(value["obstacle"])].name
        return "collision", (
            f"collision at t={t:.3f} s: the {unit} touched obstacle {obstacle!r} "
            f"({-1000 * value['gap']:.1f} mm deep; the tractor at x={value['x']:.3f}, "
            f"y={value['y']:.3f} m)"
        )
    if status == step.WARNING:
        import mujoco

        from tt_mujoco.sim.parts.plant_mujoco import warning_message

        return "diverged", warning_message(mujoco.mjtWarning(int(value["warning"])).name, t)
    if status == step.SINGULAR:
        err = SingularityError(value["phi"], value["eta"])
        return "jackknife", f"jackknife at t={t + stepper.dt:.3f} s: {err}"
    # LAW_FAILED: the nominal model's singularity, or the law's own failure
    law_status = int(value["law_status"])
    if law_status in (LAW_RAISED, LAW_NOT_FINITE) and isinstance(controller, PlainLawController):
        # what its Python form raises there, as the Python loop would have stopped it (numba
        # gives NaN for math's domain errors, where Python raises ValueError)
        again = raised_again(stepper, controller, t)
        if again is not None:
            return again
        if law_status == LAW_RAISED:
            return "failed", (
                f"{usercode.controller_label(stepper.built)} failed at t={t:.3f} s: its compiled "
                "form raised where its Python form does not (numba's semantics differ from "
                "Python's there: integer width, an error model)"
            )
    u1, u2 = value["u1"], value["u2"]
    if isinstance(controller, PlainLawController):  # the user's law returned no torques
        try:
            usercode.checked_torques((u1, u2), usercode.controller_label(stepper.built), t)
        except StopRun as stop_run:
            if law_status == LAW_NOT_FINITE:
                return stop_run.status, stop_run.message
    try:
        if law_status == NOMINAL_SINGULAR:
            raise SingularityError(value["phi"], value["eta"])
        g = tuple(value[name] for name in ("g11", "g12", "g21", "g22"))
        controller.raise_for(law_status, g if law_status == LAW_SINGULAR else (), u1, u2)
    except FloatingPointError as err:
        return "diverged", f"controller failed at t={t:.3f} s: {err}"
    raise AssertionError(f"unknown status {status}")  # pragma: no cover


def _floats(record) -> list[float]:
    """A record's values in field order (a structured array's first row, or a plain array)."""
    values = np.asarray(record)
    if values.dtype.names:
        return [float(values.reshape(-1)[0][name]) for name in values.dtype.names]
    return [float(v) for v in values.reshape(-1)]


def raised_again(stepper, controller, t: float) -> tuple[str, str] | None:
    """``(status, message)`` of a compiled plain-number law that failed at time ``t``, as the
    Python loop stops it (the traceback kept): its Python form called with what the compiled
    law was given at that step raises what it raised; None where it does not raise."""
    from tt_mujoco.controllers.base import Nominal
    from tt_mujoco.controllers.plain import LawReference, LawState
    from tt_mujoco.guard import users_failure
    from tt_mujoco.sim import usercode
    from tt_mujoco.sim.parts.measure import Measurement

    law = stepper._episode.law
    m = Measurement(*_floats(law.measurement_values))
    r = LawReference(*_floats(law.reference))
    model = Nominal(*_floats(law.model))
    state = LawState(controller.STATE)
    for name, value in zip(controller.STATE, _floats(law.user_state), strict=False):
        setattr(state, name, value)
    who = usercode.controller_label(stepper.built)
    try:
        controller.call_law(m, r, model, state)
    except BaseException as err:
        if not users_failure(err):
            raise
        stop = usercode.failure(who, t, err)
        stepper.stop_details = stop.details
        return stop.status, stop.message
    return None


#: ``stop.law_status`` of the nominal model's own singularity
NOMINAL_SINGULAR = int(law_part.NOMINAL_SINGULAR)

"""The controller protocol, and the shared machinery of the built-in velocity controllers.

**The protocol** (:class:`Controller`). A controller is built once per run from a
:class:`ControllerSetup` (the nominal parameters and model, the torque limit, the control period
and the reference path) and its gains, and is then asked at every control step for the wheel
torques ``(T_r, T_l)`` given the time, the full measurement (:class:`tt_mujoco.sim.parts.measure.
Measurement`, with the scenario's measurement noise and sensor faults already applied) and the
target (:class:`Reference`: the reference point, its arc length and curvature, the velocity
targets and their derivatives, and the path itself for nearest-point queries). The loop clips
the torques at the torque limit. A user controller subclasses :class:`Controller`, implements
:meth:`Controller.compute` and is named ``--controller package.module:Class`` or
``--controller path/to/file.py:Class``; see ``examples/kanayama.py`` and ``docs/controllers.md``.

**The built-in laws** (:class:`VelocityController`: ISMC-STA, PID, FBL) track ``z = (v, omega)``
of the reduced model.

Every controller tracks ``z = (v, omega)`` of the reduced model ``z_dot = f + g tau``
(docs/model.md Section 4; the paper's eq. 22) with ``tau = (T_r, T_l)``, and computes

    tau = sat(g^-1 r),    r = z_d_dot - f - (feedback),

where ``r`` is the closed-loop acceleration the law asks for. The controllers never see MuJoCo:
they get the *nominal* model as a callable ``model(phi, v, omega) -> (f1, f2, g11, g12, g21, g22)``
of plain floats (see :func:`reduced_model`), so a plant with other parameters, noise or a
disturbance is uncertainty the law has to cope with.

Timing convention (shared by all controllers). ``step(dt, ...)`` is called once per control
period with the measurement at time ``t_k``; ``dt`` is the time elapsed since the previous call
(the control period). Integrators advance with explicit Euler and a zero-order hold of what
they integrate: ``I(t_k) = I(t_(k-1)) + dt * x(t_(k-1))``; the torque at ``t_k`` then uses
``I(t_k)``. On the first call after :meth:`Controller.reset` there is nothing to integrate yet.

Saturation and anti-windup. Each torque is clipped to ``|T_i| <= torque_limit`` (15 N m, paper
Section 6.2). With ``anti_windup=True`` (the default) the integrators use *conditional
integration* (clamping): if a torque saturated at ``t_k``, an integrator is frozen over the next
interval when its increment would push a saturated torque further into saturation. An
increment ``+dt * x_i`` in channel ``i`` (v or omega) enters ``r_i`` with a negative sign in
every law here, so it moves torque ``j`` by ``-c * ginv[j][i] * x_i`` (``c > 0``); it is
frozen when ``s_j * ginv[j][i] * x_i < 0`` for a torque ``j`` saturated with sign ``s_j``.
Integrators that would *unwind* the saturation keep integrating, so nothing sticks.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from numbers import Real
from typing import Any, ClassVar, NamedTuple

from tt_mujoco.controllers.gains import resolve_gains
from tt_mujoco.controllers.nominal import ModelFn, reduced_model

from tt_mujoco.defaults import TORQUE_LIMIT

__all__ = [
    "Controller",
    "ControllerSetup",
    "LawStep",
    "ModelFn",
    "Nominal",
    "Reference",
    "Saturation",
    "Tracking",
    "VelocityController",
    "reduced_model",
    "resolve_gains",
]


_INF = math.inf

# |det g| below this fraction of |g11 g22| + |g12 g21| is treated as singular: g^-1 would then
# amplify rounding errors in f and z_d_dot by more than 1e12.
_SINGULAR_RTOL = 1e-12


@dataclass(frozen=True)
class ControllerSetup:
    """What a controller is built with, once per run.

    Attributes
    ----------
    params : tt_mujoco.vehicle.params.Params
        The controller's *nominal* parameters (the plant's may differ).
    model : ModelFn
        The nominal reduced model ``(phi, v, omega) -> (f1, f2, g11, g12, g21, g22)``.
    torque_limit : float
        Wheel torque saturation (N m); the loop clips at it whatever the controller returns.
    control_dt : float
        The control period (s): ``compute`` is called every ``control_dt``.
    path : tt_mujoco.reference.paths.ReferencePath or None
        The reference path (``pose_at(s)``, ``curvature(s)``, ``dense()``, ``length``).
    reverse : bool
        Whether the run drives the path backwards (``--reverse``: v_d <= 0, the trailer leads).
    axle_slew_rate : float
        How fast the trailers' axles turn at most (rad/s) where actuators steer them (the path
        schedule, ``Params.axle_slew_rate``); infinite for a linkage. The built-in laws' model
        takes the gains the axles can follow (:func:`reduced_model`).
    """

    params: Any
    model: ModelFn
    torque_limit: float = TORQUE_LIMIT
    control_dt: float = 0.001
    path: Any = None
    reverse: bool = False
    axle_slew_rate: float = _INF


class Reference:
    """The target at one control step.

    Attributes
    ----------
    t : float
        Time (s).
    s : float
        Arc length of the reference point on the path (m).
    kappa : float
        Signed path curvature at ``s`` (1/m).
    v_d, omega_d, v_d_dot, omega_d_dot : float
        Velocity targets and their time derivatives (with path feedback on: the modified ones).
    path : ReferencePath
        The reference path.
    pose : tuple
        ``(x_ref, y_ref, theta_ref)``, the path at ``s`` (computed on first access).
    """

    __slots__ = ("_pose", "kappa", "omega_d", "omega_d_dot", "path", "s", "t", "v_d", "v_d_dot")

    def __init__(self, t, s, kappa, v_d, omega_d, v_d_dot, omega_d_dot, path):
        self.t, self.s, self.kappa, self.path = t, s, kappa, path
        self.v_d, self.omega_d, self.v_d_dot, self.omega_d_dot = v_d, omega_d, v_d_dot, omega_d_dot
        self._pose = None

    @property
    def pose(self) -> tuple[float, float, float]:
        if self._pose is None:
            self._pose = tuple(self.path.pose_at(self.s))
        return self._pose

    def __repr__(self) -> str:
        return (
            f"Reference(t={self.t!r}, s={self.s!r}, kappa={self.kappa!r}, v_d={self.v_d!r}, "
            f"omega_d={self.omega_d!r})"
        )


class Controller(ABC):
    """The controller protocol: every controller, built-in or the user's, implements it.

    Subclasses set :attr:`name` and, for tunable gains, :attr:`PRESETS` (preset name -> gain
    dict) and :attr:`DEFAULT_PRESET`; ``gains`` is then a preset name or a dict of overrides
    (``--gains``, a TOML ``[gains]`` table, ``gain.<name>=...`` in a sweep), validated here.
    They implement :meth:`compute` and, if they keep state, :meth:`reset`.

    Parameters
    ----------
    setup : ControllerSetup
    gains : str, dict or None
    """

    name: ClassVar[str] = "controller"
    #: Whether the controller drives the path backwards too (``--reverse``); a run that
    #: reverses with one that does not is refused before it starts.
    REVERSE: ClassVar[bool] = True
    #: Whether, backing up, the controller steers the train itself (from the path and the
    #: measured hitch angles): the loop then gives it the path's own reverse target, where
    #: otherwise the hitch cascade (:mod:`tt_mujoco.controllers.backing`) sets the tractor's
    #: yaw-rate target ``reference.omega_d`` and starts the trailers on the path. The run's
    #: ``metrics.json`` says which drove it (``reversing``).
    BACKS_UP_ITSELF: ClassVar[bool] = False
    PRESETS: ClassVar[dict[str, dict[str, float]]] = {"default": {}}
    DEFAULT_PRESET: ClassVar[str] = "default"
    #: The last unsaturated torque request (T_r, T_l), for logging; None: what compute returned.
    command: tuple[float, float] | None = None

    def __init__(self, setup: ControllerSetup, gains: str | Mapping | None = None):
        if not isinstance(setup, ControllerSetup):
            raise ValueError(
                f"setup={setup!r} is not allowed: controllers are built with a ControllerSetup"
            )
        self.setup = setup
        self._gains, self.preset = self.resolve_gains(gains)

    @classmethod
    def resolve_gains(cls, gains: str | Mapping | None) -> tuple[dict[str, float], str]:
        """``(values, preset)``: the class's gains for ``gains`` (a preset name, a dict of
        overrides, or None), checked (:func:`resolve_gains`). The one place a run's
        ``--gains`` is resolved: the controller's construction, the sweep's table and a
        scenario file's check all call it."""
        return resolve_gains(cls.name, cls.PRESETS, cls.DEFAULT_PRESET, gains)

    @classmethod
    def from_setup(cls, setup: ControllerSetup, gains: str | Mapping | None = None) -> Controller:
        """Build the controller for a run (the loop calls this)."""
        return cls(setup, gains=gains)

    @property
    def gains(self) -> dict:
        """The gains in use plus the base preset's name, JSON-serialisable; accepted back as
        ``gains=`` to rebuild the same controller."""
        return {"preset": self.preset, **self._gains}

    def reset(self) -> None:  # noqa: B027 - optional hook: stateless controllers need none
        """Forget everything from a previous run (called before the first step)."""

    def steering_changed(self, etas) -> None:  # noqa: B027 - optional hook
        """The plant's passive gains are now ``etas`` (eta_1..eta_N), set by a scheduled
        steering (``--eta path`` or ``scheduled``): called before the first step and after
        every change. A law with a model of the vehicle updates it; the default ignores it."""

    def report(self) -> dict:
        """Figures of the whole run for ``metrics.json`` (under ``controller``): numbers or
        None, keyed by name; empty (the default) adds nothing. Called once after the run."""
        return {}

    def log(self, name: str, value: float) -> None:
        """Record a signal of this step (an error, an integrator, a prediction): it lands in
        the run's time series as the column ``ctrl_<name>``, NaN at the steps it was not
        logged. Call it from :meth:`compute`; the last value given in a step counts.

        Parameters
        ----------
        name : str
            Letters, digits and ``_``, starting with a letter.
        value : float
        """
        self.__dict__.setdefault("_signals", {})[name] = value

    def take_signals(self) -> dict:
        """The signals logged since the last call, and forget them (the loop calls this)."""
        return self.__dict__.pop("_signals", None) or {}

    @abstractmethod
    def compute(self, t: float, measurement, reference: Reference) -> tuple[float, float]:
        """Wheel torques ``(T_r, T_l)`` in N m for this control step.

        Parameters
        ----------
        t : float
            Time (s).
        measurement : tt_mujoco.sim.parts.measure.Measurement
            The vehicle as measured: tractor pose ``x, y, theta`` and velocities ``v, omega``;
            hitch and steering angles ``phi, beta``; trailer axle ``x0, y0, theta0, v0``;
            wheel angles and rates; slips. Noise and sensor faults are already applied.
        reference : Reference
        """


#: Outcomes of a law's step from plain numbers (:func:`tt_mujoco.controllers.ismc_sta.
#: ismc_sta_law`): done, ``g`` singular, torques not finite, and a user's compiled law that
#: raised (its Python form says what: :func:`tt_mujoco.sim.loop.outcome.outcome`).
LAW_OK, LAW_SINGULAR, LAW_NOT_FINITE, LAW_RAISED = 0, 1, 2, 3


class Tracking(NamedTuple):
    """What a velocity law tracks at one control step: the measured ``z = (v, omega)``, its
    target ``z_d`` and the target's rate ``z_d_dot`` (the feed-forward)."""

    v: float
    omega: float
    v_d: float
    omega_d: float
    v_d_dot: float
    omega_d_dot: float


class Nominal(NamedTuple):
    """The nominal model ``z_dot = f + g tau`` at the measurement (docs/model.md Section 4)."""

    f1: float
    f2: float
    g11: float
    g12: float
    g21: float
    g22: float


class Saturation(NamedTuple):
    """The torque limit (N m), whether the previous step saturated, and whether the
    integrators are held under saturation (module docstring)."""

    limit: float
    saturated: bool
    anti_windup: bool


class LawStep(NamedTuple):
    """One step of a plain-number law: ``status`` (:data:`LAW_OK`, :data:`LAW_SINGULAR` or
    :data:`LAW_NOT_FINITE`), the clipped torques, the unclipped request ``(u1, u2)``, whether
    it saturated, two values the law reports (ISMC-STA: its sliding variables) and its new
    state (the law's ``STATE``)."""

    status: int
    T_r: float
    T_l: float
    u1: float
    u2: float
    saturated: bool
    aux1: float
    aux2: float
    state: tuple


def inverse_of(g11: float, g12: float, g21: float, g22: float):
    """``(ok, g^-1 entries)``: ``ok`` False where g is singular or not finite."""
    det = g11 * g22 - g12 * g21
    if not abs(det) > _SINGULAR_RTOL * (abs(g11 * g22) + abs(g12 * g21)):
        return False, 0.0, 0.0, 0.0, 0.0
    return True, g22 / det, -g12 / det, -g21 / det, g11 / det


def saturate_of(u1: float, u2: float, lim: float):
    """``(T_r, T_l, s1, s2)``: ``(u1, u2)`` clipped at ``lim`` and the saturation signs."""
    s1 = 1.0 if u1 > lim else (-1.0 if u1 < -lim else 0.0)
    s2 = 1.0 if u2 > lim else (-1.0 if u2 < -lim else 0.0)
    return (s1 * lim if s1 else u1), (s2 * lim if s2 else u2), s1, s2


def finite_pair(u1: float, u2: float) -> bool:
    """Whether both torque requests are finite numbers."""
    return -_INF < u1 < _INF and -_INF < u2 < _INF


def torques_of(g11, g12, g21, g22, r1, r2, limit):
    """The torques a law asks for to get the accelerations ``(r1, r2)``: ``u = g^-1 r`` clipped
    at ``limit``. Returns ``(status, T_r, T_l, u1, u2, s1, s2, a11, a12, a21, a22)``, ``s`` the
    saturation signs and ``a`` the entries of ``g^-1``; ``status`` :data:`LAW_SINGULAR` (all
    zeros) or :data:`LAW_NOT_FINITE` (``u`` kept for the message) when there are no torques."""
    ok, a11, a12, a21, a22 = inverse_of(g11, g12, g21, g22)
    if not ok:
        return LAW_SINGULAR, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    u1 = a11 * r1 + a12 * r2
    u2 = a21 * r1 + a22 * r2
    if not finite_pair(u1, u2):
        return LAW_NOT_FINITE, 0.0, 0.0, u1, u2, 0.0, 0.0, a11, a12, a21, a22
    T_r, T_l, s1, s2 = saturate_of(u1, u2, limit)
    return LAW_OK, T_r, T_l, u1, u2, s1, s2, a11, a12, a21, a22


def deepens(x: float, gi_1: float, gi_2: float, s1: float, s2: float) -> bool:
    """Whether an integrator increment ``+x`` in a channel with g^-1 column ``(gi_1, gi_2)``
    would push a saturated torque further out (module docstring)."""
    return s1 * gi_1 * x < 0.0 or s2 * gi_2 * x < 0.0


class VelocityController(Controller):
    """The built-in laws' base: validation, the 2x2 solve, saturation and the anti-windup test.

    Subclasses set :attr:`name`, :attr:`LAW`, :attr:`PRESETS`, :attr:`DEFAULT_PRESET`, the
    law's gains and memory by name (:attr:`GAINS`, :attr:`STATE`, each a ``NamedTuple`` of
    floats; the presets' keys are :attr:`GAINS`' fields) and implement :meth:`state`.

    Parameters
    ----------
    model : callable
        Nominal model ``(phi, v, omega) -> (f1, f2, g11, g12, g21, g22)``.
    torque_limit : float
        Saturation of each wheel torque, N m (paper Section 6.2: 15).
    gains : str, dict or None
        Preset name, dict of overrides (see :func:`resolve_gains`) or None.
    anti_windup : bool
        Conditional integration under saturation (module docstring). False integrates
        regardless, for comparison.
    """

    PRESETS: ClassVar[dict[str, dict[str, float]]] = {}
    DEFAULT_PRESET: ClassVar[str] = ""

    def __init__(
        self,
        model: ModelFn,
        torque_limit: float = TORQUE_LIMIT,
        gains: str | Mapping | None = None,
        anti_windup: bool = True,
    ):
        if not callable(model):
            raise ValueError(
                f"model={model!r} is not allowed: it must be a callable "
                "(phi, v, omega) -> (f1, f2, g11, g12, g21, g22), e.g. reduced_model(params)"
            )
        if (
            isinstance(torque_limit, bool)
            or not isinstance(torque_limit, Real)
            or not (math.isfinite(torque_limit) and torque_limit > 0)
        ):
            raise ValueError(
                f"torque_limit={torque_limit!r} is not allowed: it must be a finite number > 0 "
                "(N m)"
            )
        if not isinstance(anti_windup, bool):
            raise ValueError(f"anti_windup={anti_windup!r} is not allowed: use True or False")
        self.model = model
        self.torque_limit = float(torque_limit)
        self.anti_windup = anti_windup
        self._gains, self.preset = self.resolve_gains(gains)
        #: The law's gains by name, as its plain-number function takes them.
        self.law_gains = self.GAINS(**self._gains)
        self.saturated = False
        #: The last unsaturated torque request (T_r, T_l), for logging saturation.
        self.command = (0.0, 0.0)
        self.setup = None
        self._train = False  # a train's model takes every hitch angle (Measurement.phis)
        self.reset()

    @classmethod
    def from_setup(cls, setup: ControllerSetup, gains: str | Mapping | None = None):
        ctrl = cls(setup.model, torque_limit=setup.torque_limit, gains=gains)
        ctrl.setup = setup
        ctrl._train = getattr(setup.params, "n_trailers", 1) > 1
        return ctrl

    @property
    def axle_slew_rate(self) -> float:
        """How fast actuated axles turn at most (rad/s), the setup's; inf (a linkage) without
        one."""
        return _INF if self.setup is None else self.setup.axle_slew_rate

    def compute(self, t: float, measurement, reference: Reference) -> tuple[float, float]:
        """The protocol's step: :meth:`step` on the measured (phi, v, omega) and the target,
        with the setup's control period."""
        r = reference
        return self.step(
            self.setup.control_dt,
            measurement.phis if self._train else measurement.phi,
            measurement.v,
            measurement.omega,
            r.v_d,
            r.omega_d,
            r.v_d_dot,
            r.omega_d_dot,
        )

    @property
    def gains(self) -> dict:
        """The gains in use plus the base preset's name, JSON-serialisable; accepted back as
        ``gains=`` to rebuild the same controller."""
        return {"preset": self.preset, **self._gains}

    def reset(self) -> None:
        """Zero every integrator and forget the previous step."""
        #: The law's memory by name (a :attr:`STATE`), as its function returned it last.
        self.law_state = self.STATE()
        #: What the law reports besides (:class:`LawStep`'s ``aux1``, ``aux2``).
        self.aux = (0.0, 0.0)
        self.saturated = False

    def steering_changed(self, etas) -> None:
        """The nominal model takes the plant's gains (the mechanism's ratio is known): with
        a path schedule they range over [-3, 3], far from the scenario's constant eta, and the
        model takes of them what the axles' actuators can follow (:func:`reduced_model`)."""
        params = getattr(self.model, "params", None)  # a reduced_model's
        if params is None:
            return
        bound = getattr(self.model, "axle_slew_rate", _INF)
        if params.etas != tuple(etas) or bound != self.axle_slew_rate:
            self.model = reduced_model(params.with_etas(etas), self.axle_slew_rate)

    def state(self) -> dict[str, float]:
        """Integrator values (and related internals) for logging."""
        raise NotImplementedError

    def step(
        self,
        dt: float,
        phi: float,
        v: float,
        omega: float,
        v_d: float,
        omega_d: float,
        v_d_dot: float,
        omega_d_dot: float,
    ) -> tuple[float, float]:
        """Saturated wheel torques ``(T_r, T_l)`` for the measurement at this control step:
        one step of :attr:`LAW`.

        Parameters
        ----------
        dt : float
            Time since the previous call, s (> 0).
        phi : float
            Measured articulation angle, rad (a train: every hitch angle).
        v, omega : float
            Measured forward speed (m/s) and yaw rate (rad/s).
        v_d, omega_d : float
            Targets.
        v_d_dot, omega_d_dot : float
            Target time derivatives (feedforward).
        """
        if not 0.0 < dt < _INF:
            self._check_dt(dt)
        tracking = Tracking(v, omega, v_d, omega_d, v_d_dot, omega_d_dot)
        return self.run_law(type(self).LAW, dt, phi, tracking)

    def __repr__(self) -> str:
        return (
            f"{type(self).__name__}(torque_limit={self.torque_limit!r}, gains={self.gains!r}, "
            f"anti_windup={self.anti_windup!r})"
        )

    # --- helpers for subclasses ------------------------------------------------------------
    def _inverse(self, g11: float, g12: float, g21: float, g22: float):
        """``g^-1`` by hand; FloatingPointError if g is singular or not finite."""
        ok, a11, a12, a21, a22 = inverse_of(g11, g12, g21, g22)
        if not ok:
            self.raise_for(LAW_SINGULAR, (g11, g12, g21, g22), 0.0, 0.0)
        return a11, a12, a21, a22

    def _saturate(self, u1: float, u2: float):
        """Clip ``(u1, u2)``; return the torques and the saturation signs (+1, -1 or 0)."""
        if not finite_pair(u1, u2):
            self.raise_for(LAW_NOT_FINITE, (), u1, u2)
        T_r, T_l, s1, s2 = saturate_of(u1, u2, self.torque_limit)
        self.saturated = s1 != 0.0 or s2 != 0.0
        self.command = (u1, u2)
        return T_r, T_l, s1, s2

    #: The plain-number law :meth:`step` runs: ``law(dt, tracking, model, state, gains,
    #: saturation) -> LawStep`` (:func:`tt_mujoco.controllers.ismc_sta.ismc_sta_law`).
    LAW: ClassVar[Callable]
    #: The law's gains, a ``NamedTuple`` of floats whose fields are the presets' keys.
    GAINS: ClassVar[type]
    #: The law's memory, a ``NamedTuple`` of floats, each 0.0 by default (may have none).
    STATE: ClassVar[type]

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        gains = getattr(cls, "GAINS", None)
        for preset, values in cls.PRESETS.items():
            if gains is not None and tuple(values) != gains._fields:
                raise TypeError(
                    f"{cls.__name__}.PRESETS[{preset!r}] has the keys {tuple(values)}: they "
                    f"must be {cls.__name__}.GAINS' fields {gains._fields}, in that order"
                )

    def run_law(self, law: Callable, dt: float, phi, tracking: Tracking) -> tuple[float, float]:
        """One step of ``law`` (a plain-number law such as
        :func:`tt_mujoco.controllers.ismc_sta.ismc_sta_law`) on the nominal model at the
        measurement, its memory and saturation flag carried over: :meth:`step`."""
        model = Nominal(*self.model(phi, tracking.v, tracking.omega))
        saturation = Saturation(self.torque_limit, self.saturated, self.anti_windup)
        out = law(dt, tracking, model, self.law_state, self.law_gains, saturation)
        self.law_state, self.aux = out.state, (out.aux1, out.aux2)
        self.raise_for(out.status, model[2:], out.u1, out.u2)
        self.saturated = out.saturated
        self.command = (out.u1, out.u2)
        return out.T_r, out.T_l

    def raise_for(self, status: int, g: tuple, u1: float, u2: float) -> None:
        """The FloatingPointError of a law's failed ``status`` (none for :data:`LAW_OK`)."""
        if status == LAW_SINGULAR:
            g11, g12, g21, g22 = g
            det = g11 * g22 - g12 * g21
            raise FloatingPointError(
                f"the nominal input matrix g = [[{g11!r}, {g12!r}], [{g21!r}, {g22!r}]] is "
                f"singular (det = {det!r}): the torques cannot be computed"
            )
        if status == LAW_NOT_FINITE:
            raise FloatingPointError(
                f"{self.name}: the unsaturated torques ({u1!r}, {u2!r}) are not finite "
                "(check the measurement and the target for nan/inf)"
            )

    @staticmethod
    def _check_dt(dt: float) -> None:
        if not (0.0 < dt < _INF):
            raise ValueError(f"dt={dt!r} is not allowed: it must be a finite number > 0 (s)")

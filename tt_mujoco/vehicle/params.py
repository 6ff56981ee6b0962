"""Physical parameters of the off-axle tractor-trailer: the one place for defaults.

Every other module (the MJCF generator, the reduced model, the controllers' nominal model) is
built from a :class:`Params`. The defaults are the paper's values (Section 6.1) except the
passive steering gain, which defaults to the stable ``same_path`` design (see docs/model.md Section
3:
the paper's eta = 3 jackknifes when driving forward).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

from tt_mujoco.defaults import AXLE_SLEW_RATE, JACKKNIFE_DEG, TORQUE_LIMIT
from tt_mujoco.vehicle.param_ranges import INERTIA_FIELDS, MASS_FIELDS, RANGES, in_range

__all__ = [
    "MAX_TRAILERS",
    "MOTOR_FIELDS",
    "SETTABLE_FIELDS",
    "STEERING_PRESETS",
    "TRAILER_FIELDS",
    "Params",
    "Trailer",
    "jackknife_phi_deg",
    "resolve_eta",
    "same_path_eta",
    "train_same_path_etas",
]

#: Named passive-steering designs accepted wherever an ``eta`` is asked for.
STEERING_PRESETS = ("paper", "same_path")

#: The paper's steering gain (Section 6.1).
PAPER_ETA = 3.0


def same_path_eta(L: float, L0: float) -> float:
    """Constant steering gain that puts P0 on the tractor's path in gentle steady turns.

    The small-curvature limit of the exact same-path gain (:func:`tt_mujoco.vehicle.steering.
    exact_same_path_eta`): ``eta* = (L - L0) / (L + L0)``, -1/7 = -0.1429 for the paper's
    L = 0.3 m, L0 = 0.4 m. With it the steady off-tracking vanishes like kappa^3 (-0.27 mm at
    R = 1.5 m; docs/model.md Section 3, where the half-difference gain ``-(L0 - L) / (2 L0)``
    is shown to leave an off-tracking proportional to kappa, ``tests/test_reduced.py``).
    """
    return (L - L0) / (L + L0)


def train_same_path_etas(lengths) -> list[float]:
    """Small-curvature same-path gains of a train, trailer by trailer (docs/model.md Section 12).

    Parameters
    ----------
    lengths : sequence of (L_k, L0_k)
        Hitch offset behind the body in front and drawbar length of trailers 1..N (m).

    Returns
    -------
    list of float
        ``eta_k = b_k / (L_k + L0_k + b_k - b_(k-1))`` with ``b_0 = 0`` and
        ``b_k = (L_k^2 - L0_k^2) / (2 L0_k) - (L_k / L0_k) b_(k-1)``, where ``b_k = beta_k / kappa``
        is the steering angle per unit curvature of a trailer whose axle runs on the path.
        Trailer 1 gets :func:`same_path_eta` itself. Trailers 2.. differ from their own
        ``(L_k - L0_k) / (L_k + L0_k)`` because the hitch of trailer k is fixed to the body of
        trailer k-1, whose axle rolls at beta_(k-1) to it: -1/35 for a copy of the paper's
        trailer behind it.
    """
    lengths = [(float(L), float(L0)) for L, L0 in lengths]
    etas = [0.0] * len(lengths)
    train_same_path_etas_of(lengths, etas)
    return etas


def train_same_path_etas_of(lengths, out) -> None:
    """:func:`train_same_path_etas` of ``lengths`` (N rows of L_k, L0_k) into ``out`` (the
    compiled episode shares it)."""
    b_prev = 0.0
    for k in range(len(lengths)):
        L, L0 = lengths[k][0], lengths[k][1]
        b = (L * L - L0 * L0) / (2.0 * L0) - (L / L0) * b_prev
        out[k] = same_path_eta(L, L0) if k == 0 else b / (L + L0 + b - b_prev)
        b_prev = b


#: Most trailers a train may have (a longer train is accepted by the math but untested).
MAX_TRAILERS = 8

#: The fields of one trailer (trailer k's ``L`` is its hitch offset behind trailer k-1's axle,
#: and its rod of length ``L`` and mass ``Mc1`` is part of trailer k-1's body).
TRAILER_FIELDS = ("L", "L0", "Mr", "Mc1", "Mc2", "Ird", "Ic1", "Ic2")


@dataclass(frozen=True)
class Trailer:
    """Trailer k >= 2 of a train (trailer 1 is described by :class:`Params`' own fields).

    Parameters
    ----------
    L : float
        Offset of the hitch O_k behind trailer k-1's axle midpoint, along trailer k-1's body.
    L0 : float
        Drawbar length O_k - P_k.
    Mr, Mc1, Mc2, Ird, Ic1, Ic2 : float
        As in :class:`Params`: body, front rod (rigid with trailer k-1) and drawbar. A table
        given to :class:`Params` may leave any out: it takes trailer 1's.
    eta : float or str
        Steering gain or preset (``"same_path"`` is this trailer's own, see
        :func:`train_same_path_etas`); resolved to a float by :class:`Params`.
    """

    L: float
    L0: float
    Mr: float
    Mc1: float
    Mc2: float
    Ird: float
    Ic1: float
    Ic2: float
    eta: float | str = "same_path"
    steering: str = field(default="", compare=False)

    def __post_init__(self) -> None:
        for name in TRAILER_FIELDS:
            object.__setattr__(self, name, in_range(name, getattr(self, name), "trailer "))

    def to_dict(self) -> dict:
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}


#: The drive motors' constants (:mod:`tt_mujoco.sim.parts.motors`).
MOTOR_FIELDS = (
    "motor_kt",
    "motor_resistance",
    "motor_voltage",
    "motor_current_limit",
    "motor_gear",
    "motor_lag",
)


#: Largest steering gain accepted: beyond it the singularity |eta phi| = 90 deg is within a
#: few degrees of articulation, and no run can start.
MAX_ABS_ETA = 20.0


def resolve_eta(
    eta: float | str, L: float, L0: float, same_path: float | None = None
) -> tuple[float, str]:
    """Turn a steering specification into ``(eta, preset_name)``.

    Parameters
    ----------
    eta : float or str
        ``"paper"`` (eta = 3, the paper's Section 6.1 value), ``"same_path"`` (see
        :func:`same_path_eta`) or a number, given as a float or a numeric string.
    L, L0 : float
        Link lengths (m).
    same_path : float, optional
        What ``"same_path"`` stands for, :func:`same_path_eta` of ``L, L0`` unless given (a
        trailer behind another has its own, :func:`train_same_path_etas`).

    Returns
    -------
    eta : float
    preset : str
        ``"paper"``, ``"same_path"`` or ``"custom"``.
    """
    if isinstance(eta, str):
        key = eta.strip().lower().replace("-", "_")  # also accept "same-path"
        if key == "paper":
            return PAPER_ETA, "paper"
        if key == "same_path":
            return (same_path_eta(L, L0) if same_path is None else same_path), "same_path"
        try:
            value = float(eta)  # the original text: "-3" and "1e-3" are numbers
        except ValueError:
            raise ValueError(
                f"eta={eta!r} is not allowed: use 'paper', 'same_path' or a finite number"
            ) from None
    elif isinstance(eta, bool) or not isinstance(eta, int | float):
        raise ValueError(f"eta={eta!r} is not allowed: use 'paper', 'same_path' or a finite number")
    else:
        value = float(eta)
    if not math.isfinite(value):
        raise ValueError(f"eta={eta!r} is not allowed: use 'paper', 'same_path' or a finite number")
    if abs(value) > MAX_ABS_ETA:
        raise ValueError(
            f"eta={eta!r} is not allowed: |eta| must be at most {MAX_ABS_ETA:g} (with |eta| = "
            f"{MAX_ABS_ETA:g} the trailer axle already stands across its rod at |phi| = "
            f"{90 / MAX_ABS_ETA:g} deg)"
        )
    return value, "custom"


@dataclass(frozen=True)
class Params:
    """Parameters of the vehicle, its contact with the ground and the physics step.

    Masses in kg, inertias in kg m^2, lengths in m. The paper's values (Section 6.1) are the
    defaults. Roll and pitch inertias are not in the paper; they only matter for the MuJoCo
    model, which never rolls or pitches appreciably, and are chosen as documented below.

    Parameters
    ----------
    Mf, Mr : float
        Tractor and trailer body masses, without wheels (at P and P0).
    Mw : float
        Mass of each of the four wheels.
    Mc1, Mc2 : float
        Masses of the rods P-O (rigid with the tractor) and O-P0 (rigid with the trailer),
        each centred on its rod.
    Ifd, Ird : float
        Yaw inertias of the tractor and trailer bodies about their own centres.
    Iwd : float
        Each wheel's inertia about a diameter (yaw).
    Ic1, Ic2 : float
        Yaw inertias of the rods about their centres.
    Iw : float
        Each wheel's spin inertia about its axle.
    L, L0 : float
        Lengths P-O and O-P0 of the off-axle links.
    r, d : float
        Wheel radius and track (distance between left and right wheels).
    eta : float or str
        Passive steering gain, beta = eta * phi (paper eq. 2). ``"same_path"`` (default,
        (L - L0)/(L + L0) = -1/7, see :func:`same_path_eta`),
        ``"paper"`` (3.0) or a number. Stored resolved to a float; the preset name is kept in
        :attr:`steering`.
    torque_limit : float
        Wheel torque saturation |T| (N m), the paper's 15 N m (Section 6.2).
    axle_slew_rate : float
        How fast an actuated axle turns at most (rad/s): the MuJoCo plant's axles under the
        path schedule, whose gain is no fixed linkage (docs/model.md Section 13; not in the
        paper). A linkage and the reduced plant's kinematic steering have no such bound.
    friction : float
        Sliding friction coefficient between the wheels and the floor.
    timestep : float
        Physics time step (s). The contact time constant is ``2 * timestep`` (docs/model.md Section
        5).
    impratio : float
        MuJoCo's ratio of frictional to normal constraint impedance (high values reduce
        creep in the friction cones).
    body_tilt_inertia_ratio : float
        Roll and pitch inertia of the tractor and trailer bodies as a multiple of their yaw
        inertia (not in the paper; a flat plate has 0.5, and MuJoCo needs
        the triangle inequality I_roll + I_pitch >= I_yaw, so 0.6).
    motor_kt : float
        Torque constant of each drive motor (N m/A; its back-EMF constant in V s/rad), used
        with ``actuator="dc_motor"`` (:mod:`tt_mujoco.sim.parts.motors`, not in the paper).
    motor_resistance : float
        Winding resistance (ohm).
    motor_voltage : float
        Supply voltage (V).
    motor_current_limit : float
        The driver's current limit (A): with the defaults, 15 N m at the wheel, the paper's
        torque limit.
    motor_gear : float
        Gear ratio, motor to wheel.
    motor_lag : float
        Time constant (s) of the driver's current, and so the torque, following its command.
    drag_area_tractor, drag_area_trailer : float
        Drag coefficient times reference area (m^2) of the tractor's and the trailer's bodies,
        for ``Scenario.wind`` (:mod:`tt_mujoco.sim.parts.wind`, not in the paper).
    drag_centre_tractor, drag_centre_trailer : float
        Where each body's drag acts (m), ahead of its centre of mass along its heading
        (negative: behind): the wind's yaw moment about the centre of mass is this lever times
        the drag's component across the heading. 0 (the default): no moment.
    train : tuple of Trailer (or dicts of its fields)
        Trailers 2..N behind the first (empty: the paper's single trailer). Build copies of
        trailer 1 with :meth:`with_trailers`.
    """

    Mf: float = 9.0
    Mr: float = 6.0
    Mw: float = 4.0
    Mc1: float = 1.0
    Mc2: float = 1.0
    Ifd: float = 0.03
    Ird: float = 0.02
    Iwd: float = 0.01
    Ic1: float = 0.005
    Ic2: float = 0.005
    Iw: float = 0.01
    L: float = 0.3
    L0: float = 0.4
    r: float = 0.02
    d: float = 0.2
    eta: float | str = "same_path"
    torque_limit: float = TORQUE_LIMIT
    axle_slew_rate: float = AXLE_SLEW_RATE
    friction: float = 1.0
    timestep: float = 0.001
    impratio: float = 10.0
    body_tilt_inertia_ratio: float = 0.6
    motor_kt: float = 0.1
    motor_resistance: float = 0.2
    motor_voltage: float = 48.0
    motor_current_limit: float = 30.0
    motor_gear: float = 5.0
    motor_lag: float = 0.005
    drag_area_tractor: float = 0.03
    drag_area_trailer: float = 0.04
    drag_centre_tractor: float = 0.0
    drag_centre_trailer: float = 0.0
    train: tuple = ()
    steering: str = field(default="", init=False, compare=False)

    def __post_init__(self) -> None:
        for name in RANGES:
            object.__setattr__(self, name, in_range(name, getattr(self, name)))
        for name in ("drag_centre_tractor", "drag_centre_trailer"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise ValueError(f"{name}={value!r} is not allowed: it must be a number (m)")
            if not (math.isfinite(value) and abs(value) <= 10.0):
                raise ValueError(
                    f"{name}={value!r} is not allowed: it must be a finite lever within 10 m"
                )
            object.__setattr__(self, name, float(value))
        if not 1e-5 <= self.timestep <= 0.01:
            raise ValueError(
                f"timestep={self.timestep!r} is not allowed: it must be in [1e-05, 0.01] s"
            )
        if self.r >= self.d / 2:
            # either may be the one given: both are named
            raise ValueError(
                f"r={self.r!r} with d={self.d!r} is not allowed: the wheel radius must be "
                f"smaller than half the track d/2 = {self.d / 2!r} (the wheels would overlap)"
            )
        if self.r >= min(self.L, self.L0):
            short = "L" if self.L <= self.L0 else "L0"
            raise ValueError(
                f"r={self.r!r} with {short}={getattr(self, short)!r} is not allowed: the wheel "
                f"radius must be smaller than both links (L={self.L!r}, L0={self.L0!r})"
            )
        if self.Iw > 2 * self.Iwd:
            raise ValueError(
                f"Iw={self.Iw!r} is not allowed: a wheel's spin inertia cannot exceed twice its "
                f"diametral inertia 2*Iwd = {2 * self.Iwd!r} (no rigid body has that)"
            )
        eta, preset = resolve_eta(self.eta, self.L, self.L0)
        object.__setattr__(self, "eta", eta)
        object.__setattr__(self, "steering", preset)
        object.__setattr__(self, "train", self._resolved_train())

    def _resolved_train(self) -> tuple:
        train = self.train
        if not isinstance(train, list | tuple):
            raise ValueError(f"train={train!r} is not allowed: give a list of trailers")
        if len(train) + 1 > MAX_TRAILERS:
            raise ValueError(
                f"trailers={len(train) + 1} is not allowed: at most {MAX_TRAILERS} trailers"
            )
        items = []
        first = self._first_trailer_fields()
        for k, item in enumerate(train, start=2):
            if isinstance(item, dict):
                item = {key: value for key, value in item.items() if key != "steering"}
                unknown = sorted(set(item) - {*TRAILER_FIELDS, "eta"})
                if unknown:
                    raise ValueError(
                        f"trailer {k} field {unknown[0]!r} is not allowed: use "
                        f"{', '.join((*TRAILER_FIELDS, 'eta'))}"
                    )
                item = Trailer(**{**first, **item})
            elif not isinstance(item, Trailer):
                raise ValueError(f"trailer {k}={item!r} is not allowed: give a table of fields")
            items.append(item)
        if not items:
            return ()
        lengths = [(self.L, self.L0)] + [(t.L, t.L0) for t in items]
        limits = train_same_path_etas(lengths)
        resolved = []
        for k, item in enumerate(items, start=2):
            spec = item.eta
            try:
                eta, preset = resolve_eta(spec, item.L, item.L0, same_path=limits[k - 1])
            except ValueError as err:
                raise ValueError(f"trailer {k}: {err}") from None
            if not isinstance(spec, str) and item.steering:
                preset = item.steering  # already resolved (a copy made by replace or scaled)
            if self.r >= min(item.L, item.L0):
                raise ValueError(
                    f"trailer {k}: r={self.r!r} is not allowed: the wheel radius must be smaller "
                    f"than both links (L={item.L!r}, L0={item.L0!r})"
                )
            resolved.append(dataclasses.replace(item, eta=eta, steering=preset))
        return tuple(resolved)

    # --- the train ------------------------------------------------------------------------
    @property
    def n_trailers(self) -> int:
        """Number of trailers N (1 is the paper's vehicle)."""
        return 1 + len(self.train)

    @property
    def trailers(self) -> tuple[Trailer, ...]:
        """Trailers 1..N, trailer 1 made from this object's own fields."""
        first = Trailer(**self._first_trailer_fields(), eta=self.eta, steering=self.steering)
        return (first, *self.train)

    def _first_trailer_fields(self) -> dict:
        """Trailer 1's :data:`TRAILER_FIELDS`, from this object's own fields."""
        return {name: getattr(self, name) for name in TRAILER_FIELDS}

    @property
    def etas(self) -> tuple[float, ...]:
        """The steering gains eta_1..eta_N."""
        return (self.eta, *(t.eta for t in self.train))

    def with_etas(self, etas) -> Params:
        """A copy steering with the gains ``etas`` (eta_1..eta_N, one per trailer)."""
        if len(etas) != self.n_trailers:
            raise ValueError(
                f"{len(etas)} gains are not allowed: this vehicle has {self.n_trailers} trailer(s)"
            )
        rest = zip(self.train, etas[1:], strict=True)
        train = tuple(dataclasses.replace(t, eta=float(e)) for t, e in rest)
        return self.replace(eta=float(etas[0]), train=train)

    def with_unit_fields(self, values) -> Params:
        """A copy with ``values``, ``{(unit, field): value}``: unit 0 the tractor and 1 trailer
        1 (this object's own fields), k trailer k of :attr:`train` (validated again; a gain
        stays the number it is, whatever the lengths become)."""
        own = {name: float(value) for (k, name), value in values.items() if k in (0, 1)}
        train = list(self.train)
        for (k, name), value in values.items():
            if k > 1:
                train[k - 2] = dataclasses.replace(train[k - 2], **{name: float(value)})
        return self.replace(**own, train=tuple(train))

    def with_trailers(self, n: int, overrides=()) -> Params:
        """A train of ``n`` trailers: trailers 2..n copy trailer 1's lengths, masses and
        steering (a preset gives each trailer its own value), then take ``overrides[k - 2]``
        (a dict of :data:`TRAILER_FIELDS` and ``eta``) for trailer k."""
        if isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= MAX_TRAILERS:
            raise ValueError(
                f"trailers={n!r} is not allowed: it must be an integer in [1, {MAX_TRAILERS}]"
            )
        overrides = list(overrides or ())
        if len(overrides) > n - 1:
            raise ValueError(
                f"{len(overrides)} trailer tables are not allowed with trailers={n}: give at "
                f"most {n - 1} (for trailers 2..{n})"
            )
        copy = self._first_trailer_fields()
        copy["eta"] = self.eta if self.steering == "custom" else self.steering
        train = []
        for k in range(2, n + 1):
            extra = overrides[k - 2] if k - 2 < len(overrides) else {}
            if not isinstance(extra, dict):
                raise ValueError(f"trailer {k}={extra!r} is not allowed: give a table of fields")
            train.append({**copy, **extra})
        return self.replace(train=tuple(train))

    # --- derived quantities ---------------------------------------------------------------
    @property
    def phi_singular(self) -> float:
        """|phi| at which cos(beta) = 0 (the kinematics are singular), or inf if eta = 0."""
        return self.phi_singulars[0]

    @property
    def phi_singulars(self) -> tuple[float, ...]:
        """:attr:`phi_singular` of every trailer's hitch."""
        return tuple(math.inf if e == 0 else math.pi / (2 * abs(e)) for e in self.etas)

    @property
    def total_mass(self) -> float:
        extra = sum(t.Mr + 2 * self.Mw + t.Mc1 + t.Mc2 for t in self.train)
        return self.Mf + self.Mr + 4 * self.Mw + self.Mc1 + self.Mc2 + extra

    def replace(self, **changes) -> Params:
        """A copy with some fields changed (validated again)."""
        if "eta" not in changes:
            changes["eta"] = self.eta
        out = dataclasses.replace(self, **changes)
        if out.eta == self.eta and self.steering != "custom":
            object.__setattr__(out, "steering", self.steering)  # the preset's name survives
        return out

    def scaled(self, scale: float) -> Params:
        """Masses and inertias multiplied by ``scale`` (docs/model.md §8 parameter uncertainty),
        every trailer's included."""
        if not (math.isfinite(scale) and scale > 0):
            raise ValueError(f"param scale={scale!r} is not allowed: it must be finite and > 0")
        train = tuple(
            dataclasses.replace(
                t, **{k: getattr(t, k) * scale for k in TRAILER_FIELDS if k not in ("L", "L0")}
            )
            for t in self.train
        )
        return self.replace(
            train=train, **{k: getattr(self, k) * scale for k in MASS_FIELDS + INERTIA_FIELDS}
        )

    def to_dict(self) -> dict:
        """All fields as plain floats/strings, for reports and ``metrics.json`` (``train``, a
        list of trailer tables, only for a train)."""
        out = {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}
        if self.train:
            out["train"] = [t.to_dict() for t in self.train]
        else:
            del out["train"]
        return out


def jackknife_phi_deg(eta: float) -> float:
    """|phi| (deg) at which a run stops as a jackknife: |beta| = |eta phi| reaches
    :data:`~tt_mujoco.defaults.JACKKNIFE_DEG`, or |phi| reaches 90 deg (the trailer across
    the tractor)."""
    return min(JACKKNIFE_DEG / abs(eta), 90.0) if eta else 90.0


#: Fields a scenario sets as ``params`` (``--param``, TOML ``[params]``, a sweep's
#: ``param.<field>``): every field but eta, friction and timestep, which are scenario options
#: of their own.
SETTABLE_FIELDS = tuple(
    f.name
    for f in dataclasses.fields(Params)
    if f.init and f.name not in ("eta", "friction", "timestep")
)

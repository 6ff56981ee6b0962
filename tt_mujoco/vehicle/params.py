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

__all__ = [
    "STEERING_PRESETS",
    "Params",
    "resolve_eta",
    "same_path_eta",
    "spec_same_path_eta",
]

#: Named passive-steering designs accepted wherever an ``eta`` is asked for.
STEERING_PRESETS = ("paper", "same_path")

#: The paper's steering gain (Section 6.1).
PAPER_ETA = 3.0

# Fields that scale with --param-scale (plant parameter uncertainty, docs/model.md Section 8).
MASS_FIELDS = ("Mf", "Mr", "Mw", "Mc1", "Mc2")
INERTIA_FIELDS = ("Ifd", "Ird", "Iwd", "Ic1", "Ic2", "Iw")


def same_path_eta(L: float, L0: float) -> float:
    """Constant steering gain that puts P0 on the tractor's path in gentle steady turns.

    The small-curvature limit of the exact same-path gain (:func:`tt_mujoco.vehicle.steering.
    exact_same_path_eta`): ``eta* = (L - L0) / (L + L0)``, -1/7 = -0.1429 for the paper's
    L = 0.3 m, L0 = 0.4 m. With it the steady off-tracking vanishes like kappa^3 (-0.27 mm at
    R = 1.5 m).

    docs/model.md Section 3 gives ``-(L0 - L) / (2 L0)`` (-0.125) as this limit; that is wrong: it
    leaves
    an off-tracking proportional to kappa (-2.87 mm at R = 1.5 m, -0.39 mm at R = 10 m), see
    :func:`spec_same_path_eta` and ``tests/test_reduced.py``.
    """
    return (L - L0) / (L + L0)


def spec_same_path_eta(L: float, L0: float) -> float:
    """docs/model.md Section 3's ``-(L0 - L) / (2 L0)`` (-0.125), kept to show why it was replaced:
    it is not the small-curvature limit of the same-path gain (see :func:`same_path_eta`)."""
    return -(L0 - L) / (2.0 * L0)


#: Largest steering gain accepted: beyond it the singularity |eta phi| = 90 deg is within a
#: few degrees of articulation, and no run can start.
MAX_ABS_ETA = 20.0


def resolve_eta(eta: float | str, L: float, L0: float) -> tuple[float, str]:
    """Turn a steering specification into ``(eta, preset_name)``.

    Parameters
    ----------
    eta : float or str
        ``"paper"`` (eta = 3, the paper's Section 6.1 value), ``"same_path"`` (see
        :func:`same_path_eta`) or a number, given as a float or a numeric string.
    L, L0 : float
        Link lengths (m).

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
            return same_path_eta(L, L0), "same_path"
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
    torque_limit: float = 15.0
    friction: float = 1.0
    timestep: float = 0.001
    impratio: float = 10.0
    body_tilt_inertia_ratio: float = 0.6
    steering: str = field(default="", init=False, compare=False)

    def __post_init__(self) -> None:
        positive = (
            *MASS_FIELDS,
            *INERTIA_FIELDS,
            "L",
            "L0",
            "r",
            "d",
            "torque_limit",
            "friction",
            "impratio",
            "body_tilt_inertia_ratio",
        )
        for name in positive:
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise ValueError(f"{name}={value!r} is not allowed: it must be a number > 0")
            if not math.isfinite(value) or value <= 0:
                raise ValueError(f"{name}={value!r} is not allowed: it must be finite and > 0")
            object.__setattr__(self, name, float(value))
        if not 1e-5 <= self.timestep <= 0.01:
            raise ValueError(
                f"timestep={self.timestep!r} is not allowed: it must be in [1e-05, 0.01] s"
            )
        if self.r >= self.d / 2:
            raise ValueError(
                f"r={self.r!r} is not allowed: the wheel radius must be smaller than half the "
                f"track d/2 = {self.d / 2!r} (the wheels would overlap)"
            )
        if self.r >= min(self.L, self.L0):
            raise ValueError(
                f"r={self.r!r} is not allowed: the wheel radius must be smaller than both links "
                f"(L={self.L!r}, L0={self.L0!r})"
            )
        if self.Iw > 2 * self.Iwd:
            raise ValueError(
                f"Iw={self.Iw!r} is not allowed: a wheel's spin inertia cannot exceed twice its "
                f"diametral inertia 2*Iwd = {2 * self.Iwd!r} (no rigid body has that)"
            )
        if self.body_tilt_inertia_ratio < 0.5:
            raise ValueError(
                f"body_tilt_inertia_ratio={self.body_tilt_inertia_ratio!r} is not allowed: "
                "it must be >= 0.5 (triangle inequality of the body inertias)"
            )
        eta, preset = resolve_eta(self.eta, self.L, self.L0)
        object.__setattr__(self, "eta", eta)
        object.__setattr__(self, "steering", preset)

    # --- derived quantities ---------------------------------------------------------------
    @property
    def phi_singular(self) -> float:
        """|phi| at which cos(beta) = 0 (the kinematics are singular), or inf if eta = 0."""
        return math.inf if self.eta == 0 else math.pi / (2 * abs(self.eta))

    @property
    def total_mass(self) -> float:
        return self.Mf + self.Mr + 4 * self.Mw + self.Mc1 + self.Mc2

    def replace(self, **changes) -> Params:
        """A copy with some fields changed (validated again)."""
        if "eta" not in changes:
            changes["eta"] = self.eta
        return dataclasses.replace(self, **changes)

    def scaled(self, scale: float) -> Params:
        """Masses and inertias multiplied by ``scale`` (docs/model.md §8 parameter uncertainty)."""
        if not (math.isfinite(scale) and scale > 0):
            raise ValueError(f"param scale={scale!r} is not allowed: it must be finite and > 0")
        return self.replace(**{k: getattr(self, k) * scale for k in MASS_FIELDS + INERTIA_FIELDS})

    def to_dict(self) -> dict:
        """All fields as plain floats/strings, for reports and ``metrics.json``."""
        out = {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}
        return out

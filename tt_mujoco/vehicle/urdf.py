"""URDF text for the vehicle (``models/tractor_trailer.urdf``), for ROS and Gazebo users.

It mirrors the MJCF of :mod:`tt_mujoco.vehicle.mjcf` link for link, built from the same
:class:`~tt_mujoco.vehicle.params.Params`, with the mass layout of docs/model.md Section 4:

- ``tractor`` (root link, frame at P, the tractor's wheel-axle midpoint): Mf, yaw inertia Ifd.
  The MJCF's free joint ``root`` has no URDF counterpart: the root link simply floats.
- ``tractor_rod`` (fixed), centred between P and O: Mc1, Ic1.
- ``tractor_wheel_left/right`` (continuous, axis y) at P +- (d/2) n(theta): Mw, spin Iw,
  diametral Iwd; effort limit ``torque_limit`` (paper Section 6.2, |T| <= 15 N m).
- ``trailer`` (frame at the hitch O, ``hitch`` revolute about z, ``q_hitch = -phi``): rod 2,
  Mc2, Ic2, centred between O and P0.
- ``trailer_body`` (fixed) at P0: Mr, Ird.
- ``trailer_axle`` at P0 (``steer`` revolute about z, ``q_steer = beta``) with the trailer
  wheels (continuous, axis y). As in the MJCF, the axle carries ``AXLE_MASS`` taken from the two
  trailer wheels, so the mass matrix is identical to the MJCF's.

The passive steering coupling beta = eta * phi (paper eq. 2; ``steer = -eta * hitch``) is a
closed kinematic constraint that URDF cannot express. The nearest thing, a ``<mimic>`` on
``steer``, is written; it is kinematic only (ROS tools and yourdfpy compute ``steer`` from
``hitch``), and simulators enforce it as a constraint only if they choose to (see the comment
at the top of the generated file).

Joint names: ``hitch`` and ``steer`` as in the MJCF; the wheel joints are ``<wheel link>_joint``
(the MJCF names them like their bodies) because SDFormat, and so Gazebo, rejects a joint and a
link with the same name. Nothing here imports MuJoCo.
"""

from __future__ import annotations

import math
import textwrap

from tt_mujoco.vehicle.mjcf import AXLE_MASS
from tt_mujoco.vehicle.params import Params

__all__ = ["URDF_FILE", "VELOCITY_LIMIT", "urdf_xml", "wheel_joint_name"]

URDF_FILE = "tractor_trailer.urdf"

#: Joint speed limit (rad/s) written where URDF requires one. The paper gives none; this is a
#: placeholder far above any run (the 0.8 m/s cruise is a 40 rad/s wheel rate for r = 0.02 m),
#: so it never binds.
VELOCITY_LIMIT = 1000.0

#: |beta| limit of ``steer``: the reduced model is singular at cos(beta) = 0 (docs/model.md Section
#: 2).
STEER_LIMIT = math.pi / 2

WHEELS = ("tractor_wheel_left", "tractor_wheel_right", "trailer_wheel_left", "trailer_wheel_right")

# Visual-only sizes, the MJCF's (tt_mujoco.vehicle.mjcf.vehicle_xml).
CHASSIS_HALF_HEIGHT = 0.02
MATERIALS = {
    "chassis": "0.85 0.45 0.1 1",
    "trailer": "0.2 0.45 0.8 1",
    "rod": "0.3 0.3 0.3 1",
    "tire": "0.1 0.1 0.1 1",
    "hub": "0.7 0.7 0.7 1",
}

# Cylinders in URDF lie along their z axis: these turn z onto x and onto y.
ALONG_X = f"0 {math.pi / 2!r} 0"
ALONG_Y = f"{math.pi / 2!r} 0 0"


def _trailer_parts(p: Params, k: int, hitch_limit: float) -> str:
    """Trailer k's links and joints. Trailer 1 hangs from the tractor L behind P; trailer k >= 2
    from trailer k-1's frame (at O_(k-1)), L_k behind its axle midpoint, with its front rod
    fixed to trailer k-1 (as the MJCF)."""
    t = p.trailers[k - 1]
    sfx = "" if k == 1 else f"_{k}"
    r, d, L, L0 = p.r, p.d, t.L, t.L0
    tilt = p.body_tilt_inertia_ratio
    h = CHASSIS_HALF_HEIGHT
    rod_radius = 0.15 * r
    parent, origin, front = "tractor", -L, []
    if k > 1:
        parent = f"trailer{'' if k == 2 else f'_{k - 1}'}"
        behind = -p.trailers[k - 2].L0  # trailer k-1's axle midpoint, in its frame
        origin = behind - L
        front = [
            f"\n<!-- Trailer {k}'s front rod, fixed to trailer {k - 1}. -->\n",
            _link(
                f"front_rod_{k}",
                _inertial(t.Mc1, 0.01 * t.Ic1, t.Ic1, t.Ic1)
                + _shape(
                    "visual",
                    f'<cylinder radius="{_g(rod_radius)}" length="{_g(L)}"/>',
                    rpy=ALONG_X,
                    material="rod",
                ),
            ),
            _joint(
                f"front_rod_{k}_joint",
                "fixed",
                parent,
                f"front_rod_{k}",
                f"{_g(behind - L / 2)} 0 0",
            ),
        ]
    head = (
        "\n<!-- Trailer: frame at the hitch O; hitch angle q_hitch = -phi. -->\n"
        if k == 1
        else f"\n<!-- Trailer {k}: frame at its hitch O_{k}; q_hitch_{k} = -phi_{k}. -->\n"
    )
    parts = [
        *front,
        head,
        _link(
            f"trailer{sfx}",
            _inertial(t.Mc2, 0.01 * t.Ic2, t.Ic2, t.Ic2, xyz=f"{_g(-L0 / 2)} 0 0")
            + _shape(
                "visual",
                f'<cylinder radius="{_g(rod_radius)}" length="{_g(L0)}"/>',
                xyz=f"{_g(-L0 / 2)} 0 0",
                rpy=ALONG_X,
                material="rod",
            ),
        ),
        _joint(
            f"hitch{sfx}",
            "revolute",
            parent,
            f"trailer{sfx}",
            f"{_g(origin)} 0 0",
            _revolute_z(hitch_limit, 0.0) + PASSIVE,
        ),
        _link(
            f"trailer_body{sfx}",
            _inertial(t.Mr, tilt * t.Ird, tilt * t.Ird, t.Ird)
            + _shape(
                "visual",
                f'<box size="{_g(2 * (0.35 * L0))} {_g(2 * (0.35 * d))} {_g(2 * h)}"/>',
                xyz=f"{_g(0.1 * L0)} 0 {_g(r + 3 * h)}",
                material=f"trailer{sfx}",
            ),
        ),
        _joint(
            f"trailer_body_joint{sfx}",
            "fixed",
            f"trailer{sfx}",
            f"trailer_body{sfx}",
            f"{_g(-L0)} 0 0",
        ),
        _steering_axle(p, k),
    ]
    return "".join(parts)


def _steering_axle(p: Params, k: int) -> str:
    """Trailer k's steering axle at its P0, its steer joint (mimicking the hitch) and its two
    wheels."""
    t = p.trailers[k - 1]
    sfx = "" if k == 1 else f"_{k}"
    r, d, L0 = p.r, p.d, t.L0
    rod_radius = 0.15 * r
    axle_mass = AXLE_MASS
    axle_yaw = axle_mass * d**2 / 4
    trailer_wheel_mass = p.Mw - axle_mass / 2
    steer_note = (
        "\n<!-- Steering axle at P0: q_steer = beta. AXLE_MASS is taken from the two trailer\n"
        "     wheels, with the yaw inertia that mass had at the wheel centres (as the MJCF). -->\n"
        if k == 1
        else f"\n<!-- Trailer {k}'s steering axle at P0_{k}: q_steer_{k} = beta_{k}. -->\n"
    )
    parts = [
        steer_note,
        _link(
            f"trailer_axle{sfx}",
            _inertial(axle_mass, axle_yaw, axle_yaw, axle_yaw)
            + _shape(
                "visual",
                f'<cylinder radius="{_g(rod_radius)}" length="{_g(d)}"/>',
                rpy=ALONG_Y,
                material="rod",
            ),
        ),
        _joint(
            f"steer{sfx}",
            "revolute",
            f"trailer{sfx}",
            f"trailer_axle{sfx}",
            f"{_g(-L0)} 0 0",
            _revolute_z(STEER_LIMIT, 0.0)
            + PASSIVE
            + "  <!-- Kinematic only: beta = eta * phi, see the top of this file. -->\n"
            + f'  <mimic joint="hitch{sfx}" multiplier="{_g(-t.eta)}" offset="0"/>\n',
        ),
        _wheel_link(p, f"trailer_wheel_left{sfx}", trailer_wheel_mass),
        _wheel_joint(f"trailer_wheel_left{sfx}", f"trailer_axle{sfx}", d / 2, None),
        _wheel_link(p, f"trailer_wheel_right{sfx}", trailer_wheel_mass),
        _wheel_joint(f"trailer_wheel_right{sfx}", f"trailer_axle{sfx}", -d / 2, None),
    ]
    return "".join(parts)


def wheel_joint_name(link: str) -> str:
    """URDF name of a wheel's spin joint (the MJCF calls it like the body, ``link``)."""
    return f"{link}_joint"


def _g(x: float) -> str:
    """Compact, round-trip exact number formatting (as in the MJCF), without a "-0"."""
    x = float(x) + 0.0  # -0.0 + 0.0 == +0.0
    return repr(x).removesuffix(".0") if x.is_integer() else repr(x)


def _inertial(mass: float, ixx: float, iyy: float, izz: float, xyz: str = "0 0 0") -> str:
    return (
        "  <inertial>\n"
        f'    <origin xyz="{xyz}" rpy="0 0 0"/>\n'
        f'    <mass value="{_g(mass)}"/>\n'
        f'    <inertia ixx="{_g(ixx)}" ixy="0" ixz="0" iyy="{_g(iyy)}" iyz="0" izz="{_g(izz)}"/>\n'
        "  </inertial>\n"
    )


def _shape(kind: str, geometry: str, xyz: str = "0 0 0", rpy: str = "0 0 0", material=None) -> str:
    material_tag = f'    <material name="{material}"/>\n' if material else ""
    return (
        f"  <{kind}>\n"
        f'    <origin xyz="{xyz}" rpy="{rpy}"/>\n'
        f"    <geometry>{geometry}</geometry>\n"
        f"{material_tag}"
        f"  </{kind}>\n"
    )


def _link(name: str, body: str) -> str:
    return f'<link name="{name}">\n{body}</link>\n'


def _joint(name: str, kind: str, parent: str, child: str, xyz: str, extra: str = "") -> str:
    return (
        f'<joint name="{name}" type="{kind}">\n'
        f'  <parent link="{parent}"/>\n'
        f'  <child link="{child}"/>\n'
        f'  <origin xyz="{xyz}" rpy="0 0 0"/>\n'
        f"{extra}"
        "</joint>\n"
    )


#: A passive joint's dynamics, as the MJCF's: no damping, no frictionloss.
PASSIVE = '  <dynamics damping="0" friction="0"/>\n'


def _revolute_z(limit: float, effort: float) -> str:
    """A revolute joint's axis (z) and limits."""
    return (
        '  <axis xyz="0 0 1"/>\n'
        f'  <limit lower="{_g(-limit)}" upper="{_g(limit)}" effort="{_g(effort)}" '
        f'velocity="{_g(VELOCITY_LIMIT)}"/>\n'
    )


def _wheel_link(p: Params, name: str, mass: float) -> str:
    """A wheel's link: its inertia, the sphere that touches the ground, the hub the eye sees."""
    r = p.r
    body = (
        _inertial(mass, p.Iwd, p.Iw, p.Iwd)
        + _shape("visual", f'<sphere radius="{_g(r)}"/>', material="tire")
        + _shape(
            "visual",
            f'<cylinder radius="{_g(0.6 * r)}" length="{_g(0.6 * r)}"/>',
            rpy=ALONG_Y,
            material="hub",
        )
        + _shape("collision", f'<sphere radius="{_g(r)}"/>')
    )
    return _link(name, body)


def _wheel_joint(name: str, parent: str, y: float, effort: float | None) -> str:
    """A wheel's spin joint (``effort`` None: passive, no limit)."""
    limit = (
        ""
        if effort is None
        else f'  <limit effort="{_g(effort)}" velocity="{_g(VELOCITY_LIMIT)}"/>\n'
    )
    extra = '  <axis xyz="0 1 0"/>\n' + limit + PASSIVE
    return _joint(wheel_joint_name(name), "continuous", parent, name, f"0 {_g(y)} 0", extra)


def _tractor_parts(p: Params) -> str:
    """The tractor's links and joints: its body at P, its rod, its two driven wheels."""
    r, d, L = p.r, p.d, p.L
    tilt = p.body_tilt_inertia_ratio
    h = CHASSIS_HALF_HEIGHT
    rod_radius = 0.15 * r  # the MJCF's capsule radius
    parts = [
        "\n<!-- Tractor: frame at P, x forward, z up; spawn with P at height r. -->\n",
        _link(
            "tractor",
            _inertial(p.Mf, tilt * p.Ifd, tilt * p.Ifd, p.Ifd)
            + _shape(
                "visual",
                f'<box size="{_g(2 * (0.5 * L))} {_g(2 * (0.3 * d))} {_g(2 * h)}"/>',
                xyz=f"{_g(0.25 * L)} 0 {_g(r + h)}",
                material="chassis",
            )
            + _shape(
                "visual",
                f'<cylinder radius="{_g(rod_radius)}" length="{_g(d)}"/>',
                rpy=ALONG_Y,
                material="rod",
            ),
        ),
        _link(
            "tractor_rod",
            # Slender rod: pitch inertia equal to yaw, roll nearly nothing (as the MJCF).
            _inertial(p.Mc1, 0.01 * p.Ic1, p.Ic1, p.Ic1)
            + _shape(
                "visual",
                f'<cylinder radius="{_g(rod_radius)}" length="{_g(L)}"/>',
                rpy=ALONG_X,
                material="rod",
            ),
        ),
        _joint("tractor_rod_joint", "fixed", "tractor", "tractor_rod", f"{_g(-L / 2)} 0 0"),
        _wheel_link(p, "tractor_wheel_left", p.Mw),
        _wheel_joint("tractor_wheel_left", "tractor", d / 2, p.torque_limit),
        _wheel_link(p, "tractor_wheel_right", p.Mw),
        _wheel_joint("tractor_wheel_right", "tractor", -d / 2, p.torque_limit),
    ]
    return "".join(parts)


def urdf_xml(p: Params | None = None) -> str:
    """The vehicle's URDF (``models/tractor_trailer.urdf``) for parameters ``p``.

    Parameters
    ----------
    p : Params, optional
        Vehicle parameters; ``Params()`` (paper Section 6.1 values, same-path steering) if
        omitted.

    Returns
    -------
    str
        The URDF document. Links, masses, inertias and joint frames equal the MJCF's of
        :func:`tt_mujoco.vehicle.mjcf.vehicle_xml` for the same ``p``; the steering coupling is
        only a
        kinematic ``<mimic>`` (see the module docstring).

    Raises
    ------
    ValueError
        If ``p`` is neither ``None`` nor a :class:`~tt_mujoco.vehicle.params.Params`.
    """
    if p is None:
        p = Params()
    elif not isinstance(p, Params):
        raise ValueError(f"p={p!r} is not allowed: pass a tt_mujoco.vehicle.params.Params or None")
    r, d, L, L0 = p.r, p.d, p.L, p.L0
    # Hitch range: up to the singularity |eta phi| = pi/2 (docs/model.md Section 2), at most a full
    # fold.
    hitch_limits = [min(limit, math.pi) for limit in p.phi_singulars]

    parts = [
        "<!-- Materials of the MJCF. -->\n",
        *(
            f'<material name="{name}"><color rgba="{rgba}"/></material>\n'
            for name, rgba in MATERIALS.items()
        ),
        _tractor_parts(p),
        *(_trailer_parts(p, k, hitch_limits[k - 1]) for k in range(1, p.n_trailers + 1)),
        "\n<!-- Gazebo: wheel-floor friction (Params.friction). -->\n",
        *(
            f'<gazebo reference="{name}"><mu1>{_g(p.friction)}</mu1>'
            f"<mu2>{_g(p.friction)}</mu2></gazebo>\n"
            for name in (
                *WHEELS,
                *(
                    f"trailer_wheel_{side}_{k}"
                    for k in range(2, p.n_trailers + 1)
                    for side in ("left", "right")
                ),
            )
        ),
    ]
    body = textwrap.indent("".join(parts), "  ")

    return f"""<?xml version="1.0"?>
<!-- Generated by `python -m tt_mujoco.model` from tt_mujoco.vehicle.params.Params
(tt_mujoco.vehicle.urdf);
     do not edit. The same Params build models/tractor_trailer.xml (MJCF), which this file
     mirrors link for link: masses, centres of mass, inertias and joint frames are equal.
     Off-axle tractor-trailer with a passively steered trailer axle. eta = {p.eta!r}
     ({p.steering}); L = {_g(L)} m, L0 = {_g(L0)} m, r = {_g(r)} m, d = {_g(d)} m,
     total mass {_g(p.total_mass)} kg.

     THE PASSIVE STEERING COUPLING CANNOT BE EXPRESSED IN URDF. The trailer axle must obey
     beta = eta * phi, i.e. steer = -eta * hitch (q_hitch = -phi, q_steer = beta): a closed
     kinematic constraint. URDF describes trees only. The <mimic> on `steer` is the nearest
     thing and is KINEMATIC ONLY: robot_state_publisher, MoveIt and yourdfpy compute `steer`
     from `hitch` with it, but it adds no force. Gazebo Classic ignores it unless a mimic-joint
     plugin is loaded; newer Gazebo (SDFormat >= 1.11) turns it into a mimic constraint that
     only some physics engines enforce. Without an enforced constraint `steer` swings freely
     and the trailer does not steer as modelled. The MuJoCo model (equality constraint
     `steering`) is the reference.

     Joint limits: `hitch` |phi| <= min(pi / (2 |eta|), pi) (the kinematic singularity, or a
     full fold), `steer` |beta| <= pi/2 (the singularity). Passive joints have effort 0; the
     tractor wheel joints have effort = torque_limit = {_g(p.torque_limit)} N m. Velocity limits
     ({_g(VELOCITY_LIMIT)} rad/s) are placeholders URDF requires; they never bind.
     Wheel joints are named <wheel link>_joint (the MJCF names them like their bodies).
     The root link `tractor` floats (the MJCF's free joint); robot_state_publisher (KDL) warns
     that a root link has an inertia, which does not affect TF. -->
<robot name="tractor_trailer">
{body}</robot>
"""

"""Measurement layer: MuJoCo's ``qpos``/``qvel`` -> the controller's view of the vehicle.

Pure arithmetic on the two state vectors and the joint addresses in :class:`Layout`. Every
quantity is computed from ``qpos``/``qvel`` themselves, never from ``xpos``/``xmat``/``cvel``:
after ``mj_step`` those derived arrays still describe the start of the step while ``qpos``/``qvel``
are at its end (docs/model.md Section 5), so mixing them would give readings half a step apart.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

from tt_mujoco.vehicle.reduced import hitch_and_axle

__all__ = [
    "TRAIN_FIELDS",
    "Addresses",
    "Layout",
    "Lengths",
    "Measurement",
    "TrainMeasurement",
    "measure",
    "measure_train",
]

#: What is measured of each trailer k >= 2, in order (time-series columns ``<name>_k``).
TRAIN_FIELDS = ("x0", "y0", "theta0", "phi", "beta", "v0")
#: Where each field is in a train's row.
ROW_X0, ROW_Y0, ROW_THETA0, ROW_PHI, ROW_BETA, ROW_V0 = range(len(TRAIN_FIELDS))


class Addresses(NamedTuple):
    """Where :func:`measure_values` reads the state and the step writes the torques: the
    integer part of :class:`Layout`, as the plain record the compiled episode takes."""

    root_q: int
    root_v: int
    hitch_q: int
    hitch_v: int
    steer_q: int
    wheel_left_v: int
    wheel_right_v: int
    wheel_left_q: int
    wheel_right_q: int
    act_right: int
    act_left: int


class Lengths(NamedTuple):
    """The geometry :func:`measure_values` needs (m)."""

    L: float
    L0: float
    r: float
    d: float


@dataclass(frozen=True)
class Layout:
    """Addresses of the model's joints in ``qpos``/``qvel`` and of its actuators.

    The free joint is at ``qpos[root_q:root_q + 7]`` (position, quaternion w x y z) and
    ``qvel[root_v:root_v + 6]`` (world linear velocity, body-frame angular velocity).
    """

    root_q: int
    root_v: int
    hitch_q: int
    hitch_v: int
    steer_q: int
    steer_v: int
    wheel_left_v: int
    wheel_right_v: int
    trailer_wheel_left_v: int
    trailer_wheel_right_v: int
    wheel_left_q: int
    wheel_right_q: int
    act_right: int
    act_left: int
    L: float
    L0: float
    r: float
    d: float
    #: Trailers 2..N: ``(hitch_q, hitch_v, steer_q, L_k, L0_k)`` each (empty for one trailer).
    train: tuple = ()

    def __post_init__(self) -> None:
        # What measure_values takes after the state vectors.
        addresses = Addresses(*(getattr(self, name) for name in Addresses._fields))
        object.__setattr__(self, "addresses", addresses)
        object.__setattr__(self, "lengths", Lengths(self.L, self.L0, self.r, self.d))


class Measurement(NamedTuple):
    """What the controllers and the metrics see (SI units, radians).

    ``slip_lateral`` is the side velocity of P (ideally 0), ``slip_lateral_trailer`` that of P0
    across its rolling direction alpha; ``slip_left``/``slip_right`` are the tractor wheels' rim
    speed minus their ground speed along the heading (positive: spinning).
    """

    x: float
    y: float
    theta: float
    phi: float
    beta: float
    v: float
    omega: float
    x0: float
    y0: float
    theta0: float
    v0: float
    theta_l: float
    theta_r: float
    theta_l_dot: float
    theta_r_dot: float
    slip_lateral: float
    slip_lateral_trailer: float
    slip_left: float
    slip_right: float

    @property
    def phis(self) -> tuple:
        """The hitch angles phi_1..phi_N: one trailer's, here (a :class:`TrainMeasurement`
        gives every trailer's)."""
        return (self.phi,)


_new_measurement = Measurement._make


def yaw_from_quat(w: float, x: float, y: float, z: float) -> float:
    """Heading (rotation about world z) of a body with unit quaternion (w, x, y, z)."""
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def measure(qpos, qvel, lay: Layout) -> Measurement:
    """The vehicle's planar state from MuJoCo's generalized coordinates.

    Parameters
    ----------
    qpos, qvel : array_like
        ``MjData.qpos`` and ``MjData.qvel`` (read together, after the same step).
    lay : Layout

    Returns
    -------
    Measurement
    """
    # One conversion to Python floats: indexing numpy arrays element by element is slower.
    qpos = qpos.tolist() if hasattr(qpos, "tolist") else list(qpos)
    qvel = qvel.tolist() if hasattr(qvel, "tolist") else list(qvel)
    # Positional construction (field order of Measurement): keywords are slower, every step.
    return _new_measurement(measure_values(qpos, qvel, lay.addresses, lay.lengths))


def measure_values(qpos, qvel, a: Addresses, n: Lengths) -> tuple:
    """:func:`measure` from the state vectors, the addresses and the lengths: the
    :class:`Measurement` fields as a tuple, the form the compiled episode
    (:mod:`tt_mujoco.sim.loop.compiled`) shares."""
    L, L0, r, d = n.L, n.L0, n.r, n.d
    hitch_q, hitch_v, steer_q = a.hitch_q, a.hitch_v, a.steer_q
    i = a.root_q
    x, y = qpos[i], qpos[i + 1]
    qw, qx, qy, qz = qpos[i + 3], qpos[i + 4], qpos[i + 5], qpos[i + 6]
    theta = yaw_from_quat(qw, qx, qy, qz)
    phi = -qpos[hitch_q]  # hitch axis +z: q_hitch = theta0 - theta
    beta = qpos[steer_q]

    j = a.root_v
    vx, vy = qvel[j], qvel[j + 1]
    # World z component of the body-frame angular velocity: third row of R(quat).
    wx, wy, wz = qvel[j + 3], qvel[j + 4], qvel[j + 5]
    r20 = 2.0 * (qx * qz - qw * qy)
    r21 = 2.0 * (qy * qz + qw * qx)
    r22 = 1.0 - 2.0 * (qx * qx + qy * qy)
    omega = r20 * wx + r21 * wy + r22 * wz

    c, s = math.cos(theta), math.sin(theta)
    v = vx * c + vy * s
    slip_lateral = -vx * s + vy * c

    theta0 = theta - phi
    c0, s0 = math.cos(theta0), math.sin(theta0)
    x0, y0 = hitch_and_axle(x, y, theta, theta0, L, L0)[2:]
    # Rigid-body velocities in the plane, as MuJoCo moved the bodies (slip included).
    vox, voy = vx + omega * L * s, vy - omega * L * c
    theta0_dot = omega + qvel[hitch_v]  # phi_dot = -q_hitch_dot
    v0x, v0y = vox + theta0_dot * L0 * s0, voy - theta0_dot * L0 * c0
    alpha = theta0 + beta
    ca, sa = math.cos(alpha), math.sin(alpha)
    v0 = v0x * ca + v0y * sa
    slip_lateral_trailer = -v0x * sa + v0y * ca

    thl_dot = qvel[a.wheel_left_v]
    thr_dot = qvel[a.wheel_right_v]
    half = 0.5 * d * omega
    return (
        x,
        y,
        theta,
        phi,
        beta,
        v,
        omega,
        x0,
        y0,
        theta0,
        v0,
        qpos[a.wheel_left_q],
        qpos[a.wheel_right_q],
        thl_dot,
        thr_dot,
        slip_lateral,
        slip_lateral_trailer,
        r * thl_dot - (v - half),
        r * thr_dot - (v + half),
    )


class TrainMeasurement(Measurement):
    """:class:`Measurement` of a train: trailer 1 in the usual fields, trailers 2..N in
    :attr:`train`, one tuple of :data:`TRAIN_FIELDS` each. It is a :class:`Measurement` for
    every consumer (a tuple of the same 19 values); :attr:`phis` gives every hitch angle."""

    train: tuple = ()

    @property
    def phis(self) -> tuple:
        """The hitch angles phi_1..phi_N (phi_1 as measured, faults and noise included)."""
        return (self.phi, *(row[ROW_PHI] for row in self.train))

    def _replace(self, **changes):
        out = super()._replace(**changes)
        out.train = self.train
        return out


def _new_train_measurement(values, train) -> TrainMeasurement:
    out = TrainMeasurement._make(values)
    out.train = train
    return out


def measure_train(qpos, qvel, lay: Layout) -> TrainMeasurement:
    """:func:`measure` plus trailers 2..N, each as rigid bodies moved by MuJoCo (slip included):
    trailer k's hitch O_k on trailer k-1's body, L_k behind its axle midpoint."""
    first = measure(qpos, qvel, lay)
    qpos = qpos.tolist() if hasattr(qpos, "tolist") else list(qpos)
    qvel = qvel.tolist() if hasattr(qvel, "tolist") else list(qvel)
    rows = [[0.0] * len(TRAIN_FIELDS) for _ in lay.train]
    train_rows_of(qpos, qvel, lay.addresses, lay.lengths, first, lay.train, rows)
    return _new_train_measurement(first, tuple(tuple(row) for row in rows))


#: Where the tractor's and trailer 1's fields are in a :class:`Measurement`'s values (the step
#: reads a measurement as an array of them).
X, Y, THETA, PHI, BETA, V, OMEGA, X0, Y0, THETA0, V0 = (
    Measurement._fields.index(name)
    for name in ("x", "y", "theta", "phi", "beta", "v", "omega", "x0", "y0", "theta0", "v0")
)


def train_rows_of(qpos, qvel, a: Addresses, n: Lengths, first, train, out) -> None:
    """Trailers 2..N of :func:`measure_train` into ``out[k - 2]`` (:data:`TRAIN_FIELDS`), from
    trailer 1's measurement ``first`` (the :class:`Measurement` fields) and ``train``, one row
    ``(hitch_q, hitch_v, steer_q, L_k, L0_k)`` per trailer. Plain numbers (the compiled episode
    shares it)."""
    # Trailer 1's body: axle midpoint, its rigid velocity, heading and heading rate.
    j = a.root_v
    theta, omega = first[THETA], first[OMEGA]
    vx, vy = qvel[j], qvel[j + 1]
    s, c = math.sin(theta), math.cos(theta)
    fth = first[THETA0]
    fw = omega + qvel[a.hitch_v]
    fx, fy = first[X0], first[Y0]
    fvx = vx + omega * n.L * s + fw * n.L0 * math.sin(fth)
    fvy = vy - omega * n.L * c - fw * n.L0 * math.cos(fth)
    for k in range(len(train)):
        joint = train[k]
        hitch_q, hitch_v, steer_q = int(joint[0]), int(joint[1]), int(joint[2])
        L, L0 = joint[3], joint[4]
        sf, cf = math.sin(fth), math.cos(fth)
        ox, oy = fx - L * cf, fy - L * sf
        ovx, ovy = fvx + fw * L * sf, fvy - fw * L * cf
        phi = -qpos[hitch_q]
        beta = qpos[steer_q]
        thk = fth - phi
        wk = fw + qvel[hitch_v]
        sk, ck = math.sin(thk), math.cos(thk)
        px, py = ox - L0 * ck, oy - L0 * sk
        pvx, pvy = ovx + wk * L0 * sk, ovy - wk * L0 * ck
        alpha = thk + beta
        v0 = pvx * math.cos(alpha) + pvy * math.sin(alpha)
        row = out[k]
        row[0], row[1], row[2], row[3], row[4], row[5] = px, py, thk, phi, beta, v0
        fx, fy, fth, fw, fvx, fvy = px, py, thk, wk, pvx, pvy

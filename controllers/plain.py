"""The second controller form: a plain-number law that the closed loop compiles.

A :class:`~tt_mujoco.controllers.Controller` subclass's ``compute`` is Python, which the
compiled loop calls back at every step. A law written as one plain function of numbers and
named records runs compiled, at the cost of the physics itself, wherever the episode has a
compiled form (:mod:`tt_mujoco.sim.loop.compiled`), and in the Python loop, with the same numbers,
everywhere else::

    from tt_mujoco.controllers import plain_law

    @plain_law(gains={"k_v": 20.0, "k_omega": 20.0}, state=("int_v",))
    def my_law(m, r, model, k, s, dt, torque_limit):
        e_v, e_w = r.v_d - m.v, r.omega_d - m.omega
        s.int_v += e_v * dt
        a_v = r.v_d_dot + k.k_v * e_v + s.int_v - model.f1
        a_w = r.omega_d_dot + k.k_omega * e_w - model.f2
        det = model.g11 * model.g22 - model.g12 * model.g21
        return (model.g22 * a_v - model.g12 * a_w) / det, (model.g11 * a_w - model.g21 * a_v) / det

The law's arguments, each read by field name:

- ``m``: the measurement as the controller sees it (the fields of
  :class:`tt_mujoco.sim.parts.measure.Measurement`, noise included);
- ``r``: the reference (:data:`tt_mujoco.sim.loop.records.REFERENCE_FIELDS`: ``t, s, kappa, v_d,
  omega_d, v_d_dot, omega_d_dot`` and the path's pose ``x_ref, y_ref, theta_ref`` at ``s``);
- ``model``: the nominal model ``V_dot = f + g tau`` at the measurement (``f1, f2, g11, g12,
  g21, g22``);
- ``k``: the gains (the names of ``gains=``; ``--gains``, TOML and sweeps override them);
- ``s``: the law's own state (the names of ``state=``), zero at the start of a run, float
  fields it reads and writes;
- ``dt``: the control period (s); ``torque_limit``: the wheel torque limit (N m).

It returns the two wheel torques ``(T_r, T_l)`` (N m); the loop clips them at the limit. The
body may use arithmetic, ``math`` functions, ``if`` and ``for``: what numba compiles in nopython
mode. ``math.hypot`` is compiled as CPython computes it (numba's own differs in the last bit now
and then), so both loops give the same numbers. A train's measurement carries trailer 1 only in
``m``; the model is the train's.

A law declared with ``plain_law(..., path=True)`` takes two more arguments, ``path`` and
``vehicle`` (:mod:`tt_mujoco.controllers.path_view`): the run's path, read by
``path_pose_at(path, s)`` (pose and curvature at any arc length) and ``path_nearest(path, x,
y, s_near, reach)`` (the nearest point to any point, such as a trailer's axle, with its arc
length and signed distance), and the vehicle's parameters and the direction of travel by name
(``vehicle.L0``, ``vehicle.eta``, ``vehicle.direction``, ...)::

    from tt_mujoco.controllers import plain_law
    from tt_mujoco.controllers.path_view import path_nearest

    @plain_law(gains={"k": 1.0}, state=("s0",), path=True)
    def my_law(m, r, model, k, s, dt, torque_limit, path, vehicle):
        s.s0, x, y, theta, kappa, lateral = path_nearest(path, m.x0, m.y0, s.s0, 0.5)
        ...

``examples/backing_law.py`` backs a trailer along a path this way, on its axle.
"""

from __future__ import annotations

import math
from collections import namedtuple
from collections.abc import Callable, Mapping, Sequence
from numbers import Integral
from typing import ClassVar

import numpy as np
from tt_mujoco.controllers.base import Controller, Nominal
from tt_mujoco.controllers.path_view import VEHICLE_FIELDS, path_table, vehicle_values

__all__ = ["NOMINAL_FIELDS", "REFERENCE_FIELDS", "PlainLawController", "plain_law"]

#: What a law sees of the target (the same names as :mod:`tt_mujoco.sim.loop.records`).
REFERENCE_FIELDS = (
    *("t", "s", "kappa", "v_d", "omega_d", "v_d_dot", "omega_d_dot"),
    *("x_ref", "y_ref", "theta_ref"),
)
#: The nominal model's values at the measurement.
NOMINAL_FIELDS = Nominal._fields

LawReference = namedtuple("LawReference", REFERENCE_FIELDS)
#: The vehicle as a law that sees the path is given it (its Python loop's form).
LawVehicle = namedtuple("LawVehicle", VEHICLE_FIELDS)


class LawState:
    """A law's state in the Python loop: float fields, as the compiled loop's record holds
    them (a value written is stored as a float)."""

    def __init__(self, fields: Sequence[str]):
        for name in fields:
            object.__setattr__(self, name, 0.0)

    def __setattr__(self, name: str, value) -> None:
        if name not in self.__dict__:
            fields = ", ".join(self.__dict__) or "none"
            raise AttributeError(f"the law's state has no field {name!r} (its fields: {fields})")
        object.__setattr__(self, name, float(value))


class PlainLawController(Controller):
    """A plain-number law as a :class:`Controller`: the Python loop's form of it.

    Made by :func:`plain_law`; :attr:`LAW` is the function, :attr:`STATE` its state's field
    names. :mod:`tt_mujoco.sim.loop.compiled` compiles the same function for the compiled loop.
    """

    LAW: ClassVar[Callable]
    STATE: ClassVar[tuple[str, ...]] = ()

    #: Whether the law takes the run's path and the vehicle (``plain_law(..., path=True)``).
    SEES_PATH: ClassVar[bool] = False

    def __init__(self, setup, gains=None):
        super().__init__(setup, gains)
        self.gain_record = namedtuple("Gains", tuple(self._gains))(**self._gains)
        self._train = getattr(setup.params, "n_trailers", 1) > 1
        self.path_table = self.vehicle_record = None
        if self.SEES_PATH:
            if setup.path is None:
                raise ValueError(f"the law {self.name!r} reads the path, and this run has none")
            self.path_table = path_table(setup.path)
            values = vehicle_values(setup.params, setup.reverse)
            self.vehicle_record = LawVehicle(*values)
        self.reset()

    def law_data(self) -> np.ndarray:
        """What the compiled loop hands the law as its gains: the gains, then (a law that sees
        the path) the vehicle's values, the number of the path table's samples and the table,
        row by row (:func:`tt_mujoco.sim.loop.compiled_law.compile_law` reads it back)."""
        gains = np.array(list(self.gain_record) or [0.0], dtype=float)
        if not self.SEES_PATH:
            return gains
        head = [*gains, *self.vehicle_record, float(self.path_table.shape[1])]
        return np.concatenate([np.array(head), self.path_table.ravel()])

    def reset(self) -> None:
        self.law_state = LawState(self.STATE)

    def compute(self, t, measurement, reference):
        m, setup = measurement, self.setup
        model = Nominal(*setup.model(m.phis if self._train else m.phi, m.v, m.omega))
        r = reference
        ref = LawReference(t, r.s, r.kappa, r.v_d, r.omega_d, r.v_d_dot, r.omega_d_dot, *r.pose)
        return _as_stored(self.call_law(m, ref, model, self.law_state))

    def call_law(self, m, r, model, state):
        """The law called in Python as the loops call it: with its gains, ``state``, the
        control period and the torque limit, and, a law that sees the path, its path and
        vehicle (the one call :meth:`compute` and a compiled law's failure replayed make)."""
        setup = self.setup
        path = (self.path_table, self.vehicle_record) if self.SEES_PATH else ()
        return type(self).LAW(
            m, r, model, self.gain_record, state, setup.control_dt, setup.torque_limit, *path
        )


def _as_stored(out):
    """A law's two torques as its compiled form's C entry stores them: a bool (Python's, an
    ``Integral``, or NumPy's) or an integer within numba's 64 bits as a float, so that both
    loops take the same torques; anything else as returned, for the loop's check to refuse."""
    if type(out) is not tuple or len(out) != 2:
        return out
    return tuple(
        float(v)
        if (isinstance(v, Integral) and -(2**63) <= v < 2**63) or type(v).__name__ == "bool_"
        else v
        for v in out
    )


def plain_law(
    *,
    gains: Mapping[str, float] | None = None,
    state: Sequence[str] = (),
    presets: Mapping[str, Mapping[str, float]] | None = None,
    name: str | None = None,
    reverse: bool = True,
    backs_up_itself: bool = False,
    path: bool = False,
) -> Callable[[Callable], type[PlainLawController]]:
    """Declare a plain-number law (module docstring): its gains, its state, its name.

    Parameters
    ----------
    gains : dict, optional
        The default gains, name -> value (the preset ``"default"``).
    state : sequence of str
        The names of the law's state fields (floats, zero at the start of a run).
    presets : dict, optional
        Named gain sets beside (or instead of) ``gains``; the first is the default when
        ``gains`` is not given.
    name : str, optional
        The controller's name (default: the function's).
    reverse : bool
        Whether the law drives the path backwards too.
    backs_up_itself : bool
        Whether, backing up, the law steers the train itself, so that the loop gives it the
        path's own reverse target rather than the hitch cascade's
        (:attr:`~tt_mujoco.controllers.Controller.BACKS_UP_ITSELF`).
    path : bool
        Whether the law takes two more arguments, the run's ``path`` and the ``vehicle``
        (:mod:`tt_mujoco.controllers.path_view`).

    Returns
    -------
    callable
        A decorator that turns the function into a :class:`PlainLawController` subclass,
        usable as ``--controller FILE.py:NAME`` like any controller class.

    Raises
    ------
    ValueError
        A gain that is not a finite number, or a name that is not an identifier.
    """
    table = {str(k): dict(v) for k, v in (presets or {}).items()}
    if gains is not None:
        table = {"default": dict(gains), **table}
    if not table:
        table = {"default": {}}
    state = tuple(state)
    for field in (*state, *(key for gains in table.values() for key in gains)):
        if not (isinstance(field, str) and field.isidentifier()):
            raise ValueError(f"field {field!r} is not allowed: use a Python identifier")
    for preset, values in table.items():
        for key, value in values.items():
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise ValueError(f"gain {preset}.{key}={value!r} is not allowed: use a number")
            if not math.isfinite(value):
                raise ValueError(
                    f"gain {preset}.{key}={value!r} is not allowed: use a finite number"
                )

    def decorate(fn: Callable) -> type[PlainLawController]:
        if not callable(fn):
            raise ValueError(f"plain_law decorates a function, not {fn!r}")
        attrs = {
            "LAW": staticmethod(fn),
            "STATE": state,
            "PRESETS": table,
            "DEFAULT_PRESET": next(iter(table)),
            "REVERSE": bool(reverse),
            "BACKS_UP_ITSELF": bool(backs_up_itself),
            "SEES_PATH": bool(path),
            "name": name or fn.__name__,
            "__doc__": fn.__doc__,
            "__module__": fn.__module__,
            "__qualname__": fn.__qualname__,
        }
        return type(fn.__name__, (PlainLawController,), attrs)

    return decorate

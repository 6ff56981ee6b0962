"""The numba side of :mod:`tt_mujoco.sim.loop.compiled`: imported only when an episode runs
compiled.

It is imported from a copy of this file inside the compiled-code cache
(:func:`tt_mujoco.sim.loop.compiled.kernel`), so that numba's own cache, which checks the source
file's path and time stamp, stays valid for every checkout of the same sources.

The closed loop's step (:mod:`tt_mujoco.sim.loop.closed_loop`) and the plain-number functions it
calls (:data:`tt_mujoco.sim.loop.kernel_sources.SHARED`) are registered with numba here, so the
entry points below compile them from their own source; what only compiled code has (MuJoCo's
``mj_step`` by its symbol, an array's address, exact ``hypot`` and ``remainder``) is given to
them by overloads.
"""

from __future__ import annotations

import math
import types as pytypes

from llvmlite import binding, ir
from numba import cfunc, njit, types
from numba.extending import intrinsic, overload, register_jitable

from tt_mujoco import exact
from tt_mujoco.analysis import nearest
from tt_mujoco.compiled_form import compiled_form_reason
from tt_mujoco.reference import feedback
from tt_mujoco.sim.loop import agent_step, callbacks, closed_loop, law, machine_code, target_step
from tt_mujoco.sim.loop.kernel_sources import SHARED
from tt_mujoco.sim.loop.law import BACK_STATUS, BACK_T_L, BACK_T_R, BACK_U1, BACK_U2
from tt_mujoco.sim.parts import disturbances
from tt_mujoco.vehicle import path_schedule

for _fn in SHARED:
    register_jitable(_fn)

#: The functions given a compiled form here, each marked beside its Python source
#: (:func:`tt_mujoco.compiled_form.compiled_form`; ``tests/test_kernel_sources.py`` holds the
#: two to each other).
COMPILED_FORMS_GIVEN = []


def compiled_form_of(fn):
    """numba's ``overload`` of ``fn``, a function marked with why its compiled form differs."""
    if compiled_form_reason(fn) is None:
        raise TypeError(f"{fn.__qualname__} has a compiled form but no compiled_form mark")
    COMPILED_FORMS_GIVEN.append(fn)
    return overload(fn)


LAW_OK = closed_loop.LAW_OK

#: The step compiles without numba's reference counting: numba counts a reference to every array
#: of every record argument when a function is entered and releases it on exit, pairs its
#: pruning cannot remove where the function branches (a plant record alone holds some forty
#: arrays). It is safe here: every array the step sees belongs to a record that
#: :func:`run_chunk`'s Python caller holds for the whole call, and nothing in the step allocates
#: (numba refuses to compile an allocation without the counting) or returns a new array.
for _fn in closed_loop.BORROWING:
    register_jitable(_nrt=False, inline="always" if _fn in closed_loop.INLINED else "never")(_fn)
# The halves are inlined into the chunk loop: called, each would take every record it is given
# by value, at every step. They are inlined before typing (a dispatcher's inlining), which
# types the loop once, not each half again where it is inlined (an overload's).
_sense_step = njit(_nrt=False, inline="always")(closed_loop.sense_step)
_actuate_step = njit(_nrt=False, inline="always")(closed_loop.actuate_step)

# mj_step by its symbol in MuJoCo's library, which the Python bindings load: no pointer is
# baked into the compiled code, so it can be cached on disk.
binding.load_library_permanently(closed_loop.mujoco_library())
_mj_step = types.ExternalFunction("mj_step", types.void(types.voidptr, types.voidptr))


@compiled_form_of(closed_loop.mj_step)
def _mj_step_by_symbol(model_address, data_address):
    return lambda model_address, data_address: _mj_step(model_address, data_address)


@compiled_form_of(closed_loop.floats)
def _floats(array):
    return lambda array: array


_P = types.CPointer(types.float64)
#: A compiled plain-number law (:mod:`tt_mujoco.controllers.plain`): pointers to the
#: measurement, the reference, the nominal model, the gains, the state and the two torques
#: out, then dt and the torque limit.
USER_LAW = types.void(_P, _P, _P, _P, _P, _P, types.float64, types.float64)


@cfunc(USER_LAW, cache=True)
def no_user_law(m, r, model, gains, state, out, dt, limit):  # the built-in laws' placeholder
    pass


#: A Python hook the kernel calls back (:class:`HookCallback`): what to compute
#: (:data:`~tt_mujoco.sim.loop.target_step.HOOK_CURVATURE` and the others), at which value (s or t),
#: and where to write it.
HOOK = types.void(types.float64, types.float64, _P)


@cfunc(HOOK, cache=True)
def no_hook(what, value, out):  # the placeholder where the episode has no hook
    pass


# The callbacks, as numba types them: first-class functions of the kernel's signatures.
class CalledBack(callbacks.CalledBack, types.WrapperAddressProtocol):
    """:class:`tt_mujoco.sim.loop.callbacks.CalledBack`, which numba types as a first-class
    function of the kernel's :attr:`signature_of`."""


class PythonLawCallback(callbacks.PythonLawCallback, CalledBack):
    signature_of = USER_LAW


class HookCallback(callbacks.HookCallback, CalledBack):
    signature_of = HOOK


# A law's machine code loaded from the cache (compiled_law) is a first-class function to numba
# too, where numba runs the loop (the Gym agent's steps, a test's chunk)
machine_code.CFunction.SIGNATURES.update({callbacks.LAW: USER_LAW, callbacks.HOOK: HOOK})
types.WrapperAddressProtocol.register(machine_code.CFunction)


@intrinsic
def _pointer(typingctx, array):
    """The address of a contiguous array's data (of float fields), as a C float pointer."""

    def codegen(context, builder, signature, args):
        data = context.make_array(signature.args[0])(context, builder, args[0]).data
        return builder.bitcast(data, context.get_value_type(_P))

    return _P(array), codegen


@compiled_form_of(law.pointer)
def _pointer_of(array):
    return lambda array: _pointer(array)


def address_of(function) -> int:
    """The address of a C function the kernel calls (:func:`tt_mujoco.sim.loop.callbacks.
    address_of`), which an agent's records hold (:func:`_call_hook`)."""
    return callbacks.address_of(function)


@intrinsic
def _call_hook_at(typingctx, address, what, value, out):
    """The hook (:data:`HOOK`) at ``address`` (an integer) called."""

    def codegen(context, builder, sig, args):
        wanted = HOOK.args
        function_type = ir.FunctionType(ir.VoidType(), [context.get_value_type(t) for t in wanted])
        function = builder.inttoptr(args[0], function_type.as_pointer())
        given = zip(args[1:], sig.args[1:], wanted, strict=True)
        builder.call(function, [context.cast(builder, v, kind, to) for v, kind, to in given])
        return context.get_dummy_value()

    return types.void(address, what, value, out), codegen


def _call_hook(hook, what, value, out):
    """The hook (:data:`HOOK`) a record holds called: a C function object, or its address."""


# A record names its C functions by object for the chunk loop, which takes them once a chunk,
# and by address for an agent's step, which takes them at every call (an object is looked up
# each time, an integer passed at no cost; the agent's step never calls the law). Inlined:
# called, the chunk loop's code came out a third slower on the reduced plant.
@overload(_call_hook, inline="always")
def _call_hook_by(hook, what, value, out):
    if isinstance(hook, types.Integer):
        return lambda hook, what, value, out: _call_hook_at(hook, what, value, out)
    return lambda hook, what, value, out: hook(what, value, out)


@njit(cache=True)
def project_points(points, window, extend, table, out):
    """:func:`tt_mujoco.analysis.nearest.nearest_segments_of`, compiled: every point of
    ``points = (px, py)``'s nearest segment in ``window = (lo, hi)`` into ``out = (d2, seg,
    t)``."""
    nearest.nearest_segments_of(points, window, extend, table, out)


@compiled_form_of(path_schedule.path_pose)
def _path_pose(target, s):
    """The path schedule's projection and the path feedback read the target record's path
    (:func:`~tt_mujoco.sim.loop.target_step.pose_at`)."""
    return lambda target, s: target_step.pose_at(target, s)


# A path without closed form and a user's disturbance are Python, called back (HookCallback),
# asked what closed_loop.HOOK_* name.
@compiled_form_of(target_step.hooked_curvature)
def _hooked_curvature(target, s):
    def call_back(target, s):
        out = target.hook_out
        _call_hook(target.path_hook, target_step.HOOK_CURVATURE, s, _pointer(out))
        return out[0], out[1]

    return call_back


def _pose_called_back(what: float):
    """The pose of a path called back, asked as ``what``."""

    def call_back(target, s):
        out = target.hook_out
        _call_hook(target.path_hook, what, s, _pointer(out))
        return out[0], out[1], out[2]

    return call_back


@compiled_form_of(target_step.hooked_pose)
def _hooked_pose(target, s):
    return _pose_called_back(target_step.HOOK_POSE)


@compiled_form_of(target_step.hooked_law_pose)
def _hooked_law_pose(target, s):
    return _pose_called_back(target_step.HOOK_LAW_POSE)


@compiled_form_of(disturbances.hooked_disturbance_at)
def _hooked_disturbance_at(loop, t):
    def call_back(loop, t):
        out = loop.hook_out
        _call_hook(loop.disturbance_hook, disturbances.HOOK_DISTURBANCE, t, _pointer(out))
        return out[0], out[1]

    return call_back


@compiled_form_of(law.python_law)
def _python_law(law):
    """A law Python computes (a controller class's ``compute``), called back: ``law.user`` is
    then a C function (:class:`PythonLawCallback`) that reads the law
    record from Python and writes ``(T_r, T_l, u1, u2, status)`` into ``law.torques``."""

    def call_back(law):
        out = law.torques
        at = _pointer(out)
        law.user(at, at, at, at, at, at, 0.0, 0.0)
        status = int(out[BACK_STATUS])
        return status, out[BACK_T_R], out[BACK_T_L], out[BACK_U1], out[BACK_U2]

    return call_back


def _dispatch(functions, args: str):
    """``run(kind, ARGS)`` calling ``functions[kind](ARGS)``: a test of ``kind`` for each,
    written out (numba cannot index a tuple of functions at run time)."""
    lines = [f"def run(kind, {args}):"]
    for i in range(len(functions) - 1):
        lines += [f"    if kind == {i}:", f"        return FUNCTION_{i}({args})"]
    lines.append(f"    return FUNCTION_{len(functions) - 1}({args})")
    scope = {f"FUNCTION_{i}": function for i, function in enumerate(functions)}
    exec("\n".join(lines), scope)
    return scope["run"]


@compiled_form_of(law.run_law)
def _run_law(kind, dt, tracking, model, state, gains, saturation):
    """:func:`~tt_mujoco.sim.loop.law.run_law` with a test of ``kind`` for each law, written out
    (:func:`~tt_mujoco.sim.loop.law.run_law_written_out`)."""
    return law.run_law_written_out()


@compiled_form_of(disturbances.run_disturbance)
def _run_disturbance(kind, t, v, omega, params):
    """The built-in disturbance of index ``kind`` in ``disturbances.DISTURBANCE_FORMS``."""
    return _dispatch(disturbances.DISTURBANCE_FORMS, "t, v, omega, params")


@compiled_form_of(feedback.feedback_curvature)
def _feedback_curvature(target, s):
    """The path feedback reads the target record's path
    (:func:`~tt_mujoco.sim.loop.target_step.path_at`)."""
    return lambda target, s: target_step.path_at(target, s)


#: C's IEEE remainder (exact, as Python's ``math.remainder``), which numba does not provide.
_remainder = types.ExternalFunction("remainder", types.float64(types.float64, types.float64))


@overload(math.remainder)
def _math_remainder(x, y):
    return lambda x, y: _remainder(x, y)


#: The smallest normal float (C's DBL_MIN).
_DBL_MIN = 2.2250738585072014e-308


@njit(cache=True)
def _square(a):
    """``a * a`` as an unevaluated sum ``(hi, lo)``, exactly (Dekker's split, no fma)."""
    t = a * 134217729.0  # 2**27 + 1
    hi = t - (t - a)
    lo = a - hi
    p = hi * hi
    q = hi * lo + lo * hi
    z = p + q
    return z, p - z + q + lo * lo


@njit(cache=True)
def _hypot(x, y):
    """CPython's ``math.hypot`` of two floats, the same to the last bit (tested on normal floats;
    a pair of subnormals may differ): the squares summed exactly after scaling by a power of
    two, then one differential correction of the root."""
    x, y = abs(x), abs(y)
    if math.isinf(x) or math.isinf(y):
        return math.inf
    if math.isnan(x) or math.isnan(y):
        return math.nan
    top = max(x, y)
    if top == 0.0:
        return top
    exponent, factor = math.frexp(top)[1], 1.0
    if exponent < -1023:  # 2**-exponent would overflow: scaled up first, as CPython does
        x, y, factor = x / _DBL_MIN, y / _DBL_MIN, _DBL_MIN
        exponent = math.frexp(top / _DBL_MIN)[1]
    scale = math.ldexp(1.0, -exponent)
    total, low1, low2 = 1.0, 0.0, 0.0
    for value in (x * scale, y * scale):
        hi, lo = _square(value)
        added = total + hi
        low2 += (total - added) + hi
        total = added
        low1 += lo
    h = math.sqrt(total - 1.0 + (low1 + low2))
    hi, lo = _square(h)
    added = total - hi
    low2 += (total - added) - hi
    total = added
    low1 -= lo
    h += (total - 1.0 + (low1 + low2)) / (2.0 * h)
    return factor * (h / scale)


@compiled_form_of(exact.hypot_of)
def _hypot_of(x, y):
    """The shared functions' hypot gives Python's numbers (:func:`_hypot`)."""
    return lambda x, y: _hypot(x, y)


def _with_halves(fn, **inlined):
    """``fn`` (:func:`~tt_mujoco.sim.loop.closed_loop.run_steps`, an agent's step) reading the
    inlined halves where its source names the plain ones (and the ``inlined`` functions where it
    names them)."""
    names = {**fn.__globals__, "sense_step": _sense_step, "actuate_step": _actuate_step, **inlined}
    return pytypes.FunctionType(fn.__code__, names, fn.__name__, fn.__defaults__)


_run_steps = njit(_nrt=False, inline="always")(_with_halves(closed_loop.run_steps))


@njit(cache=True, nogil=True, _nrt=False)  # without the counting: see closed_loop.BORROWING
def run_chunk(k, k_end, loop, plant, law, target, log, stop_record):
    """:func:`tt_mujoco.sim.loop.closed_loop.run_steps`, compiled: control steps ``k..k_end``;
    ``(status, k)``."""
    return _run_steps(k, k_end, loop, plant, law, target, log, stop_record)


_sense_and_observe = njit(_nrt=False, inline="always")(_with_halves(agent_step.sense_and_observe))
_act_then_sense = njit(_nrt=False, inline="always")(
    _with_halves(agent_step.act_then_sense, sense_and_observe=_sense_and_observe)
)


@njit(cache=True, nogil=True, _nrt=False)  # without the counting: see closed_loop.BORROWING
def agent_sense(k, episode, agent):
    """:func:`tt_mujoco.sim.loop.agent_step.sense_and_observe`, compiled; the stop code."""
    return _sense_and_observe(k, episode, agent)


@njit(cache=True, nogil=True, _nrt=False)
def agent_act(k, T_r, T_l, episode, agent):
    """:func:`tt_mujoco.sim.loop.agent_step.act_then_sense`, compiled; the stop code."""
    return _act_then_sense(k, T_r, T_l, episode, agent)


@njit(cache=True)
def advance_after_payload(plant, weather, stop_record):
    """:func:`tt_mujoco.sim.loop.closed_loop.advance_after_payload`, compiled; the stop code."""
    return closed_loop.advance_after_payload(plant, weather, stop_record)

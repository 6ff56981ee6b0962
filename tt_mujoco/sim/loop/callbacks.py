"""The C functions the compiled chunk loop calls: Python code called back, and placeholders.

The loop's records name three C functions (the law, the path, the disturbance). A built-in law
on a closed-form path with the paper's disturbance calls none of them, and the records hold a
placeholder; Python code the loop must run (a controller's ``compute``, a path without closed
form, a user's disturbance) is a :class:`CalledBack`, a C function made by ``ctypes``. Nothing
here imports numba: the machine-code loop (:mod:`tt_mujoco.sim.loop.machine_code`) runs without
it; the kernel (:mod:`tt_mujoco.sim.loop._kernel`) gives these classes the numba types of its
signatures, for the steps it runs through numba.
"""

from __future__ import annotations

import ctypes
import math

from tt_mujoco.sim.loop.law import BACK_STATUS, BACK_T_L, BACK_T_R, BACK_U1, BACK_U2, LAW_OK

__all__ = [
    "HOOK",
    "LAW",
    "CalledBack",
    "HookCallback",
    "Placeholder",
    "PythonLawCallback",
    "address_of",
    "c_function",
    "kind_of",
    "no_hook",
    "no_user_law",
]

#: The kinds of C function the loop calls, by their C signatures: a law (pointers to the
#: measurement, the reference, the nominal model, the gains, the state and the torques out,
#: then dt and the torque limit) and a hook (what to compute, at which value, where to write).
LAW, HOOK = "law", "hook"
_C_TYPES = {
    LAW: ctypes.CFUNCTYPE(None, *[ctypes.c_void_p] * 6, ctypes.c_double, ctypes.c_double),
    HOOK: ctypes.CFUNCTYPE(None, ctypes.c_double, ctypes.c_double, ctypes.c_void_p),
}


class CalledBack:
    """Python code as a C function the kernel calls back, of the kind :attr:`kind`. What the
    code raises cannot leave a C callback: it sets the stop record's ``raised``, which stops
    the step where CPython's would have stopped (:func:`~tt_mujoco.sim.loop.closed_loop.run_steps`),
    and waits in :attr:`raised` for the kernel's caller to raise it; once it is set, nothing
    is called back again."""

    kind = None
    signature_of = None  # the kernel's numba type of the function (tt_mujoco.sim.loop._kernel)

    def __init__(self, fn):
        self.fn = fn
        self.stop_record = None  # the episode's stop record (Stepper.begin)
        self.raised = None
        self._function = _C_TYPES[self.kind](self._call)  # held: the kernel calls its address

    def _failed(self, err: BaseException) -> None:
        self.raised = err
        self.stop_record[0]["raised"] = 1.0

    def _call(self, *args):
        raise NotImplementedError

    def __wrapper_address__(self):
        return ctypes.cast(self._function, ctypes.c_void_p).value

    def signature(self):
        return self.signature_of


class PythonLawCallback(CalledBack):
    """A law Python computes (``python_law(law) -> (status, T_r, T_l, u1, u2)``, a controller
    class's ``compute`` with its checks) as a C function of the kernel's law signature, which
    the kernel calls back at every step (``_kernel._python_law``): the step runs compiled, and
    only the law in Python."""

    kind = LAW

    def __init__(self, python_law):
        super().__init__(python_law)
        self.law_record = None  # the kernel's law record, which the law reads (Stepper.begin)

    def _call(self, *_):
        law = self.law_record
        status, T_r, T_l, u1, u2 = LAW_OK, math.nan, math.nan, math.nan, math.nan
        if not self.stop_record[0]["raised"]:
            try:
                status, T_r, T_l, u1, u2 = self.fn(law)
            except BaseException as err:  # raised by the kernel's caller
                self._failed(err)
        out = law.torques
        out[BACK_T_R], out[BACK_T_L], out[BACK_U1], out[BACK_U2] = T_r, T_l, u1, u2
        out[BACK_STATUS] = status


class HookCallback(CalledBack):
    """A user's path or disturbance, ``fn(what, value) -> tuple``, as a C function the kernel
    calls back, writing its answer into ``out`` (the record's ``hook_out``)."""

    kind = HOOK

    def __init__(self, fn, out):
        super().__init__(fn)
        self.out = out

    def _call(self, what, value, _):
        out = self.out
        if not self.stop_record[0]["raised"]:
            try:
                answer = self.fn(what, value)
                out[: len(answer)] = answer
                return
            except BaseException as err:  # raised by the kernel's caller
                self._failed(err)
        out[:] = math.nan


class Placeholder:
    """A C function of a kind that does nothing: where an episode has no such function (a
    built-in law, a path with closed form), which the loop never calls."""

    def __init__(self, kind: str):
        self.kind = kind
        self._function = _C_TYPES[kind](lambda *args: None)

    def __wrapper_address__(self):
        return ctypes.cast(self._function, ctypes.c_void_p).value


no_user_law, no_hook = Placeholder(LAW), Placeholder(HOOK)


def c_function(kind: str, address: int):
    """The C function of ``kind`` at ``address``, callable from Python (``ctypes``)."""
    return _C_TYPES[kind](address)


def kind_of(function) -> str | None:
    """The kind of C function ``function`` is (:data:`LAW` or :data:`HOOK`): a callback, a
    placeholder, or a user's law compiled by numba (a ``cfunc`` of the law signature); None
    for anything else."""
    kind = getattr(function, "kind", None)
    if kind in _C_TYPES:
        return kind
    if hasattr(function, "native_name") and hasattr(function, "address"):
        return LAW  # numba's cfunc: only a user's law is compiled apart from the loop
    return None


def address_of(function) -> int:
    """The address of a C function the kernel calls: a callback's or a placeholder's, or a
    compiled function's (a user's law, the kernel's placeholders)."""
    if hasattr(function, "__wrapper_address__"):
        return function.__wrapper_address__()
    return function.address

"""What the compiled kernel compiles: the closed loop's step and every plain-number function it
calls, discovered from the step itself, not listed by hand.

:data:`STEP` (the step's functions), :data:`LAWS` (the built-in laws) and the nearest-segment
search the metrics compile are the roots; :func:`discover` follows, through each function's
code, every function of the package it names (directly, or as ``module.function`` of one of
the package's modules), and then theirs. A function marked with
:func:`tt_mujoco.compiled_form.compiled_form` is not followed: the kernel gives it a form of its
own. :mod:`tt_mujoco.sim.loop._kernel` registers each of :data:`SHARED` with numba, and
:func:`tt_mujoco.sim.loop.cache_key.source_digest` keys the compiled-code cache by the files they
are defined in (:func:`source_files`): a helper a new part calls is compiled and watched with no
list to keep. Importing this module imports no numba.
"""

from __future__ import annotations

import dis
import inspect
import types

from tt_mujoco.analysis import nearest
from tt_mujoco.compiled_form import compiled_form_reason
from tt_mujoco.controllers import backing, path_view
from tt_mujoco.sim.loop import agent_step, closed_loop, law, records
from tt_mujoco.sim.parts import disturbances, measure, motors, wind
from tt_mujoco.vehicle import reduced, train
from tt_mujoco.world import part

__all__ = [
    "AGENT",
    "COMPILED_FORMS",
    "LAWS",
    "RECORDS",
    "SHARED",
    "STEP",
    "discover",
    "source_files",
]

#: The built-in laws (:data:`tt_mujoco.sim.loop.law.LAWS`).
LAWS = law.LAWS

#: The closed loop's step (:mod:`tt_mujoco.sim.loop.closed_loop`), which the kernel registers with
#: its own options.
STEP = (*closed_loop.BORROWING, *closed_loop.HALVES)
#: An agent's step (:mod:`tt_mujoco.sim.loop.agent_step`), which the kernel compiles as its own
#: entry points, with the step's halves inlined.
AGENT = (agent_step.act_then_sense, agent_step.sense_and_observe)

_PACKAGE = "tt_mujoco."


def _ours(obj) -> bool:
    return getattr(obj, "__module__", None) is not None and (
        obj.__module__.startswith(_PACKAGE) or obj.__module__ == "tt_mujoco"
    )


def _codes(code: types.CodeType):
    """A function's code and the code nested in it (comprehensions, inner functions)."""
    yield code
    for const in code.co_consts:
        if isinstance(const, types.CodeType):
            yield from _codes(const)


def _called(fn) -> set:
    """The package's functions that ``fn``'s code loads: a global one (``name(...)``), or one
    of a module of the package that it holds (``module.name(...)``), read from its bytecode."""
    scope, found = fn.__globals__, set()
    for code in _codes(fn.__code__):
        module = None
        for ins in dis.get_instructions(code):
            obj = None
            if ins.opname == "LOAD_GLOBAL":
                obj = scope.get(ins.argval)
                module = obj if isinstance(obj, types.ModuleType) else None
            elif ins.opname in ("LOAD_ATTR", "LOAD_METHOD") and module is not None:
                obj, module = vars(module).get(ins.argval), None
            else:
                module = None
            if isinstance(obj, types.FunctionType) and _ours(obj):
                found.add(obj)
    return found


def discover(roots, step=()) -> tuple[tuple, tuple]:
    """``(called, compiled_forms)``: the ``roots`` and every function of the package they
    call, directly or through each other, that the kernel compiles from its source (the
    ``step``'s functions, which it registers with their own options, excluded), and those they
    reach that are marked to have a compiled form of their own; each in the order of their
    modules and lines, so the same sources give the same tuples."""
    seen, stack, marked = set(roots), list(roots), set()
    while stack:
        for fn in _called(stack.pop()):
            if fn in seen:
                continue
            seen.add(fn)
            if compiled_form_reason(fn) is not None:
                marked.add(fn)
                continue
            stack.append(fn)
    order = lambda fn: (fn.__module__, fn.__code__.co_firstlineno)  # noqa: E731
    called = sorted(seen - set(step) - marked, key=order)
    return tuple(called), tuple(sorted(marked, key=order))


#: What the kernel compiles besides the step (and the functions a user's plain-number law may
#: call on its path, :data:`tt_mujoco.controllers.path_view.LAW_LIBRARY`), and the functions
#: whose compiled form it gives itself (:func:`tt_mujoco.compiled_form.compiled_form`).
SHARED, COMPILED_FORMS = discover(
    (
        *STEP,
        closed_loop.run_steps,
        *AGENT,
        *LAWS,
        *disturbances.DISTURBANCE_FORMS,
        nearest.nearest_segments_of,
        *path_view.LAW_LIBRARY,
    ),
    step=(*STEP, closed_loop.run_steps, *AGENT),
)


#: The record types the kernel takes: their fields are part of its compiled signature.
RECORDS = (
    records.Limits,
    backing.CascadeConstants,
    records.LoopRecord,
    records.FaultRecord,
    records.WindRecord,
    records.DelayRecord,
    records.GroundRecord,
    part.WorldRecord,
    wind.DragConstants,
    motors.MotorConstants,
    records.PlantRecord,
    records.SteeringRecord,
    records.MujocoRecord,
    records.LawRecord,
    records.TargetRecord,
    records.LogRecord,
    measure.Addresses,
    measure.Lengths,
    reduced.ModelConstants,
    train.TrainConstants,
)


def source_files() -> list[str]:
    """The files the shared functions and the record types are defined in, each once, in the
    order of their modules' names (so the same sources in another folder list alike); numba
    compiles the functions with their module's constants, so the whole file counts."""
    objects = (*SHARED, *STEP, *AGENT, *COMPILED_FORMS, *RECORDS)
    files = {obj.__module__: inspect.getsourcefile(obj) for obj in objects}
    return [files[module] for module in sorted(files)]

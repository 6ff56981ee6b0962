"""Which machine code a run calls: a kernel function's entry loaded from the cache, compiled
here where the process may compile, or none (then the Python loop, or the vectorised search,
serves).

An entry (:mod:`tt_mujoco.sim.loop.machine_code`) is found by the function's name and its
arguments' structure; compiling one (:mod:`tt_mujoco.sim.loop._entry_compile`) takes numba and
the kernel, and a minute for the chunk loop, so only a process that has loaded the kernel, the
background compile, or one told to (``TT_MUJOCO_COMPILE_NOW=1``) does it.
"""

from __future__ import annotations

from collections.abc import Callable

from tt_mujoco.sim.loop import machine_code

__all__ = ["call", "entry"]


def entry(name: str, args: tuple, may_compile: Callable[[], bool]):
    """The entry of the kernel's function ``name`` for ``args``: loaded from the cache, or
    compiled and written there when ``may_compile()``; None otherwise.

    Raises
    ------
    tt_mujoco.sim.loop.machine_code.MachineCodeError
        When the cache's entry is damaged or does not load.
    OSError
        When a compiled entry cannot be written.
    """
    from tt_mujoco.sim.loop import compiled

    cache = compiled._cache_dir()
    key = machine_code.entry_key(name, args)
    found = machine_code.entry_for(cache, key)
    if found is not None or not may_compile():
        return found
    from tt_mujoco.sim.loop._entry_compile import compile_entry

    obj, symbols = compile_entry(compiled.kernel(), name, args)
    machine_code.write_entry(cache, key, obj, symbols)
    compiled._write_manifest(compiled_here=True)
    return machine_code.entry_for(cache, key)


def call(found, args: tuple):
    """The entry ``found`` called on ``args``."""
    return found(*machine_code.flatten(args))

"""The kernel's entry points as machine code on disk, loaded without numba.

Loading the kernel through numba costs a cold process about a second (numba's import, its
target's registries, the cached code's typing), several times the main run's physics. So the
background compile (:func:`tt_mujoco.sim.loop.compiled.warm_up`) also writes, for each kernel
function a run calls (the chunk loop, the metrics' projection) and each kind of arguments it
is given, one *entry*: the function compiled by numba behind a plain signature,
``entry(ints, floats)``, which rebuilds the arguments from two flat arrays
(:mod:`tt_mujoco.sim.loop._entry_compile` generates it), and its object code. A process loads
that object code with llvmlite alone (a few milliseconds) and calls the entry's CPython wrapper:
the same machine code numba would run, the same numbers. A user's plain-number law is kept the
same way, as a C function (:func:`c_function_at`).

Files, in the compiled-code cache folder's ``machine/``: ``KEY.o`` (the object code) and
``KEY.json`` (its symbols, its flat sizes and the object's sha256), ``KEY`` a hash of the
function's name and its arguments' structure (:func:`entry_key`). The JSON is written last, so
a reader sees a whole pair or none; an object whose hash differs is never loaded.
"""

from __future__ import annotations

import contextlib
import ctypes
import hashlib
import importlib.util
import json
import threading
from pathlib import Path
from typing import ClassVar

import numpy as np

from tt_mujoco.outputs import atomic_write
from tt_mujoco.sim.loop import callbacks

__all__ = [
    "MACHINE_DIR",
    "CFunction",
    "MachineCodeError",
    "c_function_at",
    "entry_for",
    "entry_key",
    "flatten",
    "has_entries",
    "prepare",
    "write_entry",
    "write_object",
]

#: The cache folder's subfolder of machine-code entries.
MACHINE_DIR = "machine"
#: The object format's version: part of every key, so a change of this module's layout never
#: loads an older file.
_FORMAT = 1


class MachineCodeError(Exception):
    """An entry on disk that cannot be used (a hash that differs, a file that does not load);
    the message says which and why."""


def _shape_key(value) -> object:
    """What an entry's machine code depends on in ``value``: numba's type of it, told from
    Python (an array's dtype, dimensions, layout, writability and alignment; a named tuple's
    class; a number's class; a C function's kind)."""
    if isinstance(value, np.ndarray):
        flags = value.flags
        layout = "C" if flags.c_contiguous else ("F" if flags.f_contiguous else "A")
        return ("array", value.dtype.descr, value.ndim, layout, flags.writeable, flags.aligned)
    if isinstance(value, tuple):
        cls = type(value)
        return (f"{cls.__module__}.{cls.__qualname__}", [_shape_key(v) for v in value])
    if type(value) in (bool, int, float):
        return type(value).__name__
    kind = callbacks.kind_of(value)
    if kind is None:
        raise TypeError(f"no machine-code form for a {type(value).__name__} argument")
    return kind


def entry_key(name: str, args: tuple) -> str:
    """The key of the entry that runs the kernel's function ``name`` on ``args``: a hash of
    the name and the arguments' structure (:func:`_shape_key`)."""
    text = json.dumps([_FORMAT, name, _shape_key(tuple(args))], default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:24]


def flatten(args: tuple) -> tuple[np.ndarray, np.ndarray]:
    """``(ints, floats)``: every leaf of ``args`` in order, as an entry reads them: an
    array as its data address, its shape and its strides; a bool or an integer; a C function
    as its address (into ``ints``); a float (into ``floats``)."""
    ints, floats = [], []

    def walk(value):
        if isinstance(value, np.ndarray):
            ints.append(value.ctypes.data)
            ints.extend(value.shape)
            ints.extend(value.strides)
        elif isinstance(value, tuple):
            for item in value:
                walk(item)
        elif isinstance(value, float):
            floats.append(value)
        elif isinstance(value, int):  # bool included
            ints.append(int(value))
        else:
            ints.append(callbacks.address_of(value))

    walk(args)
    return np.array(ints, np.int64), np.array(floats, np.float64)


def _folder(cache: Path) -> Path:
    return cache / MACHINE_DIR


def has_entries(cache: Path) -> bool:
    """Whether the cache folder holds any machine-code entry."""
    try:
        return any(_folder(cache).glob("*.json"))
    except OSError:
        return False


def write_entry(cache: Path, key: str, obj: bytes, symbols: dict) -> None:
    """Write the chunk loop's entry for ``key`` (:func:`write_object` in the cache's
    :data:`MACHINE_DIR`)."""
    write_object(_folder(cache), key, obj, symbols)


def write_object(folder: Path, name: str, obj: bytes, symbols: dict) -> None:
    """Write object code and its description (atomically, the description last)."""
    folder.mkdir(parents=True, exist_ok=True)
    atomic_write(folder / f"{name}.o", obj)
    meta = {**symbols, "sha256": hashlib.sha256(obj).hexdigest(), "format": _FORMAT}
    atomic_write(folder / f"{name}.json", json.dumps(meta, indent=1))


#: Loaded entries of this process, by key; and every engine loaded (its code stays).
_LOADED: dict = {}
_ENGINES: list = []


def entry_for(cache: Path, key: str):
    """The loaded entry of ``key`` (a function of ``(ints, floats)``, :func:`flatten`'s), or
    None when the cache has none.

    Raises
    ------
    MachineCodeError
        When the entry's files are damaged or do not load.
    """
    if key not in _LOADED:
        loaded = _loaded(_folder(cache), key, _entry)
        if loaded is None:
            return None
        _LOADED[key] = loaded
    return _LOADED[key]


class CFunction:
    """A C function of machine code on disk, of a kind the loop calls
    (:func:`tt_mujoco.sim.loop.callbacks.kind_of`): a user's law."""

    #: numba's types of the kinds, which the kernel gives where numba runs (``_kernel``).
    SIGNATURES: ClassVar[dict] = {}

    def __init__(self, kind: str, address: int, engine):
        self.kind, self._address, self._engine = kind, address, engine

    def __wrapper_address__(self):
        return self._address

    def signature(self):
        return self.SIGNATURES[self.kind]

    def __call__(self, *args):
        """Called from Python as numba's ``cfunc`` is (the Python loop calls a user's law so)."""
        return callbacks.c_function(self.kind, self._address)(*args)


def c_function_at(folder: Path, name: str, kind: str) -> CFunction | None:
    """The C function of object ``name`` in ``folder`` (its description's ``symbol``), loaded;
    None when there is none.

    Raises
    ------
    MachineCodeError
        When its files are damaged or do not load.
    """

    def function(engine, meta):
        address = engine.get_function_address(meta["symbol"])
        if not address:
            raise MachineCodeError("its symbol is not in it")
        return CFunction(kind, address, engine)

    return _loaded(folder, name, function)


def _loaded(folder: Path, name: str, make):
    """``make(engine, description)`` of object ``name`` in ``folder``, loaded into an engine of
    its own (objects define the same helper functions) once its hash is checked: llvmlite
    loading damaged object code can crash the process. None when there is no such object."""
    try:
        meta = json.loads((folder / f"{name}.json").read_text())
    except FileNotFoundError:
        return None
    except (OSError, ValueError) as err:
        raise MachineCodeError(f"{folder / name}.json does not read: {err}") from err
    try:
        obj = (folder / f"{name}.o").read_bytes()
    except OSError as err:
        raise MachineCodeError(f"{folder / name}.o does not read: {err}") from err
    if not isinstance(meta, dict) or meta.get("sha256") != hashlib.sha256(obj).hexdigest():
        raise MachineCodeError(f"{folder / name}.o differs from its description")
    try:
        llvm, _ = _llvm()
        # a target machine of its own: the engine owns it and frees it with itself
        machine = llvm.Target.from_default_triple().create_target_machine()
        engine = llvm.create_mcjit_compiler(llvm.parse_assembly(""), machine)
        _ENGINES.append(engine)  # never freed: a record may still hold an address in it
        engine.add_object_file(llvm.ObjectFileRef.from_data(obj))
        engine.finalize_object()
        return make(engine, meta)
    except Exception as err:  # llvmlite refuses it: a foreign or damaged object
        raise MachineCodeError(f"{folder / name}.o does not load: {err}") from err


def _numba_extension(where: str):
    """numba's C extension module at ``where`` in its package (``_helperlib``,
    ``core/runtime/_nrt_python``), loaded alone: importing it as numba's own would import
    numba."""
    folder, name = (
        (Path(importlib.util.find_spec("numba").origin).parent / where).parent,
        Path(where).name,
    )
    path = next(folder.glob(f"{name}.*.so"), None) or next(folder.glob(f"{name}.*.pyd"))
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


_LLVM = None
_LLVM_LOCK = threading.Lock()


def prepare() -> None:
    """Set llvmlite up (:func:`_llvm`) in a thread of its own: loading its library, most of
    what a process's first entry costs, goes on beside the caller's work (the library loads
    without Python's lock)."""
    if _LLVM is None:
        threading.Thread(target=_prepared, name="tt_mujoco-machine-code", daemon=True).start()


def _prepared() -> None:
    with contextlib.suppress(Exception):  # said where the entry is loaded, if it fails again
        _llvm()


def _llvm():
    """llvmlite, set up with the symbols numba's code calls (numba's helpers and runtime,
    MuJoCo's C library for ``mj_step``), and numba's ``_dynfunc`` (the environment a CPython wrapper
    checks)."""
    global _LLVM
    with _LLVM_LOCK:
        if _LLVM is None:
            _LLVM = _set_up_llvm()
    return _LLVM


def _set_up_llvm():
    """:func:`_llvm`'s set-up, once."""
    import llvmlite.binding as llvm
    import mujoco

    llvm.initialize_native_target()
    llvm.initialize_native_asmprinter()
    for name, address in _numba_extension("_helperlib").c_helpers.items():
        llvm.add_symbol(f"numba_{name}", address)
    # its runtime (an exception's info is freed through it), as numba registers it
    for name, address in _numba_extension("core/runtime/_nrt_python").c_helpers.items():
        llvm.add_symbol(name if name.startswith("_") else f"NRT_{name}", address)
    here = Path(mujoco.__file__).parent  # MuJoCo's C library: Linux's, macOS's or Windows'
    for pattern in ("libmujoco.so*", "libmujoco*.dylib", "mujoco*.dll"):
        library = next(here.glob(pattern), None)
        if library is not None:
            llvm.load_library_permanently(str(library))
            break
    return llvm, _numba_extension("_dynfunc")


_WRAPPER = ctypes.PYFUNCTYPE(ctypes.py_object, ctypes.py_object, ctypes.py_object, ctypes.py_object)


def _entry(engine, meta: dict):
    """The entry's CPython wrapper in ``engine``, callable as ``entry(ints, floats)``: its
    environment (numba's, which the wrapper checks) set first."""
    environment = _llvm()[1].Environment({})
    env_address = engine.get_global_value_address(meta["env"])
    wrapper = engine.get_function_address(meta["wrapper"])
    if not env_address or not wrapper:
        raise MachineCodeError("its symbols are not in it")
    ctypes.c_void_p.from_address(env_address).value = id(environment)
    call = _WRAPPER(wrapper)
    n_ints, n_floats = meta["ints"], meta["floats"]

    def entry(ints, floats):
        if ints.size != n_ints or floats.size != n_floats:
            raise MachineCodeError(f"arguments of {ints.size}, {floats.size} leaves")
        return call(None, (ints, floats), None)

    entry.keep = (engine, environment, call)  # held while the entry can run
    return entry

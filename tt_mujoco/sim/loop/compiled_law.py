"""A user's plain-number law compiled with the kernel's law signature, cached across processes.

A ``@plain_law`` function (:mod:`tt_mujoco.controllers.plain`) runs in the compiled loop
through a C entry (:data:`_ENTRY_SOURCE`) that views the law record's arrays as the law's named
records. The entry is compiled once per law and version, and its machine code written into the
compiled-code cache, keyed by the law's source and everything it calls (:func:`_law_digest`),
so a law's second process loads it, without numba (:func:`_machine_law`), instead of
compiling it. ``math`` and ``math.hypot`` in the law
are read as CPython computes them (:func:`_as_compiled`), so the compiled law gives the numbers
of its Python form.
"""

from __future__ import annotations

import contextlib
import hashlib
import inspect
import math
import sys
from pathlib import Path

from tt_mujoco.outputs import atomic_write
from tt_mujoco.sim.loop.compiled import _cache_dir, kernel

__all__ = ["compile_failure", "compile_law", "frozen_values"]


def compile_law(cls):
    """The plain-number law of ``cls`` (a :class:`~tt_mujoco.controllers.plain.
    PlainLawController` subclass) compiled with the kernel's law signature: loaded from the
    compiled-code cache where a process compiled the same law before, once per process and
    class."""
    # the values numba freezes into the code are part of the key: a law whose module's
    # constants changed since (a notebook cell run again) is compiled again, as its Python
    # form would read the new ones
    key = (cls.__module__, cls.__qualname__, cls.LAW, frozen_values(_reached(cls.LAW)))
    compiled_law = _LAWS.get(key)
    if compiled_law is None:
        compiled_law = _LAWS[key] = _machine_law(cls) or _compile_law(cls)
    return compiled_law


def has_machine_law(cls) -> bool:
    """Whether the cache holds the law's machine code, told fit to run (:func:`_machine_law`
    loads it without numba)."""
    folder, name = _cache_dir() / "laws", _law_name(cls, _reached(cls.LAW)[1:])
    try:
        return (folder / f"{name}.verdict").read_text() == "" and (folder / f"{name}.o").is_file()
    except OSError:
        return False


def _machine_law(cls):
    """The law's machine code, which :func:`_compile_law` wrote into the cache, loaded without
    numba; None when the cache has none (or a damaged one: compiled again). A law refused
    before is refused again by its kept verdict."""
    from tt_mujoco.sim.loop import callbacks, machine_code

    folder, name = _cache_dir() / "laws", _law_name(cls, _reached(cls.LAW)[1:])
    try:
        site = (folder / f"{name}.verdict").read_text()
    except OSError:
        return None
    if site:
        raise LawFormError(site)
    try:
        return machine_code.c_function_at(folder, name, callbacks.LAW)
    except machine_code.MachineCodeError:
        return None


def _own_calls(fn):
    """``(name, function)`` of the plain functions of ``fn``'s own module that it calls: the
    law's helpers, compiled with it."""
    import types

    for name in fn.__code__.co_names:
        value = fn.__globals__.get(name)
        if isinstance(value, types.FunctionType) and value.__module__ == fn.__module__:
            yield name, value


def _reached(law) -> tuple:
    """The law and its helpers (:func:`_own_calls`), theirs included."""
    seen, todo = [], [law]
    while todo:
        fn = todo.pop()
        if fn not in seen:
            seen.append(fn)
            todo += [value for _, value in _own_calls(fn)]
    return tuple(seen)


def frozen_values(functions) -> str:
    """What numba freezes into the compiled code of ``functions`` as constants when it compiles
    them: the values of the globals they read that are data (numbers, strings, bytes, None,
    tuples of them, NumPy arrays and scalars), and of the attributes they read of a module
    global; a digest, which changes when one of those values does (an environment variable or
    a file read when the module was imported, a constant edited in another module). The
    digest does not depend on the order of ``functions``: each value is labelled by its
    function and name, and the labels are hashed in order."""
    import types

    import numpy as np

    entries: dict[str, bytes] = {}

    def add(label: str, value) -> None:
        if isinstance(value, np.ndarray):
            head = f"{value.dtype.str}{value.shape}".encode()
            entries[label] = head + np.ascontiguousarray(value).tobytes()
        elif isinstance(value, tuple):
            for i, item in enumerate(value):
                add(f"{label}[{i}]", item)
        elif value is None or isinstance(value, bool | int | float | complex | str | bytes):
            entries[label] = f"{type(value).__name__}:{value!r}".encode()
        elif isinstance(value, np.generic):
            entries[label] = f"{value.dtype.str}:{value!r}".encode()

    for fn in functions:
        names = fn.__code__.co_names
        for name in names:
            if name not in fn.__globals__:
                continue
            value = fn.__globals__[name]
            if isinstance(value, types.ModuleType):
                for attribute in names:
                    if hasattr(value, attribute):
                        add(f"{fn.__qualname__}:{name}.{attribute}", getattr(value, attribute))
            else:
                add(f"{fn.__qualname__}:{name}", value)
    digest = hashlib.sha256()
    for label in sorted(entries):
        digest.update(f"{label}=".encode() + entries[label] + b";")
    return digest.hexdigest()[:16]


_LAWS: dict = {}


def _exact_math():
    """A ``math`` module for the compiled law whose ``hypot`` is CPython's to the last bit (the
    kernel's form of :func:`tt_mujoco.exact.hypot_of`): numba's own, the C library's, differs."""
    import types

    from tt_mujoco.sim.loop import _kernel

    module = types.ModuleType("math")
    module.__dict__.update(math.__dict__)
    module.hypot = _kernel._hypot
    return module


def _as_compiled(fn, done: dict, exact):
    """``fn`` as numba compiles it for a law: the same code, with ``math`` and ``math.hypot``
    among its globals read as ``exact`` (:func:`_exact_math`) gives them, and the plain
    functions of its own module that it calls registered for numba, each the same way (into
    ``done``: function -> its copy). So the law's compiled loop gives the numbers of its Python
    loop."""
    import types

    from numba.extending import register_jitable

    if fn in done:
        return done[fn]
    names = dict(fn.__globals__)
    copy = types.FunctionType(fn.__code__, names, fn.__name__, fn.__defaults__, fn.__closure__)
    copy.__qualname__, copy.__module__ = fn.__qualname__, fn.__module__
    done[fn] = copy
    for name in fn.__code__.co_names:
        value = fn.__globals__.get(name)
        if value is math:
            names[name] = exact
        elif value is math.hypot:
            names[name] = exact.hypot
    for name, helper in _own_calls(fn):
        names[name] = register_jitable(boundscheck=True)(_as_compiled(helper, done, exact))
    return copy


#: The C entry of a plain-number law, written into the cache folder once per law and version
#: (:func:`_compile_law`), numba compiling it from that file: a law's second process loads its
#: machine code instead. ``{...}`` are filled in per law.
_ENTRY_SOURCE = """\
# The C entry of the plain-number law {name} ({file}), written by tt_mujoco.sim.loop.compiled:
# its machine code is kept beside this file. The law's source digest is in the name.
from numba import carray, cfunc


@cfunc(USER_LAW, error_model="numpy")
def entry(m, r, model, gains, state, out, dt, limit):
    torques = carray(out, 3)
    torques[2] = 0.0
    kept = carray(state, {n_state})
{keep}    try:
        T_r, T_l = law(
            carray(m, {n_meas}).view(MEASUREMENT)[0],
            carray(r, {n_ref}).view(REFERENCE)[0],
            carray(model, {n_model}).view(NOMINAL)[0],
            carray(gains, {n_gains}).view(GAINS)[0],
            kept.view(STATE)[0],
            dt,
            limit,
        )
    except Exception:  # it cannot leave a C function: the loop stops, Python says what
        torques[2] = 1.0
{restore}        return
    if T_r - T_r != 0.0 or T_l - T_l != 0.0:  # not finite: the loop stops, Python says what
{restore}        pass
    torques[0], torques[1] = T_r, T_l
"""
#: The C entry of a law that sees the path (``plain_law(..., path=True)``): what it is handed
#: as its gains holds the gains, the vehicle's values, the number of the path table's samples
#: and the table, row by row (:meth:`~tt_mujoco.controllers.plain.PlainLawController.law_data`).
_PATH_ENTRY_SOURCE = """\
# The C entry of the plain-number law {name} ({file}), which sees the path, written by
# tt_mujoco.sim.loop.compiled: its machine code is kept beside this file. The law's source
# digest is in the name.
from numba import carray, cfunc


@cfunc(USER_LAW, error_model="numpy")
def entry(m, r, model, gains, state, out, dt, limit):
    torques = carray(out, 3)
    torques[2] = 0.0
    samples = int(carray(gains, {n_head})[{n_head} - 1])
    data = carray(gains, {n_head} + {n_rows} * samples)
    kept = carray(state, {n_state})
{keep}    try:
        T_r, T_l = law(
            carray(m, {n_meas}).view(MEASUREMENT)[0],
            carray(r, {n_ref}).view(REFERENCE)[0],
            carray(model, {n_model}).view(NOMINAL)[0],
            data[:{n_gains}].view(GAINS)[0],
            kept.view(STATE)[0],
            dt,
            limit,
            data[{n_head}:].reshape(({n_rows}, samples)),
            data[{n_gains}:{n_gains} + {n_vehicle}].view(VEHICLE)[0],
        )
    except Exception:  # it cannot leave a C function: the loop stops, Python says what
        torques[2] = 1.0
{restore}        return
    if T_r - T_r != 0.0 or T_l - T_l != 0.0:  # not finite: the loop stops, Python says what
{restore}        pass
    torques[0], torques[1] = T_r, T_l
"""


def _law_digest(cls, helpers) -> str:
    """What a law's compiled code depends on: its gains' and state's names, the files of the
    law, of its helpers and of every function they call from elsewhere (a compiled one from
    another module of the user's), and the values of the globals they read, which numba
    freezes when it compiles (:func:`frozen_values`)."""
    from tt_mujoco.sim.loop import kernel_sources

    digest = hashlib.sha256()
    digest.update(_law_names(cls).encode())
    # the package's functions the law reaches (the path's, and what they call)
    files = {inspect.getsourcefile(fn) for fn in kernel_sources.discover((cls.LAW, *helpers))[0]}
    files |= _law_files(cls, helpers)
    for file in sorted(f for f in files if f):
        try:
            digest.update(Path(file).read_bytes())
        except OSError:
            digest.update(file.encode())
    digest.update(frozen_values((cls.LAW, *helpers)).encode())  # the constants it froze
    return digest.hexdigest()[:16]


def _law_names(cls) -> str:
    names = (*cls.PRESETS[cls.DEFAULT_PRESET], "|", *cls.STATE, "|", str(cls.SEES_PATH))
    return " ".join(names)


def _law_files(cls, helpers) -> set:
    """The files of the law, of its helpers and of the functions they call by name, and this
    one (how a law is compiled, :func:`_as_compiled`, is part of its code)."""
    files = {__file__}
    for fn in (cls.LAW, *helpers):
        for name in fn.__code__.co_names:
            used = getattr(fn.__globals__.get(name), "py_func", fn.__globals__.get(name))
            if inspect.isfunction(used):
                files.add(inspect.getsourcefile(used))
        files.add(inspect.getsourcefile(fn))
    return files


def _law_name(cls, helpers) -> str:
    """The name of the law's files in the cache's ``laws/``, keyed by :func:`_law_digest`, which
    is found by a stamp of what it reads where a process worked it out before: working it out
    finds every function of the package the law reaches (a quarter of a second)."""
    from tt_mujoco.sim.loop.cache_key import file_key, sources_stamp

    stamp = hashlib.sha256(f"{cls.__module__}.{cls.__qualname__} {_law_names(cls)}".encode())
    stamp.update(sources_stamp().encode())  # the package's files, by size and time
    for file in sorted(f for f in _law_files(cls, helpers) if f):
        with contextlib.suppress(OSError):
            stamp.update(file_key(Path(file)).encode())
    stamp.update(frozen_values((cls.LAW, *helpers)).encode())
    known = _cache_dir() / "laws" / "stamps" / stamp.hexdigest()[:32]
    with contextlib.suppress(OSError):
        name = known.read_text().strip()
        if name.startswith(f"law_{cls.LAW.__name__}_"):
            return name
    name = f"law_{cls.LAW.__name__}_{_law_digest(cls, helpers)}"
    with contextlib.suppress(OSError):  # a read-only cache: worked out again next time
        known.parent.mkdir(parents=True, exist_ok=True)
        atomic_write(known, name + "\n")
    return name


def _compile_law(cls):
    """The law's C entry, from the cache when a process compiled it before (keyed by
    :func:`_law_digest`), compiled and cached otherwise."""
    import importlib.util

    from numba import njit

    from tt_mujoco.controllers.path_view import PATH_ROWS, VEHICLE_FIELDS
    from tt_mujoco.sim.loop import machine_code, records

    k_mod = kernel()
    copies: dict = {}
    # not cached on its own: numba's cache of a function ignores its globals, which
    # _as_compiled changes; the entry below, cached, holds the law's code
    # Python's error model: a division by zero raises, as it does in the law's Python form
    # (numpy's gives inf, or 0 for integers, and the run would drive on where Python's stops)
    # Bounds-checked: an index out of range raises, as in Python, rather than reading beyond
    law = njit(error_model="python", boundscheck=True)(_as_compiled(cls.LAW, copies, _exact_math()))
    helpers = set(copies) - {cls.LAW}  # the plain functions of its module it calls
    gain_names = tuple(cls.PRESETS[cls.DEFAULT_PRESET]) or ("unused",)
    dtypes = {
        "VEHICLE": records.record_dtype(VEHICLE_FIELDS),
        "MEASUREMENT": records.MEASUREMENT_DTYPE,
        "REFERENCE": records.record_dtype(records.REFERENCE_FIELDS),
        "NOMINAL": records.record_dtype(records.NOMINAL_FIELDS),
        "GAINS": records.record_dtype(gain_names),
        "STATE": records.record_dtype(cls.STATE or ("unused",)),
    }
    sizes = {
        "n_meas": len(dtypes["MEASUREMENT"]),
        "n_ref": len(dtypes["REFERENCE"]),
        "n_model": len(dtypes["NOMINAL"]),
        "n_gains": len(dtypes["GAINS"]),
        "n_state": len(dtypes["STATE"]),
        "n_vehicle": len(VEHICLE_FIELDS),
        "n_head": len(gain_names) + len(VEHICLE_FIELDS) + 1,
        "n_rows": len(PATH_ROWS),
    }
    name = _law_name(cls, helpers)
    module_name = f"tt_mujoco_{name}"
    if module_name in sys.modules:  # the same law, of another class: compiled already
        return sys.modules[module_name].entry
    file = inspect.getsourcefile(cls.LAW) or "?"
    template = _PATH_ENTRY_SOURCE if cls.SEES_PATH else _ENTRY_SOURCE
    # the state as the law was given it, put back where the law fails: its Python form,
    # called with what the compiled law was given, sees the state the compiled one saw
    keep = "".join(f"    state_{i} = kept[{i}]\n" for i in range(sizes["n_state"]))
    restore = "".join(f"        kept[{i}] = state_{i}\n" for i in range(sizes["n_state"]))
    source = template.format(name=cls.__qualname__, file=file, keep=keep, restore=restore, **sizes)
    path = _cache_dir() / "laws" / f"{name}.py"
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        if not path.is_file() or path.read_text() != source:
            atomic_write(path, source)
    except OSError:  # no cache: a file of its own for this process
        import tempfile

        path = Path(tempfile.mkdtemp(prefix="tt_mujoco-law-")) / f"{name}.py"
        path.write_text(source)
    spec = importlib.util.spec_from_file_location(module_name, path)
    module = importlib.util.module_from_spec(spec)
    module.__dict__.update(law=law, USER_LAW=k_mod.USER_LAW, **dtypes)
    sys.modules[module_name] = module  # numba's cache finds the entry's module by its name
    try:
        spec.loader.exec_module(module)
        _refuse_unreproducible(law, copies, dtypes, cls.SEES_PATH, path.with_suffix(".verdict"))
    except BaseException:
        del sys.modules[module_name]
        raise
    with contextlib.suppress(OSError):  # a read-only cache: compiled again by the next process
        obj = module.entry._library.serialize_using_object_code()[2][0]
        machine_code.write_object(path.parent, name, obj, {"symbol": module.entry.native_name})
    return module.entry


class LawFormError(Exception):
    """A law whose compiled form would not do what its Python form does
    (:mod:`~tt_mujoco.sim.loop.law_semantics`): integer arithmetic that can pass 2**63, a
    write to what it is given to read. Its message says why and where."""


def _refuse_unreproducible(law, copies, dtypes, sees_path, verdict: Path) -> None:
    """Raise :class:`LawFormError` where the law's typed code does what its Python form would
    not. The verdict is kept beside the cached entry, since a process that loads the entry from
    the cache never types the law; where it is lost the law is typed again."""
    from numba import from_dtype

    from tt_mujoco.sim.loop.law_semantics import law_signature, unreproducible_site

    own = {fn.__code__ for fn in copies}
    state_type = from_dtype(dtypes["STATE"])
    if law.overloads:  # typed in this process: the entry was compiled, not loaded
        site = unreproducible_site(law, own, state_type)
        with contextlib.suppress(OSError):
            atomic_write(verdict, site or "")
    else:
        try:
            site = verdict.read_text() or None
        except OSError:
            law.compile(law_signature(dtypes, sees_path))
            site = unreproducible_site(law, own, state_type)
    if site:
        raise LawFormError(site)


def compile_failure(err: BaseException, source_file: str | None) -> str:
    """numba's error compiling a user's law, in one line: what has no compiled form and the
    line of ``source_file`` (the law's file) where it is used."""
    import linecache
    import os
    import re

    if isinstance(err, LawFormError):  # says its line itself
        return str(err)
    text = re.sub(r"\x1b\[[0-9;]*m", "", str(err))
    lines = [line.strip() for line in text.splitlines()]
    why = next((line for line in lines if line and not line.startswith("Failed in")), "")
    signature = next((line[3:].strip() for line in lines if line.startswith(">>>")), None)
    if why.startswith("No implementation of function") and signature:
        why = f"numba has no {signature}"
    why = re.sub(r"Function\(<function (\w+) at 0x[0-9a-f]+>\)", r"\1", why).rstrip(":")
    why = why or type(err).__name__
    if source_file is None:
        return why
    own = os.path.realpath(source_file)
    places = re.findall(r"typing of [^\n]*? at (.+?) \((\d+)\)", text)
    places += re.findall(r'File "(.+?)", line (\d+)', text)  # relative to the working folder
    for path, number in places:
        if os.path.realpath(path) == own:
            code = linecache.getline(own, int(number)).strip()
            return f"{why}, at {os.path.basename(path)} line {number}: {code}"
    return why

"""The compiled episode: the closed loop as machine code, for every controller.

:func:`tt_mujoco.sim.simulate.run_episode` hands an episode here when every part of it has a
compiled form (:func:`unsupported` says why not otherwise): a built-in law
(:data:`tt_mujoco.sim.loop.kernel_sources.LAWS`: ISMC-STA, PID, FBL, ...) on the built-in
nominal model, a user's plain-number law (:mod:`tt_mujoco.controllers.plain`, compiled once by
:func:`~tt_mujoco.sim.loop.compiled_law.compile_law` and cached on disk, keyed by its source),
or any other controller, whose Python ``compute`` the kernel calls back at every step through a
C function (:mod:`tt_mujoco.sim.loop.callbacks`); any target, path, disturbance, noise, train,
steering schedule, fault, motor, wind, delay or friction patch the step has (a payload step on
the reduced plant returns to Python, which recomputes the plant's constants and advances that
step); not a per-step callback (the live viewer).

The loop it runs is :func:`tt_mujoco.sim.loop.closed_loop.run_steps`, compiled by numba from
its source with every function it calls (:mod:`tt_mujoco.sim.loop._kernel`), the one CPython
runs for every other episode (the Python loop): both compute the same numbers bit for bit
(``tests/test_compiled.py``, ``tests/test_plain.py``, ``tests/test_closed_loop.py``). Its
machine code is stored and loaded without numba (:mod:`~tt_mujoco.sim.loop.machine_code`, a
few milliseconds), chunk by chunk over the records :class:`~tt_mujoco.sim.loop.stepper.Stepper`
makes. ``TT_MUJOCO_COMPILED=0`` turns it off.

Compiled code is cached on disk under ``$TT_MUJOCO_CACHE`` or ``~/.cache/tt_mujoco``, in a
folder keyed by :func:`~tt_mujoco.sim.loop.cache_key.source_digest` (the interpreter, numba,
llvmlite and MuJoCo versions and every file the kernel compiles). Compiling takes a minute, so
it never happens in the user's run: the first episode that could run compiled finds no cache
(:func:`not_ready`), starts one background process that compiles it, and runs the Python loop
(same numbers); later episodes load it. Every episode the Python loop runs says why in the
run's notes. A manifest of the folder's files lets a damaged cache be set aside rather than
recompiled in the foreground. ``TT_MUJOCO_COMPILE_NOW=1`` compiles in the run itself (the
tests and benchmarks).
"""

from __future__ import annotations

import hashlib
import os
import sys
from pathlib import Path

import numpy as np

from tt_mujoco.analysis import geometry
from tt_mujoco.outputs import atomic_write
from tt_mujoco.sim.loop.cache_key import digest_by_stamp, source_digest

__all__ = [
    "Fallback",
    "entry_point",
    "kernel",
    "not_ready",
    "run_compiled",
    "source_digest",
    "unavailable",
    "unsupported",
]

#: Shortest episode handed to the compiled loop (loading the compiled code is paid once per
#: process: a short episode gains less than that).
MIN_STEPS = 2000
#: Shortest first episode of a process that loads the compiled loop: loading it (numba and the
#: cached code) costs about half a second, more than the Python loop takes for the main run's
#: 13782 steps of one trailer, so a shorter single run is faster in the Python loop; the
#: process's next episode loads it. ``benchmarks/bench_cold_start.py`` times both sides of the
#: line: the main run as chosen against its Python loop, a 40 s run compiled against its own.
COLD_MIN_STEPS = 25000
#: Episodes this process has started (:func:`tt_mujoco.sim.simulate.run_episode`).
_EPISODES = 0


_KERNEL = None


def _enabled() -> bool:
    return os.environ.get("TT_MUJOCO_COMPILED", "1") != "0"


class Fallback(Exception):  # noqa: N818 - a route, not an error: the Python loop runs
    """The episode cannot run compiled after all; the message says why, in a sentence the
    run's notes carry (:func:`tt_mujoco.sim.simulate.run_episode`). Nothing has run."""


def unavailable() -> str | None:
    """Why no episode of this process runs compiled (None when it can); only a query."""
    if not _enabled():
        return "TT_MUJOCO_COMPILED=0 turns the compiled loop off"
    from importlib.util import find_spec

    if find_spec("numba") is None:  # not imported: a run that takes the Python loop never needs it
        return "numba is not installed"
    return None


def unsupported(built, controller, on_step=None) -> str | None:
    """Why the episode has no compiled form (None when it has one); only a query."""
    reasons = [
        (not _enabled(), "TT_MUJOCO_COMPILED=0 turns the compiled loop off"),
        (
            built.steps < MIN_STEPS,
            f"the run has {built.steps} control steps, fewer than the {MIN_STEPS} for which "
            "loading the compiled loop pays",
        ),
        (on_step is not None, "a per-step callback (the live viewer) runs in Python"),
    ]
    for failed, reason in reasons:
        if failed:
            return reason
    return unavailable()


def not_ready() -> str | None:
    """None when the compiled kernel can run now without compiling in the foreground: loaded
    in this process, or in the cache (``TT_MUJOCO_COMPILE_NOW=1``: compile here instead).
    Otherwise why not, and one background process will fill the cache
    (:func:`_ask_for_compile`)."""
    if _KERNEL is not None or os.environ.get("TT_MUJOCO_COMPILE_NOW") == "1":
        return None
    if _machine_code_pays():
        return None  # each entry's own hash is checked as it loads
    failed = compile_failure_of(_cache_dir())
    if failed is not None:  # not tried again for these sources: it would fail alike
        return failed
    try:
        if _cached():
            return None
        why = (
            "the compiled loop is not in the cache yet (a background process compiles it "
            "for the next run)"
        )
    except _DamagedCacheError as damaged:
        why = str(damaged)
    _ask_for_compile()
    return why


#: Written by a background compile that failed: the error in one line, and in full.
COMPILE_FAILED, COMPILE_LOG = "compile.failed", "compile.log"


def compile_failure_of(cache: Path) -> str | None:
    """Why the background compile into ``cache`` failed, in one sentence, or None."""
    try:
        error = (cache / COMPILE_FAILED).read_text().strip()
    except OSError:
        return None
    return (
        f"the background compile of the compiled loop failed ({error}; the whole error is in "
        f"{cache / COMPILE_LOG}); it is not tried again until these sources change"
    )


def compile_script(lock: Path) -> str:
    """The background compile's program: at the lowest priority (on a busy machine the user's
    run, not the compile, gets the core), the kernel compiled into the cache; what fails is
    written beside it (:data:`COMPILE_FAILED`, its traceback on the process's stderr, which is
    :data:`COMPILE_LOG`), and the lock is released either way."""
    return (
        "import os, pathlib\n"
        "os.nice(19)\n"
        f"lock = pathlib.Path({str(lock)!r})\n"
        "try:\n"
        "    os.environ['TT_MUJOCO_COMPILE_NOW'] = '1'\n"
        "    from tt_mujoco.sim.loop import compiled\n"
        "    compiled.warm_up()\n"
        "except BaseException as err:\n"
        "    text = ' '.join(f'{type(err).__name__}: {err}'.split())[:300]\n"
        f"    (lock.parent / {COMPILE_FAILED!r}).write_text(text + '\\n')\n"
        "    raise\n"
        "finally:\n"
        "    lock.unlink(missing_ok=True)\n"
    )


def ask_for_cache() -> None:
    """For an episode the Python loop runs anyway (:func:`loading_pays`): whether this
    version's cache is whole is judged as the process exits (:func:`_compile_at_exit`), not
    during the run (keying the cache reads every source the kernel compiles, and judging it
    hashes its files: a tenth of a short run), and a background compile fills it if not, so
    that the next long run finds it."""
    if _KERNEL is None:
        _ask_for_compile()


def loading_pays(built) -> str | None:
    """None when loading the compiled loop pays for this episode: it is loaded already, the
    process has run an episode before (a sweep's worker, a notebook), the episode is long
    (:data:`COLD_MIN_STEPS`), its law reads the path (a plain-number law with ``path=True``,
    whose Python form searches the path in Python at every step), or
    ``TT_MUJOCO_COMPILE_NOW=1`` asks for it; otherwise why the Python loop is faster. Counts
    the episode."""
    global _EPISODES
    _EPISODES += 1
    if _KERNEL is not None or _EPISODES > 1 or built.steps >= COLD_MIN_STEPS:
        return None
    if _machine_code_pays() and _law_loads_alike(built.controller_class):
        return None  # loading it costs milliseconds
    if getattr(built.controller_class, "SEES_PATH", False):
        return None
    if os.environ.get("TT_MUJOCO_COMPILE_NOW") == "1":
        return None
    return (
        f"a single run of {built.steps} control steps in a new process, fewer than the "
        f"{COLD_MIN_STEPS} for which loading the compiled loop pays (the process's next "
        "episode loads it)"
    )


def _machine_code_pays() -> bool:
    """Whether the cache holds machine code of the chunk loop, which loads in milliseconds
    without numba (:mod:`~tt_mujoco.sim.loop.machine_code`), and no compile is writing it."""
    from tt_mujoco.sim.loop import machine_code

    cache = _cache_dir()
    return machine_code.has_entries(cache) and not compile_in_progress(cache)


def prepare() -> None:
    """Start setting up what the machine code needs (:func:`machine_code.prepare
    <tt_mujoco.sim.loop.machine_code.prepare>`) beside an episode's set-up, where the episode
    may run it."""
    if _enabled() and _machine_code_pays():
        from tt_mujoco.sim.loop import machine_code

        machine_code.prepare()


def _law_loads_alike(cls) -> bool:
    """Whether the controller's law loads as machine code too: a built-in one, or a user's
    plain-number law whose machine code the cache holds (else numba compiles it)."""
    from tt_mujoco.controllers.plain import PlainLawController
    from tt_mujoco.sim.loop.compiled_law import has_machine_law

    return not (isinstance(cls, type) and issubclass(cls, PlainLawController)) or (
        has_machine_law(cls)
    )


#: Whether this process has asked for a background compile (see :func:`_ask_for_compile`).
_ASKED = False


def _ask_for_compile() -> None:
    """Start the background compile when this process exits, or at its second episode that
    finds no kernel, whichever comes first: started at once, its imports and compile shared the
    machine with the very run that asked (``benchmarks/bench_first_run.py``); a process that
    runs more episodes starts it after its first."""
    global _ASKED
    if _ASKED:
        _compile_in_background()
        return
    _ASKED = True
    import atexit

    atexit.register(_compile_at_exit)


def _compile_at_exit() -> None:
    """The asked-for compile, unless this process has loaded or found the kernel since."""
    try:
        if _KERNEL is not None or compile_failure_of(_cache_dir()) or _cached():
            return  # loaded, failed for these sources (not tried again), or whole
    except _DamagedCacheError:
        pass  # set aside: compile a fresh one
    _compile_in_background()


#: The cache folder's list of its files and their hashes, written once the kernel has run.
MANIFEST = "manifest.json"
#: The lock a background compile holds in the cache folder, and the age (s) past which a lock
#: is taken for a compile that died.
COMPILE_LOCK = "compiling.lock"
COMPILE_LOCK_STALE_S = 300.0


def compile_in_progress(cache: Path) -> bool:
    """Whether a background compile is filling ``cache`` now (its lock is fresh)."""
    import time

    try:
        return time.time() - (cache / COMPILE_LOCK).stat().st_mtime <= COMPILE_LOCK_STALE_S
    except OSError:
        return False


def _cache_files(cache: Path) -> dict[str, str]:
    """Every compiled-code file of a cache folder (and the kernel's copy) -> its sha256.

    Only the subfolder numba reads for the kernel's copy there counts: numba names it after
    the copy's folder and a sha1 of its path, so a cache moved elsewhere lists nothing."""
    subfolder = f"{cache.name}_{hashlib.sha1(str(cache.resolve()).encode()).hexdigest()}"
    files = [cache / "_kernel.py", *sorted((cache / subfolder).glob("*.nb[ic]"))]
    files += sorted((cache / "machine").glob("*.[oj]*"))  # machine_code.MACHINE_DIR
    return {
        str(f.relative_to(cache)): hashlib.sha256(f.read_bytes()).hexdigest()
        for f in files
        if f.is_file()
    }


def _cached() -> bool:
    """Whether this version's cache folder holds the compiled kernel, whole: every file its
    manifest lists, with the same hash. A folder whose files differ is set aside (a
    truncated or edited file would otherwise make numba compile in the foreground)."""
    import json

    cache = _cache_dir()
    if compile_in_progress(cache):
        return False  # a background compile is still writing it: not whole, not damaged
    try:
        listed = json.loads((cache / MANIFEST).read_text())
    except FileNotFoundError:
        return False
    except (OSError, ValueError) as err:
        raise _DamagedCacheError(set_aside_cache(err)) from err
    try:
        found = _cache_files(cache)
    except OSError as err:
        raise _DamagedCacheError(set_aside_cache(err)) from err
    if not isinstance(listed, dict) or not listed or found != listed:
        raise _DamagedCacheError(set_aside_cache(ValueError("its files differ from its manifest")))
    return True


def _write_manifest(compiled_here: bool = False) -> None:
    """List the cache folder's files once the kernel has run from it (atomically); again
    after this process compiled a new signature into it (numba rewrote its index then)."""
    import json

    cache = _cache_dir()
    if (cache / MANIFEST).exists() and not compiled_here:
        return
    try:
        atomic_write(cache / MANIFEST, json.dumps(_cache_files(cache), indent=1))
    except OSError:
        pass  # a read-only cache: the next run checks it again


def _compile_in_background() -> None:
    """Start one process that compiles the kernel into the cache (a lock file keeps it one)."""
    import subprocess

    cache = _cache_dir()
    lock = cache / COMPILE_LOCK
    try:
        cache.mkdir(parents=True, exist_ok=True)
        if lock.exists() and not compile_in_progress(cache):
            lock.unlink(missing_ok=True)  # a compile that died
        fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
        os.close(fd)
    except OSError:
        return  # compiling already, or no cache to compile into
    try:
        log = open(cache / COMPILE_LOG, "wb")  # the compile writes it to its end
    except OSError:
        log = subprocess.DEVNULL
    subprocess.Popen(
        [sys.executable, "-c", compile_script(lock)],
        stdin=subprocess.DEVNULL,
        stdout=log,
        stderr=log,
        start_new_session=True,
    )
    if log is not subprocess.DEVNULL:
        log.close()  # the child holds its own copy


def warm_up() -> None:
    """Compile the kernel for every signature a run can call it with: a short episode on
    each plant (MuJoCo's warning counts are a strided view, the reduced plant's are not)."""
    from tt_mujoco.sim.build import build
    from tt_mujoco.sim.loop.stepper import Stepper
    from tt_mujoco.sim.scenario import Scenario

    for plant in ("mujoco", "reduced"):
        built = build(Scenario(traj="circle", plant=plant, duration=MIN_STEPS * 0.001))
        stepper = Stepper(built)
        stepper.reset(np.random.default_rng(0))
        controller = built.new_controller()
        controller.reset()
        run_compiled(stepper, controller)
    # The metrics' projection, for both its modes.
    line = geometry.Polyline(np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 1.0]]))
    for extend in (False, True):
        line.project(np.array([[0.5, 0.5], [3.0, 1.0]]), extend_ends=extend)


def _cache_dir() -> Path:
    """A cache folder per version of every source the kernel compiles."""
    root = os.environ.get("TT_MUJOCO_CACHE", str(Path.home() / ".cache" / "tt_mujoco"))
    return Path(root) / "numba" / digest_by_stamp(Path(root) / "numba" / "stamps")


def kernel():
    """The compiled chunk loop's module (imported on first use).

    It is imported from a copy of ``_kernel.py`` in this version's cache folder, written once:
    numba's cache index checks its source file's path and time stamp, which a copy keyed by
    :func:`source_digest` keeps the same for every checkout and reinstall of these sources.
    """
    global _KERNEL
    if _KERNEL is None:
        import importlib.util

        import numba

        source = Path(__file__).parent / "_kernel.py"
        cache = _cache_dir()
        try:
            cache.mkdir(parents=True, exist_ok=True)
            copy = cache / "_kernel.py"
            if not copy.is_file():  # atomic: a concurrent reader sees all of it or none
                atomic_write(copy, source.read_bytes())
            numba.config.CACHE_DIR = str(cache)
        except OSError:
            copy = source  # no cache: compiled in memory, every process
        name = "tt_mujoco.sim.loop._kernel"
        spec = importlib.util.spec_from_file_location(name, copy)
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
        _KERNEL = module
        geometry.use_compiled_projection(_projection)
    return _KERNEL


def _projection(*args) -> bool:
    """The metrics' compiled projection (:func:`tt_mujoco.analysis.nearest.nearest_segments_of`)
    as machine code; False when the cache has none (and the process may not compile it) or
    it fails to load (the cache set aside): the vectorised search serves instead."""
    from tt_mujoco.sim.loop import entries

    try:
        found = entries.entry("project_points", args, _may_compile)
        if found is None:
            return False
        entries.call(found, args)
    except Exception as err:  # a damaged cache: the vectorised search serves instead
        set_aside_cache(err)
        return False
    return True


def _call_listed(entry, *args):
    """``entry(*args)``, a kernel entry point called from Python; when the call compiled it
    (a signature new to the cache), the cache's files are listed again: unlisted, the next
    process would find the folder differing from its manifest and set it aside."""
    compiled_before = sum(entry.stats.cache_misses.values())
    out = entry(*args)
    if sum(entry.stats.cache_misses.values()) > compiled_before:
        _write_manifest(compiled_here=True)
    return out


def _compiled_for(dispatcher, args):
    """The compiled entry point of ``dispatcher`` for ``args``' types, loaded from the cache or
    compiled: calling it skips the dispatcher's typing of every argument (the records' some
    hundred arrays), which it would otherwise redo at every chunk. Found again by
    :func:`type_key`, which costs a tenth of numba's typing, at every later episode of the
    process (a sweep's worker runs hundreds)."""
    key = (dispatcher, tuple(type_key(a) for a in args))
    entry = _ENTRIES.get(key)
    if entry is None:
        entry = dispatcher.compile(tuple(dispatcher.typeof_pyval(a) for a in args))
        _ENTRIES[key] = entry
    return entry


def entry_point(dispatcher, args):
    """The compiled entry point of the kernel's ``dispatcher`` for ``args``' types
    (:func:`_compiled_for`); when it was compiled here, the cache's files are listed again."""
    compiled_before = sum(dispatcher.stats.cache_misses.values())
    entry = _compiled_for(dispatcher, args)
    if sum(dispatcher.stats.cache_misses.values()) > compiled_before:
        _write_manifest(compiled_here=True)
    return entry


#: Compiled entry points by (dispatcher, :func:`type_key` of their arguments).
_ENTRIES: dict = {}


def type_key(value):
    """What numba's type of ``value`` depends on: an array's dtype, dimensions, layout,
    writability and alignment; a tuple's (or named tuple's) class and items; a Python
    number's class; numba's own type of anything else (the user law's compiled function)."""
    if isinstance(value, np.ndarray):  # numba's layout: "C" if C-contiguous, else "F" or "A"
        flags = value.flags
        layout = "C" if flags.c_contiguous else ("F" if flags.f_contiguous else "A")
        return value.dtype, value.ndim, layout, flags.writeable, flags.aligned
    if isinstance(value, tuple):
        return type(value), tuple(type_key(item) for item in value)
    if type(value) in (bool, int, float):
        return type(value)
    from numba import typeof

    return typeof(value)


def set_aside_cache(err: BaseException) -> str:
    """A cache that fails to load (truncated, garbage, foreign): move it aside, so that a
    fresh one is compiled in the background; what happened, in one sentence."""
    global _KERNEL
    cache = _cache_dir()
    aside = cache.with_name(f"{cache.name}.damaged-{os.getpid()}")
    try:
        os.replace(cache, aside)
        where = f"moved to {aside}"
    except OSError:
        where = f"left at {cache}"
    _KERNEL = None
    geometry.use_compiled_projection(None)
    sys.modules.pop("tt_mujoco.sim.loop._kernel", None)
    return (
        f"the compiled-code cache could not be loaded ({type(err).__name__}: {err}); it was "
        f"{where}, and a fresh one is compiled in the background"
    )


class _DamagedCacheError(Exception):
    """The cached kernel failed to load or to run its first chunk: nothing has run."""


def run_compiled(stepper, controller, progress=None) -> tuple[str, str] | None:
    """Run the (reset) ``stepper``'s episode with ``controller`` compiled; ``(status,
    message)`` as :func:`tt_mujoco.sim.simulate.run_episode`. The chunk loop runs as machine
    code loaded without numba (:mod:`~tt_mujoco.sim.loop.machine_code`), compiled here first
    when the cache has none for these records and the process may compile
    (:func:`_may_compile`).

    Raises
    ------
    Fallback
        When the compiled code cannot be loaded or the user's law has no compiled form:
        nothing has run, and the caller runs the Python loop.
    """
    from tt_mujoco.sim.loop import callbacks, entries

    stepper.begin(controller, _user_law(callbacks.no_user_law, controller), kernel=callbacks)
    geometry.use_compiled_projection(_projection)
    found = None

    def run_chunk(*args):
        nonlocal found
        if found is None:  # nothing has run: a damaged or missing entry leaves it to Python
            try:
                found = entries.entry("run_chunk", args, lambda: _may_compile() or _cached())
            except Exception as err:
                raise _DamagedCacheError() from err
            if found is None:
                raise _NoEntryError()
        out = entries.call(found, args)
        raised = stepper.hook_failure()
        if raised is not None:
            raise raised
        return out

    def advance(*args):  # not compiled by the warm-up: its first call may add to the cache
        return _call_listed(kernel().advance_after_payload, *args)

    try:
        return stepper.run(run_chunk, advance, progress)
    except _DamagedCacheError as damaged:
        raise Fallback(set_aside_cache(damaged.__cause__)) from damaged
    except _NoEntryError:
        raise Fallback(
            "the compiled loop has no machine code for this episode's records yet (a "
            "background process compiles it)"
        ) from None


def _may_compile() -> bool:
    """Whether this process compiles what the cache lacks: it has loaded the kernel, or
    ``TT_MUJOCO_COMPILE_NOW=1`` asks (as numba compiles a signature new to its cache)."""
    return _KERNEL is not None or os.environ.get("TT_MUJOCO_COMPILE_NOW") == "1"


class _NoEntryError(Exception):
    """The cache has no machine code for these records, and compiling it here would hold up
    the run (a background compile is still filling the cache)."""


def _user_law(placeholder, controller):
    """The compiled form of a plain-number law, ``placeholder`` for a built-in one, or None
    for a controller whose Python ``compute`` the kernel calls back; a law numba cannot
    compile is a :class:`Fallback`."""
    from tt_mujoco.controllers.plain import PlainLawController
    from tt_mujoco.sim.loop.compiled_law import compile_failure, compile_law
    from tt_mujoco.sim.loop.episode import runs_built_in

    if not isinstance(controller, PlainLawController):
        return placeholder if runs_built_in(controller) else None
    try:
        return compile_law(type(controller))
    except Exception as err:  # numba cannot compile the user's law: the Python loop can run it
        import inspect

        source = inspect.getsourcefile(controller.LAW)
        raise Fallback(
            f"the law {controller.name!r} has no compiled form: {compile_failure(err, source)}"
        ) from err

"""The compiled episode: the closed loop of a built-in or plain-number law as machine code.

:func:`tt_mujoco.sim.simulate.run_episode` hands an episode here when every part of it has a
compiled form (:func:`unsupported` says why not otherwise): a built-in law
(:data:`tt_mujoco.sim.kernel_sources.LAWS`: ISMC-STA, PID, FBL, ...) or a user's plain-number law
(:mod:`tt_mujoco.controllers.plain`, compiled once per process by :func:`compile_law`) on the
built-in nominal model, a static or dynamic target on a closed-form path (the S-curve, the
circle, the cycloid, a CSV spline) driven forwards or backing up (the reverse target, with the
hitch cascade or path feedback), the paper's disturbance (matched or as a wrench) or none,
measurement noise, one trailer or a train, constant steering gains or either schedule
(:mod:`tt_mujoco.sim.schedule`), path feedback, faults, DC motors, wind, a sensor delay,
friction patches; not a per-step callback (a payload step on the reduced plant returns to
Python, which recomputes the plant's constants and advances that step, then the kernel goes
on). The loop then runs in numba, chunk by chunk, calling ``mj_step`` through
MuJoCo's C library or stepping the reduced ODE, over the named records of
:mod:`tt_mujoco.sim.records`.

Every rule and formula it runs is the Python one: the step's checks and clips
(:mod:`tt_mujoco.sim.step`) and the functions marked "the compiled episode shares it"
(measurement, reduced model and its RK4, law, path curvature and pose, target, disturbance)
are compiled from their own source with ``numba.extending.register_jitable``, so the compiled
and the Python loop compute the same numbers bit for bit (``tests/test_compiled.py``,
``tests/test_plain.py``). ``TT_MUJOCO_COMPILED=0`` turns it off.

Compiled code is cached on disk under ``$TT_MUJOCO_CACHE`` or ``~/.cache/tt_mujoco``, in a
folder keyed by :func:`source_digest` (the interpreter, numba, llvmlite and MuJoCo versions and
every file the kernel compiles: numba's own cache only watches the file of the function it
caches). Compiling takes seconds, so it never happens in the user's run: the first episode that
could run compiled finds no whole cache (:func:`ready`), starts one background process that
compiles it, and runs the Python loop (same numbers); later episodes load it, once per process.
The kernel runs from a copy of its source inside that folder, so every checkout of the same
sources shares one cache, and a manifest of the folder's files lets a damaged cache be set
aside rather than recompiled in the foreground. ``TT_MUJOCO_COMPILE_NOW=1`` compiles in the
run itself (the tests and benchmarks).
"""

from __future__ import annotations

import functools
import hashlib
import math
import os
import pickle
import sys
from pathlib import Path

import numpy as np

from tt_mujoco.analysis import geometry
from tt_mujoco.outputs import atomic_write
from tt_mujoco.sim import step

__all__ = ["episode_records", "kernel", "ready", "run_compiled", "source_digest", "unsupported"]

#: Shortest episode handed to the compiled loop (loading the compiled code is paid once per
#: process: a short episode gains less than that).
MIN_STEPS = 2000


_KERNEL = None


def _enabled() -> bool:
    return os.environ.get("TT_MUJOCO_COMPILED", "1") != "0"


def unsupported(built, controller, on_step=None) -> str | None:
    """Why the episode has no compiled form (None when it has one); only a query."""
    from tt_mujoco.controllers.plain import PlainLawController
    from tt_mujoco.reference.paths import ArcsPath, CycloidPath
    from tt_mujoco.reference.reverse import ReverseTarget
    from tt_mujoco.reference.spline import SplinePath
    from tt_mujoco.reference.targets import DynamicTarget, StaticTarget
    from tt_mujoco.sim.disturbances import PaperDisturbance
    from tt_mujoco.sim.kernel_sources import LAWS

    reasons = [
        (not _enabled(), "TT_MUJOCO_COMPILED=0"),
        (built.steps < MIN_STEPS, f"fewer than {MIN_STEPS} steps"),
        (on_step is not None, "a per-step callback"),
        (
            not (_built_in(type(controller), LAWS) or isinstance(controller, PlainLawController)),
            "a Python controller class",
        ),
        (not getattr(_model_of(controller), "builtin", False), "a custom model"),
        (
            type(_inner(built.target)) not in (StaticTarget, DynamicTarget, ReverseTarget),
            "this target",
        ),
        (type(built.path) not in (ArcsPath, CycloidPath, SplinePath), "a path without closed form"),
        (
            built.disturbance is not None and type(built.disturbance) is not PaperDisturbance,
            "a custom disturbance",
        ),
    ]
    for failed, reason in reasons:
        if failed:
            return reason
    from importlib.util import find_spec

    if find_spec("numba") is None:  # not imported: a run that takes the Python loop never needs it
        return "numba is not installed"
    return None


def _inner(target):
    """The tracking target itself (inside path feedback or the hitch cascade, if any)."""
    from tt_mujoco.controllers.backing import HitchCascade
    from tt_mujoco.reference.feedback import PathFeedback

    return target.target if type(target) in (PathFeedback, HitchCascade) else target


def _built_in(cls, laws) -> bool:
    """Whether ``cls`` is a compiled law's own class (a subclass may change what it runs)."""
    law = getattr(cls, "LAW", None)
    return law in laws and cls.__module__ == law.__module__


def _model_of(controller):
    """The nominal model a controller runs (a built-in law's own, or its setup's)."""
    model = getattr(controller, "model", None)
    if model is None:
        model = getattr(getattr(controller, "setup", None), "model", None)
    return model


def ready() -> bool:
    """Whether the compiled kernel can run now without compiling in the foreground: loaded in
    this process, or in the cache (``TT_MUJOCO_COMPILE_NOW=1``: compile here instead). When
    neither, one background process will fill the cache (:func:`_ask_for_compile`)."""
    if _KERNEL is not None or _cached() or os.environ.get("TT_MUJOCO_COMPILE_NOW") == "1":
        return True
    _ask_for_compile()
    return False


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
    if _KERNEL is None and not _cached():
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
        set_aside_cache(err)
        return False
    try:
        found = _cache_files(cache)
    except OSError as err:
        set_aside_cache(err)
        return False
    if not isinstance(listed, dict) or not listed or found != listed:
        set_aside_cache(ValueError("its files differ from its manifest"))
        return False
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
    # At the lowest priority: on a busy machine the user's run, not the compile, gets the core.
    code = (
        "import os, pathlib; os.nice(19); from tt_mujoco.sim import compiled; "
        "os.environ['TT_MUJOCO_COMPILE_NOW'] = '1'; compiled.warm_up(); "
        f"pathlib.Path({str(lock)!r}).unlink(missing_ok=True)"
    )
    subprocess.Popen(
        [sys.executable, "-c", code],
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,
    )


def warm_up() -> None:
    """Compile the kernel for every signature a run can call it with: a short episode on
    each plant (MuJoCo's warning counts are a strided view, the reduced plant's are not)."""
    from tt_mujoco.sim.build import build
    from tt_mujoco.sim.scenario import Scenario
    from tt_mujoco.sim.stepper import Stepper

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
    return Path(root) / "numba" / source_digest()


@functools.cache
def source_digest() -> str:
    """A hash of what the compiled code depends on: the interpreter, the machine, numba's,
    llvmlite's and MuJoCo's versions, every file the kernel compiles
    (:func:`tt_mujoco.sim.kernel_sources.source_files`, that module's, this file and the
    kernel's) and the built-in laws in their order (a law's index is its kind)."""
    import platform
    from importlib import metadata

    from tt_mujoco.sim import kernel_sources

    versions = [metadata.version(name) for name in ("numba", "llvmlite", "mujoco")]
    laws = [f"{law.__module__}.{law.__qualname__}" for law in kernel_sources.LAWS]
    digest = hashlib.sha256(" ".join([sys.version, platform.machine(), *versions]).encode())
    digest.update(" ".join(laws).encode())
    here = Path(__file__).parent
    sources = (*kernel_sources.source_files(), kernel_sources.__file__, __file__)
    for name in (*sources, here / "_kernel.py"):
        digest.update(Path(name).read_bytes())
    return digest.hexdigest()[:16]


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
        name = "tt_mujoco.sim._kernel"
        spec = importlib.util.spec_from_file_location(name, copy)
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
        _KERNEL = module
        geometry.use_compiled_projection(_projection)
    return _KERNEL


def _projection(*args) -> bool:
    """The metrics' compiled projection (:func:`tt_mujoco.analysis.geometry.nearest_segment_of`
    in a loop); the cache's manifest is rewritten once this process has compiled it. False
    (and the cache set aside) when its compiled code fails to load."""
    try:
        _call_listed(_KERNEL.project_points, *args)
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


def set_aside_cache(err: BaseException) -> None:
    """A cache that fails to load (truncated, garbage, foreign): move it aside, so that a
    fresh one is compiled in the background, and say so in one line."""
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
    sys.modules.pop("tt_mujoco.sim._kernel", None)
    print(
        f"note: the compiled-code cache could not be loaded ({type(err).__name__}: {err}); "
        f"it was {where}, and this run uses the Python loop (same numbers)",
        file=sys.stderr,
    )


def run_compiled(stepper, controller, progress=None) -> tuple[str, str] | None:
    """Run the (reset) ``stepper``'s episode with ``controller`` compiled; ``(status,
    message)`` as :func:`tt_mujoco.sim.simulate.run_episode`, or None when the compiled code
    cannot be loaded (nothing has run then: the caller runs the Python loop)."""
    try:
        k_mod = kernel()
    except Exception as err:  # a damaged cache: its copy of the kernel does not import
        set_aside_cache(err)
        return None
    try:
        user = _user_law(k_mod, controller)
    except Exception as err:  # numba cannot compile the user's law: the Python loop can run it
        import re

        lines = [re.sub(r"\x1b\[[0-9;]*m", "", line).strip() for line in str(err).splitlines()]
        why = next((line for line in lines if line and not line.startswith("Failed in")), "")
        why = why or type(err).__name__
        print(
            f"note: the law {controller.name!r} has no compiled form ({why}); "
            "it runs in the Python loop (same numbers, slower)",
            file=sys.stderr,
        )
        return None
    from tt_mujoco.sim import records
    from tt_mujoco.sim.measure import TRAIN_FIELDS

    steps = stepper.steps
    loop, plant, law, target, stop = episode_records(stepper, controller, user)
    report_every = max(1, steps // 100)
    chunk = min(8192, report_every * max(1, 8192 // report_every))
    k, status, run_chunk = 0, step.RUNNING, None
    changes = [(0, tuple(plant.steering.etas.tolist()))]  # (first row, gains) of each change
    while status == step.RUNNING:
        k_end = min(steps, k + chunk - 1)
        n = k_end - k + 1
        log = records.LogRecord(
            measurement=np.empty((n, len(records.MEASUREMENT_DTYPE))),
            loop=np.empty(n, dtype=records.LOG_DTYPE),
            train=np.empty((n, loop.n_trailers - 1, len(TRAIN_FIELDS))),
            etas=np.empty((n if plant.steering.kind else 0, loop.n_trailers)),
        )
        args = (k, k_end, loop, plant, law, target, log, stop)
        if run_chunk is None:
            try:  # the first call loads the compiled code from the cache
                run_chunk = _compiled_for(k_mod.run_chunk, args)
                status, k_next = run_chunk(*args)
            except Exception as err:  # damaged: nothing has run, the Python loop takes over
                set_aside_cache(err)
                return None
            _write_manifest(sum(k_mod.run_chunk.stats.cache_misses.values()) > 0)
        else:
            status, k_next = run_chunk(*args)
        # Rows k..k_next-1 are logged; a stop in the plant's advance, a payload step on the
        # reduced plant or the end logs k_next too.
        ends = (step.FINISHED, step.WARNING, step.SINGULAR, step.PAYLOAD)
        logged = k_next - k + (1 if status in ends else 0)
        columns = log.loop.view(np.float64).reshape(n, -1)
        trains = log.train.reshape(n, -1)
        stepper.add_block(log.measurement[:logged], columns[:logged], trains[:logged])
        if plant.steering.kind:
            changes.extend(_changes(log.etas[:logged], changes, stepper.samples - logged))
        if stop[0]["payloads"]:  # the reduced plant's constants change, then step k_next goes on
            plant = _carry_payloads(stepper, plant, loop.faults, stop[0])
            if status == step.PAYLOAD:
                # not compiled by the warm-up: its first call here may add to the cache
                status = _call_listed(k_mod.advance_after_payload, plant, loop.wind, stop)
                k_next += 1 if status == step.RUNNING else 0
        if progress is not None:
            progress(k_next, steps)
        k = k_next
    _hand_back(stepper, controller, status, k, plant, law, target)
    faults = stepper.faults
    if faults is not None:  # what a dropout holds, where the payloads acted
        faults.held[:] = loop.faults.held.tolist()
        faults.payload_rows[:] = loop.faults.payloads.tolist()
        faults.payload_state[:] = loop.faults.payload_state.tolist()
    if stepper.motors is not None:
        stepper.motors.torques[:] = loop.motor_torques.tolist()
    if loop.ground.geoms.size:  # one mask per advance: k of them
        stepper.log_ground(loop.ground.masks[:k], loop.ground.arcs)
    if plant.steering.kind:
        _hand_back_steering(stepper, controller, plant.steering, changes)
    return _outcome(status, stop[0], stepper, controller, k)


def _carry_payloads(stepper, plant, faults, stop):
    """The payload changes of a step on the reduced plant: made to the plant (its parameters,
    in the order made), and the plant record rebuilt on its new constants (the gains in force
    kept); ``stop.payloads`` cleared."""
    from tt_mujoco.vehicle import reduced
    from tt_mujoco.vehicle.train import TRAILER_ROW

    count = int(stop["payloads"])
    for trailer, factor in faults.payload_changes[:count].tolist():
        stepper.plant.scale_trailer_mass(factor, int(trailer))
    stop["payloads"] = 0.0
    params = stepper.plant.params
    train = _train_constants(params)
    eta = TRAILER_ROW.index("eta")
    if params.n_trailers > 1:  # a schedule's gains in force, not the parameters' own
        train.trailers[:, eta] = plant.train.trailers[:, eta]
    return plant._replace(ode=reduced.model_constants(params), train=train)


def episode_records(stepper, controller, user) -> tuple:
    """The records of the (reset) ``stepper``'s episode as the step reads them
    (:mod:`tt_mujoco.sim.closed_loop`): ``(loop, plant, law, target, stop)``, with ``user`` the
    compiled form of a plain-number law (any placeholder for a built-in one)."""
    from tt_mujoco.sim import records

    plant = _plant_record(stepper, stepper.built.nominal)
    return (
        stepper.loop_record(),
        plant,
        _law_record(controller, stepper.built.nominal, user, plant.steering),
        _target_record(stepper.built, stepper.steps),
        records.new_record(records.STOP_FIELDS),
    )


def _user_law(k_mod, controller):
    """The compiled form of a plain-number law (the kernel's placeholder for a built-in)."""
    from tt_mujoco.controllers.plain import PlainLawController

    if isinstance(controller, PlainLawController):
        return compile_law(type(controller))
    return k_mod.no_user_law


def _changes(etas: np.ndarray, changes: list, first_row: int) -> list:
    """``(row, gains)`` of each logged row whose gains differ from the row before it."""
    out, last = [], changes[-1][1]
    for i, row in enumerate(map(tuple, etas.tolist())):
        if row != last:
            out.append((first_row + i, row))
            last = row
    return out


def _hand_back_steering(stepper, controller, steering, changes) -> None:
    """The schedule's state after a compiled episode: to the scheduler (its gains, arc
    lengths and change log), the plant and a built-in law's model."""
    from tt_mujoco.sim import records

    etas, seen = tuple(steering.etas.tolist()), changes[-1][1]  # the last row's: the law's
    if etas != seen:  # applied after the last logged row
        changes.append((stepper.samples, etas))
    scheduler = stepper.scheduler
    if steering.kind == records.PATH_SCHEDULE:  # the path schedule's axles
        scheduler.arc_lengths = steering.arcs.tolist()
    logged = [(row, gains[0]) for row, gains in changes[1:]]
    scheduler.restore(etas, logged, int(steering.updates[0]))
    steering_changed = getattr(controller, "steering_changed", None)
    if steering_changed is not None:
        steering_changed(seen)


def _steering_record(stepper, mujoco_plant: bool):
    """The scheduler's gains and tables, and where the plant's couplings are."""
    from tt_mujoco.sim import records
    from tt_mujoco.sim.schedule import EtaScheduler, PathEtaScheduler
    from tt_mujoco.vehicle.path_schedule import BLEND_PHI, driven_path

    scheduler, n = stepper.scheduler, stepper.built.plant_params.n_trailers
    if mujoco_plant:
        eq_data, ids, hitches_q, actuated, max_turn = stepper.plant.steering
    else:
        eq_data, ids, hitches_q, actuated, max_turn = np.zeros((1, 1)), [0] * n, [0] * n, False, 0.0
    kind, tables, arcs, bounds = 0, np.zeros((n, 5, 1)), np.zeros(n), (0.0, 0.0)
    etas, tolerance, driven = stepper.plant_etas, 0.0, driven_path(0, 0.0, 0.0)
    if isinstance(scheduler, PathEtaScheduler):
        kind, tolerance = records.PATH_SCHEDULE, scheduler.tolerance
        tables = np.array(scheduler.schedule.tables, dtype=float)
        arcs = np.array(scheduler.arc_lengths, dtype=float)
        bounds = (BLEND_PHI, scheduler.schedule.eta_max)
        driven = scheduler.driven  # its arrays: the compiled steps log into them
    elif isinstance(scheduler, EtaScheduler):
        kind, tolerance = records.CURVATURE_SCHEDULE, scheduler.tolerance
    return records.SteeringRecord(
        kind=kind,
        etas=np.array(etas, dtype=float),
        offered=np.zeros(n),
        tolerance=tolerance,
        lengths=np.array([(t.L, t.L0) for t in stepper.built.plant_params.trailers]),
        arcs=arcs,
        tables=tables,
        bounds=bounds,
        driven=driven,
        eq_data=eq_data,
        ids=np.array(ids, dtype=np.int64),
        hitches_q=np.array(hitches_q, dtype=np.int64),
        actuated=actuated,
        max_turn=max_turn,
        updates=np.zeros(1, dtype=np.int64),
    )


def _plant_record(stepper, nominal):
    from tt_mujoco.sim import records
    from tt_mujoco.sim.measure import Addresses, Lengths
    from tt_mujoco.sim.plant_mujoco import MujocoPlant
    from tt_mujoco.vehicle import reduced

    plant, substeps = stepper.plant, stepper.built.substeps

    if isinstance(plant, MujocoPlant):
        d, lay = plant.data, plant.layout
        mj = records.MujocoRecord(
            pointers=np.array([plant.model._address, d._address], dtype=np.int64),
            qpos=d.qpos,
            qvel=d.qvel,
            ctrl=d.ctrl,
            qfrc_applied=d.qfrc_applied,
            warnings=d.warning.number,
            xfrc_applied=d.xfrc_applied,
            tractor_body=plant.tractor_body,
            addresses=lay.addresses,
            lengths=lay.lengths,
            body_mass=plant.model.body_mass,
            body_inertia=plant.model.body_inertia,
            trailer_bodies=np.array(plant.trailer_bodies, dtype=np.int64),
        )
        ode_state, ode, timestep = np.zeros(8), reduced.model_constants(nominal), 0.0
        params, joints = nominal, np.array(lay.train, dtype=float).reshape(-1, 5)
    else:
        one, none = np.zeros(1), np.zeros(0, dtype=np.int64)
        mj = records.MujocoRecord(
            none, one, one, one, one, np.zeros(1, dtype=np.int32), np.zeros((1, 6)), 0,
            Addresses(*[0] * len(Addresses._fields)), Lengths(0.0, 0.0, 0.0, 0.0),
            np.zeros(1), np.zeros((1, 3)), np.zeros(1, dtype=np.int64),
        )  # fmt: skip
        ode_state = np.array(plant.ode.state, dtype=float)
        ode, timestep = reduced.model_constants(plant.params), plant.timestep
        params, joints = plant.params, np.zeros((0, 5))
    n = params.n_trailers
    return records.PlantRecord(
        mujoco=isinstance(plant, MujocoPlant),
        substeps=substeps,
        mj=mj,
        ode_state=ode_state,
        ode=ode,
        timestep=timestep,
        train=_train_constants(params),
        train_joints=joints,
        places=np.zeros((n, 5)),
        speeds=np.zeros((n, 3)),
        slopes=np.zeros((5, len(ode_state))),
        steering=_steering_record(stepper, isinstance(plant, MujocoPlant)),
    )


def _train_constants(params):
    """A train's constants with the trailers as a float array (no rows for one trailer)."""
    from tt_mujoco.vehicle.train import TRAILER_ROW, train_constants

    c = train_constants(params)
    rows = np.array(c.trailers, dtype=float) if params.n_trailers > 1 else np.zeros(0)
    return c._replace(trailers=rows.reshape(-1, len(TRAILER_ROW)))


def _law_record(controller, nominal, user, steering):
    from tt_mujoco.controllers.plain import PlainLawController
    from tt_mujoco.sim import records
    from tt_mujoco.sim.kernel_sources import LAWS
    from tt_mujoco.vehicle import reduced

    if isinstance(controller, PlainLawController):
        kind, gains, state, flags = len(LAWS), np.zeros(0), np.zeros(8), (0.0, 0.0, 0.0)
        user_gains = np.array(list(controller.gain_record), dtype=float)
        user_state = np.array([getattr(controller.law_state, f) for f in controller.STATE])
        anti_windup = False
    else:
        kind = LAWS.index(type(controller).LAW)
        gains = np.array(controller.law_gains, dtype=float)
        state = np.array(controller.law_state(), dtype=float)
        flags = (float(controller.saturated), 0.0, 0.0)
        user_gains, user_state = np.zeros(0), np.zeros(0)
        anti_windup = bool(controller.anti_windup)
    return records.LawRecord(
        kind=kind,
        gains=gains,
        state=state,
        flags=records.new_record(
            records.LAW_FLAGS, **dict(zip(records.LAW_FLAGS, flags, strict=True))
        ),
        nominal=reduced.model_constants(nominal),
        nominal_train=_train_constants(nominal),
        phis=np.zeros(nominal.n_trailers),
        rates=np.zeros((nominal.n_trailers, 3)),
        anti_windup=anti_windup,
        user=user,
        user_gains=user_gains if user_gains.size else np.zeros(1),
        user_state=user_state if user_state.size else np.zeros(1),
        reference=records.new_record(records.REFERENCE_FIELDS),
        model=records.new_record(records.NOMINAL_FIELDS),
        measurement_values=np.zeros(len(records.MEASUREMENT_DTYPE)),
        torques=np.zeros(2),
        follows_steering=not isinstance(controller, PlainLawController),
        steered_train=_train_constants(nominal.with_etas(tuple(steering.etas.tolist()))),
        axle_slew_rate=float(getattr(controller, "axle_slew_rate", math.inf)),
        reading=records.new_record(records.READING_FIELDS),
    )


def _target_record(built, steps: int):
    from tt_mujoco.controllers.backing import CascadeConstants, HitchCascade
    from tt_mujoco.reference.feedback import PathFeedback
    from tt_mujoco.reference.paths import ArcsPath
    from tt_mujoco.reference.reverse import ReverseTarget
    from tt_mujoco.reference.spline import SplinePath
    from tt_mujoco.sim import records

    target, path, outer = _inner(built.target), built.path, built.target
    fed, cascade = type(outer) is PathFeedback, type(outer) is HitchCascade
    n = built.plant_params.n_trailers
    constants = CascadeConstants(
        (0.0, 0.0, 0.0, 0.0), 0.0, np.zeros((n, 2)), np.zeros(n), np.zeros((n, 2))
    )
    if cascade:
        c = outer.constants
        constants = CascadeConstants(
            c.gains, c.preview, *(np.array(x, dtype=float) for x in (c.lengths, c.etas, c.ends))
        )
    kappas, starts = np.zeros(0), np.zeros((0, 3))
    cells, pose_cells, kappa_ends = np.zeros((0, 5)), np.zeros((0, 10)), np.zeros(2)
    if isinstance(path, ArcsPath):
        kind, (bounds, kappas, starts) = 0, path.closed_form
    elif isinstance(path, SplinePath):
        kind, (bounds, cells, pose_cells, kappa_ends) = 2, path.closed_form
    else:
        kind, bounds = 1, np.zeros(0)
    return records.TargetRecord(
        dynamic=target.kind == "dynamic",
        profile=_profile_table(target, built.control_dt, steps),
        path_kind=kind,
        length=float(path.length),
        bounds=bounds,
        kappas=kappas,
        starts=starts,
        cells=cells,
        pose_cells=pose_cells,
        kappa_ends=kappa_ends,
        state=records.new_record(
            records.TARGET_FIELDS,
            v_prev=math.nan,
            kappa=target.curvature,
            s=target.arc_length,
            s_near=outer.path_arc_length if fed else 0.0,
            s_lead=outer.leading_arc_length if cascade else 0.0,
        ),
        feedback=fed,
        feedback_gains=outer.gains if fed else (0.0, 0.0, 0.0),
        reverse=isinstance(target, ReverseTarget),
        s_end=float(getattr(target, "s_end", 0.0)),
        cascade=cascade,
        cascade_constants=constants,
        wanted=np.array(outer.hitch_targets if cascade else [0.0] * n, dtype=float),
        rates=np.zeros((n, 3)),
    )


def _hand_back(stepper, controller, status, k, plant, law, target) -> None:
    """Give the state back: the stepper, the target, the controller and the reduced ODE."""
    from tt_mujoco.controllers.plain import PlainLawController

    stepper.k = k
    stepper.finished = status == step.FINISHED
    state = target.state[0]
    _inner(stepper.built.target).set_state(
        float(state["s"]), float(state["v_prev"]), float(state["kappa"])
    )
    errors, omega_ref = (float(state["e_y"]), float(state["e_psi"])), float(state["omega_ref"])
    if target.feedback:
        stepper.built.target.set_state(float(state["s_near"]), errors, omega_ref)
    elif target.cascade:
        wanted = target.wanted.tolist()
        stepper.built.target.set_state(float(state["s_lead"]), errors, wanted, omega_ref)
    if isinstance(controller, PlainLawController):
        for name, value in zip(controller.STATE, law.user_state.tolist(), strict=False):
            setattr(controller.law_state, name, value)
    else:
        flags = law.flags[0]
        aux1, aux2 = float(flags["aux1"]), float(flags["aux2"])
        controller.set_law_state(tuple(law.state.tolist()), aux1, aux2)
        controller.saturated = bool(flags["saturated"])
    if not plant.mujoco:
        stepper.plant.ode.state = plant.ode_state.copy()
        stepper.plant.ode.time = k * stepper.dt


#: Speed-profile tables by (pickled profile, dt, steps): a sweep's episodes share their profile.
_PROFILES: dict = {}


def _profile_table(target, dt: float, steps: int) -> np.ndarray:
    """``(s_ref, v_ref, a_ref)`` of the target's speed profile at every control step, from
    the profile's own scalar ``state`` at the stepper's times ``k dt``."""
    key = (pickle.dumps(target.profile), dt, steps)
    table = _PROFILES.get(key)
    if table is None:
        times = [k * dt for k in range(steps + 1)]
        table = np.array([target.profile.state(t) for t in times], dtype=float)
        if len(_PROFILES) >= 8:
            _PROFILES.pop(next(iter(_PROFILES)))
        _PROFILES[key] = table
    return table


def _outcome(status, stop, stepper, controller, k) -> tuple[str, str]:
    """``(status, message)`` from the ``stop`` record, worded as the Python loop words them."""
    from tt_mujoco.controllers.base import LAW_NOT_FINITE, LAW_SINGULAR
    from tt_mujoco.controllers.plain import PlainLawController
    from tt_mujoco.sim import usercode
    from tt_mujoco.sim.plant import StopRun
    from tt_mujoco.sim.stepper import blew_up_message, jackknife_message
    from tt_mujoco.vehicle.reduced import SingularityError

    t = k * stepper.dt
    value = {name: float(stop[name]) for name in stop.dtype.names}
    if status == step.FINISHED:
        return "ok", f"completed {stepper.built.duration:.3f} s"
    if status == step.BLEW_UP:
        return "diverged", blew_up_message(t, value["v"])
    if status == step.JACKKNIFE:
        phi, beta, x, y, v = (value[name] for name in ("phi", "beta", "x", "y", "v"))
        hitch = int(value["hitch"])
        eta = stepper.eta if hitch == 1 else value["eta"]
        return "jackknife", jackknife_message(t, phi, beta, eta, x, y, v, hitch=hitch)
    if status == step.WARNING:
        import mujoco

        from tt_mujoco.sim.plant_mujoco import warning_message

        return "diverged", warning_message(mujoco.mjtWarning(int(value["warning"])).name, t)
    if status == step.SINGULAR:
        err = SingularityError(value["phi"], value["eta"])
        return "jackknife", f"jackknife at t={t + stepper.dt:.3f} s: {err}"
    # LAW_FAILED: the nominal model's singularity, or the law's own failure
    law_status = int(value["law_status"])
    u1, u2 = value["u1"], value["u2"]
    if isinstance(controller, PlainLawController):  # the user's law returned no torques
        try:
            usercode.checked_torques((u1, u2), usercode.controller_label(stepper.built), t)
        except StopRun as stop_run:
            if law_status == LAW_NOT_FINITE:
                return stop_run.status, stop_run.message
    try:
        if law_status == NOMINAL_SINGULAR:
            raise SingularityError(value["phi"], value["eta"])
        g = tuple(value[name] for name in ("g11", "g12", "g21", "g22"))
        controller.raise_for(law_status, g if law_status == LAW_SINGULAR else (), u1, u2)
    except FloatingPointError as err:
        return "diverged", f"controller failed at t={t:.3f} s: {err}"
    raise AssertionError(f"unknown status {status}")  # pragma: no cover


#: ``stop.law_status`` of the nominal model's own singularity (the kernel's NOMINAL_SINGULAR)
NOMINAL_SINGULAR = -1


def compile_law(cls):
    """The plain-number law of ``cls`` (a :class:`~tt_mujoco.controllers.plain.
    PlainLawController` subclass) compiled with the kernel's law signature, once per process
    and class."""
    key = (cls.__module__, cls.__qualname__, cls.LAW)
    compiled_law = _LAWS.get(key)
    if compiled_law is None:
        compiled_law = _LAWS[key] = _compile_law(cls)
    return compiled_law


_LAWS: dict = {}


def _register_helpers(fn, seen=None) -> None:
    """Let numba compile the plain functions a law calls from its own module (and theirs)."""
    import types

    from numba.extending import register_jitable

    seen = set() if seen is None else seen
    for name in fn.__code__.co_names:
        helper = fn.__globals__.get(name)
        if (
            isinstance(helper, types.FunctionType)
            and helper.__module__ == fn.__module__
            and helper not in seen
        ):
            seen.add(helper)
            register_jitable(helper)
            _register_helpers(helper, seen)


def _compile_law(cls):
    from numba import carray, cfunc, njit

    from tt_mujoco.sim import records

    k_mod = kernel()
    _register_helpers(cls.LAW)
    law = njit(error_model="numpy", cache=True)(cls.LAW)
    gain_names = tuple(cls.PRESETS[cls.DEFAULT_PRESET]) or ("unused",)
    gains_dtype = records.record_dtype(gain_names)
    state_dtype = records.record_dtype(cls.STATE or ("unused",))
    meas_dtype, ref_dtype = (
        records.MEASUREMENT_DTYPE,
        records.record_dtype(records.REFERENCE_FIELDS),
    )
    model_dtype = records.record_dtype(records.NOMINAL_FIELDS)
    n_meas, n_gains, n_state = len(meas_dtype), len(gains_dtype), len(state_dtype)
    n_ref, n_model = len(ref_dtype), len(model_dtype)

    def wrapper(m, r, model, gains, state, out, dt, limit):
        torques = carray(out, 2)
        T_r, T_l = law(
            carray(m, n_meas).view(meas_dtype)[0],
            carray(r, n_ref).view(ref_dtype)[0],
            carray(model, n_model).view(model_dtype)[0],
            carray(gains, n_gains).view(gains_dtype)[0],
            carray(state, n_state).view(state_dtype)[0],
            dt,
            limit,
        )
        torques[0], torques[1] = T_r, T_l

    return cfunc(k_mod.USER_LAW, error_model="numpy")(wrapper)

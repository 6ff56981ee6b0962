"""The compiled episode: the built-in law's closed loop as one machine-code loop.

:func:`tt_mujoco.sim.simulate.run_episode` hands an episode here when every part of it has a
compiled form (:func:`unsupported` says why not otherwise): a built-in law (ISMC-STA, PID, FBL)
on the built-in nominal model, a static or dynamic target on a closed-form path (the S-curve,
the circle, the cycloid), the paper's disturbance (matched) or none, measurement noise, one
trailer, no faults, path feedback, steering schedule, reversing or per-step callback. The loop
then runs in numba, chunk by chunk, calling ``mj_step`` through MuJoCo's C library or stepping
the reduced ODE, and logs into float arrays.

Every formula it runs is the Python one: the functions marked "the compiled episode shares it"
(measurement, reduced model, law, path curvature, disturbance, RK4) are compiled from their own
source with ``numba.extending.register_jitable``, so the compiled and the Python loop compute
the same numbers bit for bit (``tests/test_compiled.py``). ``TT_MUJOCO_COMPILED=0`` turns it off.

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

from tt_mujoco.defaults import MAX_SPEED
from tt_mujoco.outputs import atomic_write

__all__ = ["kernel", "ready", "run_compiled", "source_digest", "unsupported"]

#: Shortest episode handed to the compiled loop (loading the compiled code is paid once per
#: process: a short episode gains less than that).
MIN_STEPS = 2000

# Status codes of the kernel.
_RUNNING, _FINISHED, _BLEW_UP, _JACKKNIFE, _WARNING, _LAW_FAILED, _SINGULAR = range(7)

_KERNEL = None


def _enabled() -> bool:
    return os.environ.get("TT_MUJOCO_COMPILED", "1") != "0"


def unsupported(built, controller, on_step=None) -> str | None:
    """Why the episode has no compiled form (None when it has one); only a query."""
    from tt_mujoco.controllers.fbl import FblController
    from tt_mujoco.controllers.ismc_sta import IsmcStaController
    from tt_mujoco.controllers.pid import PidController
    from tt_mujoco.reference.paths import ArcsPath, CycloidPath
    from tt_mujoco.reference.targets import DynamicTarget, StaticTarget
    from tt_mujoco.sim.disturbances import PaperDisturbance

    s = built.scenario
    reasons = [
        (not _enabled(), "TT_MUJOCO_COMPILED=0"),
        (built.steps < MIN_STEPS, f"fewer than {MIN_STEPS} steps"),
        (bool(s.faults) or s.path_feedback is not None or s.eta_schedule, "faults or feedback"),
        (built.plant_params.n_trailers != 1, "a train"),
        (s.actuator != "ideal", "a motor model"),
        (s.sensor_delay != 0.0, "a sensor delay"),
        (s.wind != "none", "wind"),
        (bool(s.ground), "friction patches"),
        (s.plant == "mujoco" and s.disturbance == "wrench", "the wrench disturbance"),
        (on_step is not None, "a per-step callback"),
        (
            type(controller) not in (IsmcStaController, PidController, FblController),
            "a controller other than the built-in laws",
        ),
        (not getattr(getattr(controller, "model", None), "builtin", False), "a custom model"),
        (type(built.target) not in (StaticTarget, DynamicTarget), "this target"),
        (type(built.path) not in (ArcsPath, CycloidPath), "a path without closed form"),
        (
            built.disturbance is not None and type(built.disturbance) is not PaperDisturbance,
            "a custom disturbance",
        ),
    ]
    for failed, reason in reasons:
        if failed:
            return reason
    try:
        import numba  # noqa: F401
    except ImportError:
        return "numba is not installed"
    return None


def ready() -> bool:
    """Whether the compiled kernel can run now without compiling in the foreground: loaded in
    this process, or in the cache. The first call that finds neither starts one background
    process that fills the cache (``TT_MUJOCO_COMPILE_NOW=1``: compile here instead)."""
    if _KERNEL is not None or _cached() or os.environ.get("TT_MUJOCO_COMPILE_NOW") == "1":
        return True
    _compile_in_background()
    return False


#: The cache folder's list of its files and their hashes, written once the kernel has run.
MANIFEST = "manifest.json"


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
    import time

    cache = _cache_dir()
    lock = cache / "compiling.lock"
    try:
        cache.mkdir(parents=True, exist_ok=True)
        if lock.exists() and time.time() - lock.stat().st_mtime > 300:
            lock.unlink(missing_ok=True)  # a compile that died
        fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
        os.close(fd)
    except OSError:
        return  # compiling already, or no cache to compile into
    code = (
        "import os, pathlib; from tt_mujoco.sim import compiled; "
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


def _cache_dir() -> Path:
    """A cache folder per version of every source the kernel compiles."""
    root = os.environ.get("TT_MUJOCO_CACHE", str(Path.home() / ".cache" / "tt_mujoco"))
    return Path(root) / "numba" / source_digest()


@functools.cache
def source_digest() -> str:
    """A hash of what the compiled code depends on: the interpreter, the machine, numba's,
    llvmlite's and MuJoCo's versions, and every file the kernel compiles
    (:func:`tt_mujoco.sim.kernel_sources.source_files`, this file and the kernel's)."""
    import platform
    from importlib import metadata

    from tt_mujoco.sim.kernel_sources import source_files

    versions = [metadata.version(name) for name in ("numba", "llvmlite", "mujoco")]
    digest = hashlib.sha256(" ".join([sys.version, platform.machine(), *versions]).encode())
    here = Path(__file__).parent
    for name in (*source_files(), __file__, here / "_kernel.py"):
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
    return _KERNEL


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
    from tt_mujoco.sim.plant_mujoco import MujocoPlant
    from tt_mujoco.vehicle import reduced

    b = stepper.built
    plant = stepper.plant
    steps, dt = stepper.steps, stepper.dt
    target = b.target
    profile = _profile_table(target, dt, steps)
    path = b.path
    if hasattr(path, "_inner_bounds"):
        path_kind, bounds, kappas = 0, np.array(path._inner_bounds), np.array(path._kappa_list)
    else:
        path_kind, bounds, kappas = 1, np.zeros(0), np.zeros(0)
    nominal = b.nominal
    consts = reduced._constants(nominal)
    gamma = reduced._lumped(nominal)[5]
    noise = np.zeros(0) if stepper._noise is None else np.array(stepper._noise)
    mujoco_plant = isinstance(plant, MujocoPlant)
    if mujoco_plant:
        lay = plant._layout
        layout = np.array([*lay.addresses, lay.act_right, lay.act_left], dtype=np.int64)
        lengths = np.array(lay.lengths)
        d = plant.data
        pointers = np.array([plant.model._address, d._address], dtype=np.int64)
        qpos, qvel, ctrl, qfrc = d.qpos, d.qvel, d.ctrl, d.qfrc_applied
        warnings, ode_state, plant_consts = d.warning.number, np.zeros(8), np.zeros(0)
    else:
        pp = plant.params
        layout, pointers = np.zeros(11, dtype=np.int64), np.zeros(2, dtype=np.int64)
        lengths = np.array([pp.L, pp.L0, pp.r, pp.d])
        qpos = qvel = ctrl = qfrc = np.zeros(1)
        warnings = np.zeros(1, dtype=np.int32)
        ode_state = np.array(plant.ode.state, dtype=float)
        plant_consts = np.array([*reduced._constants(pp), reduced._lumped(pp)[5], plant.timestep])
    limits = np.array(
        [
            stepper._limit,
            math.inf if stepper._dist_limit is None else stepper._dist_limit,
            stepper._jk,
            stepper._jk_phi,
            *b.noise_std,
            float(b.disturbance is not None and stepper._mode == "matched"),
            float(controller.anti_windup),
        ]
    )
    law = np.array([*controller.law_state(), float(controller.saturated), 0.0, 0.0])
    law_kind = {"ismc_sta": 0, "pid": 1, "fbl": 2}[controller.name]
    target_state = np.array([0.0, math.nan, target.curvature, 0.0])  # s, v_prev, kappa, -
    scalars = np.array([dt, float(b.substeps), float(steps), MAX_SPEED, nominal.r, nominal.d])
    report_every = max(1, steps // 100)
    chunk = min(8192, report_every * max(1, 8192 // report_every))
    k, status = 0, _RUNNING
    info = np.zeros(8)
    while status == _RUNNING:
        k_end = min(steps, k + chunk - 1)
        meas = np.empty((k_end - k + 1, 19))
        loop = np.empty((k_end - k + 1, 17))
        args = (
            k,
            k_end,
            mujoco_plant,
            pointers,
            qpos,
            qvel,
            ctrl,
            qfrc,
            warnings,
            layout,
            lengths,
            ode_state,
            plant_consts,
            consts,
            gamma,
            law_kind,
            controller.law_gains,
            law,
            path_kind,
            bounds,
            kappas,
            target.kind == "dynamic",
            profile,
            target_state,
            noise,
            limits,
            scalars,
            meas,
            loop,
            info,
        )
        if k == 0:
            try:  # the first call loads the compiled code from the cache
                status, k_next = k_mod.run_chunk(*args)
            except Exception as err:  # damaged: nothing has run, the Python loop takes over
                set_aside_cache(err)
                return None
            _write_manifest(sum(k_mod.run_chunk.stats.cache_misses.values()) > 0)
        else:
            status, k_next = k_mod.run_chunk(*args)
        # Rows k..k_next-1 are logged; a stop in the plant's advance or the end logs k_next too.
        logged = k_next - k + (1 if status in (_FINISHED, _WARNING, _SINGULAR) else 0)
        stepper.add_block(meas[:logged], loop[:logged], np.empty((logged, 0)))
        if progress is not None:
            progress(k_next, steps)
        k = k_next
    # Hand the state back: the stepper, the target, the controller and the reduced ODE.
    stepper.k = k
    stepper.finished = status == _FINISHED
    target._s, target._kappa = target_state[0], target_state[2]
    if target.kind == "dynamic":
        target._v_prev = None if math.isnan(target_state[1]) else target_state[1]
    controller.set_law_state(tuple(law[:8].tolist()), float(law[9]), float(law[10]))
    controller.saturated = bool(law[8])
    if not mujoco_plant:
        plant.ode.state = ode_state.copy()
        plant.ode.time = k * dt
    return _outcome(status, info, stepper, controller, k)


#: Speed-profile tables by (pickled profile, dt, steps): a sweep's episodes share their profile.
_PROFILES: dict = {}


def _profile_table(target, dt: float, steps: int) -> np.ndarray:
    """``(s_ref, v_ref, a_ref)`` of the target's speed profile at every control step, from
    the profile's own scalar ``state`` at the stepper's times ``k dt``."""
    key = (pickle.dumps(target.profile), dt, steps)
    table = _PROFILES.get(key)
    if table is None:
        times = [k * dt for k in range(steps + 1)]
        table = np.array([target._profile_state(t) for t in times], dtype=float)
        if len(_PROFILES) >= 8:
            _PROFILES.pop(next(iter(_PROFILES)))
        _PROFILES[key] = table
    return table


def _outcome(status, info, stepper, controller, k) -> tuple[str, str]:
    """``(status, message)``, worded as the Python loop words them."""
    from tt_mujoco.controllers.base import LAW_SINGULAR
    from tt_mujoco.sim.stepper import blew_up_message, jackknife_message
    from tt_mujoco.vehicle.reduced import SingularityError

    t = k * stepper.dt
    if status == _FINISHED:
        return "ok", f"completed {stepper.built.duration:.3f} s"
    if status == _BLEW_UP:
        return "diverged", blew_up_message(t, float(info[0]))
    if status == _JACKKNIFE:
        phi, beta, x, y, v = info[:5].tolist()
        return "jackknife", jackknife_message(t, phi, beta, stepper.eta, x, y, v)
    if status == _WARNING:
        import mujoco

        from tt_mujoco.sim.plant_mujoco import warning_message

        return "diverged", warning_message(mujoco.mjtWarning(int(info[0])).name, t)
    if status == _SINGULAR:
        err = SingularityError(float(info[0]), float(info[1]))
        return "jackknife", f"jackknife at t={t + stepper.dt:.3f} s: {err}"
    # _LAW_FAILED: the nominal model's singularity (code 0) or the law's own failure
    values = info[1:5].tolist()
    try:
        if info[0] == 0.0:
            raise SingularityError(values[0], values[1])
        g = tuple(values) if int(info[0]) == LAW_SINGULAR else ()
        controller._raise_for(int(info[0]), g, values[0], values[1])
    except FloatingPointError as err:
        return "diverged", f"controller failed at t={t:.3f} s: {err}"
    raise AssertionError(f"unknown status {status}")  # pragma: no cover

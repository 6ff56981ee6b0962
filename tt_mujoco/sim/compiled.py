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

Compiled code is cached on disk, keyed by the numba and MuJoCo versions and a hash of every
source file involved (numba's own cache only watches the file of the function it caches), under
``$TT_MUJOCO_CACHE`` or ``~/.cache/tt_mujoco``. Compiling takes about 5 s, so it never happens
in the user's run: the first episode that could run compiled finds the cache empty, starts one
background process that compiles it, and runs the Python loop (same numbers); later episodes
load it (about 0.3 s, once per process). ``TT_MUJOCO_COMPILE_NOW=1`` compiles in the run
itself (the tests and benchmarks).
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

__all__ = ["run_compiled", "unsupported"]

#: Shortest episode handed to the compiled loop: loading the compiled code costs ~0.3 s once
#: per process, what the Python loop's overhead costs in about 10,000 steps.
MIN_STEPS = 2000

# Status codes of the kernel.
_RUNNING, _FINISHED, _BLEW_UP, _JACKKNIFE, _WARNING, _LAW_FAILED, _SINGULAR = range(7)

_KERNEL = None


def _enabled() -> bool:
    return os.environ.get("TT_MUJOCO_COMPILED", "1") != "0"


def unsupported(built, controller, on_step=None) -> str | None:
    """Why the episode cannot run compiled (None when it can)."""
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
    if not _compiled_yet() and os.environ.get("TT_MUJOCO_COMPILE_NOW") != "1":
        _compile_in_background()
        return "being compiled in the background (first use)"
    return None


def _compiled_yet() -> bool:
    """Whether the kernel is loaded here or in the cache."""
    return _KERNEL is not None or any(_cache_dir().glob("*/_kernel.run_chunk-*.nbi"))


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
    """Compile the kernel (for both plants: one signature) by running a short episode."""
    from tt_mujoco.sim.build import build
    from tt_mujoco.sim.scenario import Scenario
    from tt_mujoco.sim.stepper import Stepper

    built = build(Scenario(traj="circle", duration=MIN_STEPS * 0.001))
    stepper = Stepper(built)
    stepper.reset(np.random.default_rng(0))
    controller = built.new_controller()
    controller.reset()
    run_compiled(stepper, controller)


def _cache_dir() -> Path:
    """A cache folder per version of every source the kernel compiles."""
    root = os.environ.get("TT_MUJOCO_CACHE", str(Path.home() / ".cache" / "tt_mujoco"))
    return Path(root) / "numba" / _source_digest()


@functools.cache
def _source_digest() -> str:
    import mujoco
    import numba

    from tt_mujoco.controllers import base, fbl, ismc_sta, pid
    from tt_mujoco.reference import paths
    from tt_mujoco.sim import disturbances, measure, plant_reduced
    from tt_mujoco.vehicle import reduced

    digest = hashlib.sha256(f"{numba.__version__} {mujoco.__version__}".encode())
    for module in (base, fbl, ismc_sta, pid, paths, disturbances, measure, plant_reduced, reduced):
        digest.update(Path(module.__file__).read_bytes())
    digest.update(Path(__file__).read_bytes())
    digest.update((Path(__file__).parent / "_kernel.py").read_bytes())
    return digest.hexdigest()[:16]


def _kernel():
    """The compiled chunk loop (built on first use)."""
    global _KERNEL
    if _KERNEL is None:
        import numba

        cache = _cache_dir()
        try:
            cache.mkdir(parents=True, exist_ok=True)
            numba.config.CACHE_DIR = str(cache)
        except OSError:
            pass  # no cache: compiled in memory, every process
        from tt_mujoco.sim import _kernel

        _KERNEL = _kernel
    return _KERNEL


def run_compiled(stepper, controller, progress=None) -> tuple[str, str]:
    """Run the (reset) ``stepper``'s episode with ``controller`` compiled; ``(status,
    message)`` as :func:`tt_mujoco.sim.simulate.run_episode`."""
    from tt_mujoco.sim.plant_mujoco import MujocoPlant
    from tt_mujoco.vehicle import reduced

    k_mod = _kernel()
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
        status, k_next = k_mod.run_chunk(
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

        name = mujoco.mjtWarning(int(info[0])).name
        return "diverged", f"MuJoCo warning {name} by t={stepper.plant.data.time:.3f} s"
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

"""A time limit that holds for code that never returns to Python: the run in a child process,
watched by its parent.

The in-process limit (``--time-limit``, a SIGALRM that raises between Python bytecodes) cannot
stop a compiled law spinning in its own loop, or a user's class stuck in a C call: neither
returns to the interpreter, and Ctrl-C and SIGTERM do not reach them either.
:func:`supervise` forks just before the simulation. The child runs it and everything after it,
as the process would have; the parent only waits, and leaves with the child's exit code. If
the child is still running a grace period after its own limit should have stopped it (or
after an interrupt), the parent asks it for the Python traceback of where it is
(:mod:`faulthandler`, which answers from C whatever the interpreter is doing), kills it, and
hands over to ``on_expiry`` with the traceback: the caller keeps the rows the child wrote and
says where it hung.

Linux only (:func:`available`); elsewhere, or with ``TT_MUJOCO_WATCHDOG=0``, the run stays in
one process, with the in-process limit alone.

A sweep's worker runs many runs and is watched by the sweep itself: :func:`armed` sets
faulthandler's own timer (a C thread, which needs no interpreter) around each run, which,
should the run outlive its grace, writes the run's name and every thread's traceback into
the worker's hang file and ends the worker; the sweep, which sees its worker die, reads the
file (:func:`read_hangs`) and records that run as failed there instead of running it again.
"""

from __future__ import annotations

import contextlib
import math
import os
import select
import signal
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import NamedTuple

from tt_mujoco import background, guard

__all__ = [
    "GRACE_FRACTION",
    "GRACE_S",
    "INTERRUPT_GRACE_S",
    "Hang",
    "armed",
    "available",
    "disarm",
    "grace_for",
    "hang_site",
    "read_hangs",
    "supervise",
]

#: How long after its limit a run may take to stop by itself (the in-process limit stops it
#: at the next Python bytecode): this many seconds plus this fraction of the limit.
GRACE_S, GRACE_FRACTION = 2.0, 0.1
#: How long after an interrupt a run may take to stop by itself.
INTERRUPT_GRACE_S = 3.0
#: How long the parent waits for the child's traceback before it kills it.
_DUMP_WAIT_S = 1.0


def available() -> bool:
    """Whether runs are supervised here: Linux (a fork that keeps numba and MuJoCo usable,
    and pidfd), unless ``TT_MUJOCO_WATCHDOG=0`` keeps the run in one process (for a tool
    that does not follow a fork, such as a sampling profiler)."""
    if os.environ.get("TT_MUJOCO_WATCHDOG") == "0":
        return False
    return sys.platform.startswith("linux") and hasattr(os, "pidfd_open")


def supervise(
    limit_s: float,
    on_expiry: Callable[[str, bool], int],
    on_killed: Callable[[int], int],
    on_early_exit: Callable[[int], int] | None = None,
) -> None:
    """Fork; return in the child (the run goes on there), never return in the parent.

    The child stays in the parent's process group, so a terminal's Ctrl-C and a debugger's
    prompt reach it as they would the one process. The parent passes Ctrl-C and SIGTERM sent
    to it on to the child (which stops once, however often it is told:
    :func:`tt_mujoco.guard.interrupts_from_signals`); a child that has not ended within
    :data:`INTERRUPT_GRACE_S` of an interrupt is stuck where signals do not reach it, and is
    ended as at its time limit.

    Parameters
    ----------
    limit_s : float
        The run's own time limit (s); the parent waits this long plus the grace
        (:data:`GRACE_S`, :data:`GRACE_FRACTION`).
    on_expiry : callable
        Called in the parent with the child's traceback (text, maybe empty) and whether an
        interrupt (rather than the time limit) ended it, once it has been killed; returns the
        exit code.
    on_killed : callable
        Called in the parent with the signal number when something else killed the child (a
        crash in C, the kernel's out-of-memory killer); returns the exit code.
    on_early_exit : callable, optional
        Called in the parent with the child's exit code when the child exited before its
        simulation was over (:func:`disarm`, which every way out of the simulation passes):
        not the project's code, but a user's ``os._exit`` or a library's ``exit()`` in C;
        returns the exit code. None: the child's code stands.
    """
    import faulthandler
    import tempfile

    for stream in (sys.stdout, sys.stderr):
        stream.flush()
    # where the child writes its traceback when asked: a file with no name, never an output
    fd, name = tempfile.mkstemp(prefix="tt_mujoco-watch-", suffix=".txt")
    os.unlink(name)
    done_read, done_write = os.pipe()  # the child says there when its simulation is over
    pid = os.fork()
    if pid == 0:  # the child: the run
        global _DONE
        os.close(done_read)
        _DONE = done_write
        _die_with_parent()
        # the descriptor, held open, not a file object, which would warn of being left open
        # at the exit (and fail the exit where a user's code turned warnings into errors)
        faulthandler.register(signal.SIGUSR1, file=fd, all_threads=True)
        return
    os.close(done_write)
    try:
        code = _wait(pid, grace_for(limit_s), fd, done_read, on_expiry, on_killed, on_early_exit)
    finally:
        os.close(fd)
        os.close(done_read)
        background.end_workers()  # forked before this watch (the figures'): the child used them
    for stream in (sys.stdout, sys.stderr):
        stream.flush()
    os._exit(code)  # the child ran the process's exit handlers; the parent runs none


_DONE: int | None = None  # in a watched child: where it says its simulation is over


def disarm() -> None:
    """In a watched child: the simulation is over (it ended, stopped or failed), and what
    follows (metrics, figures, a video) is not bound by the run's time limit; the parent goes
    on waiting for it without a deadline. Nothing elsewhere."""
    global _DONE
    if _DONE is not None:
        try:
            os.write(_DONE, b"d")
            os.close(_DONE)
        except OSError:
            pass
        _DONE = None


def _die_with_parent() -> None:
    """The child is killed with its parent (Linux's parent-death signal): a parent killed
    outright leaves no run going on by itself."""
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        pr_set_pdeathsig = 1
        libc.prctl(pr_set_pdeathsig, signal.SIGKILL)
    except (OSError, AttributeError):
        pass
    if os.getppid() == 1:  # the parent died before the request
        os._exit(1)


def _wait(pid, seconds, traceback_fd, done_fd, on_expiry, on_killed, on_early_exit) -> int:
    deadline = [time.monotonic() + seconds, False]  # when, and whether an interrupt set it

    def interrupted(signum, frame):
        # passed on: a signal sent to the parent alone must stop the run; one sent to the
        # whole group (a terminal's Ctrl-C) reaches the child twice, which stops once
        try:
            os.kill(pid, signum)
        except ProcessLookupError:
            pass
        deadline[:] = [min(deadline[0], time.monotonic() + INTERRUPT_GRACE_S), True]

    for signum in guard.stop_signals():
        signal.signal(signum, interrupted)
    exited = os.pidfd_open(pid)  # readable once the child has exited
    watching = [exited, done_fd]
    try:
        while (left := deadline[0] - time.monotonic()) > 0.0:
            # woken at least every 0.25 s: an interrupt may bring the deadline forward
            ready = select.select(watching, [], [], min(left, 0.25))[0]
            if done_fd in watching and (done_fd in ready or exited in ready):
                # the simulation is over (a child that said so and exited: both are ready)
                if select.select([done_fd], [], [], 0.0)[0] and os.read(done_fd, 1):
                    watching.remove(done_fd)
                    if not deadline[1]:  # no deadline but an interrupt's
                        deadline[0] = math.inf
            if exited in ready:
                _, status = os.waitpid(pid, 0)
                code = os.waitstatus_to_exitcode(status)
                if code < 0:
                    return on_killed(-code)
                early = done_fd in watching and on_early_exit is not None
                return on_early_exit(code) if early else code
    finally:
        os.close(exited)
    return on_expiry(_ask_and_kill(pid, traceback_fd), deadline[1])


def _ask_and_kill(pid: int, traceback_fd: int) -> str:
    """The child's traceback (asked with SIGUSR1; faulthandler writes it from the signal
    handler, whatever the child is doing), then the child killed and reaped."""

    def written() -> str:
        return os.pread(traceback_fd, 1 << 20, 0).decode(errors="replace")

    try:
        os.kill(pid, signal.SIGUSR1)
    except ProcessLookupError:
        pass
    end, last = time.monotonic() + _DUMP_WAIT_S, None
    while time.monotonic() < end:  # until the dump has stopped growing
        time.sleep(0.05)
        text = written()
        if text and text == last:
            break
        last = text
    try:
        os.kill(pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
    os.waitpid(pid, 0)
    return written()


def hang_site(traceback: str) -> str:
    """Where the main thread of a :mod:`faulthandler` dump was: ``FILE, line N in NAME`` of its
    innermost frame, or "an unknown place". The main thread is the one that runs a module's
    code (a frame ``in <module>``: the command's)."""
    blocks, frames = [], None
    for line in traceback.splitlines():
        if "(most recent call first)" in line:
            frames = []
            blocks.append(frames)
        elif frames is not None and line.strip().startswith("File "):
            frames.append(line.strip().removeprefix("File ").replace('"', ""))
    for frames in blocks:
        if any(frame.endswith(" in <module>") for frame in frames):
            return _users_site(frames)
    return _users_site(blocks[0]) if blocks and blocks[0] else "an unknown place"


def _users_site(frames: list[str]) -> str:
    """The innermost frame, after the innermost of the user's own code where that is not it
    (a user's line that called into NumPy and hung there)."""
    from tt_mujoco.registry import users_file

    own = [f for f in frames if users_file(f.split(", line ")[0])]
    return frames[0] if not own or own[0] == frames[0] else f"{own[0]} (in {frames[0]})"


def grace_for(limit_s: float) -> float:
    """How long after it began a run of time limit ``limit_s`` is taken to hang."""
    return limit_s * (1.0 + GRACE_FRACTION) + GRACE_S


_HANG_FILE = None  # this worker's hang file and its folder, opened at its first run there


class Hang(NamedTuple):
    """A run a sweep's worker was ended for: its time limit (s) and the worker's traceback."""

    limit_s: float
    traceback: str


@contextlib.contextmanager
def armed(limit_s: float, hang_dir, run_id: str):
    """Around one run in a sweep's worker: should it outlive :func:`grace_for` its limit,
    write ``run_id``, the limit and every thread's traceback into this worker's file in
    ``hang_dir`` and end the process (faulthandler's timer, a C thread); :func:`read_hangs`
    reads it back. ``hang_dir`` None: no watch."""
    import faulthandler

    global _HANG_FILE
    if hang_dir is None:
        yield
        return
    if _HANG_FILE is None or _HANG_FILE[0] != Path(hang_dir):
        path = Path(hang_dir) / f"worker-{os.getpid()}.txt"
        _HANG_FILE = (Path(hang_dir), open(path, "w+"))  # held open
    f = _HANG_FILE[1]
    f.seek(0)
    f.truncate()
    f.write(f"{run_id} {limit_s!r}\n")
    f.flush()
    faulthandler.dump_traceback_later(grace_for(limit_s), exit=True, file=f)
    try:
        yield
    finally:
        faulthandler.cancel_dump_traceback_later()
        f.seek(0)
        f.truncate()
        f.flush()


def read_hangs(hang_dir) -> dict[str, Hang]:
    """The runs a worker was ended for hanging (:func:`armed`), by run id (each file read is
    emptied, so a run is told once)."""
    found = {}
    for file in sorted(Path(hang_dir).glob("worker-*.txt")):
        try:
            text = file.read_text(errors="replace")
        except OSError:
            continue
        label, _, traceback = text.partition("\n")
        run_id, _, limit = label.partition(" ")
        if run_id and "most recent call first" in traceback:
            found[run_id] = Hang(float(limit), traceback)
            file.write_text("")
    return found

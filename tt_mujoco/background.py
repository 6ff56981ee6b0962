"""A worker process forked ahead of its work: the run's figures are drawn on the other cores.

A :class:`Worker` is forked when the run starts, before its simulation, and at once runs its
``prepare`` (importing matplotlib costs a quarter of a second): that happens on a core the
simulation does not use. When the time series is there, :meth:`Worker.call` hands it one call
(pickled through a pipe) and the caller goes on (writing files, rendering the video) while the
figures are drawn; :meth:`Worker.result` waits for the return value or the exception the call
raised. It is forked before the caller makes an OpenGL context, so it shares nothing with the
renderer. Where fork is not the platform's safe default (not Linux), or the machine has one
core (the worker would take the simulation's), the call runs in the caller when its result is
asked for, with the same result.

A worker never outlives its caller: it ignores Ctrl-C (the caller handles it and ends the
worker), and it exits when its pipe closes, which the end of the caller's process does. A
process forked from the caller after the worker (a run's watched child) may call it, take its
result and end it; the caller reaps it.
"""

from __future__ import annotations

import multiprocessing.connection
import os
import signal
import sys
from collections.abc import Callable

from tt_mujoco import guard

__all__ = ["BackgroundError", "Worker", "end_workers", "spare_cores"]

#: The workers forked and not yet reaped: pid -> the pid of the process that forked it.
_FORKED: dict[int, int] = {}


class BackgroundError(RuntimeError):
    """The worker process ended without an answer (killed, or out of memory)."""


def spare_cores() -> int:
    """Cores this process may use beside the one it runs on (0 on a single core)."""
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # not Linux
        cores = os.cpu_count() or 1
    return max(0, cores - 1)


def _serve(channel, caller_end, prepare) -> None:
    """The worker: ``prepare()``, then one call from the pipe, its answer sent back."""
    # Ctrl-C and a hangup reach the whole process group: the caller handles them and ends
    # this process.
    guard.ignore_stop_signals()
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    caller_end.close()  # only the caller holds it: its end closing is this pipe's EOF
    try:
        if prepare is not None:
            prepare()
        fn, args, kwargs = channel.recv()
    except (EOFError, OSError):  # the caller went away (or gave up) before asking
        return
    except BaseException as err:  # a prepare that failed: the call is answered with it
        fn, args, kwargs = _raise, (err,), {}
    try:
        answer = (True, fn(*args, **kwargs))
    except BaseException as err:  # handed to the caller, which raises it
        answer = (False, err)
    try:
        channel.send(answer)
    except Exception as err:  # an exception that cannot be pickled: its text, typed plainly
        channel.send((False, RuntimeError(f"{type(answer[1]).__name__}: {answer[1]}: {err}")))
    channel.close()


def end_workers() -> None:
    """End and reap every worker this process forked and has not reaped: the workers a
    process forked from it used (a run's watched child, the figures' worker forked before
    it). Called by that process once its child is over, so that no worker outlives the
    command and their time is counted as the command's."""
    for pid, forker in list(_FORKED.items()):
        if forker != os.getpid():
            continue
        try:
            os.kill(pid, signal.SIGKILL)  # done by now, or stuck on a pipe no one reads
        except ProcessLookupError:
            pass
        try:
            os.waitpid(pid, 0)
        except ChildProcessError:
            pass
        del _FORKED[pid]


def _fork(prepare, channel, caller_end) -> int:
    """Fork the worker; its pid. The child serves and leaves by ``os._exit``: none of the
    caller's exit handlers or buffered output runs twice."""
    sys.stdout.flush()
    sys.stderr.flush()
    pid = os.fork()
    if pid == 0:
        code = 0
        try:
            _serve(channel, caller_end, prepare)
        except BaseException:
            code = 1
        finally:
            os._exit(code)
    return pid


def _raise(err: BaseException):
    raise err


class Worker:
    """One call in a process forked now, ahead of the call.

    Parameters
    ----------
    prepare : callable, optional
        Run in the worker as soon as it starts (its imports), before the call arrives.
    forked : bool, optional
        Fork the worker (default: on Linux with a core to spare, :func:`spare_cores`); False
        runs the call in the caller, when :meth:`result` is asked for.
    """

    def __init__(self, prepare: Callable | None = None, forked: bool | None = None):
        if forked is None:
            forked = sys.platform.startswith("linux") and spare_cores() > 0
        self._forked = bool(forked)
        self._process = None
        self._call = None
        self._answer = None
        if not forked:
            return
        self._channel, theirs = multiprocessing.connection.Pipe(duplex=True)
        self._process = _fork(prepare, theirs, self._channel)
        _FORKED[self._process] = os.getpid()
        theirs.close()

    @property
    def forked(self) -> bool:
        """Whether the call runs in a process of its own."""
        return self._forked

    @property
    def called(self) -> bool:
        """Whether the worker has been handed its call."""
        return self._call is not None

    def call(self, fn: Callable, *args, **kwargs) -> None:
        """Hand the worker ``fn(*args, **kwargs)`` (pickled on the way); returns at once."""
        if self.called:
            raise RuntimeError("a Worker takes one call")
        if not self._forked:
            self._call = (fn, args, kwargs)
            return
        try:
            self._channel.send((fn, args, kwargs))
        except OSError:  # the worker is gone: result() says so
            pass
        self._call = ()

    def result(self):
        """The call's return value, or the exception it raised, raised here.

        Raises
        ------
        BackgroundError
            The worker ended without answering.
        """
        if self._answer is None:
            if not self.called:
                raise RuntimeError("result() before call()")
            if not self._forked:
                fn, args, kwargs = self._call
                try:
                    self._answer = (True, fn(*args, **kwargs))
                except Exception as err:
                    self._answer = (False, err)
            else:
                self._answer = self._receive()
        ok, value = self._answer
        if ok:
            return value
        raise value

    def _receive(self):
        try:
            return self._channel.recv()
        except (EOFError, OSError):
            code = self._join()
            raise BackgroundError(
                f"the background process ended without an answer ({code})"
            ) from None
        finally:
            self._channel.close()
            self._join()

    def _join(self) -> str:
        """Wait for the worker's end; how it ended, in words."""
        if self._process is None:
            return "ended"
        try:
            _, status = os.waitpid(self._process, 0)
        except ChildProcessError:  # forked by the process this one was forked from (a run's
            self._process = None  # watchdog): that one reaps it (end_workers)
            return "ended"
        _FORKED.pop(self._process, None)
        self._process = None
        if os.WIFSIGNALED(status):
            return f"killed by signal {os.WTERMSIG(status)}"
        return f"exit code {os.waitstatus_to_exitcode(status)}"

    def cancel(self) -> None:
        """End the worker if it still runs (the caller gave up: an error, an interrupt)."""
        if self._process is not None:
            try:
                os.kill(self._process, signal.SIGKILL)
            except ProcessLookupError:
                pass
            self._join()
            self._channel.close()

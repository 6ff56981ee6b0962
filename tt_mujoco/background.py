"""One function call in a forked process, while the caller goes on: the run's figures are drawn
beside its video, on the other core, instead of before it.

The child is forked, so it starts from the caller's memory (nothing is pickled on the way in)
and sends back only the function's return value or the exception it raised. It is forked before
the caller makes an OpenGL context, so it shares nothing with the renderer. Where fork is not
the platform's safe default (not Linux), the call runs at once in the caller, with the same
result.
"""

from __future__ import annotations

import multiprocessing
import signal
import sys
from collections.abc import Callable

__all__ = ["BackgroundCall", "BackgroundError"]


class BackgroundError(RuntimeError):
    """The background process ended without an answer (killed, or out of memory)."""


def _child(writer, fn, args, kwargs) -> None:
    # Ctrl-C reaches the whole process group: the parent handles it and ends this process.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    try:
        answer = (True, fn(*args, **kwargs))
    except BaseException as err:  # handed to the parent, which raises it
        answer = (False, err)
    try:
        writer.send(answer)
    except Exception as err:  # an exception that cannot be pickled: its text, typed plainly
        writer.send((False, RuntimeError(f"{type(answer[1]).__name__}: {answer[1]}: {err}")))
    writer.close()


class BackgroundCall:
    """``fn(*args, **kwargs)`` in a forked process; :meth:`result` waits for it.

    Parameters
    ----------
    fn : callable
        The function; its return value must pickle.
    *args, **kwargs
        Its arguments (not pickled: the child has the caller's memory).
    forked : bool, optional
        Run in a forked process (default: where fork is safe, on Linux); False runs the call
        at once, here.
    """

    def __init__(self, fn: Callable, *args, forked: bool | None = None, **kwargs):
        if forked is None:
            forked = sys.platform.startswith("linux")
        self._process = None
        if not forked:
            try:
                self._answer = (True, fn(*args, **kwargs))
            except Exception as err:
                self._answer = (False, err)
            return
        ctx = multiprocessing.get_context("fork")
        self._reader, writer = ctx.Pipe(duplex=False)
        self._process = ctx.Process(target=_child, args=(writer, fn, args, kwargs), daemon=True)
        self._process.start()
        writer.close()

    def result(self):
        """The function's return value, or the exception it raised, raised here.

        Raises
        ------
        BackgroundError
            The process ended without answering.
        """
        process = self._process
        if process is not None:
            try:
                self._answer = self._reader.recv()
            except EOFError:
                process.join()
                raise BackgroundError(
                    f"the background process ended without an answer (exit code {process.exitcode})"
                ) from None
            finally:
                self._reader.close()
            process.join()
            self._process = None
        ok, value = self._answer
        if ok:
            return value
        raise value

    def cancel(self) -> None:
        """End the process if it still runs (the caller gave up: an error, an interrupt)."""
        process = self._process
        if process is not None:
            process.kill()
            process.join()
            self._reader.close()
            self._process = None

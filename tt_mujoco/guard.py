"""The one place that knows what a user's code may raise, and what is not its failure.

Every call into a user's code (a module's import, a controller's construction and methods, a
path and its factory, a disturbance, a metric, a report) catches ``BaseException`` and asks
:func:`users_failure` whether to keep what was raised as that code's failure (a bad input
before the run, exit 2; a failed run during it, exit 3, every row kept) or to let it pass:
the project's own control signals (:func:`control_signal`: a run's time limit) and a real
interrupt (Ctrl-C, SIGTERM: :func:`interrupts_from_signals`). A ``KeyboardInterrupt`` a user's
code raises itself, ``SystemExit`` (``sys.exit(0)`` included), ``GeneratorExit`` and any other
``BaseException`` are its failures. :func:`shown_error` words one safely, whatever its
``__str__`` does.

Every command's ``main`` is wrapped by :func:`command`: what escapes it that is neither bad
input (the commands turn that into exit 2 themselves) nor an interrupt is a bug of ours: one
line on stderr naming the file its traceback was written to, and exit code 70. What the file
system refused (:data:`REFUSALS`: a full disk, a quota, a read-only folder) is not: one line
naming what was refused, exit code 2. Either way the folders the command claimed and left
holding nothing are removed. A command's relative paths are taken against the folder it
started in (:func:`absolute`), whatever folder a user's code moves the process to.
"""

from __future__ import annotations

import contextlib
import errno
import functools
import os
import signal
import sys
import threading
import time
from pathlib import Path
from typing import NoReturn

from tt_mujoco.defaults import EXIT_BAD_INPUT, EXIT_BUG, EXIT_INTERRUPTED

__all__ = [
    "REFUSALS",
    "STOP_SIGNALS",
    "absolute",
    "command",
    "control_signal",
    "end",
    "ignore_stop_signals",
    "interrupts_from_signals",
    "keeping_process_state",
    "noting_interrupts",
    "shown_error",
    "stop_signals",
    "users_failure",
]

#: The signals that stop a run cleanly, as Ctrl-C does (the rows kept, exit code 130): Ctrl-C,
#: a batch system's SIGTERM, and a terminal's hangup (an ssh connection lost). A hangup that
#: was ignored when the command started (``nohup``) stays ignored (:func:`stop_signals`).
STOP_SIGNALS = tuple(
    getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, name)
)


#: A stop sent again this long (s) after the first ends the process by the signal's own
#: action: a clean-up that hangs can still be stopped without SIGKILL.
AGAIN_S = 3.0


def stop_signals() -> tuple:
    """The :data:`STOP_SIGNALS` this process takes as a stop: all of them but one it ignores
    (``nohup`` ignores the hangup for the command it starts)."""
    return tuple(sig for sig in STOP_SIGNALS if signal.getsignal(sig) is not signal.SIG_IGN)


def ignore_stop_signals() -> None:
    """In a worker process of a command: ignore Ctrl-C and the terminal's hangup, which reach
    the whole process group; the command itself handles them and ends its workers."""
    for sig in STOP_SIGNALS:
        if sig != signal.SIGTERM:
            signal.signal(sig, signal.SIG_IGN)


_CONTROL: list[type] = []
#: Whether a signal handler of ours has turned a real interrupt into KeyboardInterrupt
#: (``None``: no handler of ours is installed, so every KeyboardInterrupt counts as real).
_INTERRUPTED: threading.Event | None = None


def control_signal(cls: type) -> type:
    """Declare ``cls`` (a class decorator) one of the project's own control signals: raised
    into a user's code from outside it (an alarm), it is never that code's failure."""
    _CONTROL.append(cls)
    return cls


def interrupts_from_signals() -> None:
    """Install, in the main thread, the handlers through which a real interrupt reaches the
    run: SIGINT (Ctrl-C), SIGTERM (a batch system's stop) and SIGHUP (a terminal's hangup;
    :func:`stop_signals`) raise ``KeyboardInterrupt`` after noting that it is real. The
    command-line entry points call it; an API user's process keeps its own handlers, and there
    every KeyboardInterrupt counts as real."""
    global _INTERRUPTED
    if threading.current_thread() is not threading.main_thread():
        return
    _INTERRUPTED = threading.Event()

    first: list[float] = []

    def interrupted(signum, frame):
        if first:  # one stop is enough: the same signal sent twice (to the process and to
            # its group) must not break the clean-up of the first; one sent again later is a
            # user who waited long enough: the signal's own action
            if time.monotonic() - first[0] > AGAIN_S:
                signal.signal(signum, signal.SIG_DFL)
                os.kill(os.getpid(), signum)
            return
        _INTERRUPTED.set()
        first.append(time.monotonic())
        raise KeyboardInterrupt

    for sig in stop_signals():
        signal.signal(sig, interrupted)


@contextlib.contextmanager
def noting_interrupts():
    """While a run goes on (:func:`tt_mujoco.sim.simulate`), in a process's main thread: a
    real Ctrl-C (or a SIGTERM the command line turns into one) notes that it came, then does
    what the handler before did (raise ``KeyboardInterrupt``), so that one a user's code raises
    itself is told apart, on every route. A signal ignored or left to the system (a sweep's
    worker ignores SIGINT) raises no exception: every ``KeyboardInterrupt`` is then a user's.
    Whatever else the run raises after a real stop came is that stop: ``KeyboardInterrupt``
    (from what was raised)."""
    global _INTERRUPTED
    before = _INTERRUPTED
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    noted = _INTERRUPTED = threading.Event()
    previous = {sig: signal.getsignal(sig) for sig in STOP_SIGNALS}

    def interrupted(signum, frame):
        if noted.is_set():  # the same stop again (to the process and to its group)
            return
        noted.set()
        previous[signum](signum, frame)  # the default handler, or ours: raises
        raise KeyboardInterrupt

    for sig, handler in previous.items():
        if callable(handler):
            signal.signal(sig, interrupted)
    try:
        yield
    except BaseException as err:
        if noted.is_set() and not isinstance(err, KeyboardInterrupt):
            # the stop landed in code that made another error of it (C code calling back into
            # Python, as numba's dispatch of a compiled call does, loses the KeyboardInterrupt):
            # what fails once a real stop came is the stop, not a bug
            raise KeyboardInterrupt from err
        raise
    finally:
        for sig, handler in previous.items():
            if callable(handler):
                signal.signal(sig, handler)
        _INTERRUPTED = before


def users_failure(err: BaseException) -> bool:
    """Whether ``err``, raised while a user's code ran, is that code's failure."""
    if isinstance(err, tuple(_CONTROL)):
        return False
    if isinstance(err, KeyboardInterrupt):
        return _INTERRUPTED is not None and not _INTERRUPTED.is_set()
    return True


def one_line(text: str) -> str:
    """``text`` on one line: each run of line breaks, with the indent around it, one space (a
    message quotes what a user's code gave, whose repr or message may span lines: a NumPy
    array's, a ``raise ValueError("...\\n...")``)."""
    return " ".join(part.strip() for part in text.splitlines() if part.strip())


def shown_error(err: BaseException) -> str:
    """``err``'s message on one line (:func:`one_line`), or, where its ``__str__`` itself
    fails, what it is."""
    try:
        text = str(err)
        if not isinstance(text, str):
            raise TypeError("__str__ returned a non-string")
        return one_line(text)
    except BaseException as inner:  # a user's exception's own code
        if not users_failure(inner):
            raise
        return f"(its message cannot be shown: {type(inner).__name__} in its __str__)"


#: What the file system refuses for reasons outside the command (a full disk, a quota, a
#: read-only or forbidden folder, a folder where a file goes): one line and exit code 2.
REFUSALS = frozenset(
    getattr(errno, name)
    for name in ("ENOSPC", "EDQUOT", "EROFS", "EACCES", "EPERM", "EISDIR", "ENOTDIR", "EFBIG")
    if hasattr(errno, name)
)

#: The working folder the running command started in (None outside a command): what its
#: relative paths mean, whatever folder a user's code moves the process to.
_START_DIR: str | None = None


def absolute(path) -> Path:
    """``path`` made absolute against the folder the command started in (outside a command,
    the current folder): a user's code that changes the working folder (``os.chdir`` in a
    controller) moves none of the command's outputs."""
    path = Path(path).expanduser()
    if path.is_absolute():
        return path
    return Path(_START_DIR if _START_DIR is not None else os.getcwd()) / path


@contextlib.contextmanager
def keeping_process_state():
    """Undo, as the block ends, what a user's code run inside it changed of the process state
    the project's own code relies on: a lowered recursion limit, ``sys.stdout`` and
    ``sys.stderr`` replaced, NumPy's floating-point error handling and the warning filters (a
    ``warnings.simplefilter("error")`` in a controller's ``reset`` made a warning of the
    run's own metrics an error). The run's set-up, its episode and its metrics each run in
    one such block, so a change made in one does not reach the next."""
    import warnings

    limit, streams = sys.getrecursionlimit(), (sys.stdout, sys.stderr)
    np = sys.modules.get("numpy")  # not imported for it: a command's --help imports no NumPy
    with warnings.catch_warnings(), np.errstate(**np.geterr()) if np else contextlib.nullcontext():
        try:
            yield
        finally:
            if sys.getrecursionlimit() < limit:
                sys.setrecursionlimit(limit)
            sys.stdout, sys.stderr = streams


def crash_file(err: BaseException) -> str:
    """Write ``err``'s traceback to a new file in the temporary folder; its path."""
    import tempfile  # only when there is a bug to report: --help stays quick
    import time
    import traceback

    stamp = time.strftime("%Y%m%d-%H%M%S")
    text = "".join(traceback.format_exception(err))
    fd, path = tempfile.mkstemp(prefix=f"tt_mujoco-crash-{stamp}-", suffix=".txt")
    with os.fdopen(fd, "w", encoding="utf-8") as out:
        out.write(f"tt-mujoco {' '.join(sys.argv)}\n{text}")
    return path


class _ReaderMayGo:
    """A command's ``sys.stdout`` or ``sys.stderr``: once the reader of the stream has gone (a
    pipe into ``head`` closed), what the command writes there is dropped, not raised, and the
    command goes on to its own ending (its files written, its exit code). The stream's file
    is then pointed at the null device, so the interpreter's last flush finds a sink too. A
    user's code that closes it only flushes it."""

    def __init__(self, stream):
        self._stream, self._gone = stream, False

    def write(self, text):
        if not self._gone:
            try:
                return self._stream.write(text)
            except BrokenPipeError:
                self._went()
        return len(text)

    def flush(self):
        if not self._gone:
            try:
                self._stream.flush()
            except BrokenPipeError:
                self._went()

    def close(self):
        """Flush only: the command's streams stay open to the end (a user's code that closes
        ``sys.stdout`` does not silence the command's summary and messages)."""
        self.flush()

    @property
    def closed(self) -> bool:
        return False

    def _went(self):
        self._gone = True
        with contextlib.suppress(OSError, ValueError):
            sink = os.open(os.devnull, os.O_WRONLY)
            os.dup2(sink, self._stream.fileno())
            os.close(sink)

    def __getattr__(self, name):  # isatty, fileno, encoding, ...: the stream's own
        return getattr(self._stream, name)


def _abandon_outputs() -> list:
    """The failed command's claimed folders that hold nothing yet, removed
    (:func:`tt_mujoco.folders.abandon_claims`); the folders it had claimed."""
    from tt_mujoco import folders  # it imports this module

    try:
        return folders.abandon_claims()
    except Exception:
        return []


def _bug(err: BaseException) -> int:
    """A bug of ours: one line naming the file its traceback went to; exit code 70."""
    try:
        where = crash_file(err)
    except OSError as failed:  # a full or read-only temporary folder
        where = f"nowhere ({failed.strerror})"
    print(
        f"error: internal error, a bug of tt-mujoco ({shown_error(err)}); "
        f"its traceback is in {where}: please report it",
        file=sys.stderr,
    )
    return EXIT_BUG


def _run_exit_handlers() -> None:
    """Run the process's exit handlers now, as its exit would (a user's code may have
    registered some with :mod:`atexit`): one that fails is a one-line note, where Python
    would print its traceback after the command's last word."""
    import atexit

    previous = sys.unraisablehook

    def noted(failure) -> None:
        from tt_mujoco.registry import describe_failure  # it imports this module

        name = getattr(failure.object, "__qualname__", None) or repr(failure.object)
        with contextlib.suppress(OSError, ValueError):
            print(
                f"note: the exit handler {name} failed: {describe_failure(failure.exc_value)}",
                file=sys.stderr,
            )

    sys.unraisablehook = noted
    try:
        atexit._run_exitfuncs()  # then cleared: the exit runs none twice
    finally:
        sys.unraisablehook = previous


def end(code: int) -> NoReturn:
    """End a command's process with ``code``: ``guard.end(main())`` in its ``__main__``. The
    exit handlers run first (:func:`_run_exit_handlers`); nothing they do (``sys.exit(5)``, a
    failure) changes the code. A thread a user's code started and left running (not a
    daemon) would hold the interpreter at its exit for ever: the process ends without
    waiting for it, said in a note."""
    _run_exit_handlers()
    held = [
        t
        for t in threading.enumerate()
        if t is not threading.main_thread() and t.is_alive() and not t.daemon
    ]
    if held:
        names = ", ".join(repr(t.name) for t in held)
        with contextlib.suppress(OSError, ValueError):
            print(
                f"note: ended with {len(held)} thread(s) still running ({names}), which "
                "would have held the process at its exit",
                file=sys.stderr,
            )
            sys.stdout.flush()
            sys.stderr.flush()
        os._exit(code)
    sys.exit(code)  # the interpreter's own exit: the files a user's code left open flushed


def command(main):
    """A command's ``main(argv) -> int``, guarded: bad input it raises
    (:class:`~tt_mujoco.cliargs.BadInputError`, an unknown or malformed option from
    :class:`~tt_mujoco.cliargs.Parser` included) is one line and exit code 2; a bug of ours
    (anything else it raises but ``SystemExit`` and ``KeyboardInterrupt``) is one line naming
    the file its traceback is in, and :data:`~tt_mujoco.defaults.EXIT_BUG`."""

    from tt_mujoco.cliargs import BadInputError

    @functools.wraps(main)
    def guarded(argv=None):
        global _START_DIR
        outermost = _START_DIR is None  # a command another runs keeps the outer one's folder
        if outermost:
            with contextlib.suppress(OSError):  # a working folder removed under the shell
                _START_DIR = os.getcwd()
            # Ctrl-C, a batch system's SIGTERM, a hangup: a KeyboardInterrupt every command
            # ends cleanly on (SIGTERM's default would end it with its files half written)
            interrupts_from_signals()
        streams = sys.stdout, sys.stderr
        sys.stdout, sys.stderr = (_ReaderMayGo(s) for s in streams)  # `| head` is no bug
        try:
            with keeping_process_state():  # for a caller in this process (a test, a notebook)
                return main(argv)
        except SystemExit:
            raise
        except KeyboardInterrupt:  # one the command did not end on itself
            left = [str(p) for p in _abandon_outputs() if p.exists()]
            kept = f": the outputs in {', '.join(left)} are incomplete" if left else ""
            print(f"\ninterrupted{kept or ': nothing was written'}", file=sys.stderr)
            return EXIT_INTERRUPTED
        except BadInputError as err:  # what a command leaves to be said: one line, exit 2
            _abandon_outputs()
            print(f"error: {' '.join(str(err).split())}", file=sys.stderr)
            return EXIT_BAD_INPUT
        except OSError as err:
            claimed = _abandon_outputs()
            if err.errno not in REFUSALS:
                return _bug(err)
            # the file system refused what the command wrote (a full disk, a quota, a
            # read-only folder): no bug of ours, and nothing a traceback would help with
            named = err.filename2 or err.filename or ", ".join(map(str, claimed)) or None
            print(
                f"error: {str(named) + ': ' if named else ''}{err.strerror or err} (the file "
                "system refused it: make room or change the folder, and run again)",
                file=sys.stderr,
            )
            return EXIT_BAD_INPUT
        except BaseException as err:
            _abandon_outputs()
            return _bug(err)
        finally:
            with contextlib.suppress(OSError, ValueError):
                sys.stdout.flush()
            sys.stdout, sys.stderr = streams
            # the process left in the folder it started in; the stop handlers stay: a stop
            # that comes while the process ends is still the clean one, not SIGTERM's kill
            if outermost:
                with contextlib.suppress(OSError, TypeError):
                    os.chdir(_START_DIR)
                _START_DIR = None

    guarded.guarded = True
    return guarded

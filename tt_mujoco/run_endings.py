"""How a run that does not finish ends: one line, an exit code, and what it computed kept.

Each function here is one way a run of ``python -m tt_mujoco.run`` can stop short (bad input
found during the run, a full disk, Ctrl-C, a hang past its time limit, a crash, a process that
exits by itself): it says so in one line on stderr and returns the exit code
(docs/model.md Section 11), keeping the rows that reached the disk and labelling the folder
incomplete, or removing a folder it made that holds nothing.
"""

from __future__ import annotations

import signal
import sys
from pathlib import Path

from tt_mujoco import watchdog
from tt_mujoco.defaults import EXIT_BAD_INPUT, EXIT_BUG, EXIT_DIVERGED, EXIT_INTERRUPTED
from tt_mujoco.outputs import atomic_write, release_folder, remove_if_empty
from tt_mujoco.run_outputs import CHECKPOINT_FILE, ERROR_LOG

__all__ = [
    "abandon",
    "best_candidate_drawn",
    "exited_early",
    "fail",
    "hung",
    "interrupted",
    "killed",
    "rows_unwritable",
]


def fail(message: str, code: int = EXIT_BAD_INPUT) -> int:
    print(f"error: {message}", file=sys.stderr)
    return code


def best_candidate_drawn(err: BaseException, plots: bool) -> str:
    """``"; the best candidate is drawn in FILE"`` for a run refused for want of a plan (a
    :class:`~tt_mujoco.world.plan.PlanError` with its best candidate), its figure written beside
    the crash files (the refused run leaves nothing in its folder); ``""`` otherwise, or with
    ``plots`` off, or where the temporary folder takes no file."""
    best = getattr(err, "best", None)
    if best is None or not plots:
        return ""
    from tt_mujoco.viz.plan_figure import write_best_candidate

    try:
        file = write_best_candidate(best)
    except OSError as problem:
        return f"; its best candidate could not be drawn ({problem.strerror})"
    return f"; the best candidate is drawn in {file}"


def abandon(out: Path, created: bool, live, message: str, code: int) -> int:
    """A run that produced no result: close the viewer, remove the folder made for it."""
    if live is not None:
        live.close()
    (out / CHECKPOINT_FILE).unlink(missing_ok=True)
    if created:
        remove_if_empty(out)
    nothing = "nothing was written" if not out.exists() or not any(out.iterdir()) else ""
    return fail(f"{message}{'; ' + nothing if nothing else ''}", code)


def rows_unwritable(out: Path, created: bool, live, err: OSError) -> int:
    """The rows the run wrote as it went could not reach the disk (it is full, a quota): one
    line, exit 2, the rows that did kept; none reached it: nothing left behind."""
    t = _kept_rows(out).get("t", ())
    why = f"the run's rows cannot be written to {out}/: {err.strerror}"
    if len(t) == 0:
        return abandon(out, created, live, f"{why}; none reached it", EXIT_BAD_INPUT)
    if live is not None:
        live.close()
    release_folder(out)
    kept = f"the {len(t)} rows that reached it are kept in {out / CHECKPOINT_FILE}"
    return fail(
        f"{why}; {kept}; the folder has no metrics.json, so it is labelled incomplete",
        EXIT_BAD_INPUT,
    )


def _kept_rows(out: Path) -> dict:
    from tt_mujoco.sim.loop.checkpoint import read_checkpoint

    try:
        return read_checkpoint(out / CHECKPOINT_FILE)
    except (OSError, ValueError):
        return {}


def hung(out: Path, limit: float, controller: str, traceback: str, interrupt: bool) -> int:
    """The watchdog killed a run stuck in code that never returned to Python
    (:mod:`tt_mujoco.watchdog`), past its time limit or an interrupt: keep its rows and its
    traceback, say where it hung."""
    site = watchdog.hang_site(traceback)
    if traceback:
        atomic_write(out / ERROR_LOG, traceback)
    t = _kept_rows(out).get("t", ())
    rows = (
        f"the {len(t)} rows computed to t={t[-1]:.3f} s are kept in {out / CHECKPOINT_FILE}"
        if len(t)
        else "no rows had reached the disk"
    )
    release_folder(out)
    why = (
        "interrupted, the run did not stop"
        if interrupt
        else f"the run passed its time limit of {limit:g} s (wall clock; --time-limit)"
    )
    return fail(
        f"{why} in code that never returned to Python (a compiled law's own loop, or a call "
        f"into C; the controller: {controller}), at {site}; it was stopped; {rows}; its "
        f"traceback is in {out / ERROR_LOG}; the folder has no metrics.json, so it is labelled "
        "incomplete",
        EXIT_INTERRUPTED if interrupt else EXIT_DIVERGED,
    )


def killed(out: Path, signum: int) -> int:
    """The run's process was killed by a signal it did not handle (a crash in C code, the
    out-of-memory killer): a bug or the machine, said in one line, the rows kept."""
    t = _kept_rows(out).get("t", ())
    name = signal.Signals(signum).name if signum in signal.Signals._value2member_map_ else signum
    release_folder(out)
    return fail(
        f"the simulation's process was killed by {name} (a crash in compiled code, or the "
        f"machine ran out of memory): the {len(t)} rows that reached the disk are kept in "
        f"{out / CHECKPOINT_FILE}; if it happens again, please report it",
        EXIT_BUG,
    )


def exited_early(out: Path, code: int) -> int:
    """The run's process ended by itself while the simulation went on, with exit ``code``:
    not through any of the project's ways out (a user's code calling ``os._exit``, a library
    calling ``exit()`` in C); the rows kept, exit 3."""
    t = _kept_rows(out).get("t", ())
    release_folder(out)
    return fail(
        f"the simulation's process ended by itself with exit code {code} before the run was "
        f"over (user code calling os._exit, or a library calling exit() in C): the {len(t)} "
        f"rows that reached the disk are kept in {out / CHECKPOINT_FILE}; the folder has no "
        "metrics.json, so it is labelled incomplete",
        EXIT_DIVERGED,
    )


def interrupted(out: Path, created: bool, live) -> int:
    """Ctrl-C or SIGTERM during the simulation: keep the rows computed, say where they are."""
    partial = out / CHECKPOINT_FILE
    t = _kept_rows(out).get("t", ())
    if len(t) == 0:
        return abandon(out, created, live, "interrupted before the first row", EXIT_INTERRUPTED)
    if live is not None:
        live.close()
    return fail(
        f"interrupted at t={t[-1]:.3f} s: the {len(t)} rows computed are kept in {partial} "
        "(read them with tt_mujoco.sim.loop.checkpoint.read_checkpoint or "
        "pyarrow.ipc.open_stream); "
        "the folder has no metrics.json, so it is labelled incomplete",
        EXIT_INTERRUPTED,
    )

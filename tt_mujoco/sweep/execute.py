"""Executing a sweep: workers (processes or Dask), the journal, resume and recovery."""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import hashlib
import json
import os
import shutil
import sys
import time
from collections import deque
from dataclasses import dataclass, field
from pathlib import Path

from tt_mujoco import guard, watchdog
from tt_mujoco.executor import ExecutorError, Executors
from tt_mujoco.outputs import atomic_write, json_safe, refuse_link_or_enclosed, write_json
from tt_mujoco.progress import progress_bar
from tt_mujoco.sweep.options import JOURNAL, SPEC_FILE, TABLE, BadSpecError
from tt_mujoco.sweep.runs import expand, run_one, validate_runs
from tt_mujoco.sweep.spec import SweepSpec
from tt_mujoco.sweep.tables import (
    build_rows,
    group_options,
    plot_summary,
    read_journal,
    summarize,
    summary_csv,
    table_csv,
)


# --- execution ---------------------------------------------------------------------------------
@dataclass
class SweepResult:
    """What :func:`run_sweep` did.

    Attributes
    ----------
    out : Path
    header : list of str
    rows : list of dict
        The table, one dict per run (Python values).
    summary : dict
        See :func:`summarize`.
    reused : int
        Runs taken from the journal instead of being run.
    wall_s : float
        Wall time of this call.
    files : list of Path
    """

    out: Path
    header: list[str]
    rows: list[dict]
    summary: dict
    reused: int
    wall_s: float
    files: list[Path] = field(default_factory=list)


#: The sweep folder's folder of its workers' hang files while it runs (removed at its end).
HANG_DIR = ".hangs"
#: The file a running sweep holds locked, so that a second one into its folder is refused.
LOCK_FILE = ".lock"
#: The sha256 of the ``sweep.toml`` the sweep wrote: an edit of it before a resume is told.
SPEC_DIGEST = ".sweep.toml.sha256"


@dataclass(frozen=True)
class Resume:
    """How :func:`run_sweep` continues the unfinished sweep in its output folder: the runs in
    its journal are not run again.

    Parameters
    ----------
    retry_errors : bool
        Run again the runs whose status is "error" (a raised exception or a lost worker,
        perhaps transient); jackknifed and diverged runs are results and stay.
    extend : bool
        Accept a specification other than the saved one (more values or samples); without it
        a different specification is refused.
    """

    retry_errors: bool = False
    extend: bool = False

    def __post_init__(self):
        for name in ("retry_errors", "extend"):
            if not isinstance(getattr(self, name), bool):
                raise BadSpecError(
                    f"Resume({name}={getattr(self, name)!r}) is not allowed: it must be True "
                    "or False"
                )


def _resume_of(resume) -> Resume | None:
    """``run_sweep``'s ``resume``: False (a new sweep), True (``Resume()``) or a Resume."""
    if isinstance(resume, Resume):
        return resume
    if isinstance(resume, bool):
        return Resume() if resume else None
    raise BadSpecError(
        f"resume={resume!r} is not allowed: it must be True, False or a sweep.Resume"
    )


class _Journal:
    """The journal open for appending, and every finished run it holds by id: a record is
    written (a line, flushed) and kept in one step."""

    def __init__(self, file, done: dict[str, dict]):
        self.file, self.done = file, done

    def add(self, run: dict, result: dict) -> None:
        # As the journal holds it (NaN as None), so a resumed table is the same.
        record = json_safe({"run_id": run["run_id"], "index": run["index"], **result})
        self.file.write(_json_line(record))
        self.file.flush()
        self.done[run["run_id"]] = record

    @property
    def failures(self) -> int:
        return sum(1 for r in self.done.values() if r.get("status") != "ok")


def _failed_run(status: str, message: str = "", error: str = "") -> dict:
    """A run's result that the sweep itself records (no metrics, no wall time)."""
    return {"status": status, "message": message, "error": error, "metrics": {}, "run_wall_s": None}


def _progress(total: int, initial: int, quiet: bool):
    if quiet:
        return None
    return progress_bar(total, "sweep", "run", initial=initial)


def _lock(out: Path):
    try:
        import fcntl
    except ImportError:  # Windows: no advisory lock, the user keeps one sweep per folder
        return contextlib.nullcontext()
    try:  # never through a symlink: a planted link must not be truncated or followed
        fd = os.open(out / LOCK_FILE, os.O_WRONLY | os.O_CREAT | os.O_NOFOLLOW, 0o644)
    except OSError as err:
        raise BadSpecError(
            f"--out {str(out)!r}: its {LOCK_FILE} cannot be opened ({err.strerror}; a symlink is "
            "refused): remove it"
        ) from None
    fh = os.fdopen(fd, "w")  # held open (and locked) for the sweep's lifetime
    try:
        fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        fh.close()
        raise BadSpecError(f"--out {str(out)!r}: another sweep is running in it") from None
    return fh


def prepare_out(out: Path, resume: bool) -> bool:
    """Make the output folder; refuse a used one unless resuming, and any sweep file in it that
    is a symlink (outputs are never written through one), and a folder that is a link or lies
    inside another command's outputs. Whether the folder was new (or empty): only then does
    a sweep that fails before its first run remove it again."""
    try:
        refuse_link_or_enclosed(out)
    except ValueError as err:
        raise BadSpecError(str(err)) from None
    written = (JOURNAL, SPEC_FILE, SPEC_DIGEST, TABLE, "summary.csv", "summary.json")
    for name in (*written, LOCK_FILE, HANG_DIR):
        if (out / name).is_symlink():
            raise BadSpecError(
                f"--out {str(out)!r}: {name} is a symlink; outputs are never written through "
                "one: remove it"
            )
    used = out.exists() and (not out.is_dir() or any(out.iterdir()))
    if used:
        if not resume:
            raise BadSpecError(
                f"--out {str(out)!r} already exists and is not empty: pass --resume to continue "
                "the sweep in it, or name a new folder"
            )
        if not (out / JOURNAL).exists() and not (out / SPEC_FILE).exists():
            raise BadSpecError(f"--out {str(out)!r} holds no sweep ({JOURNAL}) to resume")
    elif resume:  # a mistyped folder would start the whole sweep again in silence
        state = "is empty" if out.exists() else "does not exist"
        raise BadSpecError(
            f"--out {str(out)!r} {state}: there is no sweep to resume; drop --resume to start "
            "one there"
        )
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise BadSpecError(f"--out {str(out)!r} cannot be made: {err.strerror}") from None
    return not used


def _undo_fresh(out: Path) -> None:
    """Remove what a sweep wrote into its new folder before its first run, and the folder:
    a sweep refused then (its scheduler unreachable) leaves nothing that blocks the retry."""
    for name in (JOURNAL, SPEC_FILE, SPEC_DIGEST, LOCK_FILE):
        with contextlib.suppress(FileNotFoundError):
            (out / name).unlink()
    with contextlib.suppress(OSError):
        out.rmdir()


def _json_line(record: dict) -> str:
    """One journal line: strict JSON (NaN as null)."""
    return json.dumps(json_safe(record), allow_nan=False) + "\n"


def _digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _check_same_spec(out: Path, spec: SweepSpec, resume: Resume | None) -> None:
    """A resumed sweep keeps its specification; another one is refused unless extending."""
    saved = out / SPEC_FILE
    if resume is None or resume.extend or not saved.exists():
        return
    recorded = out / SPEC_DIGEST
    if recorded.is_file() and recorded.read_text().strip() != _digest(saved):
        raise BadSpecError(
            f"--out {str(out)!r}: its {SPEC_FILE} was edited since the sweep wrote it, and its "
            "finished runs were made by what it held then: --resume continues a sweep as it "
            "was; pass --extend to run the edited specification beside them (the finished "
            "runs it still makes are reused), or name a new folder"
        )
    if saved.read_bytes() != spec.to_toml().encode("utf-8"):
        raise BadSpecError(
            f"--out {str(out)!r} holds a sweep with another specification ({SPEC_FILE}): "
            "--resume continues it as it is; pass --extend to add the new runs to it (its "
            "finished runs are reused), or name a new folder"
        )


def run_sweep(
    spec: SweepSpec,
    out: str | Path,
    workers: int = 1,
    scheduler: str | None = None,
    resume: bool | Resume = False,
    quiet: bool = True,
    metric: str = "rmse_lateral",
    figures: bool = True,
) -> SweepResult:
    """Run a sweep and write its table, summary and figures into ``out``.

    Parameters
    ----------
    spec : SweepSpec
    out : path
        Output folder: new or empty, or (``resume=True``) one holding an unfinished sweep.
    workers : int
        Local worker processes (``scheduler=None``), or the LocalCluster's workers
        (``scheduler="local"``); ignored for a remote scheduler.
    scheduler : str, optional
        None: a local process pool. ``"local"``: a Dask ``LocalCluster``. Otherwise the address
        of a running Dask scheduler, e.g. ``tcp://10.0.0.5:8786``.
    resume : bool or Resume
        Continue a sweep in ``out``: runs whose configuration is in its journal are not run.
        ``True`` is ``Resume()``; a :class:`Resume` also says whether to run the errors again
        and whether the specification may have grown.
    quiet : bool
        No progress bar.
    metric : str
        The metric of the scatter figure.
    figures : bool
        Write ``histograms.png`` and ``scatter.png``.

    Raises
    ------
    BadSpecError
        For a bad specification, output folder or scheduler, before any run starts.
    KeyboardInterrupt
        When interrupted; finished runs are in the journal, and ``resume=True`` continues.
    """
    t0 = time.perf_counter()
    out = guard.absolute(out)  # a user's code that changes the working folder moves nothing
    if not (isinstance(workers, int) and workers >= 1):
        raise BadSpecError(f"workers={workers!r} is not allowed: it must be an integer >= 1")
    resume = _resume_of(resume)
    retry_errors = resume is not None and resume.retry_errors
    runs = expand(spec, validate=False)
    # Every run still to do goes through the setup path before any work; a resumed sweep's
    # finished runs are not checked again (a file they read may be gone by now).
    finished = _finished(out / JOURNAL, retry_errors) if resume and not out.is_symlink() else {}
    validate_runs([r for r in runs if r["run_id"] not in finished])
    fresh = prepare_out(out, resume is not None)
    with _lock(out):
        journal_path = out / JOURNAL
        done = _finished(journal_path, retry_errors)
        # Rewrite the journal without a line cut by a kill, so appends start on a fresh line.
        if journal_path.exists():
            atomic_write(journal_path, "".join(_json_line(r) for r in done.values()))
        _check_same_spec(out, spec, resume)
        atomic_write(out / SPEC_FILE, spec.to_toml())
        atomic_write(out / SPEC_DIGEST, _digest(out / SPEC_FILE) + "\n")
        todo = deque(r for r in runs if r["run_id"] not in done)
        reused = len(runs) - len(todo)
        if todo:
            workers = _worker_count(workers, len(todo), scheduler)
            bar = _progress(len(runs), reused, quiet)
            try:
                _execute(
                    todo,
                    done,
                    journal_path,
                    Executors(workers, scheduler, guard.ignore_stop_signals),
                    bar,
                )
            except (BadSpecError, ExecutorError):  # refused before its first run
                if fresh and not done:
                    _undo_fresh(out)
                raise
        header, rows = build_rows(runs, done)
        atomic_write(out / TABLE, table_csv(header, rows))
        summary = summarize(header, rows, group_options(spec, rows))
        atomic_write(out / "summary.csv", summary_csv(summary))
        wall = time.perf_counter() - t0
        doc = {**summary, "mode": spec.mode, "seed": spec.seed, "wall_s": wall, "reused": reused}
        write_json(out / "summary.json", doc, strict=True)
        files = [out / TABLE, out / "summary.csv", out / "summary.json"]
        if figures and rows:
            if metric not in header:
                print(
                    f"note: --metric {metric!r} is not a column; drawing rmse_lateral",
                    file=sys.stderr,
                )
                metric = "rmse_lateral"
            files += plot_summary(rows, spec, out, metric)
    return SweepResult(out, header, rows, summary, reused, time.perf_counter() - t0, files)


def _finished(journal_path: Path, retry_errors: bool) -> dict[str, dict]:
    """The journal's finished runs by id, less those that raised when they run again."""
    done = read_journal(journal_path)
    if retry_errors:
        done = {k: r for k, r in done.items() if r.get("status") != "error"}
    return done


def _worker_count(workers: int, runs: int, scheduler: str | None) -> int:
    """No more local workers than runs; a note when they outnumber the cores (each worker is
    a process with its own MuJoCo: more than the cores only adds memory and switching)."""
    if scheduler not in (None, "local"):
        return workers  # a remote cluster's workers are its own
    cores = os.cpu_count() or 1
    if workers > cores:
        print(
            f"note: --workers {workers} is more than this machine's {cores} cores; runs then "
            "share cores and go no faster",
            file=sys.stderr,
        )
    return min(workers, runs)


def _execute(todo, done, journal_path: Path, executors: Executors, bar) -> None:
    """Run ``todo`` through the executor, journalling each result as it arrives. Local
    workers watch each run for a hang (:func:`tt_mujoco.watchdog.armed`, files in
    :data:`HANG_DIR`, removed at the end); a Dask cluster's workers are its own."""
    hang_dir = None
    if executors.scheduler is None:
        hang_dir = journal_path.parent / HANG_DIR
        hang_dir.mkdir(exist_ok=True)
    try:
        fd = os.open(journal_path, os.O_WRONLY | os.O_APPEND | os.O_CREAT | os.O_NOFOLLOW, 0o644)
        with os.fdopen(fd, "a", encoding="utf-8") as file:
            _execute_watched(todo, _Journal(file, done), executors, bar, hang_dir)
    finally:
        if bar is not None:
            bar.close()
        if hang_dir is not None:
            shutil.rmtree(hang_dir, ignore_errors=True)


def _execute_watched(todo, journal: _Journal, executors: Executors, bar, hang_dir) -> None:
    # The workers import run_one by its module's name (tt_mujoco.sweep.runs), which a Dask
    # worker on another machine can do too.
    executor = executors.open()
    failures = journal.failures
    crashes: dict[str, int] = {}
    inflight: dict[cf.Future, dict] = {}
    slots, slots_checked = executors.slots(), time.monotonic()
    try:
        while todo or inflight:
            if executors.client is not None and time.monotonic() - slots_checked > 10:
                slots, slots_checked = executors.slots(), time.monotonic()  # adaptive
            # A bounded window keeps memory flat for huge sweeps and makes Ctrl-C prompt.
            while todo and len(inflight) < 2 * slots + 2:
                if any(r["run_id"] in crashes for r in inflight.values()):
                    break  # a suspect of a worker death runs alone (see _recover)
                if todo[0]["run_id"] in crashes and inflight:
                    break
                run = todo.popleft()
                future = executor.submit(run_one, run["options"], hang_dir, run["run_id"])
                inflight[future] = run
            finished, _ = cf.wait(inflight, return_when=cf.FIRST_COMPLETED)
            broken = []
            for fut in finished:
                run = inflight.pop(fut)
                try:
                    result = fut.result()
                except cf.process.BrokenProcessPool:
                    broken.append(run)
                    continue
                except Exception as err:  # e.g. Dask's KilledWorker after its retries
                    result = _failed_run("error", error=f"{type(err).__name__}: {err}")
                journal.add(run, result)
                failures += result["status"] != "ok"
                if bar is not None:
                    bar.update(1)
                    bar.set_postfix(failed=failures, refresh=False)
            if broken:
                hung = watchdog.read_hangs(hang_dir) if hang_dir is not None else {}
                executor = _recover(executors, broken, inflight, todo, crashes, journal, hung)
                failures = journal.failures
    except BaseException:
        executors.close(cancel=True)
        raise
    executors.close()


def _recover(executors, broken, inflight, todo, crashes, journal: _Journal, hung) -> cf.Executor:
    """A worker process died (segfault, out of memory, or ended by its watch for a run that
    hung): every run in flight is suspect.

    A run its worker's watch names (``hung``: run id -> :class:`~tt_mujoco.watchdog.Hang`) is
    recorded as failed where it hung, never run again, and the others, only in flight beside
    it, run again. Otherwise the suspects run again one at a time; a run that was alone in
    flight when a worker died (or in flight at two deaths) is recorded as an error.
    """
    suspects = broken + list(inflight.values())
    inflight.clear()
    named = [run for run in suspects if run["run_id"] in hung]
    for run in named:
        hang = hung[run["run_id"]]
        suspects.remove(run)
        message = (
            f"the run passed its time limit of {hang.limit_s:g} s in code that never returned "
            f"to Python, at {watchdog.hang_site(hang.traceback)}: its worker was ended"
        )
        journal.add(run, _failed_run("failed", message=message))
    if named:  # the watch named the cause: the others were only in flight beside it
        todo.extendleft(reversed(suspects))
        return executors.reopen()
    alone = len(suspects) == 1
    for run in reversed(suspects):
        crashes[run["run_id"]] = crashes.get(run["run_id"], 0) + 1
        if alone or crashes[run["run_id"]] >= 2:
            journal.add(run, _failed_run("error", error="the worker process died during this run"))
        else:
            todo.appendleft(run)
    return executors.reopen()

"""Where many runs execute: local worker processes or a Dask cluster, for sweeps and the suite."""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import multiprocessing
import os
import sys
import threading
import time

__all__ = ["PRELOAD", "ExecutorError", "Executors"]


class ExecutorError(ValueError):
    """The executor cannot be opened (Dask missing, scheduler unreachable)."""


#: Imported once in the forkserver, so that no worker pays ~1 s of imports on its first run.
PRELOAD = [
    "mujoco",
    "scipy.integrate",
    "tt_mujoco.sim",
    "tt_mujoco.sim.parts.physics",
    "tt_mujoco.reference.targets",
    "tt_mujoco.analysis.metrics",
    "tt_mujoco.sim.parts.faults",
    "tt_mujoco.sim.parts.plant_mujoco",
    "tt_mujoco.controllers",
    "tt_mujoco.sweep.runs",
]


def _watch_parent(parent_pid: int, period: float = 1.0) -> None:
    """End this worker once the process that opened the pool is gone (killed, crashed): pool
    workers are the forkserver's children and would otherwise finish every run they hold."""

    def watch() -> None:
        while True:
            time.sleep(period)
            try:
                os.kill(parent_pid, 0)
            except ProcessLookupError:
                os._exit(1)
            except PermissionError:  # alive, another user's
                pass

    threading.Thread(target=watch, name="parent-watch", daemon=True).start()


def _worker_start(parent_pid: int, initializer) -> None:
    _watch_parent(parent_pid)
    if initializer is not None:
        initializer()


#: How long a pool's worker may take to end once its work is done (s): one that a thread a
#: user's code left running holds at its exit (Python joins such threads) is ended then.
WORKER_EXIT_S = 5.0


def _shut_down(pool: cf.ProcessPoolExecutor, cancel: bool) -> None:
    """Shut ``pool`` down (its pending work cancelled): wait for its workers to end, except
    one a user's thread holds (:data:`WORKER_EXIT_S`), which is ended, said in a note.
    ``cancel``: runs in flight are stopped, not waited for (their results would be dropped
    anyway; Python 3.11 has no ``terminate_workers()``)."""
    processes = list(getattr(pool, "_processes", {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    held = 0
    for proc in processes:
        with contextlib.suppress(Exception):
            proc.join(timeout=0.0 if cancel else WORKER_EXIT_S)
            if proc.is_alive():
                held += not cancel
                proc.terminate()
                proc.join(timeout=WORKER_EXIT_S)
    if not any(proc.is_alive() for proc in processes):
        pool.shutdown(wait=True)  # its manager thread too, now that every worker has ended
    if held:
        print(
            f"note: {held} worker(s) held at their end by a thread a user's code left running "
            "were ended",
            file=sys.stderr,
        )


#: How long a connection to a Dask scheduler may take, handshake included (s).
CONNECT_TIMEOUT_S = 20.0


def _connect(client_class, address: str, timeout: float):
    """A Dask client of the scheduler at ``address``, within ``timeout`` seconds whatever the
    peer does: Dask's own timeout does not bound a peer that accepts and never answers, so
    the connection is made on a daemon thread and abandoned at the deadline."""
    import threading

    outcome: dict = {}

    def connect() -> None:
        try:
            outcome["client"] = client_class(address, timeout=f"{timeout:g}s")
        except Exception as err:
            outcome["error"] = err

    thread = threading.Thread(target=connect, daemon=True)
    thread.start()
    thread.join(timeout)
    if "client" in outcome:
        return outcome["client"]
    reason = outcome.get("error") or f"no answer within {timeout:g} s"
    raise ExecutorError(f"--scheduler {address!r}: cannot connect to a Dask scheduler ({reason})")


class Executors:
    """Opens the executor: a process pool, or a Dask client's concurrent.futures executor.

    Parameters
    ----------
    workers : int
        Worker processes (of the pool, or of a local Dask cluster).
    scheduler : str or None
        None: local processes (forkserver, with :data:`PRELOAD` imported once); ``"local"``: a
        Dask ``LocalCluster``; else the address of a running Dask scheduler.
    initializer : callable, optional
        Run in each pool worker at start (e.g. :func:`tt_mujoco.guard.ignore_stop_signals`).
    """

    def __init__(self, workers: int, scheduler: str | None, initializer=None):
        self.workers = workers
        self.initializer = initializer
        self.scheduler = scheduler
        self.client = self.cluster = None
        self.pool: cf.Executor | None = None

    def open(self) -> cf.Executor:
        if self.scheduler is None:
            # forkserver: workers start from a clean preloaded process, not a fork of a parent
            # that may hold threads (the progress bar's, a Dask client's).
            if "forkserver" in multiprocessing.get_all_start_methods():
                ctx = multiprocessing.get_context("forkserver")
                ctx.set_forkserver_preload(PRELOAD)
            else:  # Windows
                ctx = multiprocessing.get_context("spawn")
            self.pool = cf.ProcessPoolExecutor(
                max_workers=self.workers,
                mp_context=ctx,
                initializer=_worker_start,
                initargs=(os.getpid(), self.initializer),
            )
            return self.pool
        try:
            from distributed import Client, LocalCluster
        except ImportError:
            raise ExecutorError(
                "--scheduler needs Dask distributed: pip install 'tt-mujoco[dask]'"
            ) from None
        if self.scheduler == "local":
            self.cluster = LocalCluster(
                n_workers=self.workers,
                threads_per_worker=1,
                processes=True,
                dashboard_address=":0",  # any free port: never clash with a running one
            )
            self.client = Client(self.cluster)
        else:
            self.client = _connect(Client, self.scheduler, CONNECT_TIMEOUT_S)
        # pure=False: a resubmitted run must run again, not return a cached failure
        self.pool = self.client.get_executor(pure=False)
        return self.pool

    def slots(self) -> int:
        if self.client is not None:
            return max(1, sum(self.client.nthreads().values()))
        return self.workers

    def reopen(self) -> cf.Executor:
        self.close(cancel=True)
        return self.open()

    def close(self, cancel: bool = False) -> None:
        if self.pool is not None:
            if isinstance(self.pool, cf.ProcessPoolExecutor):
                _shut_down(self.pool, cancel)
            else:  # Dask's executor cancels what is pending on shutdown(wait=False)
                self.pool.shutdown(wait=not cancel)
            self.pool = None
        if self.client is not None:
            self.client.close()
            self.client = None
        if self.cluster is not None:
            self.cluster.close()
            self.cluster = None

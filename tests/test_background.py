"""tt_mujoco.background: a worker forked ahead of its call hands back its value or its
exception, and never outlives its caller."""

from __future__ import annotations

import os
import signal
import time

import numpy as np
import pytest

from tt_mujoco.background import BackgroundError, Worker

_PREPARED = []


def _total(values, scale=1.0):
    return float(np.sum(values)) * scale


def _fails(text):
    raise ValueError(text)


def _pid():
    return os.getpid()


def _prepare():
    _PREPARED.append(os.getpid())


def _prepared():
    return list(_PREPARED)


def _prepare_fails():
    raise RuntimeError("no matplotlib here")


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    return True


@pytest.mark.parametrize("forked", [True, False])
def test_the_value_comes_back_from_either_route(forked):
    worker = Worker(forked=forked)
    worker.call(_total, np.arange(10.0), scale=2.0)  # pickled on the way in
    assert worker.result() == 90.0
    worker = Worker(forked=forked)
    worker.call(_pid)
    assert (worker.result() == os.getpid()) is not forked
    assert worker.forked is forked


def test_prepare_runs_in_the_worker_before_the_call():
    worker = Worker(_prepare, forked=True)
    worker.call(_prepared)
    assert worker.result() not in ([], [os.getpid()])  # the worker's own pid
    assert _PREPARED == []  # not in the caller


@pytest.mark.parametrize("forked", [True, False])
def test_the_exception_is_raised_in_the_caller(forked):
    worker = Worker(forked=forked)
    worker.call(_fails, "bad value 3")
    with pytest.raises(ValueError, match="bad value 3"):
        worker.result()


def test_a_prepare_that_fails_answers_the_call_with_its_error():
    worker = Worker(_prepare_fails, forked=True)
    worker.call(_total, [1.0])
    with pytest.raises(RuntimeError, match="no matplotlib here"):
        worker.result()


def test_a_worker_takes_one_call_and_an_answer_needs_a_call():
    worker = Worker(forked=False)
    with pytest.raises(RuntimeError, match="before call"):
        worker.result()
    worker.call(_pid)
    with pytest.raises(RuntimeError, match="one call"):
        worker.call(_pid)


def test_a_worker_that_dies_without_answering_says_so():
    worker = Worker(forked=True)
    worker.call(time.sleep, 60.0)
    os.kill(worker._process, signal.SIGKILL)
    with pytest.raises(BackgroundError, match=r"without an answer.*signal 9"):
        worker.result()


def test_cancel_ends_a_running_worker():
    worker = Worker(forked=True)
    pid = worker._process
    worker.call(time.sleep, 60.0)
    worker.cancel()
    assert not _alive(pid)
    worker.cancel()  # twice is harmless


def test_a_worker_whose_caller_goes_away_ends_itself():
    """The caller's end of the pipe closing (its process ending) ends a waiting worker."""
    worker = Worker(forked=True)
    pid = worker._process
    worker._channel.close()  # as the caller's exit would
    deadline = time.monotonic() + 10.0
    while time.monotonic() < deadline:
        done, _ = os.waitpid(pid, os.WNOHANG)
        if done:
            break
        time.sleep(0.01)
    assert done == pid


@pytest.mark.parametrize("called", [True, False])
def test_a_worker_used_by_a_later_fork_is_reaped_by_the_process_that_forked_it(called):
    """As a run does: the figures' worker forked first, then the watched child that calls it,
    takes its answer (or gives up on it) and ends; the first process then ends and reaps every
    worker it forked (end_workers), so none outlives the command."""
    from tt_mujoco import background

    worker = Worker(forked=True)
    pid = worker._process
    child = os.fork()
    if child == 0:  # the watched child: the worker is its parent's, not its own
        code = 1
        try:
            if called:
                worker.call(_total, [1.0, 2.0])
                code = 0 if worker.result() == 3.0 else 1
            else:
                worker.cancel()
                code = 0
        finally:
            os._exit(code)
    _, status = os.waitpid(child, 0)
    assert os.waitstatus_to_exitcode(status) == 0
    assert pid in background._FORKED
    background.end_workers()
    assert pid not in background._FORKED
    with pytest.raises(ChildProcessError):  # reaped
        os.waitpid(pid, os.WNOHANG)

"""tt_mujoco.background: a call in a forked process hands back its value or its exception."""

from __future__ import annotations

import os
import signal
import time

import numpy as np
import pytest

from tt_mujoco.background import BackgroundCall, BackgroundError


def _total(values, scale=1.0):
    return float(np.sum(values)) * scale


def _fails(text):
    raise ValueError(text)


def _pid():
    return os.getpid()


@pytest.mark.parametrize("forked", [True, False])
def test_the_value_comes_back_from_either_route(forked):
    values = np.arange(10.0)  # not pickled on the way in: the child has the caller's memory
    assert BackgroundCall(_total, values, scale=2.0, forked=forked).result() == 90.0
    runs_here = BackgroundCall(_pid, forked=forked).result() == os.getpid()
    assert runs_here is not forked


@pytest.mark.parametrize("forked", [True, False])
def test_the_exception_is_raised_in_the_caller(forked):
    call = BackgroundCall(_fails, "bad value 3", forked=forked)
    with pytest.raises(ValueError, match="bad value 3"):
        call.result()


def test_a_child_that_dies_without_answering_says_so():
    call = BackgroundCall(time.sleep, 60.0, forked=True)
    os.kill(call._process.pid, signal.SIGKILL)
    with pytest.raises(BackgroundError, match="without an answer"):
        call.result()


def test_cancel_ends_a_running_child():
    call = BackgroundCall(time.sleep, 60.0, forked=True)
    process = call._process
    call.cancel()
    assert not process.is_alive()
    call.cancel()  # twice is harmless

"""The time limit that holds for code that never returns to Python (tt_mujoco/watchdog.py): the
command's run in a watched child. Each case runs the command in a process of its own, as a
user does, and checks the exit code, the one line, the rows and traceback kept, and that no
process is left behind."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

from tt_mujoco import guard, watchdog
from tt_mujoco.defaults import EXIT_BUG, EXIT_DIVERGED, EXIT_INTERRUPTED, EXIT_OK

pytestmark = pytest.mark.skipif(not watchdog.available(), reason="no fork here")

#: A plain-number law that spins in its own compiled loop after ``spin_after`` m of travel, a
#: class whose compute calls machine code that never returns, and one that kills its process.
USER_CODE = textwrap.dedent(
    """
    from numba import njit
    from tt_mujoco.controllers import Controller, plain_law


    @plain_law(gains={"spin_after": 0.3})
    def spin_law(m, r, model, k, s, dt, torque_limit):
        if m.x > k.spin_after:
            x = 0.0
            while x >= 0.0:
                x += 1.0
                if x > 1e300:
                    x = 0.0
        return 0.5, 0.5


    @njit(cache=False)
    def forever(x):
        while x >= 0.0:
            x += 1.0
            if x > 1e300:
                x = 0.0
        return x


    class StuckInC(Controller):
        def compute(self, t, measurement, reference):
            if t > 0.3:
                forever(1.0)  # the line the message names
            return 0.5, 0.5


    class Crash(Controller):
        def compute(self, t, measurement, reference):
            if t > 0.3:
                import os, signal
                os.kill(os.getpid(), signal.SIGKILL)
            return 0.5, 0.5


    class HardExit(Controller):
        def compute(self, t, measurement, reference):
            if t > 0.3:
                import os
                os._exit(int(self.gains["code"]))  # gains are > 0: code + 0.5
            return 0.5, 0.5

        PRESETS = {"default": {"code": 0.5}}
    """
)
BASE = ["--plant", "reduced", "--no-video", "--no-plots", "--quiet"]


def _start(
    tmp_path: Path, *argv: str, duration: str = "20", compile_now: bool = True
) -> subprocess.Popen:
    (tmp_path / "user.py").write_text(USER_CODE)
    env = {**os.environ, "TT_MUJOCO_COMPILE_NOW": "1" if compile_now else "0"}
    cmd = [sys.executable, "-m", "tt_mujoco.run", *BASE, "--duration", duration, "--out", "o"]
    cmd += argv
    return subprocess.Popen(
        cmd, cwd=tmp_path, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )


@pytest.fixture
def compiled_spin(tmp_path):
    """The spinning law compiled (and cached) by a run that does not spin: the runs under test
    load it, so that their time limit is not spent compiling."""
    proc = _start(tmp_path, "--controller", "user.py:spin_law", "--gains", '{"spin_after": 1e9}')
    _, err = proc.communicate(timeout=300)
    assert proc.returncode in (EXIT_OK, EXIT_DIVERGED), err  # driven open loop: it may tip
    import shutil

    shutil.rmtree(tmp_path / "o")


def _no_process_left(tmp_path: Path) -> None:
    time.sleep(0.3)
    found = subprocess.run(["pgrep", "-f", "--out o"], capture_output=True, text=True)
    mine = [
        pid
        for pid in found.stdout.split()
        if Path(f"/proc/{pid}/cwd").exists() and os.readlink(f"/proc/{pid}/cwd") == str(tmp_path)
    ]
    assert not mine, mine


@pytest.mark.parametrize(
    ("controller", "names"),
    [("user.py:spin_law", "machine_code.py"), ("user.py:StuckInC", "user.py, line 29 in compute")],
)
def test_code_that_never_returns_is_stopped_at_its_time_limit(
    compiled_spin, tmp_path, controller, names
):
    # 3 s: the limit counts from the start, imports included, and the code must get stuck
    # before it (0.3 s simulated); with 1 s, a CI machine under load once ran out of it while
    # still importing
    proc = _start(tmp_path, "--controller", controller, "--time-limit", "3")
    began = time.monotonic()
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == EXIT_DIVERGED, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "time limit of 3 s" in err and "never returned" in err, err
    assert names in err, err
    out = tmp_path / "o"
    assert "most recent call first" in (out / "error.log").read_text()
    assert not (out / "metrics.json").exists()  # labelled incomplete
    assert time.monotonic() - began < 60
    _no_process_left(tmp_path)


def test_an_interrupt_ends_code_that_never_returns(compiled_spin, tmp_path):
    proc = _start(tmp_path, "--controller", "user.py:spin_law")
    time.sleep(4)  # loaded and spinning
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == EXIT_INTERRUPTED, err
    assert "interrupted" in err and len(err.strip().splitlines()) == 1, err
    _no_process_left(tmp_path)


@pytest.mark.parametrize("signum", guard.STOP_SIGNALS, ids=lambda s: signal.Signals(s).name)
def test_a_signal_to_the_command_reaches_its_run_once(tmp_path, signum):
    """Every stop signal (Ctrl-C, a batch system's SIGTERM, a terminal's hangup) ends the run
    as Ctrl-C does: one line, exit 130, the rows kept, no process left."""
    proc = _start(tmp_path, "--traj", "circle", "--trailers", "3", duration="600")
    time.sleep(4)
    proc.send_signal(signum)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == EXIT_INTERRUPTED, err
    assert err.startswith("error: interrupted at t=") and len(err.strip().splitlines()) == 1
    assert (tmp_path / "o" / "timeseries.partial.arrows").exists()
    _no_process_left(tmp_path)


def test_a_killed_command_leaves_no_run_behind(tmp_path):
    proc = _start(tmp_path, "--traj", "circle", "--trailers", "3", duration="600")
    time.sleep(3)
    proc.kill()
    proc.communicate(timeout=30)
    _no_process_left(tmp_path)


def test_a_run_killed_by_a_signal_is_one_line_and_exit_70(tmp_path):
    proc = _start(tmp_path, "--controller", "user.py:Crash", compile_now=False)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == EXIT_BUG, err
    assert "killed by SIGKILL" in err and len(err.strip().splitlines()) == 1, err


@pytest.mark.parametrize("code", [0, 7])
def test_a_run_whose_process_exits_by_itself_is_not_taken_for_its_end(tmp_path, code):
    # os._exit in a user's code (or exit() in a library's C) ends the run's process, past
    # every handler: the parent, which the simulation never told it was over, says so
    gains = f'{{"code": {code + 0.5}}}'
    proc = _start(tmp_path, "--controller", "user.py:HardExit", "--gains", gains, duration="1")
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == EXIT_DIVERGED, err
    assert f"ended by itself with exit code {code} before the run was over" in err, err
    assert len(err.strip().splitlines()) == 1 and not (tmp_path / "o" / "metrics.json").exists()


def test_a_run_that_ends_passes_its_exit_code_and_output_through(tmp_path):
    proc = _start(tmp_path, duration="1", compile_now=False)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == EXIT_OK, err
    assert "wrote" in out and (tmp_path / "o" / "metrics.json").exists()


def test_the_hang_site_is_the_main_threads_innermost_frame():
    dump = textwrap.dedent(
        """\
        Thread 0x00007f (most recent call first):
          File "/x/threading.py", line 327 in wait
          File "/x/threading.py", line 1002 in _bootstrap

        Current thread 0x00007e (most recent call first):
          File "/u/user.py", line 29 in compute
          File "/p/run.py", line 692 in <module>
          File "<frozen runpy>", line 88 in _run_code
        """
    )
    assert watchdog.hang_site(dump) == "/u/user.py, line 29 in compute"
    assert watchdog.hang_site("") == "an unknown place"
    # stuck inside a library the user's code called: the user's line, then the library's
    numpy = str(Path(np.__file__).parent / "linalg" / "_linalg.py")
    inside = dump.replace(
        "Current thread 0x00007e (most recent call first):\n",
        f'Current thread 0x00007e (most recent call first):\n  File "{numpy}", line 7 in inv\n',
    )
    assert watchdog.hang_site(inside) == (
        f"/u/user.py, line 29 in compute (in {numpy}, line 7 in inv)"
    )


def test_a_sweeps_run_that_never_returns_is_recorded_and_the_sweep_goes_on(compiled_spin, tmp_path):
    import csv

    env = {**os.environ, "TT_MUJOCO_COMPILE_NOW": "1"}
    cmd = [sys.executable, "-m", "tt_mujoco.sweep", "plant=reduced", "duration=4"]
    cmd += ["controller=user.py:spin_law", "gain.spin_after=0.3,1e9", "time_limit_s=2"]
    cmd += ["--workers", "1", "--out", "sw", "--quiet", "--no-figures"]
    done = subprocess.run(cmd, cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300)
    rows = {r["gain.spin_after"]: r for r in csv.DictReader(open(tmp_path / "sw" / "runs.csv"))}
    hung = rows["0.3"]
    assert hung["status"] == "failed", done.stderr
    assert "never returned to Python" in hung["message"] and "machine_code.py" in hung["message"]
    assert rows["1000000000.0"]["status"] != "error", rows  # the other run was run, once
    assert not (tmp_path / "sw" / ".hangs").exists()
    _no_process_left(tmp_path)


def test_the_outputs_after_the_simulation_are_not_bound_by_its_limit(tmp_path):
    """The limit bounds the simulation (its episode and metrics), not the figures and the
    video written after it: the child tells its watch when the simulation is over. A 3 s run
    with a 1 s limit and a video takes longer than the limit's grace in all."""
    env = {**os.environ, "TT_MUJOCO_COMPILE_NOW": "0"}
    cmd = [sys.executable, "-m", "tt_mujoco.run", "--duration", "3", "--time-limit", "1"]
    cmd += ["--quiet", "--out", "o"]
    began = time.monotonic()
    done = subprocess.run(cmd, cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300)
    if done.returncode == 1 and "rendering unavailable" in done.stderr:
        pytest.skip("no OpenGL backend here")
    assert done.returncode == EXIT_OK, done.stderr
    assert (tmp_path / "o" / "video.mp4").exists() and (tmp_path / "o" / "metrics.json").exists()
    if time.monotonic() - began < watchdog.grace_for(1.0):
        pytest.skip("the outputs were written within the grace: nothing to show here")


def test_a_hangup_ignored_by_nohup_stays_ignored(tmp_path):
    """nohup starts the command with SIGHUP ignored: the run goes on through a hangup."""
    code = (
        "import signal\n"
        "signal.signal(signal.SIGHUP, signal.SIG_IGN)\n"
        "from tt_mujoco import guard\n"
        "guard.interrupts_from_signals()\n"
        "print(signal.SIGHUP in guard.stop_signals(), "
        "signal.getsignal(signal.SIGHUP) is signal.SIG_IGN)\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.stdout.split() == ["False", "True"], done.stderr

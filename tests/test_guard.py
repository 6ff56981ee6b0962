"""One guard for user code (tt_mujoco.guard): every hook kind x every way of failing x both
loops, generated, not listed. A failure before the run is bad input (exit 2, nothing left); one
during the run stops it as "failed" (exit 3, its rows and metrics kept); a report or metric that
fails after it is kept as an error beside the run's metrics (exit 0). Never a traceback, never a
KeyboardInterrupt taken for Ctrl-C, never the process ended by the user's sys.exit."""

from __future__ import annotations

import json
import textwrap

import pytest
from hooked_runs import run_hooked

from tt_mujoco import guard
from tt_mujoco.registry import describe_failure

#: Ways a user's code fails: (name, statement that fails, what the message shows)
FAILURES = {
    # a message over two lines is said on one
    "ValueError": ("raise ValueError('bad\\n  value')", "ValueError: bad value"),
    "BaseException": ("raise BaseException('base')", "BaseException: base"),
    "GeneratorExit": ("raise GeneratorExit('gone')", "GeneratorExit: gone"),
    "KeyboardInterrupt": ("raise KeyboardInterrupt", "KeyboardInterrupt"),
    "SystemExit(0)": ("sys.exit(0)", "it called sys.exit(0)"),
    "SystemExit(3)": ("sys.exit(3)", "it called sys.exit(3)"),
    "recursion": ("recurse(0)", "RecursionError"),
    "raising __str__": ("raise Unprintable()", "Unprintable: (its message cannot be shown"),
}

PRELUDE = """
import io
import math
import os
import sys
import tempfile
import traceback
import warnings

import numpy as np

from tt_mujoco.controllers import Controller
from tt_mujoco.reference.paths import ArcsPath


def recurse(n):
    return recurse(n + 1)


class Unprintable(Exception):
    def __str__(self):
        raise RuntimeError("no words")


def fail():
    FAIL
"""

#: Hook kinds: (the user's code after PRELUDE, the options that use it, when it fails)
HOOKS = {
    "import": (
        "fail()\n\nclass C(Controller):\n    def compute(self, t, m, r):\n"
        "        return 0.0, 0.0\n",
        ["--controller", "{file}:C"],
        "before",
    ),
    "controller __init__": (
        "class C(Controller):\n    def __init__(self, setup, gains=None):\n"
        "        super().__init__(setup, gains)\n        fail()\n\n"
        "    def compute(self, t, m, r):\n        return 0.0, 0.0\n",
        ["--controller", "{file}:C"],
        "before",
    ),
    "controller reset": (
        "class C(Controller):\n    def reset(self):\n        fail()\n\n"
        "    def compute(self, t, m, r):\n        return 0.0, 0.0\n",
        ["--controller", "{file}:C"],
        "before",
    ),
    "controller compute": (
        "class C(Controller):\n    def compute(self, t, m, r):\n"
        "        if t > 0.5:\n            fail()\n        return 0.5, 0.5\n",
        ["--controller", "{file}:C"],
        "during",
    ),
    "controller report": (
        "class C(Controller):\n    def compute(self, t, m, r):\n        return 0.5, 0.5\n\n"
        "    def report(self):\n        fail()\n",
        ["--controller", "{file}:C"],
        "after",
    ),
    "disturbance": (
        "def d(t):\n    if t > 0.5:\n        fail()\n    return 0.1, 0.0\n",
        ["--disturbance-model", "{file}:d"],
        "during",
    ),
    "disturbance class": (
        "class D:\n    def __init__(self):\n        fail()\n\n"
        "    def __call__(self, t):\n        return 0.0, 0.0\n",
        ["--disturbance-model", "{file}:D"],
        "before",
    ),
    "path factory": (
        "def p():\n    fail()\n    return ArcsPath('arc', (0.0, 0.0, 0.0), [(10.0, 0.5)])\n",
        ["--traj", "{file}:p"],
        "before",
    ),
    "path method": (
        "class P(ArcsPath):\n    def curvature_and_rate(self, s):\n        if s > 0.5:\n"
        "            fail()\n        return super().curvature_and_rate(s)\n\n"
        "def p():\n    return P('arc', (0.0, 0.0, 0.0), [(10.0, 0.5)])\n",
        ["--traj", "{file}:p"],
        "during",
    ),
    "metric": ("def m(ts, path):\n    fail()\n", ["--metric", "{file}:m"], "after"),
}


@pytest.fixture(autouse=True)
def _compile_now(monkeypatch):
    monkeypatch.setenv("TT_MUJOCO_COMPILE_NOW", "1")


def _cases():
    for hook, (_, _, when) in HOOKS.items():
        for failure in FAILURES:
            for loop in ("python", "compiled") if when == "during" else ("python",):
                yield pytest.param(hook, failure, loop, id=f"{hook}-{failure}-{loop}")


@pytest.mark.parametrize(("hook", "failure", "loop"), list(_cases()))
def test_every_hook_failing_every_way_ends_as_promised(
    tmp_path, monkeypatch, capsys, hook, failure, loop
):
    code, options, when = HOOKS[hook]
    statement, shown = FAILURES[failure]
    file = tmp_path / f"user_{abs(hash((hook, failure, loop)))}.py"
    file.write_text(PRELUDE.replace("FAIL", statement) + "\n" + textwrap.dedent(code))
    exit_code, out = run_hooked(tmp_path, monkeypatch, file, options, loop)
    err = capsys.readouterr().err
    assert "Traceback" not in err
    if when == "before":
        assert exit_code == 2 and shown in err, err
        assert not out.exists() or not any(out.iterdir())
        return
    doc = json.loads((out / "metrics.json").read_text())
    if when == "during":
        assert exit_code == 3 and shown in err, err
        assert doc["status"] == "failed" and doc["steps"] > 400 and shown in doc["message"]
        return
    assert exit_code == 0 and doc["status"] == "ok"
    assert any(shown in e for e in doc["metric_errors"].values()), doc["metric_errors"]


def test_a_real_interrupt_is_not_the_users_failure(monkeypatch):
    # a KeyboardInterrupt the signal handlers raise is Ctrl-C; one a user's code raises is not
    event = guard.threading.Event()
    monkeypatch.setattr(guard, "_INTERRUPTED", event)
    assert guard.users_failure(KeyboardInterrupt())
    event.set()
    assert not guard.users_failure(KeyboardInterrupt())
    monkeypatch.setattr(guard, "_INTERRUPTED", None)  # no handler of ours: an API user's
    assert not guard.users_failure(KeyboardInterrupt())
    from tt_mujoco.sim.simulate import TimeLimitExceeded

    assert not guard.users_failure(TimeLimitExceeded(1.0))  # the project's own signal
    assert guard.users_failure(GeneratorExit()) and guard.users_failure(SystemExit(0))


def test_the_failure_is_worded_whatever_the_exception_does():
    class UnrepresentableError(Exception):
        def __str__(self):
            raise RecursionError

    class Code:
        def __repr__(self):
            raise ValueError("no repr")

    assert "its message cannot be shown: RecursionError" in describe_failure(UnrepresentableError())
    assert "sys.exit(<a Code whose repr fails>)" in describe_failure(SystemExit(Code()))


def test_an_interrupt_that_other_code_turned_into_another_error_is_still_the_interrupt():
    """A stop that lands in C code calling back into Python (numba's dispatch of a compiled
    call) can come out as another error (a TypeError from numba once, in CI): once a real stop
    came, what the run raises is that stop (exit 130, rows kept), not a bug of ours (exit 70)."""
    import os
    import signal
    import time

    def swallowing_c_code():
        try:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(1.0)  # the handler runs here and raises
        except KeyboardInterrupt:
            raise TypeError(
                "_get_wrapper_address() missing 1 required positional argument"
            ) from None

    with pytest.raises(KeyboardInterrupt) as caught, guard.noting_interrupts():
        swallowing_c_code()
    assert isinstance(caught.value.__cause__, TypeError)
    # without a stop, an error is what it is
    with pytest.raises(TypeError), guard.noting_interrupts():
        raise TypeError("a bug")


#: Ways a user's code disturbs the process it runs in without failing: (name, statement)
MISCHIEF = {
    "changes the working folder": "os.chdir(tempfile.mkdtemp())",
    "closes sys.stdout": "sys.stdout.close()",
    "closes sys.stderr": "sys.stderr.close()",
    "replaces sys.stdout": "sys.stdout = io.StringIO()",
    "replaces sys.stderr": "sys.stderr = io.StringIO()",
    # a limit just above where the hook is: the run's own code after it went deeper
    "lowers the recursion limit": "sys.setrecursionlimit(len(traceback.extract_stack()) + 20)",
    "turns warnings into errors": "warnings.simplefilter('error')",
    "makes NumPy raise on floating-point errors": "np.seterr(all='raise')",
}


def _outcome(tmp_path, monkeypatch, capsys, name: str, hook: str, statement: str):
    """A hooked run from its own folder, with a relative ``--out``: its exit code, what it
    printed, its files and its metrics, the folder's name and the run's time taken out."""
    from tt_mujoco import run

    folder = tmp_path / name
    folder.mkdir()
    monkeypatch.chdir(folder)
    code, options, _ = HOOKS[hook]
    (folder / "user.py").write_text(
        PRELUDE.replace("FAIL", statement) + "\n" + textwrap.dedent(code)
    )
    argv = [o.format(file="user.py") for o in options]
    argv += ["--plant", "reduced", "--traj", "circle"] if "--traj" not in argv else []
    argv += ["--duration", "2", "--no-video", "--no-plots", "--quiet", "--out", "out"]
    monkeypatch.setenv("TT_MUJOCO_COMPILED", "0")
    exit_code = run.main(argv)
    captured = capsys.readouterr()
    out = folder / "out"
    files = sorted(p.name for p in out.iterdir()) if out.is_dir() else []
    metrics = (out / "metrics.json").read_text() if "metrics.json" in files else "{}"
    doc = json.loads(metrics.replace(str(folder), "FOLDER"))
    doc.pop("wall_time_s", None)
    said = [
        line
        for line in (captured.out + captured.err).replace(str(folder), "FOLDER").splitlines()
        if not line.startswith("wall_time_s")
    ]
    return exit_code, files, doc, said


@pytest.mark.parametrize("mischief", list(MISCHIEF))
@pytest.mark.parametrize("hook", list(HOOKS))
def test_every_hook_disturbing_the_process_changes_nothing_of_the_run(
    tmp_path, monkeypatch, capsys, hook, mischief
):
    """The run's folder, its files, its numbers and what it says are those of the same hook
    doing nothing of the kind: the outputs go where the command line said, and the command's
    streams stay open."""
    clean = _outcome(tmp_path, monkeypatch, capsys, "clean", hook, "pass")
    disturbed = _outcome(tmp_path, monkeypatch, capsys, "disturbed", hook, MISCHIEF[mischief])
    assert clean[1], clean  # the clean run wrote its folder
    assert disturbed == clean


@pytest.mark.parametrize(
    ("source", "line", "kind"),
    [
        ("x = 1\ndef f(:\n    pass\n", 2, "SyntaxError"),
        ("def f():\n    x = 1\n   y = 2\n", 3, "IndentationError"),
    ],
)
def test_a_file_that_does_not_compile_is_named_at_its_own_line(
    tmp_path, monkeypatch, capsys, source, line, kind
):
    """The compiler's error names the user's file and line, not the import machinery's."""
    from tt_mujoco import run

    (tmp_path / "bad.py").write_text(source)
    monkeypatch.chdir(tmp_path)
    argv = ["--controller", "bad.py:C", "--plant", "reduced", "--duration", "0.3", "--no-video"]
    assert run.main([*argv, "--out", "out"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"bad.py, line {line}: {kind}" in err[0], err
    assert "importlib" not in err[0] and not (tmp_path / "out").exists()


def test_a_sweep_whose_controller_changes_the_working_folder_writes_where_asked(
    tmp_path, monkeypatch, capsys
):
    from tt_mujoco.sweep import cli

    monkeypatch.chdir(tmp_path)
    code = HOOKS["controller __init__"][0]
    (tmp_path / "user.py").write_text(
        PRELUDE.replace("FAIL", MISCHIEF["changes the working folder"])
        + "\n"
        + textwrap.dedent(code)
    )
    argv = ["--out", "sweep", "--workers", "1", "--quiet", "--no-figures"]
    argv += ["controller=user.py:C", "plant=reduced", "traj=circle", "duration=1"]
    assert cli.main(argv) == 0, capsys.readouterr().err
    assert (tmp_path / "sweep" / "runs.csv").is_file()
    assert len((tmp_path / "sweep" / "runs.csv").read_text().splitlines()) == 2


@pytest.mark.parametrize("hook", [h for h, (_, _, when) in HOOKS.items() if when == "before"])
def test_every_hook_that_does_not_return_before_the_run_is_stopped_by_its_time_limit(
    tmp_path, monkeypatch, capsys, hook
):
    """A user's import, constructor or path factory that never returns is bad input once the
    run's time limit has passed: exit 2 naming its file and line, nothing written."""
    code, options, _ = HOOKS[hook]
    file = tmp_path / "user_hangs.py"
    file.write_text(PRELUDE.replace("FAIL", "while True:\n        pass") + "\n" + code)
    exit_code, out = run_hooked(tmp_path, monkeypatch, file, [*options, "--time-limit", "0.5"])
    err = capsys.readouterr().err
    assert exit_code == 2, err
    assert "passed its time limit of 0.5 s" in err and f"{file}, line " in err, err
    assert not out.exists() or not any(out.iterdir())


THREAD_LEFT = """
import threading
import time

from tt_mujoco.controllers import Controller

threading.Thread(target=time.sleep, args=(600,), name="left-running").start()


class C(Controller):
    def compute(self, t, m, r):
        return 0.2, 0.2
"""


@pytest.mark.parametrize(
    "command",
    [
        ["tt_mujoco.run", "--no-video", "--no-plots", "--plant", "reduced", "--duration", "0.3"],
        ["tt_mujoco.sweep", "--workers", "1", "--no-figures", "plant=reduced", "duration=0.3"],
    ],
    ids=["run", "sweep"],
)
def test_a_thread_a_users_code_leaves_running_does_not_keep_the_command_alive(tmp_path, command):
    import subprocess
    import sys

    (tmp_path / "left.py").write_text(THREAD_LEFT)
    hook = "--controller=left.py:C" if command[0] == "tt_mujoco.run" else "controller=left.py:C"
    proc = subprocess.run(
        [sys.executable, "-m", *command, hook, "--quiet", "--out", "out"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=120,
        env={**__import__("os").environ, "TT_MUJOCO_COMPILED": "0"},
    )
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "out").is_dir()
    # the run's own process forked its watched run after the import: the thread stayed in
    # the parent, which leaves by os._exit; the sweep ends the thread's holders and says so
    assert command[0] == "tt_mujoco.run" or "'left-running'" in proc.stderr, proc.stderr


def test_a_stop_sent_again_after_a_while_ends_a_clean_up_that_hangs(tmp_path):
    """The first SIGTERM is the clean stop; one sent again after guard.AGAIN_S is the
    signal's own action, so a clean-up that hangs needs no SIGKILL."""
    import signal
    import subprocess
    import sys
    import time

    script = (
        "import time\nfrom tt_mujoco import guard\n\n@guard.command\ndef main(argv):\n"
        "    try:\n        time.sleep(60)\n    except KeyboardInterrupt:\n"
        "        print('cleaning', flush=True)\n        time.sleep(60)\n    return 0\n\n"
        "guard.end(main())\n"
    )
    proc = subprocess.Popen(
        [sys.executable, "-c", script], stdout=subprocess.PIPE, text=True, cwd=tmp_path
    )
    time.sleep(3.0)  # imported and asleep
    proc.send_signal(signal.SIGTERM)
    assert proc.stdout.readline().strip() == "cleaning"
    proc.send_signal(signal.SIGTERM)  # the same stop again at once: still the clean-up
    time.sleep(0.5)
    assert proc.poll() is None
    time.sleep(guard.AGAIN_S)
    proc.send_signal(signal.SIGTERM)
    assert proc.wait(timeout=10) == -signal.SIGTERM


EXIT_HANDLERS = """
import atexit
import sys

from tt_mujoco import guard

def fails():
    raise RuntimeError("no words at the exit")

atexit.register(lambda: sys.exit(5))
atexit.register(fails)
guard.end(0)
"""


def test_a_users_exit_handler_changes_neither_the_exit_code_nor_the_last_word(tmp_path):
    """Before: a handler that raised printed its traceback after the command's last line,
    and one calling sys.exit(5) made a run that had succeeded exit 5."""
    import subprocess
    import sys

    proc = subprocess.run(
        [sys.executable, "-c", EXIT_HANDLERS], capture_output=True, text=True, timeout=60
    )
    assert proc.returncode == 0, proc.stderr
    assert "Traceback" not in proc.stderr, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 2, lines
    assert "note: the exit handler fails failed: <string>, line 8" in lines[0], lines
    assert "no words at the exit" in lines[0]
    assert "<lambda>" in lines[1] and "sys.exit(5)" in lines[1]

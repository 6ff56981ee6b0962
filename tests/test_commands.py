"""Every command of the package, found rather than listed: its ``main`` is guarded, so that a bug
of ours is one line on stderr naming the file its traceback went to, and exit code 70."""

import argparse
import importlib
import pkgutil
import re
from pathlib import Path

import pytest

import tt_mujoco
from tt_mujoco.defaults import EXIT_BUG


def _commands() -> list[str]:
    """The modules with a ``main`` that ``python -m`` runs (``if __name__ == "__main__"`` or
    a package's ``__main__.py``)."""
    found = []
    root = Path(tt_mujoco.__file__).parent
    for info in pkgutil.walk_packages([str(root)], "tt_mujoco."):
        if info.name.endswith("__main__"):
            continue  # importing it runs the command; its package stands for it
        path = root.joinpath(*info.name.split(".")[1:])
        source = path / "__main__.py" if info.ispkg else path.with_suffix(".py")
        if source.exists() and re.search(r"^\s*guard\.end\(main\(\)\)$", source.read_text(), re.M):
            found.append(info.name + (".cli" if info.ispkg else ""))
    return sorted(found)


COMMANDS = _commands()


def test_the_commands_are_found():
    assert {"tt_mujoco.run", "tt_mujoco.sweep.cli", "tt_mujoco.render"} <= set(COMMANDS)


@pytest.mark.parametrize("name", COMMANDS)
def test_a_bug_of_ours_is_one_line_and_exit_70(name, monkeypatch, tmp_path, capsys):
    module = importlib.import_module(name)
    assert getattr(module.main, "guarded", False), f"{name}.main is not @guard.command"

    def broken(self, *args, **kwargs):
        raise RuntimeError("a bug planted by the test")

    monkeypatch.setattr(argparse.ArgumentParser, "parse_known_args", broken)
    monkeypatch.setenv("TMPDIR", str(tmp_path))
    monkeypatch.setattr("tempfile.tempdir", None)
    monkeypatch.chdir(tmp_path)
    code = module.main(["--help"])
    err = capsys.readouterr().err
    assert code == EXIT_BUG, err
    assert len(err.strip().splitlines()) == 1 and "a bug of tt-mujoco" in err, err
    (crash,) = tmp_path.glob("tt_mujoco-crash-*.txt")
    assert str(crash) in err
    text = crash.read_text()
    assert "Traceback" in text and "RuntimeError: a bug planted by the test" in text


@pytest.mark.parametrize("name", COMMANDS)
def test_an_unknown_option_is_one_line_and_exit_2_with_nothing_written(
    name, monkeypatch, tmp_path, capsys
):
    """Every command parses its options with tt_mujoco.cliargs.Parser, whose errors the guard
    says in one line (argparse's own would print the usage over several), before any work."""
    module = importlib.import_module(name)
    monkeypatch.chdir(tmp_path)
    code = module.main(["x", "--no-such-option"])
    err = capsys.readouterr().err
    assert code == 2, err
    assert len(err.strip().splitlines()) == 1 and "--no-such-option" in err, err
    assert not any(tmp_path.iterdir())


def test_no_command_parses_with_argparse_itself():
    root = Path(tt_mujoco.__file__).parent
    for path in root.rglob("*.py"):
        assert "argparse.ArgumentParser(" not in path.read_text(), path


@pytest.mark.parametrize("name", COMMANDS)
def test_a_reader_that_goes_away_is_no_bug(name, tmp_path):
    """``python -m ... | head -1``: the pipe's reader closes it, and what the command still
    prints is dropped (guard._ReaderMayGo), not a Broken pipe reported as a bug of ours."""
    import subprocess
    import sys

    module = name.removesuffix(".cli")  # a package's command runs as the package
    proc = subprocess.Popen(
        [sys.executable, "-m", module, "--help"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        cwd=tmp_path,
    )
    proc.stdout.close()  # gone before the command writes a line
    err = proc.stderr.read().decode()
    proc.stderr.close()
    assert proc.wait(timeout=120) == 0, err
    assert "bug" not in err and "Traceback" not in err, err


@pytest.mark.parametrize("name", COMMANDS)
def test_an_interrupt_no_command_ended_on_itself_is_one_line_and_exit_130(
    name, monkeypatch, tmp_path, capsys
):
    """Ctrl-C (or the SIGTERM the guard turns into one) wherever a command did not catch it:
    one line, exit code 130, no traceback, nothing left."""
    module = importlib.import_module(name)

    def stopped(self, *args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(argparse.ArgumentParser, "parse_known_args", stopped)
    monkeypatch.chdir(tmp_path)
    code = module.main(["--help"])
    err = capsys.readouterr().err
    assert code == 130, err
    assert len(err.strip().splitlines()) == 1 and "interrupted" in err, err
    assert not any(tmp_path.iterdir())


def test_every_command_takes_sigterm_as_a_stop_and_removes_what_it_claimed(tmp_path, capsys):
    """A batch system's SIGTERM reaches a command as Ctrl-C does (its default action would end
    the process with its files half written): the folder it claimed and left empty goes."""
    import os
    import signal
    import time

    from tt_mujoco import guard, outputs

    out = tmp_path / "out"

    @guard.command
    def main(argv):
        outputs.claim_folder(out, out)
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(5.0)  # the handler raises here
        return 0

    assert main([]) == 130
    assert "interrupted: nothing was written" in capsys.readouterr().err
    assert not out.exists()


def _parser_of(name, monkeypatch):
    """The command's parser, as its ``main`` builds it (caught as it parses)."""
    from tt_mujoco import cliargs

    caught = []

    def catch(self, *args, **kwargs):
        caught.append(self)
        raise KeyboardInterrupt  # out of main at once: the guard says "interrupted"

    monkeypatch.setattr(cliargs.Parser, "parse_known_args", catch)
    importlib.import_module(name).main([])
    monkeypatch.undo()
    return caught[0]


def _two_values(parser, action):
    """Two texts the option reads as two different values, or None."""
    for pair in (("1", "2"), ("3", "4"), ("a", "b"), ("0.5", "0.25"), ("none", "1")):
        try:
            values = [parser._get_values(action, [text]) for text in pair]
        except Exception:
            continue
        if values[0] != values[1]:
            return pair
    return None


@pytest.mark.parametrize("name", COMMANDS)
def test_every_option_of_every_command_given_twice_with_two_values_is_refused(
    name, monkeypatch, tmp_path, capsys
):
    """Before: a command's own options (``--out``, ``--workers``, ...) took the last of two in
    silence, where the scenario's refused the second; cliargs.Parser now stores every option
    once."""
    monkeypatch.chdir(tmp_path)
    parser = _parser_of(name, monkeypatch)
    capsys.readouterr()
    module = importlib.import_module(name)
    tried = 0
    for action in parser._actions:
        if not action.option_strings or action.nargs not in (None, 1) or action.dest == "help":
            continue
        if isinstance(action, argparse._AppendAction):  # repeatable by design (--param)
            continue
        pair = _two_values(parser, action)
        if pair is None:
            continue
        flag = action.option_strings[0]
        code = module.main([flag, pair[0], flag, pair[1]])
        err = capsys.readouterr().err
        assert code == 2, (flag, err)
        assert len(err.strip().splitlines()) == 1 and "both set" in err, (flag, err)
        tried += 1
    assert tried, f"{name}: no option takes a value"
    assert not any(tmp_path.iterdir())

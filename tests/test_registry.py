"""The registries of named parts (tt_mujoco/registry.py): a name is one part. Generated from
every Registry the package holds: each built-in name refuses another part, takes the same part
again, and is replaced only on purpose."""

from __future__ import annotations

import importlib
import pkgutil

import pytest

import tt_mujoco
from tt_mujoco.registry import Registry


def _registries() -> dict[str, Registry]:
    """Every Registry at the top of a module of the package, by where it lives."""
    found = {}
    for info in pkgutil.walk_packages(tt_mujoco.__path__, "tt_mujoco."):
        if info.name.endswith("__main__") or ".paper." in info.name:
            continue
        try:
            module = importlib.import_module(info.name)
        except ImportError:  # an optional extra's module
            continue
        for name, value in vars(module).items():
            if isinstance(value, Registry):
                found.setdefault(id(value), (f"{info.name}.{name}", value))
    return {label: registry for label, registry in found.values()}


REGISTRIES = _registries()


def test_the_registries_are_found():
    kinds = {registry.what for registry in REGISTRIES.values()}
    assert {"controller", "path", "metric", "disturbance"} <= kinds, kinds


@pytest.fixture
def restored():
    saved = {label: dict(r._items) for label, r in REGISTRIES.items()}
    yield
    for label, registry in REGISTRIES.items():
        registry._items.clear()
        registry._items.update(saved[label])


def _stranger():
    def stranger(*args, **kwargs):  # another part, defined here
        return None

    return stranger


CASES = [(label, name) for label, r in REGISTRIES.items() for name in r.names()]


@pytest.mark.parametrize(("label", "name"), CASES)
def test_a_built_in_name_refuses_another_part(restored, label, name):
    registry = REGISTRIES[label]
    built_in = registry[name]
    with pytest.raises(ValueError, match=f"name '{name}' is taken by the built-in"):
        registry.register(name, _stranger())
    assert registry[name] is built_in
    registry.register(name, built_in)  # the same part again
    replacement = _stranger()
    registry.register(name, replacement, replace=True)  # on purpose
    assert registry[name] is replacement


@pytest.mark.parametrize("label", list(REGISTRIES))
def test_a_users_name_takes_its_part_again_and_refuses_another(restored, label):
    registry = REGISTRIES[label]
    first = _stranger()
    registry.register("users_part", first)
    registry.register("users_part", _stranger())  # the same definition run again
    other = lambda *args: None  # noqa: E731 - a part defined elsewhere
    with pytest.raises(ValueError, match="is taken by"):
        registry.register("users-part", other)  # the same name, spelled otherwise


def test_finite_number_is_the_one_test_of_a_number():
    import math

    import numpy as np

    from tt_mujoco.registry import finite_number

    for good in (0, -3, 2.5, np.float32(1.5), np.int64(7), 1e308):
        assert finite_number(good) == float(good)
    for bad in (True, np.bool_(False), math.nan, -math.inf, 10**400, "1", 1j, None, [1.0], b"1"):
        assert finite_number(bad) is None, bad


#: How the command line names a part of each kind that declares how it is called
#: (``Registry.called_as``): its option.
OPTION_OF = {"metric": "--metric", "disturbance": "--disturbance-model"}
CALLED = {label: r for label, r in REGISTRIES.items() if r.called_as is not None}


def test_every_kind_called_as_declared_has_its_option_here():
    assert {r.what for r in CALLED.values()} <= set(OPTION_OF), CALLED
    assert {"metric", "disturbance"} <= {r.what for r in CALLED.values()}


@pytest.mark.parametrize("label", list(CALLED))
def test_a_part_that_is_not_callable_is_bad_input(tmp_path, monkeypatch, capsys, label):
    from tt_mujoco import run

    registry = CALLED[label]
    (tmp_path / "part.py").write_text("part = [0.0,\n        0.0]\n")
    monkeypatch.chdir(tmp_path)
    argv = ["--plant", "reduced", "--duration", "0.5", "--no-video", "--no-plots", "--quiet"]
    code = run.main([*argv, OPTION_OF[registry.what], "part.py:part", "--out", "out"])
    err = capsys.readouterr().err
    assert code == 2 and "[0.0, 0.0] is not callable" in err, err
    assert len(err.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("label", list(CALLED))
@pytest.mark.parametrize("shape", ["one too many", "one too few", "a keyword it needs"])
def test_a_part_whose_signature_does_not_take_its_call_is_bad_input(
    tmp_path, monkeypatch, capsys, label, shape
):
    """A part that cannot be called as its kind is called fails before the run (exit 2,
    nothing written), naming its signature, not after a long run (a metric) or at its first
    step (a disturbance)."""
    from tt_mujoco import run

    registry = CALLED[label]
    names = list(registry.called_as)
    parameters = {
        "one too many": [*names, "extra"],
        "one too few": names[:-1],
        "a keyword it needs": [*names, "*", "scale"],
    }[shape]
    (tmp_path / "part.py").write_text(f"def part({', '.join(parameters)}):\n    return 0.0, 0.0\n")
    monkeypatch.chdir(tmp_path)
    argv = ["--plant", "reduced", "--duration", "0.5", "--no-video", "--no-plots", "--quiet"]
    code = run.main([*argv, OPTION_OF[registry.what], "part.py:part", "--out", "out"])
    err = capsys.readouterr().err
    assert code == 2 and f"it is called as {registry.what}(" in err, err
    assert f"signature ({', '.join(parameters)})" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists()


def test_check_call_takes_what_fits_and_what_it_cannot_read():
    registry = Registry("shape", called_as=("a", "b"))
    registry.check_call(lambda a, b, c=1: None, "fits")
    registry.check_call(lambda *args: None, "takes anything")
    registry.check_call(max, "written in C")  # no signature Python can read: taken as it is
    with pytest.raises(ValueError, match=r"called as shape\(a, b\), which its signature \(a\)"):
        registry.check_call(lambda a: None, "too few")


def test_a_call_that_does_not_fit_names_no_file_of_the_package():
    """Where the user's code never ran (the call itself failed), the message names no line of
    the package's, which would point the user at the wrong file."""
    from tt_mujoco.registry import HookError, call_hook

    def takes_one(a):
        return a

    with pytest.raises(HookError) as caught:
        call_hook("metric 'm'", takes_one, 1, 2)
    message = str(caught.value)
    assert "takes 1 positional argument but 2 were given" in message
    assert "registry.py" not in message and ".py, line" not in message


@pytest.mark.parametrize("label", list(REGISTRIES))
def test_an_unknown_name_says_what_is_allowed_in_a_sentence(label):
    registry = REGISTRIES[label]
    for r in (registry, Registry(registry.what, also=registry.also)):  # and with none registered
        message = str(r.unknown("zzz_no_such_part"))
        assert "a hook 'package.module:Name'" in message, message
        assert "one of ," not in message and "use or" not in message, message
        assert ("use one of" in message) == bool(r.names()), message


def test_a_built_in_metric_or_run_key_given_as_an_extra_metric_is_named_as_such():
    from tt_mujoco.analysis.metric_names import RUN_KEYS, resolve_metrics

    for name in ("rmse_v", "trailer_offtrack_rms", *RUN_KEYS):
        with pytest.raises(ValueError, match=r"every run's metrics\.json holds it"):
            resolve_metrics([name])


def test_a_value_in_a_message_is_shown_as_the_number_it_is():
    """NumPy 2's repr of its scalars (``np.int64(-3)``) is no way to name a user's value: a
    scalar is shown as the Python number it holds, in a tuple or a list too; an array stays
    an array."""
    import numpy as np

    from tt_mujoco.registry import shown

    assert shown(np.int64(-3)) == "-3"
    assert shown(np.float64(np.nan)) == "nan"
    assert shown((np.float64(1.5), "x", [np.bool_(True)])) == "(1.5, 'x', [True])"
    assert shown(np.array(1.0)) == "array(1.)"


def test_a_failure_inside_a_library_is_named_at_the_users_line_too(tmp_path):
    # Before: a user's json.loads("{") was placed in json/decoder.py, and a time limit that
    # struck inside re in re/__init__.py: neither is the line the user would look at
    from tt_mujoco.registry import describe_failure

    user = tmp_path / "user_code.py"
    user.write_text("import json\n\n\ndef parse():\n    return json.loads('{')\n")
    namespace = {}
    exec(compile(user.read_text(), str(user), "exec"), namespace)
    try:
        namespace["parse"]()
    except ValueError as err:
        said = describe_failure(err)
    assert said.startswith(f"{user}, line 5 (in ") and "json" in said, said
    assert "JSONDecodeError" in said

"""What the compiled kernel compiles is discovered from the step, and every substitution is
declared beside the function it stands for (tt_mujoco.sim.loop.kernel_sources,
tt_mujoco.compiled_form)."""

import inspect
import types

import pytest

from tt_mujoco.compiled_form import compiled_form, compiled_form_reason
from tt_mujoco.sim.loop import closed_loop, kernel_sources, law


def test_every_function_the_step_calls_is_compiled_from_its_source():
    # the discovery over the step's bytecode finds the step's helpers, the built-in laws and
    # the metrics' search, and nothing outside the package
    shared = set(kernel_sources.SHARED)
    assert set(law.LAWS) <= shared
    assert all(f.__module__.startswith("tt_mujoco") for f in shared)
    assert not shared & set(kernel_sources.STEP)
    for fn in (*kernel_sources.STEP, *shared):
        for called in kernel_sources._called(fn):
            assert (
                called in shared or called in kernel_sources.STEP or compiled_form_reason(called)
            ), f"{fn.__qualname__} calls {called.__qualname__}, which the kernel would not know"


def test_a_helper_added_to_a_part_is_found_without_a_list(tmp_path):
    # a new part's helper, called as module.function or by its own name, is discovered
    module = types.ModuleType("tt_mujoco.sim._a_new_part")
    exec(
        "def inner(x):\n    return x + 1.0\n\ndef helper(x):\n    return inner(x) * 2.0\n",
        module.__dict__,
    )
    module.helper.__module__ = module.inner.__module__ = module.__name__
    scope = {"part": module}
    step = types.FunctionType(
        compile("def step(x):\n    return part.helper(x)\n", "<step>", "exec").co_consts[0],
        scope,
    )
    step.__module__ = "tt_mujoco.sim._a_step"
    called, marked = kernel_sources.discover((step,), step=(step,))
    assert set(called) == {module.helper, module.inner}
    assert marked == ()


def test_the_compiled_forms_are_the_marked_functions_and_only_they():
    kernel = pytest.importorskip("tt_mujoco.sim.loop.compiled").kernel()
    given = set(kernel.COMPILED_FORMS_GIVEN)
    marked = set(kernel_sources.COMPILED_FORMS)
    assert given == marked, (
        sorted(f.__qualname__ for f in given - marked),
        sorted(f.__qualname__ for f in marked - given),
    )
    for fn in marked:  # each says why, beside its Python form
        assert len(compiled_form_reason(fn)) > 20, fn.__qualname__
        assert "compiled_form(" in inspect.getsource(fn).splitlines()[0]


def test_a_compiled_form_for_an_unmarked_function_is_refused():
    kernel = pytest.importorskip("tt_mujoco.sim.loop.compiled").kernel()

    def unmarked(x):
        return x

    with pytest.raises(TypeError, match="unmarked has a compiled form but no compiled_form mark"):
        kernel.compiled_form_of(unmarked)
    assert compiled_form("why")(unmarked) is unmarked and compiled_form_reason(unmarked) == "why"


def test_the_hooks_are_asked_distinct_questions():
    asked = (
        closed_loop.HOOK_CURVATURE,
        closed_loop.HOOK_POSE,
        closed_loop.HOOK_LAW_POSE,
        closed_loop.HOOK_DISTURBANCE,
    )
    assert len(set(asked)) == len(asked)

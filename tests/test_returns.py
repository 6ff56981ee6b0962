"""What a user's code returns, checked in one place (tt_mujoco.registry.finite_number and the
checks of tt_mujoco.sim.usercode): every hook that returns numbers x every wrong value x both
loops, generated, not listed. A controller, disturbance or path that returns something other
than finite numbers mid-run stops the run as "failed" (exit 3, its rows kept, the value named);
a metric or a report that does is kept as None beside an error (exit 0); and whatever a user's
code returned, the run's folder reads back through the strict reader."""

from __future__ import annotations

import json
import textwrap

import pytest
from hooked_runs import run_hooked

from tt_mujoco.runfolder import read_run

#: A wrong item in a pair of numbers: (name, expression)
ITEMS = {
    "NaN": "math.nan",
    "inf": "-math.inf",
    "huge int": "10 ** 400",
    "bool": "True",
    "numpy bool": "np.bool_(False)",
    "string": "'0.5'",
    "complex": "1j",
    "None": "None",
    "list": "[0.5]",
}
#: A wrong value instead of the pair itself
WHOLES = {
    "None": "None",
    "three numbers": "(0.5, 0.5, 0.5)",
    "one number": "0.5",
    "generator": "(v for v in (0.5, 0.5))",
    "string": "'05'",
    "dict": "{'a': 0.5, 'b': 0.5}",
    "set": "{0.5, 0.25}",
}

PRELUDE = """
import math

import numpy as np

from tt_mujoco.controllers import Controller
from tt_mujoco.reference.paths import ArcsPath


def wrong():
    return WRONG
"""

#: Hooks that return a pair of numbers mid-run: (code after PRELUDE, options)
PAIRS = {
    "controller compute": (
        "class C(Controller):\n    def compute(self, t, m, r):\n"
        "        return wrong() if t > 0.5 else (0.5, 0.5)\n",
        ["--controller", "{file}:C"],
    ),
    "disturbance": (
        "def d(t):\n    return wrong() if t > 0.5 else (0.1, 0.0)\n",
        ["--disturbance-model", "{file}:d"],
    ),
    "path curvature": (
        "class P(ArcsPath):\n    def curvature_and_rate(self, s):\n"
        "        return wrong() if s > 0.5 else super().curvature_and_rate(s)\n\n"
        "def p():\n    return P('arc', (0.0, 0.0, 0.0), [(10.0, 0.5)])\n",
        ["--traj", "{file}:p"],
    ),
}


@pytest.fixture(autouse=True)
def _compile_now(monkeypatch):
    monkeypatch.setenv("TT_MUJOCO_COMPILE_NOW", "1")


def _run(tmp_path, monkeypatch, code, options, wrong, loop="python"):
    file = tmp_path / "user.py"
    file.write_text(PRELUDE.replace("WRONG", wrong) + "\n" + textwrap.dedent(code))
    return run_hooked(tmp_path, monkeypatch, file, options, loop)


def _pair_cases():
    wrongs = {f"({v}, 0.0)": f"item {k}" for k, v in ITEMS.items()}
    wrongs |= {v: f"whole {k}" for k, v in WHOLES.items()}
    for hook in PAIRS:
        for wrong, name in wrongs.items():
            for loop in ("python", "compiled"):
                yield pytest.param(hook, wrong, loop, id=f"{hook}-{name}-{loop}")


@pytest.mark.parametrize(("hook", "wrong", "loop"), list(_pair_cases()))
def test_a_hook_that_returns_a_wrong_pair_mid_run_stops_it_as_failed(
    tmp_path, monkeypatch, capsys, hook, wrong, loop
):
    code, options = PAIRS[hook]
    exit_code, out = _run(tmp_path, monkeypatch, code, options, wrong, loop)
    err = capsys.readouterr().err
    assert exit_code == 3 and "Traceback" not in err and "returned" in err, err
    finished = read_run(out)  # the strict reader takes what was kept
    assert finished.metrics["status"] == "failed" and finished.metrics["steps"] > 400
    assert "returned" in finished.metrics["message"]


#: What a metric may wrongly return: any wrong item, any wrong whole but a single number
METRIC_WRONGS = ITEMS | {f"whole {k}": v for k, v in WHOLES.items() if k != "one number"}


@pytest.mark.parametrize("wrong", list(METRIC_WRONGS.values()), ids=list(METRIC_WRONGS))
def test_a_metric_that_returns_a_wrong_value_is_kept_as_an_error(
    tmp_path, monkeypatch, capsys, wrong
):
    code = "def m(ts, path):\n    return wrong()\n"
    exit_code, out = _run(tmp_path, monkeypatch, code, ["--metric", "{file}:m"], wrong)
    assert exit_code == 0, capsys.readouterr().err
    doc = read_run(out).metrics  # strict JSON, whatever the metric returned
    assert doc["m"] is None
    assert (wrong == "None") == ("m" not in doc.get("metric_errors", {}))


@pytest.mark.parametrize("wrong", list(ITEMS.values()), ids=list(ITEMS))
def test_a_report_with_a_wrong_value_never_breaks_the_run_folder(
    tmp_path, monkeypatch, capsys, wrong
):
    code = (
        "class C(Controller):\n    def compute(self, t, m, r):\n        return 0.5, 0.5\n\n"
        "    def report(self):\n        return {'r': wrong()}\n"
    )
    exit_code, out = _run(tmp_path, monkeypatch, code, ["--controller", "{file}:C"], wrong)
    assert exit_code == 0, capsys.readouterr().err
    text = (out / "metrics.json").read_text()
    json.loads(text)
    assert read_run(out).metrics["status"] == "ok"

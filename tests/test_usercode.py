"""User code is a boundary (tt_mujoco.sim.usercode): a user's controller, disturbance or metric
that fails ends in one message naming it, the right exit code, and nothing lost or left."""

from __future__ import annotations

import json
import textwrap

import numpy as np
import pytest

from tt_mujoco import outputs, run, run_outputs
from tt_mujoco.outputs import read_timeseries

ARGV = ["--plant", "reduced", "--traj", "circle", "--duration", "1", "--no-video", "--no-plots"]

CONTROLLER = """
import sys
from tt_mujoco.controllers import Controller

class Broken(Controller):
    name = "broken"

    def compute(self, t, measurement, reference):
        if t >= START:
            BODY
        return 0.5, 0.5
"""


def controller(tmp_path, body: str, start: float = 0.3) -> str:
    path = tmp_path / "broken.py"
    text = CONTROLLER.replace("BODY", body).replace("START", repr(start))
    path.write_text(textwrap.dedent(text))
    return f"{path}:Broken"


def cli(tmp_path, capsys, *extra):
    out = tmp_path / "out"
    # an option in extra replaces ARGV's (one command line may not give an option twice)
    flags, base, value_of_dropped = {a for a in extra if a.startswith("--")}, [], False
    for a in ARGV:
        if value_of_dropped and not a.startswith("--"):
            value_of_dropped = False
            continue
        value_of_dropped = a in flags
        if not value_of_dropped:
            base.append(a)
    code = run.main([*base, *extra, "--quiet", "--out", str(out)])
    return code, out, capsys.readouterr().err


def assert_nothing_left(out):
    assert not out.exists() or not any(out.iterdir())


@pytest.mark.parametrize(
    ("body", "said"),
    [
        ("return None", "returned None at t=0.000 s: compute must return two numbers (T_r, T_l)"),
        ("return 1.0, 2.0, 3.0", "returned (1.0, 2.0, 3.0) at t=0.000 s"),
        ("return 'ab'", "returned 'ab' at t=0.000 s"),
        ("return float('inf'), 0.0", "returned T_r=inf, T_l=0.0 at t=0.000 s"),
        ("raise KeyError('gain')", "broken.py, line 10: KeyError: 'gain'"),
        ("sys.exit(0)", "broken.py, line 10: it called sys.exit(0)"),
        # what spans lines is said on one: a NumPy array's repr, a message with line breaks
        (
            "return __import__('numpy').full((2, 1), 0.5)",
            "returned array([[0.5], [0.5]]) at t=0.000 s",
        ),
        ("raise ValueError('first\\nsecond')", "broken.py, line 10: ValueError: first second"),
    ],
)
def test_a_controller_that_fails_on_the_initial_state_is_bad_input(tmp_path, capsys, body, said):
    code, out, err = cli(tmp_path, capsys, "--controller", controller(tmp_path, body, 0.0))
    assert code == 2 and said in err and "Traceback" not in err, err
    assert err.count("\n") == 1 and "controller '" in err
    assert_nothing_left(out)


@pytest.mark.parametrize(
    ("body", "said"),
    [
        ("raise ZeroDivisionError('gain')", "failed at t=0.300 s: "),
        ("return None", "returned None at t=0.300 s"),
        ("return float('-inf'), 1.0", "returned T_r=-inf, T_l=1.0 at t=0.300 s"),
        ("sys.exit(0)", "it called sys.exit(0)"),
    ],
)
def test_a_controller_that_fails_during_the_run_keeps_its_rows(tmp_path, capsys, body, said):
    code, out, err = cli(tmp_path, capsys, "--controller", controller(tmp_path, body))
    assert code == 3 and said in err and "Traceback" not in err, err
    ts = read_timeseries(out / "timeseries.parquet")
    assert len(ts["t"]) == 300 and ts["t"][-1] == pytest.approx(0.299)
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["status"] == "failed" and metrics["sim_time_s"] == pytest.approx(0.3)
    assert metrics["cross_track_rms"] is not None
    assert not (out / outputs.CLAIM_FILE).exists()
    assert not (out / run_outputs.CHECKPOINT_FILE).exists()
    if body.startswith(("raise", "sys")):
        log = (out / run_outputs.ERROR_LOG).read_text()
        assert "Traceback" in log and "broken.py" in log


def test_an_init_that_skips_the_base_class_is_named_before_the_run(tmp_path, capsys):
    path = tmp_path / "stanley.py"
    path.write_text(
        textwrap.dedent(
            """
            from tt_mujoco.controllers import Controller

            class Stanley(Controller):
                name = "stanley"

                def __init__(self, setup, gains=None):
                    self.k = 1.0

                def compute(self, t, measurement, reference):
                    return 0.0, 0.0
            """
        )
    )
    code, out, err = cli(tmp_path, capsys, "--controller", f"{path}:Stanley")
    assert code == 2 and "super().__init__(setup, gains)" in err and "'preset'" in err, err
    assert_nothing_left(out)


def test_a_reset_that_raises_is_bad_input(tmp_path, capsys):
    path = tmp_path / "r.py"
    path.write_text(
        "from tt_mujoco.controllers import Controller\n"
        "class R(Controller):\n"
        "    def reset(self):\n"
        "        raise RuntimeError('no state')\n"
        "    def compute(self, t, m, r):\n"
        "        return 0.0, 0.0\n"
    )
    code, out, err = cli(tmp_path, capsys, "--controller", f"{path}:R")
    assert code == 2 and "r.py, line 4: RuntimeError: no state" in err, err
    assert_nothing_left(out)


@pytest.mark.parametrize("exit_code", [0, 3])
def test_sys_exit_at_a_hooks_import_is_bad_input(tmp_path, capsys, exit_code):
    path = tmp_path / "m.py"
    path.write_text(f"import sys\nsys.exit({exit_code})\ndef m(ts, path):\n    return 1.0\n")
    code, out, err = cli(tmp_path, capsys, "--metric", f"{path}:m")
    assert code == 2 and f"it called sys.exit({exit_code})" in err, err
    assert_nothing_left(out)


def test_a_disturbance_that_turns_nan_stops_the_run_where_it_did(tmp_path, capsys):
    path = tmp_path / "d.py"
    path.write_text("def gust(t):\n    return (float('nan'), 0.0) if t >= 0.5 else (0.1, 0.0)\n")
    argv = ["--plant", "mujoco", "--disturbance-model", f"{path}:gust"]
    code, out, err = cli(tmp_path, capsys, *argv)
    assert code == 3 and "returned a_v=nan, a_omega=0.0 at t=0.500 s" in err, err
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["status"] == "failed" and metrics["sim_time_s"] == pytest.approx(0.5)


def test_a_disturbance_that_fails_at_the_start_is_bad_input(tmp_path, capsys):
    path = tmp_path / "d.py"
    path.write_text("def gust(t):\n    return 1.0\n")
    code, out, err = cli(tmp_path, capsys, "--disturbance-model", f"{path}:gust")
    assert code == 2 and "returned 1.0 at t=0.000 s: a disturbance must return two" in err
    assert_nothing_left(out)


def test_a_metric_sees_a_read_only_series_and_a_bad_value_is_kept_as_an_error(tmp_path, capsys):
    path = tmp_path / "m.py"
    path.write_text(
        "def zero_x(ts, path):\n"
        "    ts['x'][:] = 0.0\n"
        "    return 1.0\n"
        "def thing(ts, path):\n"
        "    return object()\n"
        "def fine(ts, path):\n"
        "    return float(ts['x'].max())\n"
    )
    metrics = [a for name in ("zero_x", "thing", "fine") for a in ("--metric", f"{path}:{name}")]
    code, out, err = cli(tmp_path, capsys, *metrics)
    assert code == 0, err
    ts = read_timeseries(out / "timeseries.parquet")
    assert np.all(ts["x"] != 0.0)
    doc = json.loads((out / "metrics.json").read_text())
    assert doc["zero_x"] is None and "read-only" in doc["metric_errors"]["zero_x"]
    assert doc["thing"] is None and "a metric returns a number" in doc["metric_errors"]["thing"]
    assert doc["fine"] == pytest.approx(ts["x"].max())


def test_a_sweep_refuses_a_controller_that_fails_on_the_initial_state(tmp_path, capsys):
    from tt_mujoco import sweep

    spec = controller(tmp_path, "return None", 0.0)
    out = tmp_path / "s"
    argv = [f"controller={spec}", "duration=0.5", "plant=reduced", "--out", str(out)]
    assert sweep.main([*argv, "--quiet", "--no-figures"]) == 2
    err = capsys.readouterr().err
    assert "returned None at t=0.000 s" in err and err.count("\n") == 1
    assert not out.exists()


def test_a_sweep_whose_every_run_fails_exits_3_and_keeps_its_table(tmp_path, capsys):
    from tt_mujoco import sweep

    spec = controller(tmp_path, "raise ZeroDivisionError('late')", 0.2)
    out = tmp_path / "s"
    argv = [f"controller={spec}", "duration=0.5,0.6", "plant=reduced", "traj=circle"]
    assert sweep.main([*argv, "--out", str(out), "--quiet", "--no-figures", "--workers", "1"]) == 3
    err = capsys.readouterr().err
    assert "every run failed" in err and "ZeroDivisionError: late" in err
    assert (out / "runs.csv").exists()


def test_a_metric_that_returns_an_object_is_a_column_of_errors_in_a_sweep(tmp_path):
    from tt_mujoco import sweep

    path = tmp_path / "m.py"
    path.write_text("def thing(ts, path):\n    return object()\n")
    result = sweep.run_one({"duration": 0.3, "plant": "reduced", "metrics": f"{path}:thing"})
    assert result["status"] == "ok", result
    assert result["metrics"]["thing"] is None
    assert "a metric returns a number" in result["metrics"]["metric_errors.thing"]


def test_a_hung_controller_is_stopped_at_the_time_limit_with_its_rows(tmp_path, capsys):
    import time

    spec = controller(tmp_path, "import time; time.sleep(3600)", 0.2)
    start = time.monotonic()
    code, out, err = cli(tmp_path, capsys, "--controller", spec, "--time-limit", "1.5")
    assert time.monotonic() - start < 30
    assert code == 3 and "passed its time limit of 1.5 s" in err and "broken.py, line 10" in err
    ts = read_timeseries(out / "timeseries.parquet")
    assert len(ts["t"]) == 200
    assert "TimeLimitExceeded" in (out / run_outputs.ERROR_LOG).read_text()


def test_a_sweep_run_that_hangs_is_a_failed_row(tmp_path):
    from tt_mujoco import sweep

    spec = controller(tmp_path, "import time; time.sleep(3600)", 0.1)
    options = {"controller": spec, "duration": 0.5, "plant": "reduced", "time_limit_s": 1.0}
    result = sweep.run_one(options)
    assert result["status"] == "failed" and "time limit of 1 s" in result["message"]
    assert result["metrics"]["steps"] == 100


@pytest.mark.parametrize("value", ["0", "-1", "inf", "nan", "soon"])
def test_a_bad_time_limit_is_refused(tmp_path, capsys, value):
    code, out, err = cli(tmp_path, capsys, "--time-limit", value)
    assert code == 2 and "--time-limit" in err and value in err, err
    assert_nothing_left(out)


def test_a_sweep_whose_controller_file_goes_while_it_runs_still_writes_its_table(tmp_path):
    # The controller deletes its own file during the first run (as a user's clean-up would):
    # every run is journalled and the table is built from the journal, not from the file.
    from tt_mujoco import sweep

    path = tmp_path / "gone.py"
    path.write_text(
        "import os\n"
        "from tt_mujoco.controllers import Controller\n"
        "class Gone(Controller):\n"
        "    def compute(self, t, m, r):\n"
        "        if t >= 0.1 and os.path.exists(__file__):\n"
        "            os.remove(__file__)\n"
        "        return 0.5, 0.5\n"
    )
    out = tmp_path / "s"
    argv = [f"controller={path}:Gone", "duration=0.2,0.3", "plant=reduced", "traj=circle"]
    assert sweep.main([*argv, "--out", str(out), "--quiet", "--no-figures", "--workers", "1"]) == 0
    assert not path.exists()
    rows = (out / "runs.csv").read_text().splitlines()
    assert len(rows) == 3 and ",ok," in rows[1]  # the second run found no file: its error
    assert ",error," in rows[2] and "not found" in rows[2]


def test_sys_exit_inside_a_metric_is_that_metrics_error(tmp_path, capsys):
    path = tmp_path / "m.py"
    path.write_text("import sys\ndef m(ts, path):\n    sys.exit(0)\n")
    code, out, err = cli(tmp_path, capsys, "--metric", f"{path}:m")
    assert code == 0, err
    doc = json.loads((out / "metrics.json").read_text())
    assert doc["m"] is None and "it called sys.exit(0)" in doc["metric_errors"]["m"]


def test_a_huge_circle_on_a_short_run_costs_what_the_run_covers(tmp_path, capsys):
    # R = 1e9 m once asked for 9 TiB of polyline: the path is kept as far as the run can go.
    from tt_mujoco.outputs import REFERENCE_FILE

    code, out, err = cli(tmp_path, capsys, "--path-option", "R=1e9")
    assert code == 0, err
    line = read_timeseries(out / REFERENCE_FILE)
    assert 2 <= len(line["x"]) <= 20.0 / 0.005 + 2  # MAX_SPEED x 1 s at 5 mm


def test_logged_signals_are_columns_nan_where_a_step_logged_none(tmp_path, capsys):
    path = tmp_path / "logs.py"
    path.write_text(
        "from tt_mujoco.controllers import Controller\n"
        "class Logs(Controller):\n"
        "    def compute(self, t, m, r):\n"
        "        if t < 0.5:\n"
        "            self.log('early', t)\n"
        "        self.log('v_seen', m.v)\n"
        "        return 0.5, 0.5\n"
    )
    code, out, err = cli(tmp_path, capsys, "--controller", f"{path}:Logs")
    assert code == 0, err
    ts = read_timeseries(out / "timeseries.parquet")
    np.testing.assert_array_equal(ts["ctrl_v_seen"], ts["v_meas"])
    early = ts["ctrl_early"]
    np.testing.assert_array_equal(early[ts["t"] < 0.5], ts["t"][ts["t"] < 0.5])
    assert np.all(np.isnan(early[ts["t"] >= 0.5]))


@pytest.mark.parametrize(
    ("call", "said"),
    [
        ("self.log('bad name', 1.0)", "logged a signal named 'bad name'"),
        ("self.log('x', 'text')", "logged x='text'"),
    ],
)
def test_a_bad_logged_signal_is_named(tmp_path, capsys, call, said):
    code, out, err = cli(tmp_path, capsys, "--controller", controller(tmp_path, call, 0.0))
    assert code == 2 and said in err, err
    assert_nothing_left(out)
    later = tmp_path / "later"  # another file: a hook's module is imported once per path
    later.mkdir()
    code, out, err = cli(later, capsys, "--controller", controller(later, call, 0.2))
    assert code == 3 and said in err and "t=0.200 s" in err, err


def test_a_controller_logging_ever_new_names_stops_at_the_limit_with_its_rows(tmp_path, capsys):
    """A name made afresh at every step (an f-string with the time in it) would be a column
    as long as the run per step; the run stops as failed at the name past the limit."""
    from tt_mujoco.sim.usercode import MAX_SIGNALS

    path = tmp_path / "names.py"
    path.write_text(
        "from tt_mujoco.controllers import Controller\n"
        "class Names(Controller):\n"
        "    def compute(self, t, m, r):\n"
        "        self.log('kept', 1.0)\n"
        "        self.log(f'k{round(t * 1000)}', t)\n"
        "        return 0.5, 0.5\n"
    )
    code, out, err = cli(tmp_path, capsys, "--controller", f"{path}:Names")
    assert code == 3 and f"beyond the {MAX_SIGNALS} names a run may log" in err, err
    assert f"'k{MAX_SIGNALS - 1}'" in err  # 'kept' and k0..k98 fit; k99 is the 101st
    ts = read_timeseries(out / "timeseries.parquet")
    assert len([c for c in ts if c.startswith("ctrl_")]) == MAX_SIGNALS
    assert len(ts["t"]) == MAX_SIGNALS - 1  # the rows before the stop


def test_what_user_code_changes_in_the_path_it_is_given_changes_nothing_of_the_run(
    tmp_path, capsys
):
    # the controller (at the check before the run and in it) and each metric get copies
    path = tmp_path / "breaks.py"
    path.write_text(
        "from tt_mujoco.controllers import Controller\n\n"
        "class C(Controller):\n"
        "    def compute(self, t, m, r):\n"
        "        r.path.length, r.path.name = 0.0, 'broken'\n"
        "        return 0.1, 0.1\n\n"
        "def m(ts, path):\n"
        "    path.length = 0.0\n"
        "    return 1.0\n"
    )
    code, out, err = cli(tmp_path, capsys, "--controller", f"{path}:C", "--metric", f"{path}:m")
    assert code == 0, err
    clean, clean_out, _ = cli(tmp_path / "clean", capsys, "--controller", f"{path}:C")
    assert clean == 0
    kept = read_timeseries(out / "reference_path.parquet")
    again = read_timeseries(clean_out / "reference_path.parquet")
    assert all(np.array_equal(kept[k], again[k]) for k in kept)
    assert json.loads((out / "metrics.json").read_text())["m"] == 1.0


def test_the_check_before_the_run_leaves_a_stateful_disturbance_as_it_was(tmp_path, capsys):
    # the command checks the disturbance at t = 0 before the run (on a copy): the run's calls
    # are those of the Python API's run all the same
    from tt_mujoco.sim import Scenario, simulate

    path = tmp_path / "counting.py"
    path.write_text(
        "class Counting:\n"
        "    def __init__(self):\n        self.calls = 0\n\n"
        "    def __call__(self, t):\n"
        "        self.calls += 1\n"
        "        return 0.01 * min(self.calls, 50), 0.0\n"
    )
    spec = f"{path}:Counting"
    code, out, err = cli(tmp_path, capsys, "--disturbance-model", spec)
    assert code == 0, err
    cli_series = read_timeseries(out / "timeseries.parquet")
    options = {"disturbance_model": spec, "plant": "reduced", "traj": "circle", "duration": 1.0}
    api = simulate(Scenario(**options)).timeseries
    assert np.array_equal(cli_series["dist_T_r"], api["dist_T_r"])


VANDAL = """
import dataclasses

import numpy as np

from tt_mujoco.controllers import Controller


def _vandalise(obj, seen):
    # every field a controller can reach from its setup, frozen ones included, written over
    if id(obj) in seen or obj is None:
        return
    seen.add(id(obj))
    if isinstance(obj, np.ndarray):
        if obj.flags.writeable and obj.dtype.kind == "f":
            obj[...] = 0.0
        return
    names = [f.name for f in dataclasses.fields(obj)] if dataclasses.is_dataclass(obj) else []
    names += list(getattr(obj, "__dict__", {}))
    for name in names:
        value = getattr(obj, name, None)
        if isinstance(value, bool):
            continue
        if isinstance(value, int | float):
            try:
                object.__setattr__(obj, name, type(value)(123))
            except (AttributeError, TypeError):
                pass
        else:
            _vandalise(value, seen)


class C(Controller):
    VANDAL = False

    def compute(self, t, m, r):
        if self.VANDAL:
            _vandalise(self.setup, set())
        return 0.3 * (r.v_d - m.v) + 0.2, 0.3 * (r.v_d - m.v) + 0.25


class Vandal(C):
    VANDAL = True
"""


@pytest.mark.parametrize("traj", ["circle", "s_curve"])
def test_a_controller_that_writes_over_everything_it_was_given_changes_nothing_of_the_run(
    tmp_path, capsys, traj
):
    """Its setup (the nominal parameters, frozen or not, and the path with its arrays) is its
    own copy: the run's checks, its plant and its metrics read their own."""
    (tmp_path / "vandal.py").write_text(VANDAL)
    docs = []
    for name in ("C", "Vandal"):
        out = tmp_path / name
        argv = ["--controller", f"{tmp_path / 'vandal.py'}:{name}", "--plant", "reduced"]
        argv += ["--traj", traj, "--duration", "2", "--no-video", "--no-plots", "--quiet"]
        run.main([*argv, "--out", str(out)])
        doc = json.loads((out / "metrics.json").read_text())
        docs.append({k: v for k, v in doc.items() if k not in ("wall_time_s", "config")})
    capsys.readouterr()
    assert docs[1]["status"] == docs[0]["status"] and docs[1] == docs[0]

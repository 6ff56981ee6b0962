"""docs/robustness_study.md is what its command prints (sample rows re-run here)."""

import importlib.util
import math
from pathlib import Path

import pytest

from tt_mujoco.sim.parts.terrain import GRAVITY

DOCS = Path(__file__).resolve().parents[1] / "docs"


def _study():
    spec = importlib.util.spec_from_file_location("robustness", DOCS / "robustness_study.py")
    study = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(study)
    return study


def test_the_grade_is_delta_1s_bias():
    study = _study()
    assert GRAVITY * math.sin(math.radians(study.GRADE_DEG)) == pytest.approx(3.5, rel=1e-12)


@pytest.mark.parametrize(
    ("path", "case", "controller"),
    [
        ("cycloid", "grade 20.9 deg", "ISMC-STA"),
        ("cycloid", "20 ms sensor delay", "LQR"),
        ("cycloid", "DC motor, 20 ms, 20 A", "PID"),
    ],
)
def test_a_row_is_what_the_study_prints(path, case, controller):
    study = _study()
    line = "| " + " | ".join(study.row(path, case, controller)) + " |"
    section = (DOCS / "robustness_study.md").read_text().split(f"## {path}: {case}\n", 1)[1]
    assert line in section.split("\n## ", 1)[0]

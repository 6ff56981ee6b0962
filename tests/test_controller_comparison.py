"""docs/controller_comparison.md is what its command prints (sample rows re-run here)."""

import importlib.util
import re
from pathlib import Path

import pytest
from tt_mujoco.controllers import CONTROLLERS

DOCS = Path(__file__).resolve().parents[1] / "docs"


def _study():
    spec = importlib.util.spec_from_file_location("comparison", DOCS / "controller_comparison.py")
    study = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(study)
    return study


def _section(case: str) -> str:
    text = (DOCS / "controller_comparison.md").read_text()
    return text.split(f"## {case}\n", 1)[1].split("\n## ", 1)[0]


@pytest.mark.parametrize(
    ("case", "controller"),
    [
        ("S-curve, no disturbance", "NMPC"),
        ("circle, no disturbance", "LQR"),
        ("cycloid, paper disturbance (Table 3)", "ISMC-STA"),
        ("cycloid, paper disturbance (Table 3)", "pure pursuit"),
        ("S-curve backing up, no disturbance", "ISMC-STA"),
    ],
)
def test_a_row_is_what_the_study_prints(case, controller):
    study = _study()
    cells = study.row(case, controller, "reduced")
    # every figure but the three timings, which are this machine's
    line = "| " + " | ".join(cells[:-3]) + " | "
    assert line in _section(case)


def test_every_case_lists_every_controller_that_drives_it():
    study = _study()
    for case in study.CASES:
        rows = re.findall(r"^\| ([^|]+?) \| (mujoco|reduced) \|", _section(case), re.M)
        expected = {(name, plant) for name in study.CONTROLLERS for plant in ("mujoco", "reduced")}
        if "backing up" in case:  # the laws that drive forward only have no row
            forward_only = {
                name
                for name, kw in study.CONTROLLERS.items()
                if not CONTROLLERS[kw["controller"]].REVERSE
            }
            expected = {(n, p) for n, p in expected if n not in forward_only}
        assert set(rows) == expected


def _rows(case: str) -> dict:
    out = {}
    for line in _section(case).splitlines():
        cells = [c.strip() for c in line.strip("|").split("|")]
        if len(cells) > 2 and cells[1] in ("mujoco", "reduced"):
            out[(cells[0], cells[1])] = cells
    return out


def test_the_results_page_quotes_the_comparison():
    readme = (DOCS / "results.md").read_text()
    quoted = re.search(
        r"NMPC holds the tractor's cross-track error to ([\d.]+) mm rms\s+\(ISMC-STA ([\d.]+) mm, "
        r"LQR ([\d.]+) mm\) and solves its QP in a median ([\d.]+) ms of its 40 ms sample\s+"
        r"period: the run goes ([\d.]+) times faster",
        readme,
    )
    assert quoted, "the results page's baseline sentence changed: update this test with it"
    rows = _rows("S-curve, no disturbance")
    nmpc, ismc, lqr = (rows[(name, "mujoco")] for name in ("NMPC", "ISMC-STA", "LQR"))
    assert quoted.groups() == (nmpc[6], ismc[6], lqr[6], nmpc[10], nmpc[11])


def test_the_readme_headline_table_is_the_pages():
    readme = (DOCS.parent / "README.md").read_text()
    table = readme.split("## Headline results", 1)[1].split("\n## ", 1)[0]
    cases = ("cycloid, paper disturbance (Table 3)", "S-curve, no disturbance")
    cases += ("S-curve backing up, no disturbance",)
    pages = [_rows(case) for case in cases]
    lines = [line for line in table.splitlines() if line.startswith("| ") and "---" not in line]
    assert len(lines) == 1 + len(_study().CONTROLLERS)  # the header and every controller
    for line in lines[1:]:
        name, *cells = (c.strip() for c in line.strip("|").split("|"))
        name = name.replace(" (the paper's)", "")
        expected = [
            rows[(name, "mujoco")][6] if (name, "mujoco") in rows else "—" for rows in pages
        ]
        assert cells == expected, name


def test_the_readme_quotes_the_nmpc_timing_of_the_page():
    readme = (DOCS.parent / "README.md").read_text()
    quoted = re.search(
        r"The NMPC solves its QP in a median ([\d.]+) ms of its 40 ms sample period, and its "
        r"S-curve run goes\s+([\d.]+) times faster than real time",
        readme,
    )
    assert quoted, "the README's NMPC timing sentence changed: update this test with it"
    nmpc = _rows("S-curve, no disturbance")[("NMPC", "mujoco")]
    assert quoted.groups() == (nmpc[10], nmpc[11])

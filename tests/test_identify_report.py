"""tt_mujoco.identify_report: the identification's figures, and its Markdown as one HTML page
that says what the Markdown says, its figures inside."""

from __future__ import annotations

import base64
import json
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest

from tt_mujoco import identify
from tt_mujoco.identify_report import CORRELATION_PNG, REPLAY_PNG, SIMULATED_PNG, html_page
from tt_mujoco.outputs import write_timeseries
from tt_mujoco.sim import Scenario, simulate


class _Page(HTMLParser):
    """The tags, the table cells' text and the images' sources of a page."""

    def __init__(self):
        super().__init__()
        self.tags, self.cells, self.images, self.text = [], [], [], []
        self._cell = None

    def handle_starttag(self, tag, attrs):
        self.tags.append(tag)
        if tag in ("td", "th"):
            self._cell = ""
        if tag == "img":
            self.images.append(dict(attrs)["src"])

    def handle_endtag(self, tag):
        if tag in ("td", "th"):
            self.cells.append(self._cell)
            self._cell = None

    def handle_data(self, data):
        self.text.append(data)
        if self._cell is not None:
            self._cell += data


def _parsed(page: str) -> _Page:
    parser = _Page()
    parser.feed(page)
    parser.close()
    return parser


def test_the_page_holds_every_block_of_the_markdown_and_its_images():
    markdown = "\n".join(
        [
            "# Identified from log.csv",
            "",
            "| parameter | estimate |",
            "|---|---|",
            "| L_1 | 0.32 |",
            "| L0_1 | 0.42 |",
            "",
            "A paragraph with `code` and a <tag> that is text,",
            "over two lines.",
            "- a pair not told apart",
            "- another",
            "",
            "![fig.png](fig.png)",
            "![missing.png](missing.png)",
        ]
    )
    png = b"\x89PNG\r\n\x1a\n-not-a-real-image"
    page = _parsed(html_page(markdown, {"fig.png": png}, "t"))
    assert page.tags.count("h1") == 1 and page.tags.count("table") == 1
    assert page.cells == ["parameter", "estimate", "L_1", "0.32", "L0_1", "0.42"]
    assert page.tags.count("li") == 2 and "code" in page.tags
    assert any("a <tag> that is text, over two lines." in t for t in page.text)
    assert len(page.images) == 1  # an image with no file is left out
    assert base64.b64decode(page.images[0].split(",", 1)[1]) == png


@pytest.fixture(scope="module")
def identified(tmp_path_factory):
    folder = tmp_path_factory.mktemp("identify")
    ts = simulate(Scenario(traj="s_curve", plant="reduced", trailers=2, duration=8.0)).timeseries
    names = ["t", "v", "omega", "phi", "phi_2"]
    write_timeseries(folder / "log.csv", {k: ts[k] for k in names}, names)
    out = folder / "out"
    assert identify.main([str(folder / "log.csv"), "--out", str(out)]) == 0
    return out


def test_the_command_writes_the_report_as_html_with_the_figures_inside(identified):
    report = json.loads((identified / "identify.json").read_text())
    page = _parsed((identified / "identify.html").read_text())
    for name, estimate in report["estimates"].items():  # each one's row, as the Markdown's
        low, high = estimate["ci95"]
        row = page.cells.index(name)
        assert page.cells[row + 1 : row + 3] == [
            f"{estimate['value']:.6g}",
            f"{low:.6g} .. {high:.6g}",
        ], name
    markdown = (identified / "identify.md").read_text()
    figures = [REPLAY_PNG, CORRELATION_PNG]
    assert [f"![{name}]({name})" in markdown for name in figures] == [True, True]
    inside = [base64.b64decode(src.split(",", 1)[1]) for src in page.images]
    assert inside == [(identified / name).read_bytes() for name in figures]
    assert all(data.startswith(b"\x89PNG\r\n\x1a\n") for data in inside)


def test_the_replay_figure_draws_the_fits_own_replay(identified):
    """The replay drawn is the one whose rms error the report gives."""
    ts = simulate(Scenario(traj="s_curve", plant="reduced", trailers=2, duration=8.0)).timeseries
    phis = np.column_stack([ts["phi"], ts["phi_2"]])
    fit = identify.fit_train(
        ts["t"], ts["v"], ts["omega"], phis, Scenario(trailers=2).plant_params()
    )
    rms = np.sqrt(np.nanmean((fit.replayed - fit.logged) ** 2, axis=0))
    np.testing.assert_array_equal(rms, fit.replay_rms)
    report = json.loads((identified / "identify.json").read_text())
    assert report["replay_phi_rms_deg"] == pytest.approx(np.degrees(rms), rel=1e-9)


def test_a_fit_of_a_mass_draws_the_train_simulated_from_the_torques(tmp_path):
    """With torques in the log and a mass to fit, the report draws the log's v and omega
    against the fitted train's, and every figure is inside the page."""
    weave = str(Path(__file__).resolve().parents[1] / "examples" / "weave_surge.csv")
    scenario = Scenario(traj=weave, plant="reduced", disturbance="none", duration=20)
    ts = simulate(scenario).timeseries
    names = ["t", "v", "omega", "phi", "T_r", "T_l"]
    write_timeseries(tmp_path / "log.csv", {k: ts[k] for k in names}, names)
    out = tmp_path / "out"
    assert identify.main([str(tmp_path / "log.csv"), "--fit", "L,L0,Mr", "--out", str(out)]) == 0
    figures = [REPLAY_PNG, SIMULATED_PNG, CORRELATION_PNG]
    page = _parsed((out / "identify.html").read_text())
    inside = [base64.b64decode(src.split(",", 1)[1]) for src in page.images]
    assert inside == [(out / name).read_bytes() for name in figures]

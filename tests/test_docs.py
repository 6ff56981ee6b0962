"""What the README and the documentation point a reader to exists.

The pages are found, not listed: every Markdown file of the README, ``docs/`` and
``examples/``. A path in backticks under one of the repository's top-level folders names a file
or folder of the checkout (``controllers/plain.py``, not the installed
``tt_mujoco/controllers/plain.py``, which a reader of the repository cannot open); outputs under
``renders/`` that a command makes, and placeholders in capitals (``benchmarks/BENCH.py``), are
not checked.
"""

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = sorted(
    [ROOT / "README.md", *(ROOT / "docs").glob("*.md"), *(ROOT / "examples").rglob("*.md")]
)
FOLDERS = ("tt_mujoco", "controllers", "tests", "benchmarks", "docs", "examples", "models")
PATH = re.compile(rf"`((?:{'|'.join(FOLDERS)})/[\w./-]*)`")


def _named_paths(page: Path):
    for match in PATH.finditer(page.read_text()):
        path = match.group(1).rstrip("/.")
        if re.search(r"/[A-Z][A-Z_]*(\.|/|$)", path):  # a placeholder: benchmarks/BENCH.py
            continue
        yield page.read_text()[: match.start()].count("\n") + 1, path


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_repository_path_a_page_names_exists(page):
    missing = [(line, path) for line, path in _named_paths(page) if not (ROOT / path).exists()]
    assert not missing, f"{page.relative_to(ROOT)} names paths the checkout lacks: {missing}"


def test_the_check_finds_what_it_is_for():
    # the case it was written for: the installed package's path of a repository file
    assert not (ROOT / "tt_mujoco/controllers/plain.py").exists()
    assert PATH.search("see `tt_mujoco/controllers/plain.py`").group(1).endswith("plain.py")


def test_the_synopsis_on_the_getting_started_page_is_the_parsers():
    # written by hand it fell behind the options and the registries (smc, --trailers, ...);
    # it is the parser's own usage, so a new option or controller fails here until the page
    # is regenerated (python -c "from tt_mujoco import run; print(run.usage(), end='')")
    from tt_mujoco import run

    page = (ROOT / "docs" / "getting-started.md").read_text()
    block = page.split("## The main command\n\n```\n", 1)[1].split("```\n", 1)[0]
    assert block == run.usage()
    from tt_mujoco.controllers import CONTROLLERS

    assert all(name in block for name in CONTROLLERS)

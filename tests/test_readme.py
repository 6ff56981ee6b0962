"""Every quick command block of the README and the docs runs as printed (python-control runs
its examples).

A block is run unless an HTML comment right above it says ``readme-test: skip: REASON``;
``readme-test: last command`` runs only the last ``&&`` part (the install is CI's own step). A
TOML or Python block whose first line is ``# path/file.toml`` (``.py``) is written to that path
first instead of being run (or, for a file the repository ships, must equal it). Everything runs
in a fresh folder per document with the repository's ``examples/``, so nothing lands in the
checkout.
"""

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
BLOCK = re.compile(r"(?:<!-- readme-test: ([^>]*?) -->\n)?```(bash|python|toml)\n(.*?)```", re.S)
#: The documents whose blocks run (every page of the README and docs/, found, not listed), and
#: how many blocks some must run at least.
DOCUMENTS = {
    **{str(p.relative_to(ROOT)): 0 for p in sorted((ROOT / "docs").glob("*.md"))},
    "README.md": 2,
    "docs/controllers.md": 4,
    "docs/extending.md": 1,
    "docs/scenarios.md": 3,
    "docs/trains.md": 1,
}


def _file_name(kind: str, body: str) -> str | None:
    """The path a block is written to (``# path/file.toml`` or ``.py`` first line), or None."""
    first = body.splitlines()[0] if body.strip() else ""
    suffix = {"toml": ".toml", "python": ".py"}.get(kind)
    if suffix and first.startswith("# ") and first.endswith(suffix) and " " not in first[2:]:
        return first[2:].strip()
    return None


def _blocks():
    out = []
    for doc in DOCUMENTS:
        text = (ROOT / doc).read_text()
        for m in BLOCK.finditer(text):
            line = text[: m.start(2)].count("\n") + 1
            out.append((doc, line, m.group(1) or "", m.group(2), m.group(3)))
    return out


BLOCKS = _blocks()
RUN = [
    b
    for b in BLOCKS
    if b[3] != "toml" and not b[2].startswith("skip") and not _file_name(b[3], b[4])
]


def test_a_file_block_of_a_shipped_file_is_that_file():
    # A block headed by a file the repository ships (examples/icy_circle.toml) is shown as it
    # is, so the commands beside it work as printed from a checkout.
    shipped = [(doc, line, _file_name(kind, body), body) for doc, line, _, kind, body in BLOCKS]
    shipped = [(doc, line, name, body) for doc, line, name, body in shipped if name]
    shipped = [b for b in shipped if (ROOT / b[2]).exists()]
    assert shipped, "the README shows examples/icy_circle.toml"
    for doc, line, name, body in shipped:
        assert (ROOT / name).read_text() == body, f"{doc} line {line}: {name} differs"


def test_every_block_is_run_or_says_why_not():
    for doc, line, marker, kind, body in BLOCKS:
        if kind == "toml" or _file_name(kind, body):
            continue
        assert marker in ("", "last command") or re.match(r"skip: \S", marker), (doc, line)
    # the README: the main job, the extension examples, the TOML scenario, the Gym snippet
    for doc, least in DOCUMENTS.items():
        assert len([b for b in RUN if b[0] == doc]) >= least, doc


@pytest.fixture(scope="module")
def workdirs(tmp_path_factory):
    folders = {}
    for doc in DOCUMENTS:
        folder = tmp_path_factory.mktemp(Path(doc).stem)
        (folder / "examples").symlink_to(ROOT / "examples")
        for block_doc, _, _, kind, body in BLOCKS:
            name = _file_name(kind, body)
            if block_doc == doc and name and not (ROOT / name).exists():
                path = folder / name
                path.parent.mkdir(parents=True, exist_ok=True)
                path.write_text(body)
        folders[doc] = folder
    return folders


@pytest.mark.parametrize(
    ("doc", "line", "marker", "kind", "body"),
    RUN,
    ids=lambda v: str(v) if isinstance(v, int) else (v if v in DOCUMENTS else ""),
)
def test_block_runs(workdirs, doc, line, marker, kind, body):
    env = {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}"}
    env["MPLBACKEND"] = "Agg"
    if kind == "python":
        cmd = [sys.executable, "-c", body]
    else:
        script = body.split("&&")[-1].strip() if marker == "last command" else body
        cmd = ["bash", "-e", "-c", script]
    proc = subprocess.run(
        cmd, cwd=workdirs[doc], env=env, capture_output=True, text=True, timeout=300
    )
    assert proc.returncode == 0, f"{doc} line {line}: {proc.stderr[-2000:]}"

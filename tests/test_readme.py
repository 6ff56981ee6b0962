"""Every quick command block of the README runs as printed (python-control runs its examples).

A block is run unless an HTML comment right above it says ``readme-test: skip: REASON``;
``readme-test: last command`` runs only the last ``&&`` part (the install is CI's own step). A
TOML block whose first line is ``# path/file.toml`` is written to that path first. Everything
runs in a fresh folder with the repository's ``examples/``, so nothing lands in the checkout.
"""

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
BLOCK = re.compile(r"(?:<!-- readme-test: ([^>]*?) -->\n)?```(bash|python|toml)\n(.*?)```", re.S)


def _blocks():
    text = (ROOT / "README.md").read_text()
    out = []
    for m in BLOCK.finditer(text):
        line = text[: m.start(2)].count("\n") + 1
        out.append((line, m.group(1) or "", m.group(2), m.group(3)))
    return out


BLOCKS = _blocks()


def test_every_block_is_run_or_says_why_not():
    for line, marker, kind, _ in BLOCKS:
        if kind == "toml":
            continue
        assert marker in ("", "last command") or re.match(r"skip: \S", marker), (line, marker)
    # the main job, the extension examples, the TOML scenario, the Gym snippet
    assert len([b for b in BLOCKS if not b[1].startswith("skip") and b[2] != "toml"]) >= 4


@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    folder = tmp_path_factory.mktemp("readme")
    (folder / "examples").symlink_to(ROOT / "examples")
    for _, _, kind, body in BLOCKS:
        first = body.splitlines()[0]
        if kind == "toml" and first.startswith("# ") and first.endswith(".toml"):
            path = folder / first[2:].strip()
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(body)
    return folder


@pytest.mark.parametrize(
    ("line", "marker", "kind", "body"),
    [b for b in BLOCKS if b[2] != "toml" and not b[1].startswith("skip")],
    ids=lambda v: str(v) if isinstance(v, int) else "",
)
def test_readme_block_runs(workdir, line, marker, kind, body):
    env = {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}"}
    env["MPLBACKEND"] = "Agg"
    if kind == "python":
        cmd = [sys.executable, "-c", body]
    else:
        script = body.split("&&")[-1].strip() if marker == "last command" else body
        cmd = ["bash", "-e", "-c", script]
    proc = subprocess.run(cmd, cwd=workdir, env=env, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, f"README line {line}: {proc.stderr[-2000:]}"

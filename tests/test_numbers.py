"""Numbers that cannot go stale: every figure quoted on the front pages is in the file a command
of the repository wrote.

A quoted figure stands in a paragraph or table headed by ``<!-- numbers: FILE[, FILE] -->``;
every decimal number in it (outside inline code) must appear, as written, in one of the FILEs.
A FILE is a generated page (its "Written by `python ...`" line names the command), a
benchmark's recorded output (``benchmarks/record.py``, whose first line is the command), a
test that asserts the figure, or the module that defines it (a constant such as Delta_1's).
On every page but a command's output, every decimal number outside code must stand in such a
block.
"""

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
MARKER = re.compile(r"<!-- numbers: (.+?) -->")
#: A figure: a decimal number, a number in scientific notation or one with thousands separators.
FIGURE = re.compile(
    r"(?<![\w.,])-?(?:\d+(?:\.\d+)?e[-+]?\d+|\d{1,3}(?:,\d{3})+(?:\.\d+)?|\d+\.\d+)"
    r"(?!\.\d|[0-9_A-Za-wyz])"
)
#: What is not a figure: versions of the tools named, and numbered sections and equations.
NOT_FIGURES = re.compile(r"Python 3\.\d+|(?:Sections?|Tables?|eqs?\.|Appendix) \d+(?:\.\d+)*")


def _prose(line: str) -> str:
    """A line without its inline code and link targets."""
    line = re.sub(r"`[^`]*`", " ", line)
    return re.sub(r"\]\([^)]*\)", "]", line)


def blocks(text: str):
    """(source files, first line number, lines) of each marked block, and the lines outside
    code and blocks with their numbers."""
    marked, loose = [], []
    lines = text.splitlines()
    fenced = False
    k = 0
    while k < len(lines):
        line = lines[k]
        if line.startswith("```"):
            fenced = not fenced
            k += 1
            continue
        found = MARKER.search(re.sub(r"`[^`]*`", " ", line))  # a marker shown as code is text
        if found and not fenced:
            sources = [s.strip() for s in found.group(1).split(",")]
            k += 1
            while k < len(lines) and MARKER.search(lines[k]):  # markers in a row: one block
                sources += [s.strip() for s in MARKER.search(lines[k]).group(1).split(",")]
                k += 1
            start, body = k, []
            while k < len(lines) and lines[k].strip():
                body.append(lines[k])
                k += 1
            marked.append((sources, start + 1, body))
            continue
        if not fenced:
            # The previous line's last word joins it: "Section" may end one line, "6.1" begin the
            # next.
            loose.append((k + 1, _with_tail(lines[k - 1] if k else "", line)))
        k += 1
    return marked, loose


def figures(line: str) -> list[str]:
    return FIGURE.findall(NOT_FIGURES.sub(" ", _prose(line)))


def _with_tail(previous: str, line: str) -> str:
    """``line`` after the previous line's last word when that is a word ("Section" may end one
    line and "6.1" begin the next)."""
    tail = previous.split()[-1:]
    return f"{tail[0]} {line}" if tail and tail[0].rstrip(".").isalpha() else line


def _joined(body: list[str]) -> list[str]:
    """Each line of a block after the previous one's last word (:func:`_with_tail`)."""
    return [_with_tail(body[i - 1] if i else "", line) for i, line in enumerate(body)]


def _source_figures(path: Path) -> set[str]:
    text = path.read_text()
    text = re.sub(r"(?<=\d)_(?=\d{3})", ",", text)  # Python's 1_200_000 is the page's 1,200,000
    return set(FIGURE.findall(text))


def _all_pages():
    return [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


@pytest.mark.parametrize("page", _all_pages(), ids=lambda p: p.name)
def test_every_quoted_figure_is_in_its_source(page):
    marked, _ = blocks(page.read_text())
    for sources, line_no, body in marked:
        known: set[str] = set()
        for name in sources:
            source = ROOT / name
            assert source.is_file(), f"{page.name}:{line_no}: source {name} does not exist"
            # A test asserts its numbers; a module of the package defines its constants.
            if source.parts[len(ROOT.parts)] not in ("tests", "tt_mujoco", "controllers"):
                head = source.read_text()[:4000]
                assert "python " in head, f"{name} does not say which command wrote it"
            known |= _source_figures(source)
        for offset, line in enumerate(_joined(body)):
            for figure in figures(line):
                assert figure in known, (
                    f"{page.name}:{line_no + offset}: {figure} is not in {', '.join(sources)}"
                )


@pytest.mark.parametrize("page", _all_pages(), ids=lambda p: p.name)
def test_every_figure_on_a_page_has_a_source(page):
    text = page.read_text()
    if "Written by `python" in text:
        return  # the page is a command's output: its figures are that command's
    _, loose = blocks(text)
    unsourced = [(n, f) for n, line in loose for f in figures(line) if "<!--" not in line]
    assert not unsourced, (
        f"{page.name}: figures without a <!-- numbers: FILE --> source: {unsourced}"
    )


def test_the_marker_reader_finds_blocks_and_figures():
    text = "a 1.5 b\n<!-- numbers: x.txt -->\n| 2.25 | 1,200 |\n| `3.5` |\n\nc 4.75\n"
    marked, loose = blocks(text)
    assert marked == [(["x.txt"], 3, ["| 2.25 | 1,200 |", "| `3.5` |"])]
    assert [f for _, line in loose for f in figures(line)] == ["1.5", "4.75"]
    assert figures("Python 3.11, 0.88-0.91 of it, 3.2x, v0.6 run_2.5") == ["0.88", "0.91", "3.2"]

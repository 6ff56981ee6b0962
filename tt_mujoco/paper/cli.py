"""``python -m tt_mujoco.paper``: the command line."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from tt_mujoco import guard
from tt_mujoco.cliargs import BadInputError, Parser, integer_at_least
from tt_mujoco.defaults import EXIT_BAD_INPUT, EXIT_INTERRUPTED, EXIT_OK
from tt_mujoco.outputs import atomic_write, claim_folder, release_folder, remove_if_empty
from tt_mujoco.paper.execute import run_suite
from tt_mujoco.paper.report import build_report
from tt_mujoco.paper.suite import COMMAND, DEFAULT_OUT, suite
from tt_mujoco.runfolder import check_out


# --- command line -------------------------------------------------------------------------------
def build_parser() -> argparse.ArgumentParser:
    p = Parser(
        prog=COMMAND,
        description=(
            "Run every scenario behind the paper's Tables 1-5 on the reduced model and MuJoCo, "
            "with isolation runs, a passive-steering study and a path-feedback study, and write "
            "report.md, report.json, summary.md and figures."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    p.add_argument(
        "--out",
        type=Path,
        default=None,
        metavar="DIR",
        help="output folder, new or empty (default: renders/paper, or renders/paper-N if taken)",
    )
    p.add_argument(
        "--workers", type=integer_at_least("--workers", 1), default=2, help="worker processes"
    )
    p.add_argument("--quick", action="store_true", help="a reduced set of short runs (smoke test)")
    p.add_argument("--no-figures", action="store_true", help="skip the PNG figures")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument(
        "--docs-page",
        default=None,
        metavar="FILE",
        help="also write the summary as this documentation page (docs/paper.md), replacing it",
    )
    return p


def docs_page(summary: str, command: str) -> str:
    """The summary as a page of its own: its headings one level up, and the command that
    wrote it."""
    lines = [line[1:] if line.startswith("##") else line for line in summary.splitlines()]
    return "\n".join(lines).rstrip() + f"\n\nWritten by `{command}`.\n"


@guard.command
def main(argv: list[str] | None = None) -> int:
    """Exit 0 done, 2 bad input, 1 if a run raised an error (it is in the report)."""
    try:
        args = build_parser().parse_args(argv)
        if args.docs_page is not None:  # a page of Markdown, never a run's file
            check_out(Path(args.docs_page), ".md", "--docs-page")
            if not Path(args.docs_page).parent.is_dir():
                raise BadInputError(
                    f"--docs-page {args.docs_page!r} is not allowed: its folder does not exist"
                )
        out, _ = claim_folder(args.out, DEFAULT_OUT)  # before the suite: a bad --out fails now
    except (BadInputError, ValueError) as err:
        print(f"error: {err}", file=sys.stderr)
        return EXIT_BAD_INPUT
    specs = suite(quick=args.quick)
    start = time.perf_counter()
    try:
        records = run_suite(specs, workers=args.workers, progress=not args.quiet)
    except KeyboardInterrupt:
        remove_if_empty(out)
        print("interrupted: the suite was abandoned; nothing was written", file=sys.stderr)
        return EXIT_INTERRUPTED
    wall = time.perf_counter() - start
    info = {
        "command": COMMAND + (" --quick" if args.quick else ""),
        "runs": len(specs),
        "unique_runs": len({r["same_as"] for r in records.values()}),
        "workers": args.workers,
        "wall_time_s": wall,
    }
    report = build_report(records, out, info, figures=not args.no_figures)
    if args.docs_page is not None:
        command = f"{info['command']} --docs-page {args.docs_page}"
        atomic_write(Path(args.docs_page), docs_page((out / "summary.md").read_text(), command))
    release_folder(out)
    errors = [k for k, r in records.items() if r.get("status") == "error"]
    print(f"report: {report} ({len(specs)} runs in {wall:.1f} s)")
    if errors:
        print(f"{len(errors)} run(s) failed, see the report: {', '.join(errors)}", file=sys.stderr)
        return 1
    return EXIT_OK

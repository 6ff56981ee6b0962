"""``python -m tt_mujoco.validate``: MuJoCo against the reduced model, as a report."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from tt_mujoco.analysis.validate import DEFAULT_OUT, run_all, validation_markdown
from tt_mujoco.outputs import OutputError, atomic_write, claim_folder, write_json


def main(argv: list[str] | None = None) -> int:
    """Exit 0 written, 2 a used or unwritable ``--out`` (refused before the checks run)."""
    parser = argparse.ArgumentParser(
        prog="python -m tt_mujoco.validate",
        description="Check the MuJoCo model against the analytic reduced model. Writes "
        "report.md and report.json into a new folder (never into one with files in it).",
    )
    parser.add_argument(
        "--out", type=Path, default=None, help=f"output folder (default: a new {DEFAULT_OUT}[-N])"
    )
    args = parser.parse_args(argv)
    try:
        out, _ = claim_folder(args.out, DEFAULT_OUT)
    except OutputError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    results = run_all()
    write_json(out / "report.json", results)
    text = validation_markdown(results)
    atomic_write(out / "report.md", text + "\n")
    print(text)
    print(f"\nwrote {out / 'report.md'} and {out / 'report.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

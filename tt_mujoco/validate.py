"""``python -m tt_mujoco.validate``: MuJoCo against the reduced model, as a report."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from tt_mujoco.analysis.validate import DEFAULT_OUT, _markdown, run_all


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m tt_mujoco.validate",
        description="Check the MuJoCo model against the analytic reduced model.",
    )
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT, help="output folder")
    args = parser.parse_args(argv)
    results = run_all()
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "report.json").write_text(json.dumps(results, indent=2) + "\n")
    text = _markdown(results)
    (args.out / "report.md").write_text(text + "\n")
    print(text)
    print(f"\nwrote {args.out / 'report.md'} and {args.out / 'report.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

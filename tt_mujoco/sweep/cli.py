"""``python -m tt_mujoco.sweep``: the command line."""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

from tt_mujoco import guard
from tt_mujoco.cliargs import BadInputError, Parser
from tt_mujoco.defaults import EXIT_BAD_INPUT, EXIT_DIVERGED, EXIT_INTERRUPTED, EXIT_OK
from tt_mujoco.executor import ExecutorError
from tt_mujoco.outputs import free_name
from tt_mujoco.sweep.execute import Resume, run_sweep
from tt_mujoco.sweep.options import (
    DICT_OPTIONS,
    JOURNAL,
    KEY_METRICS,
    RENDERS,
    SCALABLE,
    SCENARIO_OPTIONS,
    SETTABLE,
    SPEC_FILE,
    BadSpecError,
)
from tt_mujoco.sweep.runs import expand
from tt_mujoco.sweep.spec import parse_spec
from tt_mujoco.sweep.tables import summary_text
from tt_mujoco.world.plan import NO_PLAN, START_REFUSED

# --- command line ------------------------------------------------------------------------------
_DICT_HELP = "".join(
    f"  {n:<16} on (its defaults), off, or {n}.<key>=x for one entry (implies on)\n"
    for n in DICT_OPTIONS
)


EPILOG = f"""\
options (OPTION=VALUES):
  Scenario fields: {", ".join(SCENARIO_OPTIONS)}
  gain.<name>      a controller gain, e.g. gain.k1_v (ISMC-STA), gain.kp_v (PID)
  scale.<field>    Params default times the factor; field one of {", ".join(SCALABLE)}
  param.<field>    a Params value; field one of {", ".join(SETTABLE)}
{_DICT_HELP}  faults           one fault spec per value, several in a run joined by ";" (e.g.
                   faults="payload:t=2,factor=1.5"); on the command line a single value,
                   several values as a list in a --config TOML file; "none" for no faults
VALUES:
  5                 fixed          5,10,20          a list
  lin:0.8:1.2:5     5 evenly spaced values, ends included
  log:1:100:3       geometric      range:0:10       integers 0..9
  uniform:A:B  loguniform:A:B  normal:MEAN:STD       random mode (--samples) only
example:
  python -m tt_mujoco.sweep traj=s_curve duration=10 noise_snr_db=20 \\
      gain.k1_v=5,10,20 scale.Mr=lin:0.8:1.2:3 --repeats 4 --workers 2 --out renders/sweep1
"""


def build_parser() -> argparse.ArgumentParser:
    p = Parser(
        prog="python -m tt_mujoco.sweep",
        description=(
            "Run a grid or random sweep of closed-loop runs in parallel and write one table "
            "(runs.csv: configuration and metrics of every run), a summary and figures."
        ),
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("items", nargs="*", metavar="OPTION=VALUES", help="options (see below)")
    p.add_argument("--config", type=Path, metavar="FILE.toml", help="sweep specification file")
    p.add_argument("--repeats", type=int, default=None, help="grid: runs per point (default 1)")
    p.add_argument("--samples", type=int, default=None, help="random sampling: number of runs")
    p.add_argument("--seed", type=int, default=None, help="sweep seed (default 0)")
    p.add_argument(
        "--out",
        type=Path,
        default=None,
        metavar="DIR",
        help="output folder (default: a new folder under renders/)",
    )
    p.add_argument(
        "--resume",
        action="store_true",
        help="continue the sweep in --out (without options: with its saved spec)",
    )
    p.add_argument(
        "--retry-errors",
        action="store_true",
        help="with --resume: run again the runs that ended with status 'error'",
    )
    p.add_argument(
        "--extend",
        action="store_true",
        help="with --resume: the sweep's options changed (more values or samples); run the new "
        "runs and reuse the finished ones (without it a changed sweep is refused)",
    )
    p.add_argument(
        "--workers", type=int, default=None, help="worker processes (default: the CPU count)"
    )
    p.add_argument(
        "--scheduler",
        default=None,
        metavar="ADDRESS",
        help="Dask scheduler address, or 'local' for a LocalCluster",
    )
    p.add_argument("--metric", default="rmse_lateral", help="metric of the scatter figure")
    p.add_argument("--no-figures", action="store_true", help="skip the PNG figures")
    p.add_argument("--dry-run", action="store_true", help="check the sweep and list its runs")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    return p


def _checked_workers(args) -> int:
    """The worker count, once the options that only make sense together are checked: a
    conflict or an option that would be ignored is refused, not resolved in silence."""
    workers = args.workers if args.workers is not None else (os.cpu_count() or 1)
    if workers < 1:
        raise BadSpecError(f"--workers {workers} is not allowed: it must be >= 1")
    if args.workers is not None and args.scheduler is not None:
        raise BadSpecError(
            f"--workers {args.workers} is not allowed with --scheduler {args.scheduler!r}: "
            "the scheduler's cluster has its own workers; give one of them"
        )
    for flag, name in (("--extend", "extend"), ("--retry-errors", "retry_errors")):
        if getattr(args, name) and not args.resume:  # it would be ignored in silence
            raise BadSpecError(f"{flag} is not allowed without --resume: it changes a resume")
    if args.resume and args.out is None:
        raise BadSpecError("--resume needs --out DIR, the folder of the sweep to continue")
    return workers


def _unwritable(err: OSError, out: Path | None) -> str:
    """What a sweep whose files cannot be written says: the file, why, and how to go on."""
    named = err.filename2 or err.filename  # a replace's target, not its temporary file
    where = f"{named}: " if named else ""
    kept = (
        f"; its finished runs are kept in {out / JOURNAL}: make room and continue with "
        f"python -m tt_mujoco.sweep --resume --out {out}"
        if out is not None
        else ""
    )
    return f"the sweep's files cannot be written ({where}{err.strerror or err}){kept}"


@guard.command
def main(argv: list[str] | None = None) -> int:
    out = None
    try:
        args = build_parser().parse_args(argv)
        workers = _checked_workers(args)
        config = args.config
        if args.resume and not args.items and config is None:
            config = args.out / SPEC_FILE
            if not config.exists():
                raise BadSpecError(f"--out {str(args.out)!r} holds no {SPEC_FILE} to resume")
        spec = parse_spec(args.items, config, args.seed, args.repeats, args.samples)
        if not spec.axes and args.samples is None and args.repeats is None:
            raise BadSpecError(
                "nothing to sweep: give options as OPTION=VALUES, --repeats N, --samples N or "
                "--config FILE.toml (see --help)"
            )
        noise = spec.axis("noise_snr_db")
        if spec.mode == "grid" and spec.repeats > 1 and (noise is None or None in noise.values):
            print(
                "note: repeats differ only in the noise seed; runs without noise_snr_db are "
                "identical copies",
                file=sys.stderr,
            )
        if args.dry_run:
            runs = expand(spec)
            for run in runs:
                print(run["index"], run["run_id"], json.dumps(run["options"]))
            print(f"{len(runs)} runs ({spec.mode})")
            return EXIT_OK
        out = args.out
        if out is None:
            out = free_name(RENDERS / f"sweep-{time.strftime('%Y%m%d-%H%M%S')}")
        result = run_sweep(
            spec,
            out,
            workers=workers,
            scheduler=args.scheduler,
            resume=args.resume and Resume(retry_errors=args.retry_errors, extend=args.extend),
            quiet=args.quiet,
            metric=args.metric,
            figures=not args.no_figures,
        )
    except (BadSpecError, BadInputError, ExecutorError) as err:
        print(f"error: {err}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except OSError as err:  # a full disk, a quota, a folder where a table goes
        if err.errno not in guard.REFUSALS:
            raise  # not the file system's refusal: the guard says it is a bug of ours
        print(f"error: {_unwritable(err, out)}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        said = (
            f"finished runs are in {out / JOURNAL}; continue with python -m tt_mujoco.sweep "
            f"--resume --out {out}"
            if out is not None
            else "nothing was written"
        )
        print(f"\ninterrupted: {said}", file=sys.stderr)
        return EXIT_INTERRUPTED
    metric_names = [m for m in dict.fromkeys([*KEY_METRICS, args.metric])]
    print(summary_text(result.summary, metric_names))
    ran = len(result.rows) - result.reused
    rate = f", {ran / result.wall_s:.2f} runs/s" if ran else ""
    print(
        f"{len(result.rows)} runs ({result.reused} reused) in {result.wall_s:.1f} s{rate}; "
        f"wrote {', '.join(p.name for p in result.files)} to {result.out}/"
    )
    failed = [
        r for r in result.rows if r.get("status") in ("error", "failed", NO_PLAN, START_REFUSED)
    ]
    if result.rows and len(failed) == len(result.rows):
        first = failed[0].get("error") or failed[0].get("message") or ""
        print(
            f"error: every run failed (the first: {first}); runs.csv has each one's error",
            file=sys.stderr,
        )
        return EXIT_DIVERGED
    return EXIT_OK

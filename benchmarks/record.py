"""Run a benchmark (or a study) and keep what it printed: the file the docs quote it from.

    python benchmarks/record.py [--runs 2] bench_cli.py [ARGS ...]
    python benchmarks/record.py --runs 1 docs/backing_study.py [ARGS ...]
    python benchmarks/record.py --runs 1 tt_mujoco.validate [ARGS ...]

runs ``python benchmarks/BENCH ARGS`` (a script named with its folder: that script; a dotted
name without ``.py``: ``python -m`` that module) ``--runs`` times, one after the other, and
writes ``benchmarks/results/<script>[--<args>].txt``:
the command, the machine (cores, CPU, Python, MuJoCo and numba versions, the date) and each
run's output. A page that quotes a figure names
this file in a ``<!-- numbers: ... -->`` marker, and ``tests/test_numbers.py`` fails when the
figure is not in it, so re-recording a benchmark shows every page whose figures moved.
"""

from __future__ import annotations

import argparse
import os
import platform
import re
import subprocess
import sys
import time
from importlib.metadata import version
from pathlib import Path

HERE = Path(__file__).resolve().parent
RESULTS = HERE / "results"


def result_file(bench: str, args: list[str]) -> Path:
    """Where the output of ``bench`` with ``args`` is kept."""
    slug = re.sub(r"[^A-Za-z0-9_.=-]+", "_", "_".join(a.lstrip("-") for a in args)).strip("_")
    stem = bench.removesuffix(".py").replace("/", "_")
    return RESULTS / (Path(stem).name + (f"--{slug}" if slug else "") + ".txt")


def machine() -> str:
    """One line about the machine and the versions that set the figures."""
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return (
        f"{platform.system()} {platform.machine()}, {os.cpu_count()} cores ({cpu}), "
        f"Python {platform.python_version()}, mujoco {version('mujoco')}, "
        f"numba {version('numba')}"
    )


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--runs", type=int, default=2, help="how many runs (default 2)")
    p.add_argument("bench", help="a script in benchmarks/, e.g. bench_cli.py")
    p.add_argument("args", nargs=argparse.REMAINDER, help="its arguments")
    a = p.parse_args(argv)
    named = Path(a.bench)
    module = a.bench if named.suffix != ".py" and a.bench.replace(".", "").isidentifier() else None
    script = (HERE.parent / named) if named.parent != Path() else HERE / named
    if (module is None and (script.suffix != ".py" or not script.is_file())) or a.runs < 1:
        print(
            f"error: {a.bench!r} is not a script of the repository (give bench_X.py, "
            "FOLDER/SCRIPT.py or a module such as tt_mujoco.validate), or --runs < 1",
            file=sys.stderr,
        )
        return 2
    target = ["-m", module] if module else [str(script)]
    shown = ["-m", module] if module else [str(script.relative_to(HERE.parent))]
    command = " ".join(["python", *shown, *a.args])
    lines = [f"# {command}  ({a.runs} runs)", f"# {machine()}", f"# {time.strftime('%Y-%m-%d')}"]
    for k in range(1, a.runs + 1):
        done = subprocess.run(
            [sys.executable, *target, *a.args], capture_output=True, text=True, check=False
        )
        if done.returncode != 0:
            print(done.stdout + done.stderr, file=sys.stderr)
            print(f"error: run {k} of {command} exited {done.returncode}", file=sys.stderr)
            return 1
        lines += [f"## run {k}", done.stdout.rstrip()]
        print(done.stdout, end="")
    out = result_file(module or script.name, a.args)
    out.parent.mkdir(exist_ok=True)
    temporary = out.with_suffix(".partial")
    temporary.write_text("\n".join(lines) + "\n")
    temporary.replace(out)  # whole or not at all
    print(f"wrote {out.relative_to(HERE.parent)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

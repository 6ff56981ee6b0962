"""One run of ``python -m tt_mujoco.run`` with a user's file of hooks, for the generated
matrices of user code (tests/test_guard.py, tests/test_returns.py)."""

from __future__ import annotations

from tt_mujoco import run


def run_hooked(tmp_path, monkeypatch, file, options, loop: str = "python") -> tuple[int, object]:
    """``(exit code, output folder)`` of a 2 s run with ``options`` (``{file}`` filled in),
    on the reduced plant's circle unless the options name a path; ``loop`` "compiled" or
    "python"."""
    monkeypatch.setenv("TT_MUJOCO_COMPILED", "1" if loop == "compiled" else "0")
    out = tmp_path / "out"
    argv = [o.format(file=file) for o in options]
    argv += ["--plant", "reduced", "--traj", "circle"] if "--traj" not in argv else []
    argv += ["--duration", "2", "--no-video", "--no-plots", "--quiet", "--out", str(out)]
    return run.main(argv), out

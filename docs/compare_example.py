"""The comparison of docs/compare.md: ISMC-STA, PID and FBL on the S-curve, then ``compare``.

    python docs/compare_example.py

Runs the three controllers with the paper's Section 6.2 gains (its Table 3 comparison) on the
MuJoCo plant into renders/compare-example/, compares them, prints the table and copies the
tracks and errors figures to renders/reference/compare_paths.png and compare_errors.png.
"""

import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RUNS = ROOT / "renders" / "compare-example"


def main() -> None:
    folders = []
    for controller in ("ismc_sta", "pid", "fbl"):
        out = RUNS / controller
        if not (out / "metrics.json").exists():
            cmd = [sys.executable, "-m", "tt_mujoco.run", "--traj", "s_curve"]
            cmd += ["--controller", controller, "--gains", "paper_6_2", "--no-video"]
            subprocess.run([*cmd, "--no-plots", "--quiet", "--out", str(out)], check=True)
        folders.append(str(out))
    table = RUNS / "compare"
    shutil.rmtree(table, ignore_errors=True)
    cmd = [sys.executable, "-m", "tt_mujoco.compare", *folders, "--out", str(table)]
    subprocess.run(cmd, check=True)
    reference = ROOT / "renders" / "reference"
    for name in ("paths", "errors"):
        shutil.copyfile(table / f"{name}.png", reference / f"compare_{name}.png")


if __name__ == "__main__":
    main()

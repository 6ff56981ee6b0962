"""Make the README's images in ``renders/reference/``.

Run: ``python docs/readme_images.py``. It runs the main command
(``python -m tt_mujoco.run --traj s_curve``) and the paper's forward-jackknifing gain
(``--eta paper``) into a temporary folder, then saves, reduced to 480 px wide: frame 5 of the
main video (the start), frame 200 (in the second turn), the end card of the jackknife video,
the main run's ``path.png``, frame 250 of a three-trailer train on the S-curve
(``--trailers 3 --no-disturbance``), and the ``path.png`` of a three-trailer train on the circle
with the path schedule (``--traj circle --trailers 3 --eta path --no-disturbance``), and the
``path.png`` of the main command with the path schedule (``--eta path``). Existing images are
replaced only because they are this script's own outputs.
"""

import subprocess
import sys
import tempfile
from pathlib import Path

import imageio_ffmpeg
import numpy as np
from PIL import Image

OUT = Path(__file__).resolve().parent.parent / "renders" / "reference"
WIDTH = 480


def small(img: Image.Image) -> Image.Image:
    return img.resize((WIDTH, round(img.height * WIDTH / img.width)), Image.LANCZOS)


def frames(video: Path, wanted: set[int]) -> dict[int, np.ndarray]:
    """Frames ``wanted`` of a video (-1: the last one)."""
    reader = imageio_ffmpeg.read_frames(str(video))
    w, h = next(reader)["size"]
    out, last = {}, None
    for i, raw in enumerate(reader):
        last = np.frombuffer(raw, dtype=np.uint8).reshape(h, w, 3)
        if i in wanted:
            out[i] = last
    if -1 in wanted:
        out[-1] = last
    return out


def run(folder: Path, *options: str, traj: str = "s_curve") -> None:
    cmd = [sys.executable, "-m", "tt_mujoco.run", "--traj", traj, "--quiet", *options]
    subprocess.run([*cmd, "--out", str(folder)], check=False)  # the jackknife exits with 3


def main() -> int:
    OUT.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        main_run, jackknife = Path(tmp) / "run", Path(tmp) / "jackknife"
        run(main_run)
        run(jackknife, "--eta", "paper", "--no-plots")
        train = Path(tmp) / "train"
        run(train, "--trailers", "3", "--no-disturbance", "--no-plots")
        got_train = frames(train / "video.mp4", {250})
        small(Image.fromarray(got_train[250])).save(OUT / "train_frame.png", optimize=True)
        scheduled = Path(tmp) / "scheduled"
        options = ("--trailers", "3", "--eta", "path", "--no-disturbance", "--no-video")
        run(scheduled, *options, traj="circle")
        small(Image.open(scheduled / "path.png").convert("RGB")).save(
            OUT / "circle_path_schedule.png", optimize=True
        )
        same_path = Path(tmp) / "same_path"
        run(same_path, "--eta", "path", "--no-video")
        small(Image.open(same_path / "path.png").convert("RGB")).save(
            OUT / "s_curve_path_schedule.png", optimize=True
        )
        got = frames(main_run / "video.mp4", {5, 200})
        small(Image.fromarray(got[5])).save(OUT / "s_curve_start.png", optimize=True)
        small(Image.fromarray(got[200])).save(OUT / "s_curve_frame.png", optimize=True)
        end = frames(jackknife / "video.mp4", {-1})[-1]
        small(Image.fromarray(end)).save(OUT / "jackknife_end.png", optimize=True)
        small(Image.open(main_run / "path.png").convert("RGB")).save(
            OUT / "s_curve_path.png", optimize=True
        )
    print(
        "wrote s_curve_start.png, s_curve_frame.png, jackknife_end.png, s_curve_path.png, "
        f"train_frame.png, circle_path_schedule.png, s_curve_path_schedule.png to {OUT}"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Make the two small README images in ``renders/reference/``.

Run: ``python docs/readme_images.py``. It runs the main command
(``python -m tt_mujoco.run --traj s_curve``) into a temporary folder, then saves frame 138 of its
video and its ``path.png``, both reduced to 480 px wide. Existing images are replaced only
because they are this script's own outputs.
"""

import subprocess
import sys
import tempfile
from pathlib import Path

import imageio_ffmpeg
import numpy as np
from PIL import Image

OUT = Path(__file__).resolve().parent.parent / "renders" / "reference"
FRAME = 138
WIDTH = 480


def small(img: Image.Image) -> Image.Image:
    return img.resize((WIDTH, round(img.height * WIDTH / img.width)), Image.LANCZOS)


def main() -> int:
    OUT.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        run_dir = Path(tmp) / "run"
        cmd = [sys.executable, "-m", "tt_mujoco.run", "--traj", "s_curve", "--quiet"]
        subprocess.run([*cmd, "--out", str(run_dir)], check=True)
        reader = imageio_ffmpeg.read_frames(str(run_dir / "video.mp4"))
        meta = next(reader)
        w, h = meta["size"]
        for i, raw in enumerate(reader):
            if i == FRAME:
                frame = np.frombuffer(raw, dtype=np.uint8).reshape(h, w, 3)
                break
        small(Image.fromarray(frame)).save(OUT / "s_curve_frame.png", optimize=True)
        small(Image.open(run_dir / "path.png").convert("RGB")).save(
            OUT / "s_curve_path.png", optimize=True
        )
    print(f"wrote {OUT / 's_curve_frame.png'} and {OUT / 's_curve_path.png'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""What a video frame says besides the scene: the legend and the end card (drawn with Pillow).

The legend is drawn once into a small RGBA patch and blended into every frame with numpy (about
0.1 ms a frame); the end card, drawn over the last frame, says how the run ended.
"""

from __future__ import annotations

import numpy as np

__all__ = ["END_CARD_S", "Legend", "end_card"]

#: How long the end card stays on screen (s).
END_CARD_S = 2.0


def _font(size: int):
    from PIL import ImageFont

    return ImageFont.load_default(size=max(8, size))


class Legend:
    """A key of colours in the bottom-left corner of every frame.

    Parameters
    ----------
    entries : sequence of (label, rgba)
        ``rgba`` with components in [0, 1], as the scene's colours.
    height : int
        The frame's height (sets the font size).
    """

    def __init__(self, entries, height: int):
        from PIL import Image, ImageDraw

        font = _font(height // 40)
        size = max(8, height // 40)
        line = size + 6
        width = max(int(ImageDraw.Draw(Image.new("RGB", (1, 1))).textlength(label, font=font))
                    for label, _ in entries) + 3 * size + 12  # fmt: skip
        patch = Image.new("RGBA", (width, line * len(entries) + 8), (0, 0, 0, 150))
        draw = ImageDraw.Draw(patch)
        for k, (label, rgba) in enumerate(entries):
            y = 4 + k * line
            colour = (*(int(255 * c) for c in rgba[:3]), 255)
            draw.rectangle((6, y + 3, 6 + 2 * size, y + size - 1), fill=colour)
            draw.text((12 + 2 * size, y), label, fill=(255, 255, 255, 255), font=font)
        rgba_patch = np.asarray(patch, dtype=np.float32) / 255.0
        self._rgb = rgba_patch[..., :3] * 255.0
        self._alpha = rgba_patch[..., 3:4]

    def apply(self, image: np.ndarray) -> np.ndarray:
        """``image`` (H, W, 3) uint8 with the legend blended into its bottom-left corner."""
        h, w = self._alpha.shape[:2]
        h, w = min(h, image.shape[0]), min(w, image.shape[1])
        region = image[-h:, :w].astype(np.float32)
        alpha = self._alpha[:h, :w]
        image[-h:, :w] = (alpha * self._rgb[:h, :w] + (1.0 - alpha) * region).astype(np.uint8)
        return image


def end_card(image: np.ndarray, title: str, lines) -> np.ndarray:
    """``image`` darkened, with ``title`` (large) and ``lines`` centred on it."""
    from PIL import Image, ImageDraw

    height, width = image.shape[:2]
    im = Image.fromarray((image.astype(np.float32) * 0.35).astype(np.uint8))
    draw = ImageDraw.Draw(im)
    big, small = _font(height // 10), _font(height // 32)
    y = height // 3
    for text, font, gap in [(title, big, height // 8)] + [(t, small, height // 22) for t in lines]:
        w = draw.textlength(text, font=font)
        draw.text(((width - w) / 2, y), text, fill=(255, 255, 255), font=font)
        y += gap
    return np.asarray(im).copy()

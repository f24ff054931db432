"""Text as RGBA images (Pillow's bundled font), for the GL layer to draw as textures."""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from PIL import Image, ImageDraw, ImageFont


@lru_cache(maxsize=8)
def font(size_px: int) -> ImageFont.FreeTypeFont | ImageFont.ImageFont:
    """Pillow's bundled scalable font at ``size_px``."""
    return ImageFont.load_default(size=size_px)


def text_rgba(lines: tuple[str, ...], size_px: int, rgb=(255, 255, 255),
              background=(0, 0, 0, 170), pad_px: int = 4) -> np.ndarray:
    """``lines`` drawn in ``rgb`` on a translucent box: uint8 (height, width, 4), row 0 on top."""
    f = font(size_px)
    probe = ImageDraw.Draw(Image.new("RGBA", (1, 1)))
    line_h = int(round(size_px * 1.25))
    width = max((int(np.ceil(probe.textlength(line, font=f))) for line in lines), default=0)
    img = Image.new("RGBA", (width + 2 * pad_px, line_h * len(lines) + 2 * pad_px), background)
    draw = ImageDraw.Draw(img)
    for k, line in enumerate(lines):
        draw.text((pad_px, pad_px + k * line_h), line, font=f, fill=(*rgb, 255))
    return np.asarray(img)


@lru_cache(maxsize=256)
def wrap(text: str, size_px: int, width_px: float, sep: str = " ") -> tuple[str, ...]:
    """``text`` split into lines no wider than ``width_px`` px, breaking only at ``sep``
    (" | " keeps a status line's phrases whole; the separator that ends a line is dropped);
    a phrase wider than a line alone is broken between its words. Remembered: a frame
    wraps the same status lines as the last."""
    f = font(size_px)
    probe = ImageDraw.Draw(Image.new("RGBA", (1, 1)))

    def fits(line: str) -> bool:
        return probe.textlength(line, font=f) <= width_px

    lines: list[str] = []

    def put(line: str) -> None:
        if sep == " " or fits(line):
            lines.append(line)
        else:  # one phrase wider than a line: between its words
            lines.extend(wrap(line, size_px, width_px))

    for para in text.splitlines() or [""]:
        line = ""
        for unit in para.split(sep):
            candidate = f"{line}{sep}{unit}" if line else unit
            if line and not fits(candidate):
                put(line)
                line = unit
            else:
                line = candidate
        put(line)
    return tuple(lines)

"""Regenerate raster-map.png, the friction map of raster-map.toml (deterministic).

160 x 96 px, 8-bit greyscale: concentric rings 12 px apart (a raised-cosine ripple)
around the image centre, fading linearly from full depth at the left edge to none at
the right edge. Grey = friction (black = most slippery). Run from anywhere:

    .venv/bin/python textures/library/make_raster_map.py
"""

from pathlib import Path

import numpy as np
from PIL import Image

ROWS, COLS, RING_PX = 96, 160, 12.0


def grey_map() -> np.ndarray:
    """The map as uint8 (ROWS, COLS)."""
    y, x = np.mgrid[0:ROWS, 0:COLS] + 0.5
    r = np.hypot(x - COLS / 2, y - ROWS / 2)
    ripple = 0.5 + 0.5 * np.cos(2 * np.pi * r / RING_PX)
    depth = 1.0 - x / COLS
    return np.round(255.0 * (1.0 - depth * (1.0 - ripple))).astype(np.uint8)


if __name__ == "__main__":
    out = Path(__file__).with_name("raster-map.png")
    Image.fromarray(grey_map(), mode="L").save(out, optimize=True)
    print(f"wrote {out}")

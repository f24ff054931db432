"""AUTHORING.md's account of how a layer's mu' becomes a colour holds on the drawing."""

import re
from pathlib import Path

import numpy as np
from PIL import Image

from frictex.app.commands.cli import main
from frictex.rendering.visual.scene_image import layer_rgb, to_srgb8
from scenes import grating_scene

PAGE = " ".join((Path(__file__).resolve().parents[1] / "textures" / "AUTHORING.md")
                .read_text(encoding="utf-8").split())


def test_the_greys_it_gives_are_the_drawings_blend():
    greys = re.search(r"u = 0\.25, 0\.5, 0\.75 are sRGB greys (\d+), (\d+), (\d+)", PAGE).groups()
    layer = grating_scene(5.0, mu_low=0.6).layers[0]  # black at 0.6, white at 1.0
    drawn = to_srgb8(layer_rgb(layer, np.array([0.7, 0.8, 0.9])))
    assert drawn[:, 0].tolist() == [int(g) for g in greys]


def test_the_ridges_flanks_draw_as_it_says(tmp_path):
    lit_low, lit, rest, dark = re.search(r"left flank draws (\d+) to (\d+) against (\d+), its "
                                         r"right flank (\d+)", PAGE).groups()
    assert main(["preview", "height-ridge", "-o", str(tmp_path / "r.png")]) == 0
    row = np.asarray(Image.open(tmp_path / "r-scene.png").convert("L"))[240].astype(int)
    x_mm = (np.arange(row.size) + 0.5) * 108.0 / row.size
    left, right = row[(x_mm > 51.2) & (x_mm < 53.8)], row[(x_mm > 54.2) & (x_mm < 56.8)]
    assert row[0] == int(rest)
    assert int(lit_low) <= left.min() and left.max() == int(lit)
    assert right.min() == int(dark)

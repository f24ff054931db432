"""The bundled height-bump's comments give what the layer renders: its gain's comment
said +-0.15 at the steepest point, the linear term, where the tanh saturation gives
0.2 tanh(0.758) = +-0.128."""

import math
import re

import numpy as np

from frictex.textures.library import resolve_scene
from frictex.textures.loader import load_scene


def test_the_gain_comment_gives_mu_at_the_steepest_slope():
    path = resolve_scene("height-bump")
    bump = load_scene(path).layers[0]
    steepest = bump.shape.height_mm / bump.shape.sigma_mm * math.exp(-0.5)  # at r = sigma
    said = re.search(r"^gain = .*# .*\+-([\d.]+) at the steepest point", path.read_text("utf-8"),
                     re.M)
    assert said, "the gain's comment no longer says mu' at the steepest point"
    climbing, descending = bump.mu_of_slope(np.array([steepest, -steepest])) - bump.mu_rest
    assert round(climbing, 2) == round(-descending, 2) == float(said.group(1)), (climbing, said[0])

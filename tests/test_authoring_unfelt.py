"""Layers nothing of which can be felt are warned about when the file is read, one line
each naming the file, the layer and why (``textures.sections.layers.unfelt_warnings``);
the same layers with something to feel are not."""

import numpy as np
import pytest
from PIL import Image

from frictex.textures.loader import check_scene
from test_texture_loader import write

BUMP = ('[[layer]]\ntype = "height"\nshape = "bump"\ncx_mm = 50.0\ncy_mm = 30.0\n'
        'sigma_mm = 5.0\nrise_mm = {}\n')
MAP = ('[[layer]]\ntype = "height"\nshape = "map"\nimage = "{}"\nx_mm = 10.0\ny_mm = 20.0\n'
       'width_mm = 80.0\nheight_mm = 30.0\nrise_mm = 1.0\n')
ENVELOPE = ('[[layer]]\ntype = "clip"\ntrigger = "down"\nclip = "envelope"\n'
            'times_s = [0.0, 0.1]\nlevels = [1.0, 0.0]\nintensity = {}\n')
RAMP = '[[layer]]\ntype = "clip"\ntrigger = "down"\nclip = "ramp"\nduration_s = {}\n'
GRATING = '[[layer]]\ntype = "grating"\nperiod_mm = 5.0\nmu_low = {}\n'
RECT = ('[[layer]]\ntype = "rectangle"\nx_mm = 10.0\ny_mm = 10.0\nwidth_mm = 20.0\n'
        'height_mm = 20.0\nmu = {}\n')


def _maps(tmp_path):
    Image.fromarray(np.full((1, 1), 30000, np.uint16)).save(tmp_path / "one.png")
    Image.fromarray(np.full((4, 5), 30000, np.uint16)).save(tmp_path / "even.png")
    Image.fromarray(np.arange(3, dtype=np.uint16)[None, :] * 1000).save(tmp_path / "ramp.png")


@pytest.mark.parametrize("body, heard, key, why", [
    (BUMP.format(0.0), BUMP.format(0.5), "rise_mm", "rise_mm = 0 makes the shape flat"),
    (MAP.format("one.png"), MAP.format("ramp.png"), "image", "the 1 x 1 map has one height"),
    (MAP.format("even.png"), MAP.format("ramp.png"), "image", "the 5 x 4 map has one height"),
    (ENVELOPE.format(0.0), ENVELOPE.format(0.1), "clip", "its intensity are 0 throughout"),
    (RAMP.format(1e-9), RAMP.format(1e-3), "clip", "it lasts 1e-09 s, under one output sample"),
    (GRATING.format(1.0), GRATING.format(0.8), "mu_low", "asks for mu' 1 everywhere"),
    (RECT.format(1.0), RECT.format(0.8), "mu", "asks for mu' 1 everywhere"),
    # a replace layer at 1 takes away what the layers before it lower: felt
    (RECT.format(1.0), GRATING.format(0.8) + RECT.format(1.0) + 'blend = "replace"\n', "mu",
     "asks for mu' 1 everywhere"),
])
def test_a_layer_that_cannot_be_felt_is_warned_about(tmp_path, body, heard, key, why):
    _maps(tmp_path)
    scene, problems, warnings = check_scene(write(tmp_path, body))
    assert scene is not None and problems == [] and len(warnings) == 1, warnings
    line = str(warnings[0])
    assert "scene.toml:" in line and f"layer[1].{key}: layer " in line and why in line, line
    assert "nothing of it is felt" in line, line
    scene, problems, warnings = check_scene(write(tmp_path, heard))
    assert scene is not None and problems == [] and warnings == [], warnings


def test_validate_prints_the_warning_and_still_says_ok(tmp_path, capsys):
    from frictex.app.commands.cli import main
    path = write(tmp_path, BUMP.format(0.0))
    assert main(["validate", str(path)]) == 0
    out, err = capsys.readouterr()
    assert out.startswith("ok ") and err.count("\n") == 1 and "frictex: warning: " in err, err
    assert main(["validate", "--strict", str(path)]) == 2

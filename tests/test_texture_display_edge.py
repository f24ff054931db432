"""Shapes at the display's edge: a shape partly off the display is clipped there (every
layer is evaluated per position), a shape wholly off it is refused, with the display's
extent in the message."""

import numpy as np
import pytest
from PIL import Image

from frictex.textures.errors import TextureError
from frictex.textures.extent import shares_display
from frictex.textures.loader import load_scene
from frictex.textures.model import DiscRegion, Display, RectRegion

HEAD = "format = 1\n[display]\nwidth_mm = 100.0\nheight_mm = 60.0\nwidth_px = 1000\nheight_px = 600\n"
DISPLAY = Display(100.0, 60.0, 1000, 600)

PARTLY_OFF = {
    "rectangle": 'type = "rectangle"\nx_mm = -10\ny_mm = 10\nwidth_mm = 30\nheight_mm = 20\nmu = 0.7\n',
    "line": 'type = "line"\nx0_mm = 50\ny0_mm = 30\nx1_mm = 60\ny1_mm = -5\nwidth_mm = 2\nmu = 0.8\n',
    "disc": 'type = "disc"\ncx_mm = 102\ncy_mm = 30\nradius_mm = 5\nmu = 0.8\n',
    "bump": 'type = "bump"\ncx_mm = 105\ncy_mm = 30\nsigma_mm = 2\nmu = 0.8\n',
    "region": 'type = "grating"\nperiod_mm = 5\nmu_low = 0.7\n[layer.region]\ncx_mm = 0\ncy_mm = 0\nradius_mm = 10\n',
    "raster": 'type = "raster"\nimage = "r.png"\nmode = "one-to-one"\nx_mm = 70\ny_mm = 20\nmu_black = 0.6\n',
}


def _scene(tmp_path, layer):
    Image.fromarray(np.zeros((100, 405), np.uint8)).save(tmp_path / "r.png")
    path = tmp_path / "scene.toml"
    path.write_text(HEAD + "[[layer]]\n" + layer, encoding="utf-8")
    return load_scene(path)


@pytest.mark.parametrize("kind", PARTLY_OFF)
def test_a_shape_partly_off_the_display_loads_and_acts_where_it_is_on(tmp_path, kind):
    layer = _scene(tmp_path, PARTLY_OFF[kind]).layers[0]
    x, y = np.meshgrid(np.linspace(0.05, 99.95, 1000), np.linspace(0.05, 59.95, 600))
    on = layer.covers(x, y) & (layer.mu_at(x, y) < 1.0)
    assert on.any()


def test_the_raster_past_the_right_edge_keeps_its_size(tmp_path):
    """The review's one-to-one image: 405 px at 10 px/mm from x 70 mm runs to 110.5 mm;
    its first 30 mm are on the display, at mu_black (the image is black)."""
    layer = _scene(tmp_path, PARTLY_OFF["raster"]).layers[0]
    assert layer.width_mm == 40.5
    assert layer.covers(np.array([99.9]), np.array([25.0]))[0]
    assert layer.mu_at(np.array([99.9]), np.array([25.0]))[0] == 0.6


@pytest.mark.parametrize("layer, message", [
    ('type = "rectangle"\nx_mm = -40\ny_mm = 10\nwidth_mm = 30\nheight_mm = 20\nmu = 0.7\n',
     r"layer\[1\]\.x_mm: rectangle at x -40 to -10 mm, y 10 to 30 mm lies wholly off the display "
     r"\(x 0 to 100 mm, y 0 to 60 mm\)"),
    ('type = "line"\nx0_mm = 50\ny0_mm = -1.5\nx1_mm = 60\ny1_mm = -1.5\nwidth_mm = 2\nmu = 0.8\n',
     r"layer\[1\]\.x0_mm: line at x 49 to 61 mm, y -2\.5 to -0\.5 mm lies wholly off the display"),
    ('type = "raster"\nimage = "r.png"\nmode = "one-to-one"\nx_mm = 100\ny_mm = 20\nmu_black = 0.6\n',
     r"layer\[1\]\.x_mm: image at x 100 to 140\.5 mm, y 20 to 30 mm lies wholly off the display"),
    ('type = "bump"\ncx_mm = 109\ncy_mm = 30\nsigma_mm = 2\nmu = 0.8\n',
     r"layer\[1\]\.cx_mm: bump \(to 4 sigma\) at x 101 to 117 mm, y 22 to 38 mm lies wholly off"),
])
def test_a_shape_wholly_off_the_display_is_refused(tmp_path, layer, message):
    with pytest.raises(TextureError, match=message):
        _scene(tmp_path, layer)


@pytest.mark.parametrize("shape, on", [
    (RectRegion(-30, 10, 30, 20), False),           # touches x = 0 along an edge only
    (RectRegion(-29.9, 10, 30, 20), True),
    (RectRegion(-9, -9, 10, 10, 45.0), False),       # its box reaches the display, it does not
    (RectRegion(-8, -8, 10, 10, 45.0), True),
    (DiscRegion(-7, -7, 9.8), False),               # 9.90 mm from the display's corner
    (DiscRegion(-7, -7, 10.0), True),
    ((50, -3, 60, -3, 6.0), False),                 # a 6 mm wide line along y = -3
    ((50, -3, 60, -3, 6.2), True),
    ((-10, 70, 110, 70, 4.0), False),
    ((-10, 70, 110, -10, 1.0), True),               # crosses the display, ends off it
])
def test_shares_display(shape, on):
    assert shares_display(shape, DISPLAY) is on

"""frictex preview says why its scene image is not at the display's pixels."""

from PIL import Image

from frictex.app.commands.cli import main
from frictex.app.commands.preview import why_this_size
from frictex.textures.model import Display

#: 800 x 480 px on 120 x 64.8 mm: 6.67 px/mm along x, 7.41 along y
NOT_SQUARE = """
format = 1
name = "not-square"

[display]
width_mm = 120.0
height_mm = 64.8
width_px = 800
height_px = 480

[device]
profile = "plate-seed003"
normal_force_n = 0.5

[[layer]]
type = "grating"
name = "lines"
period_mm = 5
mu_low = 0.6
mu_high = 1.0
"""


def test_pixels_that_are_not_square_are_named_as_the_reason(tmp_path, capsys):
    scene = tmp_path / "ns.toml"
    scene.write_text(NOT_SQUARE)
    assert main(["preview", str(scene), "-o", str(tmp_path / "ns.png")]) == 0
    drawn = capsys.readouterr().out.splitlines()[1]
    assert Image.open(tmp_path / "ns-scene.png").size == (800, 432)
    assert drawn.endswith("(the display has 800 x 480 px; fitted keeping the mm aspect "
                          "(120 x 64.8 mm): its pixels are not square)")


def test_a_display_over_the_largest_image_is_said_to_be_scaled_down():
    square = Display(108.0, 64.8, 8000, 4800)
    assert why_this_size(square, (4096, 2458), None) == (
        "the display has 8000 x 4800 px; scaled down to at most 4096 px a side")


def test_a_size_asked_for_is_named():
    square = Display(108.0, 64.8, 800, 480)
    assert why_this_size(square, (600, 360), (600, 600)) == (
        "the display has 800 x 480 px; fitted in --size 600x600 keeping the mm aspect")
    assert why_this_size(square, (800, 480), None) == "the display's pixels"

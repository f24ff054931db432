"""What an author reads matches what the loader and renderer do: a lift clip is warned
about (it is felt only by other fingers still touching), the format page's colour and
raster rows say what the code does (color_high at the layer's highest mu', bilinear
sampling between pixel centres)."""

import numpy as np

from frictex.app.commands.cli import main
from frictex.textures.format_doc import render
from frictex.textures.loader import check_scene
from frictex.textures.model import RasterMap

HEAD = """format = 1
[display]
width_mm = 140.0
height_mm = 30.0
width_px = 700
height_px = 150
"""

CLIP = """[[layer]]
type = "clip"
name = "{name}"
trigger = "{trigger}"
clip = "tick"
depth = 0.3
"""


def _clip_scene(tmp_path, *triggers):
    path = tmp_path / "clips.toml"
    path.write_text(HEAD + "".join(CLIP.format(name=f"click-{t}", trigger=t) for t in triggers))
    return path


def test_a_lift_clip_is_warned_about_once_naming_its_layer(tmp_path):
    _, problems, warnings = check_scene(_clip_scene(tmp_path, "down", "lift"))
    assert not problems
    lifts = [w for w in warnings if "lift" in w.message]
    assert len(lifts) == 1
    assert lifts[0].field == "layer[2].trigger" and '"click-lift"' in lifts[0].message
    assert "other fingers still touching" in lifts[0].message


def test_a_down_clip_gets_no_lift_warning(tmp_path):
    _, _, warnings = check_scene(_clip_scene(tmp_path, "down"))
    assert not [w for w in warnings if "lift" in w.message]


def test_validate_prints_the_lift_warning_on_one_line_and_still_passes(tmp_path, capsys):
    path = _clip_scene(tmp_path, "lift")
    assert main(["validate", str(path)]) == 0
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if '"lift"' in line]
    assert len(lines) == 1 and lines[0].startswith("frictex: warning: ")
    assert 'layer "click-lift"' in lines[0]


def _row(page: str, key: str, context: str) -> str:
    """The table row of ``key`` in the section that contains ``context``."""
    section = page[page.index(context):]
    return next(line for line in section.splitlines() if line.startswith(f"| `{key}` |"))


def test_the_page_says_color_high_is_the_layers_highest_mu_not_1():
    row = _row(render(), "color_high", "### [layer.visual]")
    assert "highest" in row and "(1)" not in row


def test_the_page_says_raster_images_are_sampled_bilinearly_between_pixel_centres():
    row = _row(render(), "image", '### [[layer]] type = "raster"')
    assert "bilinearly between pixel centres" in row and "ramp" in row


def test_a_one_pixel_stripe_is_a_ramp_two_pixels_wide_as_the_page_says():
    """Black | white | black, 1 mm a pixel: mu' peaks at the stripe's centre (1.5 mm),
    is halfway at its edges and back at mu_black at the neighbours' centres."""
    stripe = RasterMap(name="s", render="auto", region=None, blend="multiply", visual=None,
                       image=np.array([[0.0, 1.0, 0.0]]), width_mm=3.0, height_mm=1.0,
                       mu_black=0.6, mu_white=1.0)
    x = np.array([0.5, 1.0, 1.5, 2.0, 2.5])
    assert np.allclose(stripe.mu_at(x, np.full_like(x, 0.5)), [0.6, 0.8, 1.0, 0.8, 0.6])

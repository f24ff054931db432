"""Height layers in texture files: the bundled examples, and line-located errors."""

import numpy as np
import pytest
from numpy.testing import assert_allclose
from PIL import Image

from test_texture_loader import write
from frictex.textures.errors import TextureError
from frictex.textures.heights import ButtonRim, GaussianBump, HeightLayer, HeightMap, Ridge
from frictex.textures.library import resolve_scene
from frictex.textures.loader import check_scene, load_scene


def test_bundled_examples_load_as_written():
    bump = load_scene(resolve_scene("height-bump")).layers[0]
    assert isinstance(bump, HeightLayer) and bump.shape == GaussianBump(54.0, 32.4, 8.0, 1.0)
    assert (bump.gain, bump.mu_rest, bump.rendering) == (2.0, 0.8, "slope")
    assert load_scene(resolve_scene("height-ridge")).layers[0].shape == Ridge(54.0, 32.4, 90.0, 6.0, 0.8)
    button = load_scene(resolve_scene("height-button")).layers
    assert button[0].shape == ButtonRim(54.0, 32.4, 12.0, 4.0, 0.5)
    assert button[1].trigger == "down"


BUMP = 'type = "height"\nshape = "bump"\nrise_mm = 1.0\n'


@pytest.mark.parametrize("body, message", [
    (BUMP + "cx_mm = 50\ncy_mm = 30\n",
     r"scene\.toml:7: layer\[1\]\.sigma_mm: missing \(required with shape = \"bump\"\)"),
    (BUMP + "cx_mm = 50\ncy_mm = 30\nsigma_mm = 5\nchamfer_mm = 1\n",
     r"scene\.toml:14: layer\[1\]\.chamfer_mm: not used with shape = \"bump\""),
    (BUMP + "cx_mm = 50\ncy_mm = 30\nsigma_mm = 5\nmu_rest = 0.5\n",
     r"scene\.toml:14: layer\[1\]\.mu_rest: mu_min 0\.6 < mu_rest 0\.5 < mu_max 1 does not hold"),
    (BUMP + "cx_mm = 500\ncy_mm = 30\nsigma_mm = 5\n", r"scene\.toml:11: layer\[1\]\.cx_mm: bump \(to 4 sigma\) at x 480 to 520 mm"),
    ('type = "height"\nshape = "button"\nrise_mm = 1\ncx_mm = 50\ncy_mm = 30\nradius_mm = 5\nrim_mm = 6\n',
     r"scene\.toml:14: layer\[1\]\.rim_mm: 6 mm is not below radius_mm 5"),
    ('type = "height"\nshape = "cone"\nrise_mm = 1\n', r"scene\.toml:9: layer\[1\]\.shape: \"cone\" is not one of"),
    (BUMP.replace("1.0", "150") + "cx_mm = 50\ncy_mm = 30\nsigma_mm = 5\n",
     r"scene\.toml:10: layer\[1\]\.rise_mm: 150 is outside \[-100, 100\]"),
])
def test_problems_are_reported_at_their_line(tmp_path, body, message):
    with pytest.raises(TextureError, match=message):
        load_scene(write(tmp_path, "[[layer]]\n" + body))


def test_a_height_map_from_a_16_bit_png_and_an_8_bit_one_refused(tmp_path):
    levels = (np.arange(40) * 1000).astype(np.uint16)[None, :].repeat(20, axis=0)
    Image.fromarray(levels).save(tmp_path / "ramp.png")
    body = ('[[layer]]\ntype = "height"\nshape = "map"\nimage = "ramp.png"\nrise_mm = 2.0\n'
            'x_mm = 10\nwidth_mm = 40\nheight_mm = 20\n')
    layer = load_scene(write(tmp_path, body)).layers[0]
    assert isinstance(layer.shape, HeightMap)
    _, gx, _ = layer.shape.height_and_gradient(np.array([30.0]), np.array([10.0]))
    assert_allclose(gx, 2.0 * 1000 / 65535 / 1.0)  # 1 mm per pixel
    Image.fromarray(np.zeros((4, 4), np.uint8)).save(tmp_path / "eight.png")
    _, problems, _ = check_scene(write(tmp_path, body.replace("ramp.png", "eight.png")))
    assert len(problems) == 1 and problems[0].line == 10 and "16-bit" in str(problems[0])
    _, problems, _ = check_scene(write(tmp_path, body.replace("ramp.png", "missing.png")))
    assert len(problems) == 1 and "expected 16-bit greyscale PNG" in str(problems[0])


def test_preview_shows_a_height_as_felt_sliding_towards_plus_x(tmp_path):
    from frictex.app.commands.preview import as_previewed, write_preview
    from frictex.rendering.compose import ideal_mu

    scene = load_scene(resolve_scene("height-bump"))
    x = np.array([54.0 - 8.0, 54.0, 54.0 + 8.0, 5.0])
    mu = ideal_mu(as_previewed(scene), x, np.full(4, 32.4))
    slope = np.array([1.0, 0.0, -1.0, 0.0]) * np.exp(-0.5) / 8.0  # +-H/sigma e^-1/2, flat
    up, down = 1.0 - 0.8, 0.8 - 0.6
    assert_allclose(mu, 0.8 + np.where(slope >= 0, up * np.tanh(2 * slope / up),
                                       down * np.tanh(2 * slope / down)), atol=1e-4)
    info = write_preview(scene, tmp_path / "bump.png", (200, 120))
    assert info["mu_min"] < 0.8 < info["mu_max"]


def test_a_colour_height_map_is_refused_from_its_header_before_decoding(tmp_path, monkeypatch):
    """An RGB height map was decoded whole (367 MB at 8 Mpx) before being refused: now
    its header refuses it, and no pixel is decoded (the decoder is never called)."""
    from frictex.textures import heights
    from frictex.textures.raster_io import PixelBudget
    Image.fromarray(np.zeros((300, 400, 3), np.uint8)).save(tmp_path / "rgb.png")
    from PIL import Image as PILImage

    def no_decoding(*args, **kwargs):
        raise AssertionError("decoded")
    monkeypatch.setattr(PILImage, "open", no_decoding)
    budget = PixelBudget()
    with pytest.raises(TextureError, match="its header says 8-bit RGB pixels; expected 16-bit"):
        heights.read_height_png(tmp_path / "rgb.png", 1.0, budget)
    assert budget.spent == 0


def test_the_magnitude_rendering_is_not_warned_of_mu_it_never_asks_for(tmp_path):
    """The magnitude rendering never goes below mu_rest (0.8): a mu_min of 0.3 under the
    device's floor (0.5717) was warned of as 'lower values will be clamped', though a
    replay asked for 0.8 to 0.99 and clamped nothing; the slope rendering still is."""
    from frictex.textures.format_examples import EXAMPLES
    text = EXAMPLES["height"].replace("mu_min = 0.6", "mu_min = 0.3")
    magnitude = write(tmp_path, text.replace('rendering = "slope"', 'rendering = "magnitude"'),
                      head="")
    _, problems, warnings = check_scene(magnitude)
    assert problems == [] and not any("clamped" in w.message for w in warnings)
    assert load_scene(magnitude).layers[0].mu_range == (0.8, 1.0)
    _, _, warnings = check_scene(write(tmp_path, text, head=""))
    assert any("lower values will be clamped" in w.message for w in warnings)


def test_a_height_layer_is_said_to_run_its_own_renderer(tmp_path):
    """summary.json's layers named SHO's variant for a height layer, which the slope
    renderer plays."""
    import json
    from frictex.app.commands.cli import main
    out = tmp_path / "o"
    assert main(["replay", "height-bump", "swipe-40mms-50hz", "--out", str(out), "--quiet"]) == 0
    layers = json.loads((out / "summary.json").read_text())["scene"]["layers"]
    assert [(layer["type"], layer["renderer"]) for layer in layers] == [("height", "height")]

"""Texture files that are right: every layer type, the device, colours, rasters, warnings."""

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose
from PIL import Image

from frictex.device import profile as profiles
from frictex.textures import model
from frictex.textures.errors import TextureError
from frictex.textures.loader import check_scene, load_scene

HEAD = """\
format = 1
[display]
width_mm = 108.0
height_mm = 64.8
width_px = 800
height_px = 480
"""


def write(tmp_path, body: str, head: str = HEAD, name: str = "scene.toml"):
    path = tmp_path / name
    path.write_text(head + body, encoding="utf-8")
    return path


def only_layer(tmp_path, body: str):
    scene = load_scene(write(tmp_path, "[[layer]]\n" + body))
    assert len(scene.layers) == 1
    return scene.layers[0]


def test_grating_fields_and_profile(tmp_path):
    g = only_layer(tmp_path, 'type = "grating"\nperiod_mm = 5.0\nduty = 0.25\nmu_low = 0.6\n'
                             'offset_mm = 1.0\nangle_deg = 0\n')
    assert isinstance(g, model.Grating)
    assert (g.period_mm, g.duty, g.mu_low, g.mu_high, g.offset_mm) == (5.0, 0.25, 0.6, 1.0, 1.0)
    # vertical lines: the low band is x in [1, 2.25) mod 5
    x = np.array([1.0, 2.2, 2.3, 5.9, 6.3, 0.9])
    assert_allclose(g.mu_at(x, np.zeros_like(x)), [0.6, 0.6, 1.0, 1.0, 0.6, 1.0], rtol=0, atol=0)


@pytest.mark.parametrize("period", [15.0, 5.01, 5.0, 0.6])
def test_auto_render_picks_the_hybrid_for_every_period(tmp_path, period):
    g = only_layer(tmp_path, f'type = "grating"\nperiod_mm = {period}\nmu_low = 0.6\n')
    assert g.render == "hybrid"


def test_auto_render_picks_sho_for_an_object(tmp_path):
    g = only_layer(tmp_path, 'type = "disc"\ncx_mm = 50\ncy_mm = 30\nradius_mm = 10\nmu = 0.7\n')
    assert g.render == "sho"


def test_explicit_render_is_kept(tmp_path):
    g = only_layer(tmp_path, 'type = "grating"\nperiod_mm = 15\nmu_low = 0.6\nrender = "hybrid"\n')
    assert g.render == "hybrid"


def test_defaults(tmp_path):
    scene = load_scene(write(tmp_path, '[[layer]]\ntype = "bump"\ncx_mm = 50\ncy_mm = 30\n'
                                       'sigma_mm = 4\nmu = 0.7\n', name="my-bump.toml"))
    assert scene.name == "my-bump"
    assert scene.description == ""
    assert scene.device == profiles.DeviceProfile()
    layer = scene.layers[0]
    assert (layer.name, layer.render, layer.blend, layer.region) == ("bump-1", "sho", "multiply", None)
    assert layer.visual == model.VisualHints()


def test_objects_match_their_formulas(tmp_path):
    body = """
[[layer]]
type = "rectangle"
x_mm = 10
y_mm = 20
width_mm = 30
height_mm = 10
angle_deg = 90
mu = 0.7
[[layer]]
type = "disc"
cx_mm = 60
cy_mm = 30
radius_mm = 5
mu = 0.8
edge_mm = 2
[[layer]]
type = "edge"
x_mm = 90
y_mm = 10
angle_deg = 180
mu = 0.75
[[layer]]
type = "bump"
cx_mm = 80
cy_mm = 50
sigma_mm = 3
mu = 0.6
[[layer]]
type = "line"
x0_mm = 5
y0_mm = 5
x1_mm = 45
y1_mm = 5
width_mm = 2
mu = 0.9
"""
    rect, disc, edge, bump, line = load_scene(write(tmp_path, body)).layers
    # rectangle rotated 90 deg about its centre (25, 25): now 10 wide in x, 30 tall in y
    assert rect.mu_at(np.array([21.0, 29.0, 25.0]), np.array([25.0, 25.0, 11.0])).tolist() == [0.7, 0.7, 0.7]
    assert rect.mu_at(np.array([31.0]), np.array([25.0])).tolist() == [1.0]
    # soft disc edge: half-way (mu' midway) exactly on the outline, full depth 1 mm inside
    assert_allclose(disc.mu_at(np.array([65.0, 64.0, 66.0]), np.array([30.0] * 3)),
                    [0.9, 0.8, 1.0], atol=1e-12)
    # edge with its normal along -x: slippery to the left of x = 90
    assert edge.mu_at(np.array([89.0, 91.0]), np.array([10.0, 10.0])).tolist() == [0.75, 1.0]
    assert_allclose(bump.mu_at(np.array([83.0]), np.array([50.0])), [1 - 0.4 * math.exp(-0.5)], rtol=1e-14)
    assert line.mu_at(np.array([25.0, 25.0]), np.array([5.9, 6.1])).tolist() == [0.9, 1.0]


def test_waveform_samples_and_shapes(tmp_path):
    w = only_layer(tmp_path, 'type = "waveform"\nshape = "samples"\nperiod_mm = 1.0\n'
                             'samples = [1.0, 0.8, 0.6, 0.8]\n')
    assert w.samples == (1.0, 0.8, 0.6, 0.8)
    assert w.mu_range == (0.6, 1.0)
    assert_allclose(w.profile(np.array([0.0, 0.125, 0.5, 1.5])), [1.0, 0.9, 0.6, 0.6], atol=1e-15)
    sq = only_layer(tmp_path, 'type = "waveform"\nshape = "square"\nperiod_mm = 0.8\nduty = 0.3\n'
                              'mu_min = 0.7\nmu_max = 0.9\n')
    assert (sq.shape, sq.duty, sq.mu_min, sq.mu_max, sq.render) == ("square", 0.3, 0.7, 0.9, "hybrid")


def test_region_rect_and_disc(tmp_path):
    body = """
[[layer]]
type = "grating"
period_mm = 1
mu_low = 0.7
region = { cx_mm = 54, cy_mm = 32.4, radius_mm = 10 }
[[layer]]
type = "grating"
period_mm = 1
mu_low = 0.7
blend = "replace"
[layer.region]
x_mm = 0
y_mm = 0
width_mm = 20
height_mm = 10
"""
    a, b = load_scene(write(tmp_path, body)).layers
    assert a.region == model.DiscRegion(54.0, 32.4, 10.0)
    assert b.region == model.RectRegion(0.0, 0.0, 20.0, 10.0, 0.0)
    assert b.blend == "replace"


def test_colours_are_linearised_srgb(tmp_path):
    layer = only_layer(tmp_path, 'type = "bump"\ncx_mm = 50\ncy_mm = 30\nsigma_mm = 4\nmu = 0.7\n'
                                 '[layer.visual]\ncolor_low = "#ff8000"\ncolor_high = "#FFF"\noutline = true\n')
    # sRGB 0x80 = 128/255 -> ((0.50196 + 0.055) / 1.055) ** 2.4 = 0.21586 (IEC 61966-2-1)
    assert_allclose(layer.visual.color_low, (1.0, 0.2158605001138992, 0.0), rtol=1e-12)
    assert layer.visual.color_high == (1.0, 1.0, 1.0)
    assert layer.visual.outline is True


def test_device_friction_and_calibration(tmp_path):
    body = """
[device]
amplitude_limit_um = 3.0
normal_force_n = 0.4
[device.friction]
b_per_um = 2.0
asymptote_per_n = 1.0
[device.calibration]
amplitudes_um = [0, 0.5, 1, 2, 3]
forces_n = [0.3, 0.6]
mu = [[1, 0.8, 0.6, 0.45, 0.4], [1, 0.85, 0.7, 0.6, 0.58]]
[[layer]]
type = "grating"
period_mm = 15
mu_low = 0.6
"""
    device = load_scene(write(tmp_path, body)).device
    assert (device.amplitude_limit_um, device.normal_force_n) == (3.0, 0.4)
    assert device.friction == profiles.FrictionParams(b_per_um=2.0, asymptote_per_n=1.0)
    assert device.calibration.forces_n == (0.3, 0.6)
    assert device.calibration.mu[1] == (1.0, 0.85, 0.7, 0.6, 0.58)


def raster_file(tmp_path, array, mode=None, name="map.png"):
    Image.fromarray(array, mode=mode).save(tmp_path / name)
    return name


RASTER = 'type = "raster"\nimage = "{image}"\nmu_black = 0.6\nmu_white = 1.0\n'


def test_raster_8bit_stretch(tmp_path):
    grey = np.array([[0, 255], [51, 102]], dtype=np.uint8)
    name = raster_file(tmp_path, grey)
    r = only_layer(tmp_path, RASTER.format(image=name) + "x_mm = 10\ny_mm = 10\nwidth_mm = 20\nheight_mm = 20\n")
    assert r.image.dtype == np.float64
    assert_allclose(r.image, grey / 255.0, rtol=0, atol=0)
    # pixel centres of the 2 x 2 image stretched over 20 x 20 mm sit at 15 and 25 mm
    assert_allclose(r.mu_at(np.array([15.0, 25.0, 15.0]), np.array([15.0, 15.0, 25.0])),
                    [0.6, 1.0, 0.6 + 0.4 * 0.2], rtol=1e-14)
    assert r.image_path == (tmp_path / name).resolve()


def test_raster_16bit_one_to_one_and_tile_default(tmp_path):
    grey = (np.arange(6, dtype=np.uint16).reshape(2, 3) * 13107)  # 0 .. 65535
    name = raster_file(tmp_path, grey)
    r = only_layer(tmp_path, RASTER.format(image=name) + 'mode = "one-to-one"\n')
    assert_allclose(r.image, grey / 65535.0, rtol=0, atol=0)
    # 800 px over 108 mm: one pixel is 0.135 mm
    assert_allclose((r.width_mm, r.height_mm), (3 * 0.135, 2 * 0.135), rtol=1e-12)
    t = only_layer(tmp_path, RASTER.format(image=name) + 'mode = "tile"\nwidth_mm = 50\nheight_mm = 40\n')
    assert_allclose((t.tile_width_mm, t.tile_height_mm), (3 * 0.135, 2 * 0.135), rtol=1e-12)


def test_raster_rgb_is_rec601_luma(tmp_path):
    rgb = np.zeros((1, 3, 3), dtype=np.uint8)
    rgb[0, 0] = (255, 0, 0)
    rgb[0, 1] = (0, 255, 0)
    rgb[0, 2] = (10, 20, 30)
    name = raster_file(tmp_path, rgb)
    r = only_layer(tmp_path, RASTER.format(image=name) + "width_mm = 30\nheight_mm = 10\n")
    assert_allclose(r.image[0], [0.299, 0.587, (0.299 * 10 + 0.587 * 20 + 0.114 * 30) / 255], rtol=1e-12)


def test_reachability_warning_names_the_field_and_floor(tmp_path):
    path = write(tmp_path, '[[layer]]\ntype = "grating"\nperiod_mm = 5\nmu_low = 0.5\n')
    scene, problems, warnings = check_scene(path)
    assert scene is not None and problems == []
    assert len(warnings) == 1
    w = warnings[0]
    # seed 003 eq 2 at 0.5 N and 2.5 um: (1 - 0.565) exp(-1.67 * 2.5) + 0.565
    floor = (1 - 0.565) * math.exp(-1.67 * 2.5) + 0.565
    assert (w.line, w.field, w.warning) == (10, "layer[1].mu_low", True)
    assert f"{floor:.4g}" in w.message and "0.5 N" in w.message
    assert str(w).startswith(f"{path}:10: layer[1].mu_low:")


def test_no_warning_at_a_reachable_level(tmp_path):
    path = write(tmp_path, '[[layer]]\ntype = "grating"\nperiod_mm = 5\nmu_low = 0.58\n')
    assert check_scene(path)[2] == []


def test_reachability_uses_the_calibration_table(tmp_path):
    body = """
[device]
amplitude_limit_um = 3.0
[device.calibration]
amplitudes_um = [0, 1, 3]
forces_n = [0.5]
mu = [[1, 0.9, 0.8]]
[[layer]]
type = "disc"
cx_mm = 50
cy_mm = 30
radius_mm = 5
mu = 0.79
[[layer]]
type = "disc"
cx_mm = 20
cy_mm = 30
radius_mm = 5
mu = 0.81
"""
    _, problems, warnings = check_scene(write(tmp_path, body))
    assert problems == []
    assert [w.field for w in warnings] == ["layer[1].mu"]
    assert "calibration table" in warnings[0].message


def test_raster_warning_uses_the_image_range(tmp_path):
    # the darkest pixel is 0.5 grey: mu' never goes below 0.3 + 0.5 * 0.7 = 0.65
    name = raster_file(tmp_path, np.array([[128, 255]], dtype=np.uint8))
    path = write(tmp_path, "[[layer]]\n" + RASTER.format(image=name).replace("0.6", "0.3")
                 + "width_mm = 10\nheight_mm = 10\n")
    assert check_scene(path)[2] == []


def test_load_scene_raises_texture_error_with_all_problems(tmp_path):
    path = write(tmp_path, '[[layer]]\ntype = "grating"\nperiod_mm = -1\nmu_low = 2\nduty = 1\n')
    with pytest.raises(TextureError, match=r"scene\.toml:9: layer\[1\]\.period_mm: -1 is outside \[0\.01, 10000\] "
                                           r"\(mm\) \(and 2 more problems") as info:
        load_scene(path)
    assert [p.field for p in info.value.problems] == ["layer[1].period_mm", "layer[1].mu_low",
                                                      "layer[1].duty"]
    assert "\n" not in str(info.value)


def test_the_retired_asymptote_cap_is_ignored_with_one_warning(tmp_path, capsys):
    """Format 1 files written when [device.friction] documented asymptote_cap still load:
    the key is ignored (the scene is the one without it) and named in one warning line."""
    from frictex.app.commands.cli import main
    layer = '[[layer]]\ntype = "grating"\nperiod_mm = 2.0\nmu_low = 0.6\n'
    friction = "[device.friction]\nb_per_um = 1.5\n"
    path = write(tmp_path, friction + "asymptote_cap = 0.95\n" + layer)
    scene, problems, warnings = check_scene(path)
    assert problems == [] and len(warnings) == 1
    w = warnings[0]
    assert (w.line, w.field) == (9, "device.friction.asymptote_cap") and "ignored" in w.message
    plain = load_scene(write(tmp_path, friction + layer, name="plain.toml"))
    assert scene.device == plain.device
    capsys.readouterr()
    assert main(["validate", str(path)]) == 0
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith("frictex: warning: ") and "asymptote_cap" in err[0], err

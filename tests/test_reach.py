"""rendering.reach: the share of a scene's area and of a typical stroke below the device's
floor, and the layers that cause it."""

import numpy as np
import pytest

from frictex.device.friction import mu_floor
from frictex.rendering import reach as R
from frictex.rendering.compose import ideal_mu
from frictex.textures.loader import load_scene

HEAD = "format = 1\n[display]\nwidth_mm = 108.0\nheight_mm = 64.8\nwidth_px = 800\nheight_px = 480\n"
RECT = ('[[layer]]\ntype = "rectangle"\nname = "{name}"\nx_mm = {x}\ny_mm = {y}\nwidth_mm = {w}\n'
        'height_mm = {h}\nmu = {mu}\n{extra}')


def scene(tmp_path, *layers):
    path = tmp_path / "s.toml"
    path.write_text(HEAD + "".join(layers), encoding="utf-8")
    return load_scene(path)


def halves(tmp_path, extra_layers=(), fingers=""):
    """Left half at 0.7 times a top band 27 mm high at 0.7: 0.49 < 0.5717 where they overlap
    (not on the display's midline, where the typical stroke starts and often stays)."""
    return scene(tmp_path, RECT.format(name="left", x=0, y=0, w=54.0, h=64.8, mu=0.7, extra=""),
                 RECT.format(name="top", x=0, y=0, w=108.0, h=27.0, mu=0.7, extra=fingers),
                 *extra_layers)


def test_the_area_share_is_where_the_two_overlap(tmp_path):
    got = R.scene_reach(halves(tmp_path))
    assert got.floor == pytest.approx(mu_floor(halves(tmp_path).device, 0.5))
    # the grid's 0.45 mm cells align with both edges: exactly 54 x 27 of 108 x 64.8 mm
    assert got.area_share == pytest.approx(0.5 * 27.0 / 64.8, abs=1e-12)
    assert got.overlap.lowest == pytest.approx(0.49)
    assert got.causes == ("left", "top") and got.below


def test_the_stroke_share_is_the_share_of_the_strokes_path_where_they_overlap(tmp_path):
    """The pipeline's composed targets against the map along the stroke's true path."""
    s = halves(tmp_path)
    got = R.scene_reach(s)
    trace = R.stroke_trace(s)
    t = np.arange(0.0, trace.t_s[-1], 1e-4)
    x = np.interp(t, trace.t_s, trace.x_mm)
    y = np.interp(t, trace.t_s, trace.y_mm)
    expected = float((ideal_mu(s, x, y) < got.floor).mean())
    assert 0.02 < expected < 0.98
    assert got.stroke_share == pytest.approx(expected, abs=0.02)


def test_a_layer_with_a_small_part_of_the_drop_is_not_named(tmp_path):
    """A grating at 0.95 holds -ln 0.95 / (2 (-ln 0.7) - ln 0.95) = 7 % < CAUSE_SHARE."""
    grating = '[[layer]]\ntype = "grating"\nname = "faint"\nperiod_mm = 1.0\nmu_low = 0.95\n'
    got = R.scene_reach(halves(tmp_path, [grating]))
    assert got.causes == ("left", "top")


def test_a_layer_for_a_second_finger_never_multiplies_with_the_first_fingers(tmp_path):
    got = R.scene_reach(halves(tmp_path, fingers='fingers = "2"\n'))
    assert (got.area_share, got.stroke_share, got.causes) == (0.0, 0.0, ())
    assert got.overlap.lowest == pytest.approx(0.7) and not got.below


def test_a_scene_within_reach_runs_nothing(tmp_path, monkeypatch):
    def fail(*args):
        raise AssertionError("the pipeline ran")
    monkeypatch.setattr(R, "_stroke", fail)
    monkeypatch.setattr(R, "_area", fail)
    got = R.scene_reach(scene(tmp_path, RECT.format(name="a", x=0, y=0, w=54, h=64.8, mu=0.8,
                                                    extra="")))
    assert (got.area_share, got.stroke_share, got.overlap.lowest, got.below) == (0.0, 0.0, 0.8, False)


def test_the_grid_covers_the_display_in_cells_of_equal_size():
    from types import SimpleNamespace
    x, y = R.grid(SimpleNamespace(width_mm=350.0, height_mm=6.0))
    assert x.size == 240 * 4 and x.min() == pytest.approx(350 / 480) and y.max() == pytest.approx(6.0 - 0.75)


@pytest.mark.parametrize("size", [(108.0, 64.8), (350.0, 6.0), (1.0, 1.0), (20.0, 300.0)])
def test_the_typical_stroke_stays_on_the_display_whatever_its_size(tmp_path, size):
    path = tmp_path / "s.toml"
    path.write_text(HEAD.replace("108.0", str(size[0])).replace("64.8", str(size[1]))
                    + '[[layer]]\ntype = "grating"\nperiod_mm = 0.5\nmu_low = 0.6\n', encoding="utf-8")
    trace = R.stroke_trace(load_scene(path))
    assert (trace.x_mm >= 0).all() and (trace.x_mm <= size[0]).all()
    assert (trace.y_mm >= 0).all() and (trace.y_mm <= size[1]).all()
    assert np.ptp(trace.x_mm) > 0.2 * size[0] or np.ptp(trace.y_mm) > 0.2 * size[1]


def test_a_key_push_beyond_what_the_beam_actuators_give_is_out_of_reach(tmp_path):
    # keyclick-beam asking a 0.1 N push: from release_n 0.4 N the channels' 3 um, 2.58 um
    # of envelope mid-span (the actuator references peak at 1.164 W), push 0.07-0.08 N;
    # the bundled scene's 0.065 N is within reach over the whole button
    from frictex.textures.library import resolve_scene
    bundled = resolve_scene("keyclick-beam")
    assert R.force_reach(load_scene(bundled)).presses == (('button', 0.0),)
    text = bundled.read_text(encoding="utf-8")
    path = tmp_path / "keyclick-beam.toml"
    path.write_text(text.replace("force_n = 0.065 ", "force_n = 0.1 "), encoding="utf-8")
    found = R.force_reach(load_scene(path))
    (name, share), = found.presses
    assert name == "button" and share > 0.02

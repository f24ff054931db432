"""Clip layers in texture files: authored shapes, AHAP files, and line-located errors."""

import numpy as np
import pytest
from numpy.testing import assert_allclose

from test_texture_loader import write
from frictex.textures.clips import ClipLayer
from frictex.textures.errors import TextureError
from frictex.textures.library import resolve_scene
from frictex.textures.loader import check_scene, load_scene

RATE = 10_000.0


def test_the_bundled_slider_has_an_ahap_end_stop_and_a_press_ramp():
    layers = load_scene(resolve_scene("slider-clips")).layers
    stop, press = layers[1], layers[2]
    assert isinstance(stop, ClipLayer) and (stop.trigger, stop.x_mm) == ("edge", 90.0)
    assert [e.kind for e in stop.clip.events] == ["transient", "continuous"]
    assert press.trigger == "force" and press.force_n == 1.5
    mu, _ = press.clip.sample(RATE)
    t = np.arange(mu.size) / RATE
    assert_allclose(mu, 1.0 - 0.3 * np.clip(1.0 - t / 0.15, 0.0, 1.0), atol=1e-9)


def test_an_envelope_is_piecewise_linear_through_its_points(tmp_path):
    body = ('[[layer]]\ntype = "clip"\ntrigger = "down"\nclip = "envelope"\n'
            'times_s = [0, 0.01, 0.05]\nlevels = [0, 1, 0.5]\ndepth = 0.2\n')
    mu, _ = load_scene(write(tmp_path, body)).layers[0].clip.sample(RATE)
    t = np.arange(mu.size) / RATE
    level = np.where(t < 0.05, np.interp(t, [0, 0.01, 0.05], [0, 1, 0.5]), 0.0)
    assert_allclose(mu, 1.0 - 0.2 * level, atol=1e-9)


CLIP = '[[layer]]\ntype = "clip"\n'


@pytest.mark.parametrize("body, message", [
    (CLIP + 'trigger = "edge"\nclip = "tick"\n', r"scene\.toml:7: layer\[1\]\.x_mm: missing \(required with trigger = \"edge\"\)"),
    (CLIP + 'trigger = "down"\nclip = "tick"\nforce_n = 1\n', r"scene\.toml:11: layer\[1\]\.force_n: not used with trigger = \"down\""),
    (CLIP + 'trigger = "down"\nclip = "ramp"\n', r"layer\[1\]\.duration_s: missing \(required with clip = \"ramp\"\)"),
    (CLIP + 'trigger = "down"\nclip = "tick"\nduration_s = 1\n', r"scene\.toml:11: layer\[1\]\.duration_s: not used with clip = \"tick\""),
    (CLIP + 'trigger = "down"\nclip = "envelope"\ntimes_s = [0, 0.2, 0.1]\nlevels = [0, 1, 0]\n',
     r"scene\.toml:11: layer\[1\]\.times_s: \[0\.0, 0\.2, 0\.1\]: expected times from 0, strictly increasing"),
    (CLIP + 'trigger = "down"\nclip = "ahap"\nfile = "missing.ahap"\n', r"scene\.toml:11: layer\[1\]\.file: \"missing\.ahap\""),
    (CLIP + 'trigger = "down"\nclip = "tick"\ndepth = 1\n', r"scene\.toml:11: layer\[1\]\.depth: 1 is outside \(0, 1\)"),
    # a quoted number in a list: the second value (counted from 1, as layer[1]), and the
    # list shown with it unquoted, never "levels = 1"
    (CLIP + 'trigger = "down"\nclip = "envelope"\ntimes_s = [0, 0.1, 0.2]\nlevels = [0.0, "1", 0.0]\n',
     r'scene\.toml:12: layer\[1\]\.levels\[2\]: expected a number \(level, 0 to 1\), got the string "1"; '
     r"write the number without quotes: levels = \[0\.0, 1, 0\.0\]$"),
    (CLIP + 'trigger = "down"\nclip = "envelope"\ntimes_s = [0, 1, 2, 3, 4, 5, 6, 7]\n'
     'levels = [0, 0.1, 0.2, 0.3, "0.4 um", 0.5, 0.6, 0]\n',
     r"layer\[1\]\.levels\[5\]: .*; write the number without quotes or units: "
     r"levels = \[\.\.\., 0\.2, 0\.3, 0\.4, 0\.5, 0\.6, \.\.\.\]$"),
])
def test_problems_are_reported_at_their_line(tmp_path, body, message):
    with pytest.raises(TextureError, match=message):
        load_scene(write(tmp_path, body))


def test_an_ahap_problem_names_the_file_line_and_json_place(tmp_path):
    (tmp_path / "bad.ahap").write_text('{"Pattern": [{"Event": {"Time": 0, "EventType": "HapticTransient",'
                                       ' "EventParameters": [{"ParameterID": "HapticIntensity",'
                                       ' "ParameterValue": 2}]}}]}', encoding="utf-8")
    _, problems, _ = check_scene(write(tmp_path, CLIP + 'trigger = "down"\nclip = "ahap"\nfile = "bad.ahap"\n'))
    assert len(problems) == 1 and problems[0].line == 11
    assert "Pattern[0].Event.EventParameters[0]: HapticIntensity is 2" in str(problems[0])


def test_a_bad_trigger_and_a_bad_shape_are_both_reported(tmp_path):
    body = CLIP + 'trigger = "force"\nclip = "envelope"\ntimes_s = [0.1, 0.2]\nlevels = [1, 0]\n'
    _, problems, _ = check_scene(write(tmp_path, body))
    assert [(p.line, p.field) for p in problems] == [(7, "layer[1].force_n"), (11, "layer[1].times_s")]


def test_a_clip_asks_for_its_deepest_sample_not_1_minus_depth(tmp_path):
    """A tick of intensity 0.8 at depth 0.4 plays mu' = 1 - 0.4 x 0.8 = 0.68 at its peak, so
    what the scene checks multiply (``lowest_overlap``) is 0.68, not 1 - depth = 0.6."""
    from frictex.textures.overlap import lowest_overlap
    body = (CLIP + 'trigger = "down"\nclip = "tick"\nintensity = 0.8\ndepth = 0.4\n'
            + CLIP + 'trigger = "lift"\nclip = "tick"\ndepth = 0.4\n')
    scene = load_scene(write(tmp_path, body))
    soft, full = scene.layers
    mu, _ = soft.clip.sample(RATE)
    assert soft.mu_range == (float(mu.min()), 1.0)
    # the 17.5 ms pulse peaks half way between two samples at 10 kHz: 2.6e-5 above its peak
    assert soft.mu_range[0] == pytest.approx(1.0 - 0.4 * 0.8, abs=1e-4)
    assert full.mu_range[0] == pytest.approx(0.6, abs=1e-4)
    assert lowest_overlap(scene.display, scene.layers).lowest == pytest.approx(
        soft.mu_range[0] * full.mu_range[0], rel=1e-12)
    assert soft.mu_range[0] * full.mu_range[0] > 0.4  # 0.36 from 1 - depth

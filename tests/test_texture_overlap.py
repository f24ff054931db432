"""The lowest product where layers overlap (``textures.overlap``), and the floor warning
of ``frictex validate`` that gives it: checked against the composed mu' map itself."""

import re

import numpy as np
from hypothesis import given, settings, strategies as st

from frictex.app.commands.cli import main
from frictex.device.profile import DeviceProfile
from frictex.rendering.compose import ideal_mu
from frictex.textures.extent import lowering
from frictex.textures.loader import load_scene
from frictex.textures.model import Display, Line, RectRegion, Scene, Shape, VisualHints
from frictex.textures.overlap import lowest_overlap

HEAD = "format = 1\n[display]\nwidth_mm = 100.0\nheight_mm = 60.0\nwidth_px = 1000\nheight_px = 600\n"
RECT = ('[[layer]]\ntype = "rectangle"\nname = "{name}"\nx_mm = {x}\ny_mm = {y}\nwidth_mm = {w}\n'
        'height_mm = {h}\nmu = {mu}\n')
DISPLAY = Display(100.0, 60.0, 1000, 600)


def _grid(step=0.25):
    """Cell centres of a grid over DISPLAY: every rectangle with edges on whole mm holds some."""
    x, y = np.meshgrid(np.arange(step / 2, 100.0, step), np.arange(step / 2, 60.0, step))
    return x.ravel(), y.ravel()


def _warning(tmp_path, capsys, text):
    path = tmp_path / "scene.toml"
    path.write_text(HEAD + text, encoding="utf-8")
    assert main(["validate", str(path)]) == 0
    [line] = [w for w in capsys.readouterr().err.splitlines() if ": layers: " in w]
    return load_scene(path), line


def _composed_lowest(scene):
    """The lowest mu' of the scene's map and the layers covering it there."""
    x, y = _grid()
    mu = ideal_mu(scene, x, y)
    k = int(np.argmin(mu))
    names = tuple(layer.name for layer in scene.layers
                  if layer.covers(x[k:k + 1], y[k:k + 1])[0] and layer.mu_at(x[k:k + 1], y[k:k + 1])[0] < 1)
    return float(mu[k]), names


def test_layers_apart_warn_with_the_lowest_layer_alone(tmp_path, capsys):
    """Three rectangles that never overlap: the lowest is the lowest layer's own mu',
    not the product of all three (0.5 x 0.6 x 0.7 = 0.21)."""
    text = (RECT.format(name="a", x=5, y=5, w=20, h=20, mu=0.6)
            + RECT.format(name="b", x=40, y=5, w=20, h=20, mu=0.5)
            + RECT.format(name="c", x=70, y=30, w=20, h=20, mu=0.7))
    scene, line = _warning(tmp_path, capsys, text)
    lowest, names = _composed_lowest(scene)
    assert (lowest, names) == (0.5, ("b",))
    assert 'lowest where layers overlap: 0.5, layer "b" alone;' in line


def test_overlapping_layers_warn_with_their_product_and_names(tmp_path, capsys):
    """"a" and "b" overlap (0.75 x 0.7 = 0.525, below the floor 0.5717); "c" lies apart
    and is not named, though it is the lowest layer alone above the floor."""
    text = (RECT.format(name="a", x=5, y=5, w=30, h=20, mu=0.75)
            + RECT.format(name="b", x=20, y=15, w=30, h=20, mu=0.7)
            + RECT.format(name="c", x=70, y=30, w=20, h=20, mu=0.6))
    scene, line = _warning(tmp_path, capsys, text)
    lowest, names = _composed_lowest(scene)
    assert names == ("a", "b")
    shown = float(re.search(r"lowest where layers overlap: ([\d.]+), the product of layers "
                            r'"a", "b";', line).group(1))
    assert shown == float(f"{lowest:.3g}") == 0.525


def _rect(name, x, y, w, h, mu, angle=0.0):
    return Shape(name=name, render="sho", region=None, blend="multiply", visual=VisualHints(),
                 geometry=RectRegion(x, y, w, h, angle), mu=mu)


rects = st.builds(lambda x, y, w, h, mu: (x, y, w, h, mu),
                  st.integers(-20, 95), st.integers(-20, 55), st.integers(1, 40), st.integers(1, 40),
                  st.sampled_from([0.5, 0.6, 0.7, 0.8, 0.9]))


@settings(max_examples=60, deadline=None, derandomize=True)
@given(st.lists(rects, min_size=1, max_size=6))
def test_axis_aligned_rectangles_give_the_composed_minimum_exactly(specs):
    """Rectangles with edges on whole mm: the boxes are the shapes, so the bound is the
    composed map's minimum (a grid of quarter-mm cells holds every overlap)."""
    layers = [_rect(f"r{k}", *spec) for k, spec in enumerate(specs)]
    scene = Scene(1, "s", "", DISPLAY, DeviceProfile(), tuple(layers))
    overlap = lowest_overlap(DISPLAY, layers)
    x, y = _grid()
    assert overlap.lowest == float(ideal_mu(scene, x, y).min())
    at = np.array([overlap.at_mm[0]]), np.array([overlap.at_mm[1]])
    assert float(ideal_mu(scene, *at)[0]) == overlap.lowest
    assert overlap.names == tuple(layer.name for layer in layers if layer.covers(*at)[0])


@settings(max_examples=40, deadline=None, derandomize=True)
@given(st.lists(st.tuples(rects, st.floats(0, 180), st.booleans()), min_size=1, max_size=5))
def test_rotated_shapes_and_lines_never_go_below_the_bound(specs):
    """Rotated rectangles and lines: their boxes are larger than they are, so the bound
    may lie below the composed map, never above it."""
    layers = []
    for k, ((x, y, w, h, mu), angle, line) in enumerate(specs):
        if line:
            layers.append(Line(name=f"l{k}", render="sho", region=None, blend="multiply",
                               visual=VisualHints(), x0_mm=x, y0_mm=y, x1_mm=x + w, y1_mm=y + h,
                               width_mm=2.0, mu=mu))
        else:
            layers.append(_rect(f"r{k}", x, y, w, h, mu, angle))
    scene = Scene(1, "s", "", DISPLAY, DeviceProfile(), tuple(layers))
    x, y = _grid(0.5)
    assert lowest_overlap(DISPLAY, layers).lowest <= float(ideal_mu(scene, x, y).min()) + 1e-12


def test_a_height_layer_lowers_its_region_at_rest_and_its_slope_to_mu_min(tmp_path):
    """The review's scene: a sine disc and a button far from it; the button's layer
    covers the display at mu_rest 0.9, so the disc's lowest is 0.584 x 0.9, and its
    mu_min 0.75 only near the button."""
    path = tmp_path / "s.toml"
    path.write_text(HEAD + '[[layer]]\ntype = "waveform"\nname = "sine"\nshape = "sine"\n'
                    'period_mm = 3.0\nmu_min = 0.584\n[layer.region]\ncx_mm = 25.0\ncy_mm = 30.0\n'
                    'radius_mm = 15.0\n[[layer]]\ntype = "height"\nname = "knob"\nshape = "button"\n'
                    'cx_mm = 80.0\ncy_mm = 45.0\nradius_mm = 8.0\nrim_mm = 2.0\nrise_mm = 0.5\n'
                    'mu_rest = 0.9\nmu_min = 0.75\n', encoding="utf-8")
    scene = load_scene(path)
    assert lowering(scene.layers[1], scene.display) == [((0.0, 0.0, 100.0, 60.0), 0.9),
                                                         ((72.0, 37.0, 88.0, 53.0), 0.75)]
    overlap = lowest_overlap(scene.display, scene.layers)
    assert overlap.names == ("sine", "knob")
    assert overlap.lowest == 0.584 * 0.9


CLIP_OVER = ('[[layer]]\ntype = "clip"\nname = "stop"\nregion = {{ x_mm = 10.0, y_mm = 10.0, '
             'width_mm = 40.0, height_mm = 20.0 }}\ntrigger = "edge"\nx_mm = 30.0\ny_mm = 20.0\n'
             'clip = "ramp"\nduration_s = 0.1\nlevel_from = 1.0\nlevel_to = 0.0\n'
             'depth = {depth}\nfingers = "{fingers}"\n')
TRACK = RECT.format(name="track", x=10, y=10, w=40, h=20, mu=0.9)


def _floor_warnings(tmp_path, body):
    from frictex.textures.loader import check_scene
    path = tmp_path / "scene.toml"
    path.write_text(HEAD + body, encoding="utf-8")
    scene, problems, warnings = check_scene(path)
    assert scene is not None and not problems
    return [w.message for w in warnings if "the device reaches only" in w.message]


def test_a_clip_playing_over_a_fixed_layer_below_the_floor_is_warned_of(tmp_path):
    """A typical stroke seldom fires an edge clip, so the scene's reach showed nothing; yet
    each crossing plays its deepest, 0.6, over the track's 0.9: 0.54, under the 0.5717 the
    default plate reaches at 0.5 N."""
    [said] = _floor_warnings(tmp_path, TRACK + CLIP_OVER.format(depth=0.4, fingers="any"))
    assert said.startswith('playing over layer "track" it may ask for mu\' down to 0.54 '
                           "(its deepest, 0.6, times theirs), but the device reaches only "
                           "0.5717 at the nominal 0.5 N"), said


def test_a_clip_that_stays_within_reach_or_is_not_felt_alone_is_not_warned_of(tmp_path):
    assert _floor_warnings(tmp_path, TRACK + CLIP_OVER.format(depth=0.35, fingers="any")) == []
    assert _floor_warnings(tmp_path, TRACK + CLIP_OVER.format(depth=0.4, fingers="2")) == []
    bump = ('[[layer]]\ntype = "height"\nshape = "bump"\nname = "bump"\ncx_mm = 30.0\n'
            'cy_mm = 20.0\nsigma_mm = 8.0\nrise_mm = 1.0\nmu_rest = 0.9\nmu_min = 0.6\n')
    assert _floor_warnings(tmp_path, bump + CLIP_OVER.format(depth=0.4, fingers="any")) == []


def test_a_clip_is_not_blamed_for_layers_overlapping_away_from_it(tmp_path):
    """Two rectangles at 0.7 overlap each other (0.49, the scene's own warning) far from
    a clip's region (20 ms: felt at most 20 mm beyond it, FAST_FINGER_MM_S): the clip was
    warned of as playing over them."""
    far = CLIP_OVER.format(depth=0.1, fingers="any").replace("x_mm = 10.0, y_mm = 10.0",
                                                             "x_mm = 70.0, y_mm = 10.0")
    far = far.replace("x_mm = 30.0\n", "x_mm = 80.0\n").replace("duration_s = 0.1",
                                                                  "duration_s = 0.02")
    body = (RECT.format(name="a", x=0, y=10, w=30, h=20, mu=0.7)
            + RECT.format(name="b", x=10, y=10, w=30, h=20, mu=0.7) + far)
    assert _floor_warnings(tmp_path, body) == []

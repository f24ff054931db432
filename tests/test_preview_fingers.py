"""frictex preview's friction map is what a finger touching alone gets: layers felt only
with two or more fingers down are left out of it, and named."""

import numpy as np

from frictex.app.commands.cli import main
from frictex.app.commands.preview import preview_figure
from frictex.app.engine.replay import run_replay
from frictex.textures.loader import load_scene

#: a plate (108 x 64.8 mm, 800 x 480 px) with a film on its left half for any finger, a
#: 10 mm grating for the first finger down and a slippery sheet for the second
FINGER_LAYERS = """
format = 1
name = "finger-layers"

[display]
width_mm = 108.0
height_mm = 64.8
width_px = 800
height_px = 480

[device]
profile = "plate-seed003"
amplitude_limit_um = 2.5
normal_force_n = 0.5

[[layer]]
type = "rectangle"
name = "film"
x_mm = 0.0
y_mm = 0.0
width_mm = 54.0
height_mm = 64.8
mu = 0.9

[[layer]]
type = "grating"
name = "lines"
fingers = "1"
render = "sho"
period_mm = 10.0
duty = 0.5
mu_low = 0.8
mu_high = 1.0

[[layer]]
type = "rectangle"
name = "sheet"
fingers = "2"
x_mm = 0.0
y_mm = 0.0
width_mm = 108.0
height_mm = 64.8
mu = 0.5
"""


def _scene_file(tmp_path):
    path = tmp_path / "finger-layers.toml"
    path.write_text(FINGER_LAYERS)
    return path


def test_the_map_is_what_a_lone_fingers_replay_gets_at_the_same_places(tmp_path):
    scene = load_scene(_scene_file(tmp_path))
    _, info = preview_figure(scene)
    run_replay(scene, "swipe-40mms-50hz", tmp_path / "r", progress=False)
    played = np.genfromtxt(tmp_path / "r" / "friction.csv", delimiter=",", names=True)
    mu = info["map"]
    px_per_mm = mu.shape[1] / 108.0
    cols = np.floor(played["x_mm"] * px_per_mm).astype(int)
    rows = np.floor(played["y_mm"] * px_per_mm).astype(int)
    # pixels a level edge crosses are averaged in the map: compare where it is one level
    whole = (mu[rows, cols - 1] == mu[rows, cols]) & (mu[rows, cols + 1] == mu[rows, cols])
    assert whole.mean() > 0.8
    np.testing.assert_allclose(mu[rows, cols][whole], played["mu_target"][whole], atol=1e-6)
    assert set(np.round(played["mu_target"][whole], 6)) == {0.72, 0.8, 0.9, 1.0}


def test_the_layers_left_out_of_the_map_are_named(tmp_path, capsys):
    out = tmp_path / "p.png"
    assert main(["preview", str(_scene_file(tmp_path)), "-o", str(out)]) == 0
    figure = capsys.readouterr().out.splitlines()[0]
    assert "mu' of a finger touching alone 0.720 to 1.000" in figure
    assert figure.endswith('left out of the map: sheet (fingers = "2": only with 2 or more '
                           'fingers down)')


def test_a_scene_whose_layers_all_apply_alone_leaves_nothing_out(capsys, tmp_path):
    assert main(["preview", "grating-5mm", "-o", str(tmp_path / "p.png")]) == 0
    assert "left out" not in capsys.readouterr().out

"""Force layers and [device.driving] in texture files: parsed on the travelling-wave
profiles, refused elsewhere with file, line and field."""

import re

import pytest

from frictex.app.commands.cli import main
from frictex.textures.loader import check_scene
from frictex.device.profile import DrivingForceParams
from frictex.textures.model import Directional, Guidance, KeyClick

HEAD = """\
format = 1
[display]
width_mm = {width}
height_mm = 30.0
width_px = 700
height_px = 150
[device]
profile = "{profile}"
amplitude_limit_um = 3.0
"""

LAYERS = """
[[layer]]
type = "directional"
angle_deg = 180
mu_forward = 0.3
mu_backward = 0.9

[[layer]]
type = "guidance"
x_mm = 70
y_mm = 15
gain_n_per_mm = 0.002
max_force_n = 0.05

[[layer]]
type = "keyclick"
x_mm = 50
y_mm = 5
width_mm = 40
height_mm = 20
first_push = "-x"
"""


def check(tmp_path, text):
    path = tmp_path / "s.toml"
    path.write_text(text, encoding="utf-8")
    scene, problems, _ = check_scene(path)
    return scene, [str(p) for p in problems]


def test_force_layers_and_driving_model_parse_on_the_ring(tmp_path):
    text = HEAD.format(width=140, profile="ring-seed004") + \
        "[device.driving]\nslope_per_um = 0.2\nthreshold_um = 1.3\n" + LAYERS
    scene, problems = check(tmp_path, text)
    assert problems == []
    directional, guidance, keyclick = scene.layers
    assert isinstance(directional, Directional) and directional.axis_sign == -1
    assert directional.target == "mu" and (directional.forward, directional.backward) == (0.3, 0.9)
    assert isinstance(guidance, Guidance) and not guidance.line
    assert isinstance(keyclick, KeyClick) and keyclick.first_push == -1
    assert (keyclick.press_n, keyclick.click_n, keyclick.release_n) == (0.5, 0.8, 0.4)  # seed 004
    assert scene.device.driving == DrivingForceParams(slope_per_um=0.2, threshold_um=1.3)
    # to the friction path a force layer is neutral
    assert directional.mu_at(10.0, 10.0) == 1.0 and directional.blend == "multiply"


@pytest.mark.parametrize("body, field, message", [
    ('type = "directional"\nangle_deg = 45\nmu_forward = 0.3\nmu_backward = 0.9',
     "angle_deg", "45 deg: the waves push only along x"),
    ('type = "directional"\nmu_forward = 0.3\nforce_backward_n = 0.1',
     "type", "both mu_\\* and force_\\*_n"),
    ('type = "directional"\nforce_forward_n = -0.1', "force_backward_n", "missing"),
    ('type = "directional"\nblend = "replace"\nmu_forward = 0.3\nmu_backward = 0.9',
     "blend", "not used on a force layer"),
    ('type = "keyclick"\nx_mm = 50\ny_mm = 5\nwidth_mm = 40\nheight_mm = 20\nclick_n = 0.45',
     "click_n", r"0.45 N is out of order: .* got release_n 0.4 \(default\), press_n 0.5 "
                r"\(default\), click_n 0.45"),
    ('type = "keyclick"\nx_mm = 150\ny_mm = 5\nwidth_mm = 40\nheight_mm = 20',
     "x_mm", "button at x 150 to 190 mm, y 5 to 25 mm lies wholly off the display"),
    ('type = "guidance"\nx_mm = 70\ny_mm = 15\ngain_n_per_mm = 0.01\nmax_force_n = 0.1\n'
     'line_angle_deg = 0', "line_angle_deg", "with line = false"),
])
def test_bad_force_layers_name_the_field(tmp_path, body, field, message):
    text = HEAD.format(width=140, profile="ring-seed004") + "[[layer]]\n" + body + "\n"
    scene, problems = check(tmp_path, text)
    assert scene is None
    assert any(f"layer[1].{field}: " in p and re.search(message, p) for p in problems), problems


def test_force_layers_and_driving_are_refused_on_a_friction_only_profile(tmp_path):
    text = HEAD.format(width=108, profile="plate-seed003") + "[device.driving]\nmu0 = 0.4\n" + LAYERS
    scene, problems = check(tmp_path, text)
    assert scene is None
    assert any(":10: device.driving: not used with profile \"plate-seed003\"" in p for p in problems), problems
    kinds = [p for p in problems if "needs a travelling wave to push the finger" in p]
    assert len(kinds) == 3 and "layer[1].type" in kinds[0]


def test_display_longer_than_the_ring_and_bad_driving_values(tmp_path):
    text = HEAD.format(width=200, profile="ring-seed004") + "[device.driving]\nslope_per_um = 0\n" + LAYERS
    scene, problems = check(tmp_path, text)
    assert scene is None
    assert any("display.width_mm: 200 mm is longer than the 140 mm surface of ring-seed004" in p
               for p in problems), problems
    assert any("device.driving.slope_per_um: 0 is not > 0" in p for p in problems), problems


def test_validate_command_exits_2_with_one_line_per_problem(tmp_path, capsys):
    path = tmp_path / "bad.toml"
    path.write_text(HEAD.format(width=108, profile="plate-seed003") + LAYERS, encoding="utf-8")
    assert main(["validate", str(path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 3 and all(line.startswith(f"frictex: error: {path}") for line in err)

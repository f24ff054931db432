"""The texture file's ``control`` key and the pipeline's ``control`` parameter."""

import pytest

from frictex.rendering.pipeline import build_pipeline
from frictex.textures.errors import TextureError
from frictex.textures.loader import load_scene

BODY = '''format = 1
{control}
[display]
width_mm = 100.0
height_mm = 60.0
width_px = 100
height_px = 60
{device}
[[layer]]
type = "disc"
name = "d"
cx_mm = 50.0
cy_mm = 30.0
radius_mm = 10.0
mu = 0.8
'''


def _scene(tmp_path, control="", device=""):
    path = tmp_path / "s.toml"
    path.write_text(BODY.format(control=control, device=device))
    return load_scene(path)


def test_control_defaults_to_open_loop(tmp_path):
    scene = _scene(tmp_path)
    assert scene.control == "open"
    assert build_pipeline(scene).control is None


@pytest.mark.parametrize("mode", ["closed", "adaptive"])
def test_the_file_selects_the_loop_and_the_caller_may_override(tmp_path, mode):
    scene = _scene(tmp_path, f'control = "{mode}"')
    assert scene.control == mode
    assert build_pipeline(scene).control.mode == mode
    assert build_pipeline(scene, control="open").control is None


def test_an_unknown_mode_is_named(tmp_path):
    with pytest.raises(TextureError, match="control.*not one of open, closed, adaptive"):
        _scene(tmp_path, 'control = "sideways"')


def test_the_loop_needs_seed_003s_model(tmp_path):
    table = ('[device]\n[device.calibration]\namplitudes_um = [0.0, 1.0, 2.0]\n'
             'forces_n = [0.5]\nmu = [[1.0, 0.8, 0.7]]\n')
    with pytest.raises(TextureError, match="control.*plate-seed003"):
        _scene(tmp_path, 'control = "closed"', table)
    assert _scene(tmp_path, "", table).control == "open"


def test_a_closed_loop_asked_of_a_calibrated_scene_says_what_to_do(tmp_path):
    """--control closed on a scene whose [device] has the table frictex calibrate writes
    where the model does not fit: the refusal said 'needs profile plate-seed003 ... got
    plate-seed003 with a calibration table'."""
    from frictex.device.errors import InputError
    table = ('[device]\n[device.calibration]\namplitudes_um = [0.0, 1.0, 2.0]\n'
             'forces_n = [0.5]\nmu = [[1.0, 0.8, 0.7]]\n')
    with pytest.raises(InputError, match=r"has a measured \[device.calibration\] table .*: "
                                         r"play it with --control open, or remove the table"):
        build_pipeline(_scene(tmp_path, "", table), control="closed")

"""Friction constants beyond what frictex calibrate's fit gives (b outside its bounds,
k above them) load, with one warning each naming the file, line, the fit's range and
seed 003's value: b_per_um = 1e6 replayed silently with amplitudes near 1e-6 um."""

import pytest

from frictex.app.commands.cli import main
from frictex.device import calibration_fit
from frictex.textures.loader import check_scene

SCENE = """format = 1
name = "range"
[display]
width_mm = 108.0
height_mm = 64.8
width_px = 800
height_px = 480
[device]
[device.friction]
b_per_um = {b}
asymptote_per_n = {k}
[[layer]]
type = "grating"
name = "lines"
period_mm = 5
mu_low = 0.6
"""


def friction_warnings(tmp_path, b, k):
    scene = tmp_path / "range.toml"
    scene.write_text(SCENE.format(b=b, k=k))
    loaded, problems, warnings = check_scene(scene)
    assert loaded is not None and problems == []
    return [str(w) for w in warnings if w.field.startswith("device.friction")]


@pytest.mark.parametrize("b", [1e6, 0.01])
def test_b_outside_the_fit_s_bounds_is_warned_at_its_line(tmp_path, b):
    low, high = calibration_fit.B_BOUNDS
    assert friction_warnings(tmp_path, b, 1.13) == [
        f"{tmp_path / 'range.toml'}:10: device.friction.b_per_um: {b:g} /um is outside the "
        f"{low:g} to {high:g} /um frictex calibrate's fit allows (seed 003 measured 1.67 /um): "
        f"a typo or a wrong unit?"]


def test_k_above_the_fit_s_bound_is_warned_at_its_line(tmp_path):
    assert friction_warnings(tmp_path, 1.67, 1e5) == [
        f"{tmp_path / 'range.toml'}:11: device.friction.asymptote_per_n: 100000 /N is above "
        f"the {calibration_fit.K_BOUNDS[1]:g} /N frictex calibrate's fit allows (seed 003 "
        f"measured 1.13 /N): a typo or a wrong unit?"]


@pytest.mark.parametrize("b, k", [(0.05, 0.0), (20.0, 5.0), (1.49876, 0.9)])
def test_what_the_fit_can_give_loads_without_a_warning(tmp_path, b, k):
    assert friction_warnings(tmp_path, b, k) == []


def test_validate_prints_the_warning(tmp_path, capsys):
    (tmp_path / "range.toml").write_text(SCENE.format(b=1e6, k=1.13))
    assert main(["validate", str(tmp_path / "range.toml")]) == 0
    err = capsys.readouterr().err
    assert err.count("device.friction.b_per_um: 1e+06 /um is outside the 0.05 to 20 /um") == 1


def test_replay_says_the_scene_files_warnings(tmp_path, capsys):
    """A replay loads the file as validate does and says its warnings (on stderr and in
    summary.json's warnings, first): it replayed b_per_um = 1e6 without a word."""
    import json
    (tmp_path / "range.toml").write_text(SCENE.format(b=1e6, k=1.13))
    out = tmp_path / "out"
    assert main(["replay", str(tmp_path / "range.toml"), "swipe-40mms-50hz", "--out", str(out),
                 "--quiet"]) == 0
    said = "device.friction.b_per_um: 1e+06 /um is outside the 0.05 to 20 /um"
    assert capsys.readouterr().err.count(said) == 1
    assert said in json.loads((out / "summary.json").read_text())["warnings"][0]

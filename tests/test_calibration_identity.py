"""A calibration says what it was fitted on ([device.fitted]) and a replay to another
device or simulated finger warns; files written before the table load as before."""

import json

import numpy as np
import pytest

from frictex.app.commands.cli import main
from frictex.device.calibration_fit import device_toml, fit_points
from frictex.device.calibration_identity import mismatch, simulated_finger
from frictex.device.friction import forward_mu
from frictex.device.profile import FittedOn, FrictionParams
from frictex.textures.loader import load_scene

SCENE = ('format = 1\nname = "c"\n[display]\nwidth_mm = 100.0\nheight_mm = 60.0\n'
         'width_px = 100\nheight_px = 60\n{device}'
         '[[layer]]\ntype = "grating"\nname = "g"\nperiod_mm = 15.0\nmu_low = 0.6\n')


def _section(fitted):
    w = np.repeat(np.linspace(0.0, 2.5, 13), 2)
    normal = np.tile([0.4, 0.6], 13)
    fit = fit_points(w, normal, forward_mu(w, normal, FrictionParams(1.6, 1.05)))
    return device_toml(fit, 2.5, 0.5, fitted=fitted)


@pytest.mark.parametrize("fitted", [FittedOn("frictex sim \"plate\" \\ 1", 3),
                                    FittedOn("Lab plate", None),
                                    FittedOn("Lab plate", None, 60.0)])
def test_the_section_written_reads_back_with_what_it_was_fitted_on(tmp_path, fitted):
    scene = tmp_path / "s.toml"
    scene.write_text(SCENE.format(device=_section(fitted)))
    assert load_scene(scene).device.fitted == fitted


def test_a_file_from_before_the_table_loads_unchecked(tmp_path):
    scene = tmp_path / "s.toml"
    scene.write_text(SCENE.format(device=_section(None)))
    assert load_scene(scene).device.fitted is None
    assert mismatch(None, "any", 7) is None


@pytest.mark.parametrize("table, said", [
    ('[device.fitted]\nfinger = 3\n', "device.fitted.device"),
    ('[device.fitted]\ndevice = "x"\nfinger = -1\n', "device.fitted.finger"),
    ('[device.fitted]\ndevice = "x"\nwho = 1\n', "unknown key"),
    ('[device.fitted]\ndevice = "x"\nspeed_mm_s = 0\n', "device.fitted.speed_mm_s"),
])
def test_a_bad_fitted_table_is_named(tmp_path, table, said):
    scene = tmp_path / "s.toml"
    scene.write_text(SCENE.format(device="[device]\n" + table))
    with pytest.raises(Exception, match=said):
        load_scene(scene)


def test_mismatch_names_what_differs():
    fitted = FittedOn("sim", 3)
    assert mismatch(fitted, "sim", 3) is None
    other_finger = mismatch(fitted, "sim", 7)
    assert "simulated finger 3 (this is simulated finger 7)" in other_finger
    assert "device" not in other_finger.split("fitted")[1].split(":")[0]
    both = mismatch(fitted, "plate", None)
    assert "device 'sim' (this is 'plate')" in both and "a finger not simulated" in both
    assert mismatch(FittedOn("plate"), "plate", 5) is None  # a real finger: not recorded


def test_the_simulated_finger_of_a_device_spec_and_flags():
    assert simulated_finger("sim:finger=2") == 2
    assert simulated_finger("sim", ("--finger", "7")) == 7
    assert simulated_finger("sim") is None
    assert simulated_finger(None) is None


def test_a_replay_on_another_simulated_finger_warns(tmp_path):
    scene = tmp_path / "s.toml"
    scene.write_text(SCENE.format(device=_section(FittedOn("frictex sim-device", 3))))
    warnings = {}
    for finger in (3, 7):
        out = tmp_path / f"f{finger}"
        assert main(["replay", str(scene), "swipe-40mms-50hz", "--out", str(out), "--quiet",
                     "--device", "sim", "--sim-finger", str(finger), "--max-unplayed", "1"]) == 0
        warnings[finger] = json.loads((out / "summary.json").read_text())["warnings"]
    said = [w for w in warnings[7] if "fitted by frictex calibrate" in w]
    assert len(said) == 1 and "simulated finger 3 (this is simulated finger 7)" in said[0]
    assert not any("fitted by frictex calibrate" in w for w in warnings[3])

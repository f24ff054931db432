"""A scene's amplitude limit against what its device profile's drive reaches."""

from pathlib import Path

import pytest

from frictex.app.commands.cli import main
from frictex.device import profile as profiles
from frictex.textures.loader import check_scene

LIBRARY = Path(profiles.__file__).parents[1] / "textures" / "library"


def grating(tmp_path, limit_um: float) -> Path:
    """The bundled grating-15mm scene (plate-seed003) with ``amplitude_limit_um``."""
    text = (LIBRARY / "grating-15mm.toml").read_text(encoding="utf-8")
    old = "amplitude_limit_um = 2.5"
    assert text.count(old) == 1
    path = tmp_path / "grating.toml"
    path.write_text(text.replace(old, f"amplitude_limit_um = {limit_um!r}"), encoding="utf-8")
    return path


def reach_warnings(path):
    scene, problems, warnings = check_scene(path)
    assert scene is not None and problems == []
    return [w for w in warnings if w.field == "device.amplitude_limit_um"]


def test_a_limit_above_the_plates_drive_is_a_warning_naming_both(tmp_path, capsys):
    """validate accepted amplitude_limit_um = 100 on plate-seed003, whose drive reaches
    0.02 um/V x 150 V = 3 um (the audio output clamped 20,000 samples there)."""
    spec = profiles.PROFILES.get("plate-seed003")
    assert spec.amplitude_is_drive
    (w,) = reach_warnings(grating(tmp_path, 100.0))
    assert w.warning and "100 um is above the 3 um" in w.message
    assert "0.02 um/V at its 150 V limit" in w.message
    assert main(["validate", str(grating(tmp_path, 100.0))]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("frictex: warning: ") and "100 um" in err[0]


@pytest.mark.parametrize("limit_um", [2.5, 3.0])
def test_a_limit_the_drive_reaches_is_not_warned(tmp_path, limit_um):
    assert reach_warnings(grating(tmp_path, limit_um)) == []
    assert reach_warnings(grating(tmp_path, 3.01)) != []


def test_a_travelling_waves_limit_is_compared_with_one_channels_reach(tmp_path):
    """A travelling wave's amplitude is each mode's (A cos(kx - wt) = A cos kx cos wt +
    A sin kx sin wt), so each channel is driven up to it: the ring asked 5 um of a
    profile whose one channel reaches 3 um (seed 004: +-3 um at +-80 V) is warned (it
    was not, and keyclick-ring at 100 um drove mode_sym_um to 3.06 um)."""
    ring = profiles.PROFILES.get("ring-seed004")
    assert not ring.amplitude_is_drive and ring.drive_reach_um == pytest.approx(3.0)
    text = (LIBRARY / "keyclick-ring.toml").read_text(encoding="utf-8")
    old = "amplitude_limit_um = 3.0"
    assert text.count(old) == 1
    (tmp_path / "ring.toml").write_text(text.replace(old, "amplitude_limit_um = 5.0"),
                                        encoding="utf-8")
    assert len(reach_warnings(tmp_path / "ring.toml")) == 1

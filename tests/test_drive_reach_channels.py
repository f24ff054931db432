"""Each channel's limit against what one channel's drive reaches, on the modal and
travelling-wave profiles too, and what the warning says clamps where."""

from pathlib import Path

import pytest

from frictex.device import profile as profiles
from frictex.textures.loader import check_scene

LIBRARY = Path(profiles.__file__).parents[1] / "textures" / "library"


def scene(tmp_path, name: str, old: str, new: str) -> Path:
    """The bundled scene ``name`` with its one ``old`` line written ``new``."""
    text = (LIBRARY / f"{name}.toml").read_text(encoding="utf-8")
    assert text.count(old) == 1
    path = tmp_path / f"{name}.toml"
    path.write_text(text.replace(old, new), encoding="utf-8")
    return path


def reach_warnings(path, field: str):
    found, problems, warnings = check_scene(path)
    assert found is not None and problems == []
    return [w for w in warnings if w.field == field and "reaches" in w.message]


def beam(tmp_path, limit_um: float) -> Path:
    return scene(tmp_path, "two-finger-beam-seed000", "channel_limit_um = 0.75",
                 f"channel_limit_um = {limit_um!r}")


def ring(tmp_path, limit_um: float) -> Path:
    return scene(tmp_path, "keyclick-ring", "amplitude_limit_um = 3.0",
                 f"amplitude_limit_um = {limit_um!r}")


def test_a_beam_channel_limit_past_the_drive_is_warned(tmp_path):
    """channel_limit_um = 100 on the beam, whose 0.005125 um/V at 150 V reaches 0.769 um,
    gave commands up to 100 um and validate said ok."""
    (w,) = reach_warnings(beam(tmp_path, 100.0), "device.structure.channel_limit_um")
    assert w.warning and "100 um is above the 0.769 um" in w.message
    assert "0.005125 um/V at its 150 V limit" in w.message


@pytest.mark.parametrize("limit_um", [0.75, 0.76875])
def test_a_beam_channel_limit_the_drive_reaches_is_not_warned(tmp_path, limit_um):
    assert reach_warnings(beam(tmp_path, limit_um), "device.structure.channel_limit_um") == []


def test_a_travelling_wave_limit_past_the_drive_is_warned(tmp_path):
    """keyclick-ring at amplitude_limit_um = 100 asked mode_sym up to 3.059 um of a ring
    whose drive reaches 3 um (0.0375 um/V at 80 V)."""
    (w,) = reach_warnings(ring(tmp_path, 100.0), "device.amplitude_limit_um")
    assert "100 um is above the 3 um" in w.message and "80 V limit" in w.message
    assert reach_warnings(ring(tmp_path, 3.0), "device.amplitude_limit_um") == []


def test_the_warning_says_which_output_clamps_where(tmp_path):
    """The audio output clamps at the profile's voltage limit; a link device (the sim's
    4 um) only at its own declared limit: 'the drive clamps there' was wrong for it."""
    path = scene(tmp_path, "grating-15mm", "amplitude_limit_um = 2.5", "amplitude_limit_um = 4.0")
    (w,) = reach_warnings(path, "device.amplitude_limit_um")
    assert "the drive clamps there" not in w.message
    assert "the audio output clamps" in w.message
    assert "a link device (sim, serial) only at its own declared limit" in w.message

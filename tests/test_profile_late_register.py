"""A device profile registered after a scene was read is one a scene may name: the
profiles a file's ``[device] profile`` may name, and the tables derived from them
(friction loop, modal, travelling-wave), were made once, the first time they were read,
so ``PROFILES.register("myplate", ...)`` in a notebook after ``load_scene("grating-5mm")``
was refused ('"myplate" is not one of plate-seed003, ...') though ``PROFILES.names()``
listed it."""

import dataclasses
from pathlib import Path

import numpy as np
import pytest

import frictex
from frictex.device.profile import PROFILES, BeamStructure, ProfileSpec
from frictex.textures.errors import TextureError

ROOT = Path(__file__).resolve().parents[1]
LIBRARY = ROOT / "textures" / "library"


@pytest.fixture
def in_process_profiles(monkeypatch):
    """PROFILES as it is, restored after the test (what it registers leaves with it)."""
    for field in ("_entries", "_origin", "_registered_by"):
        monkeypatch.setattr(PROFILES, field, dict(getattr(PROFILES, field)))
    monkeypatch.setattr(PROFILES, "_readings", PROFILES._readings)


def naming(tmp_path: Path, bundled: str, profile: str, *, old: str = "plate-seed003",
           more: str = "") -> Path:
    """The bundled scene ``bundled`` with its profile ``old`` replaced by ``profile`` and
    ``more`` appended, written to ``tmp_path``."""
    text = (LIBRARY / f"{bundled}.toml").read_text(encoding="utf-8")
    assert f'profile = "{old}"' in text
    path = tmp_path / "my.toml"
    path.write_text(text.replace(f'profile = "{old}"', f'profile = "{profile}"') + more,
                    encoding="utf-8")
    return path


def test_a_profile_registered_after_a_load_is_one_a_file_may_name(tmp_path,
                                                                  in_process_profiles):
    frictex.load_scene("grating-5mm")  # an earlier notebook cell
    path = naming(tmp_path, "grating-5mm", "myplate")
    with pytest.raises(TextureError, match='"myplate" is not one of plate-seed003'):
        frictex.load_scene(path)
    PROFILES.register("myplate", ProfileSpec("my plate", "single-mode",
                                             amplitude_is_drive=True))
    assert frictex.load_scene(path).device.profile == "myplate"


def test_a_scene_changed_in_code_may_name_a_profile_registered_late(in_process_profiles):
    scene = frictex.load_scene("grating-5mm")
    mine = dataclasses.replace(scene, device=dataclasses.replace(scene.device,
                                                                 profile="myplate"))
    with pytest.raises(TextureError, match='"myplate" is not one of'):
        frictex.build_pipeline(mine)
    PROFILES.register("myplate", ProfileSpec("my plate", "single-mode",
                                             amplitude_is_drive=True))
    assert frictex.build_pipeline(mine).scene.device.profile == "myplate"


def test_the_friction_loop_runs_on_a_profile_registered_late(tmp_path, in_process_profiles):
    frictex.load_scene("grating-5mm")
    frictex.build_pipeline("grating-5mm", control="closed")  # the loop's checks made once
    PROFILES.register("myloop", ProfileSpec("my plate with a force sensor", "single-mode",
                                            friction_loop=True, amplitude_is_drive=True))
    PROFILES.register("noloop", ProfileSpec("my plate without one", "single-mode"))
    closed = naming(tmp_path, "grating-5mm", "myloop")
    closed.write_text('control = "closed"\n' + closed.read_text(encoding="utf-8"),
                      encoding="utf-8")
    assert frictex.load_scene(closed).control == "closed"
    scene = frictex.load_scene(naming(tmp_path, "grating-5mm", "myloop"))
    pipeline = frictex.build_pipeline(scene, control="closed")
    out = pipeline.process(frictex.synth_trace("swipe", duration_s=0.1))
    assert np.all(np.isfinite(out.amplitude_um))
    refused = frictex.load_scene(naming(tmp_path, "grating-5mm", "noloop"))
    with pytest.raises(frictex.FrictexError, match='needs profile plate-seed003 or myloop'):
        frictex.build_pipeline(refused, control="closed")


def test_a_modal_profile_registered_late_takes_its_structure_table(tmp_path,
                                                                   in_process_profiles):
    frictex.load_scene("two-finger-beam-seed000")
    PROFILES.register("mybeam", ProfileSpec("my beam", "modal", structure=BeamStructure))
    path = naming(tmp_path, "two-finger-beam-seed000", "mybeam", old="beam-seed000")
    scene = frictex.load_scene(path)
    assert scene.device.profile == "mybeam"
    assert scene.device.structure == frictex.load_scene("two-finger-beam-seed000").device.structure


def test_a_travelling_wave_profile_registered_late_pushes(tmp_path, in_process_profiles):
    frictex.load_scene("keyclick-beam")
    PROFILES.register("mywave", ProfileSpec("my beam", "travelling-beam",
                                            surface_length_mm=600.0))
    scene = frictex.load_scene(naming(tmp_path, "keyclick-beam", "mywave",
                                      old="travelling-beam-seed002"))
    trace = frictex.synth_trace("swipe", duration_s=0.2)
    mine = frictex.build_pipeline(scene).process(trace)
    bundled = frictex.build_pipeline("keyclick-beam").process(trace)
    np.testing.assert_allclose(mine.commands_um, bundled.commands_um, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(mine.phases_rad, bundled.phases_rad, rtol=1e-12, atol=1e-12)

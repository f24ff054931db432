"""Ctrl+S in the layer panel refuses a file without its owner-write bit (chmod 444):
the save renames a new file over the old, which only the folder's permission governs,
so without this check a read-only scene was silently replaced (also as root)."""

import os
import stat
from pathlib import Path

from frictex.app.live.layer_edit import EditError, LayerEdit
from frictex.textures.library import resolve_scene

import pytest


def read_only_grating(tmp_path) -> Path:
    path = tmp_path / "g.toml"
    path.write_text(resolve_scene("grating-5mm").read_text())
    os.chmod(path, 0o444)
    return path


def test_a_read_only_file_is_not_saved_over(tmp_path):
    path = read_only_grating(tmp_path)
    before = path.read_text()
    ed = LayerEdit(path)
    ed.select(0)
    ed.set("mu_low", 0.5)
    with pytest.raises(EditError) as refused:
        ed.save()
    assert str(refused.value) == ("cannot save g.toml: the file is read-only "
                                  "(chmod u+w g.toml to let the panel save it)")
    assert path.read_text() == before
    assert stat.S_IMODE(os.stat(path).st_mode) == 0o444
    assert [p.name for p in tmp_path.iterdir()] == ["g.toml"]


def test_a_read_only_file_made_writable_saves(tmp_path):
    path = read_only_grating(tmp_path)
    ed = LayerEdit(path)
    ed.select(0)
    ed.set("mu_low", 0.5)
    with pytest.raises(EditError):
        ed.save()
    os.chmod(path, 0o644)
    assert ed.save() == path
    assert "mu_low = 0.5" in path.read_text()


def test_the_panel_shows_the_refusal(tmp_path, monkeypatch, capfd):
    from test_layer_panel_demo import run_demo, save_an_edit
    path = read_only_grating(tmp_path)
    before = path.read_text()
    rec = tmp_path / "rec"
    rec.mkdir()

    def hand(window, loop, haptic):
        save_an_edit(window, loop, said="not saved")
        assert "the file is read-only (chmod u+w g.toml" in loop.panel_note

    run_demo(path, rec, hand)
    assert path.read_text() == before
    assert "saved: " not in capfd.readouterr().out

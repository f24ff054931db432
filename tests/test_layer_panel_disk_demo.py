"""The layer panel in the demo loop (headless window) against a file edited by hand
meanwhile: a good edit of the file reloads and keeps the panel's unsaved values on top
of it; a bad one keeps the last good scene, and Ctrl+S then refuses to overwrite it,
says so, and a second Ctrl+S overwrites it (with the file's permission bits)."""

import os
import stat

import pytest

from frictex.textures.library import resolve_scene
from test_layer_panel_demo import make_edge_smooth, run_demo, wait_for


def test_the_panel_saves_only_onto_the_file_it_read(tmp_path, monkeypatch, capfd):
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "data"))
    path = tmp_path / "lines.toml"
    path.write_text(resolve_scene("grating-5mm").read_text())
    os.chmod(path, 0o644)
    rec = tmp_path / "rec"
    rec.mkdir()

    def hand(window, loop, haptic):
        make_edge_smooth(window, loop)
        assert loop.scene.layers[0].edge_mm == pytest.approx(1.25)  # half the 2.5 mm band
        wait_for("the save button's news", lambda: any(r.text.startswith("unsaved changes")
                                                       for r in loop.compositor.panel_rows))

        path.write_text(path.read_text().replace("mu_high = 1.0", "mu_high = 0.95") + "# by hand\n")
        wait_for("the reload", lambda: loop.scene.layers[0].mu_high == 0.95)
        assert loop.scene.layers[0].edge == "smooth"  # the panel's values kept on top
        wait_for("the panel's note", lambda: "kept 2 unsaved panel values" in loop.panel_note)

        bad = path.read_text().replace("mu_high = 0.95", "mu_high = 1.95")
        path.write_text(bad)
        wait_for("the refused reload", lambda: "reload failed" in (loop.error or ""))
        window.key("ctrl+s")
        wait_for("the refused save", lambda: "changed on disk" in loop.panel_note)
        assert path.read_text() == bad
        window.key("ctrl+s")
        wait_for("the save", lambda: loop.panel_note.startswith("saved"))

    run_demo(path, rec, hand)
    saved = path.read_text()
    assert "mu_high = 0.95" in saved and 'edge = "smooth"' in saved and saved.endswith("# by hand\n")
    assert stat.S_IMODE(os.stat(path).st_mode) == 0o644
    err = capfd.readouterr().err
    assert "kept 2 unsaved panel values" in err
    assert "lines.toml changed on disk since the panel read it: not saved" in err

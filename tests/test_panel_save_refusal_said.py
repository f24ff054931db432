"""A save the layer panel refuses (a read-only file) is said in full: on stderr as one
line, in the error banner, and in the panel wrapped over as many rows as it takes, so
that its end, what to do about it, is in view (it was cut to 'not saved: cannot save
g.toml: the file is r…' in the panel, and said nowhere else); a save that then
succeeds takes the banner down."""

import os

import pytest

from frictex.rendering.visual.layer_panel import PanelView, panel_layout
from frictex.rendering.visual.text import font

from test_layer_edit_read_only import read_only_grating
from test_layer_panel_demo import run_demo, save_an_edit, wait_for

REFUSAL = ("not saved: cannot save g.toml: the file is read-only "
           "(chmod u+w g.toml to let the panel save it)")


def note_rows(rows):
    return [row for row in rows if row.kind == "note"]


def test_a_long_note_is_wrapped_to_the_panel_width():
    label_px, width_px = 14, 240.0
    rows = note_rows(panel_layout(PanelView((), None, (), note=REFUSAL),
                                  (0.0, 0.0, width_px, 600.0), 28.0, label_px))
    assert len(rows) > 1
    assert " ".join(row.text for row in rows) == REFUSAL
    for row in rows:
        assert font(label_px).getlength(row.text) <= row.box[2] - 8.0


def test_a_path_longer_than_a_row_is_broken_inside():
    path = "/home/someone/.local/share/frictex/scenes/a-very-long-scene-name-indeed.toml"
    rows = note_rows(panel_layout(PanelView((), None, (), note=f"saved {path}"),
                                  (0.0, 0.0, 240.0, 600.0), 28.0, 14))
    assert [row.text for row in rows][0] == "saved"
    assert "".join(row.text for row in rows[1:]) == path


def test_a_refused_save_is_said_on_stderr_in_the_banner_and_whole_in_the_panel(
        tmp_path, capfd):
    pytest.importorskip("moderngl", reason="moderngl (Python package) not installed")
    path = read_only_grating(tmp_path)
    rec = tmp_path / "rec"
    rec.mkdir()
    seen = {}

    def hand(window, loop, haptic):
        save_an_edit(window, loop, said="not saved")
        wait_for("the note drawn", lambda: note_rows(loop.compositor.panel_rows))
        seen["note"] = " ".join(row.text for row in note_rows(loop.compositor.panel_rows))
        seen["banner"] = loop.error
        os.chmod(path, 0o644)
        window.key("ctrl+s")
        wait_for("the save", lambda: loop.panel_note.startswith("saved"))
        seen["banner after saving"] = loop.error

    run_demo(path, rec, hand)
    assert seen["note"] == REFUSAL
    assert seen["banner"] == REFUSAL
    assert seen["banner after saving"] is None
    said = capfd.readouterr()
    assert f"frictex demo: {REFUSAL}\n" in said.err
    assert "saved: " in said.out

"""Q with unsaved layer-panel edits: the edits are said lost on stderr, as a scene
switch says them ("... unsaved panel values dropped"); they used to go without a word.
The demo loop runs on the headless window (test_layer_panel_demo's run_demo)."""

from test_layer_edit_disk import grating
from test_layer_panel_demo import make_edge_smooth, run_demo, save_an_edit, wait_for


def test_quitting_with_unsaved_edits_says_they_are_dropped(tmp_path, capfd):
    path = grating(tmp_path)
    rec = tmp_path / "rec"
    rec.mkdir()

    def hand(window, loop, haptic):
        make_edge_smooth(window, loop)
        wait_for("an unsaved edit", lambda: loop.editor is not None and loop.editor.dirty)

    run_demo(path, rec, hand)  # then Q
    err = capfd.readouterr().err
    assert "frictex demo: lines.toml: 2 unsaved panel values dropped (the demo ended)\n" in err


def test_quitting_after_a_save_says_nothing_of_edits(tmp_path, capfd):
    path = grating(tmp_path)
    rec = tmp_path / "rec"
    rec.mkdir()

    run_demo(path, rec, lambda window, loop, haptic: save_an_edit(window, loop))
    assert "dropped" not in capfd.readouterr().err

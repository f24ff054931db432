"""The layer panel and the file on disk: a save writes only onto the text the panel
read (a file changed since is refused once, overwritten by a second save), keeps the
file's permission bits, and a file taken again after it changed keeps the panel's
unsaved edits where they still apply; slider ranges from the format's own bounds; a
grating's edge menu carries its edge_mm; a refused change leaves no undo entry."""

import os
import stat
from pathlib import Path

import pytest

from frictex.app.live import layer_edit
from frictex.app.live.layer_edit import LayerEdit, SaveConflict, Slider, panel_view
from frictex.textures.keys import LAYER_KEYS
from frictex.textures.library import resolve_scene
from frictex.textures.loader import load_scene


@pytest.fixture(autouse=True)
def user_folder(tmp_path, monkeypatch):
    """The user's scene folder under the test's own folder."""
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "data"))
    return tmp_path / "data" / "frictex" / "scenes"


def grating(tmp_path) -> Path:
    path = tmp_path / "lines.toml"
    path.write_text(resolve_scene("grating-5mm").read_text())
    return path


BUMP = """format = 1
name = "my-bump"

[display]
width_mm = 108.0
height_mm = 64.8
width_px = 800
height_px = 480

[[layer]]
type = "height"
name = "bump"
shape = "bump"
cx_mm = 40.0        # left of centre
cy_mm = 32.4
sigma_mm = 5.0
rise_mm = 1.0
"""


def edited(tmp_path) -> LayerEdit:
    ed = LayerEdit(grating(tmp_path))
    ed.select(0)
    ed.set("mu_low", 0.5)
    return ed


def test_a_file_changed_on_disk_is_not_overwritten_until_saved_again(tmp_path):
    ed = edited(tmp_path)
    by_hand = ed.path.read_text().replace("mu_low = 0.6", "mu_low = 0.65") + "# a note\n"
    ed.path.write_text(by_hand)
    with pytest.raises(SaveConflict, match="changed on disk since the panel read it: not saved. "
                                           "Ctrl\\+S again overwrites it"):
        ed.save()
    assert ed.path.read_text() == by_hand and ed.dirty
    ed.save()  # again, the file as the refusal found it: deliberately
    assert "mu_low = 0.5" in ed.path.read_text() and "# a note" not in ed.path.read_text()
    assert not ed.dirty


def test_a_second_save_overwrites_only_the_file_the_refusal_found(tmp_path):
    ed = edited(tmp_path)
    ed.path.write_text(ed.path.read_text() + "# one\n")
    with pytest.raises(SaveConflict):
        ed.save()
    ed.path.write_text(ed.path.read_text() + "# two\n")  # changed again meanwhile
    with pytest.raises(SaveConflict):
        ed.save()
    assert ed.path.read_text().endswith("# one\n# two\n")


def test_a_file_touched_with_the_same_text_is_a_change_too(tmp_path):
    ed = edited(tmp_path)
    info = os.stat(ed.path)
    os.utime(ed.path, ns=(info.st_atime_ns, info.st_mtime_ns + 10**9))
    with pytest.raises(SaveConflict):
        ed.save()


def test_saves_in_a_row_need_no_second_press(tmp_path):
    ed = edited(tmp_path)
    ed.save()
    ed.set("mu_low", 0.4)
    ed.save()
    assert "mu_low = 0.4" in ed.path.read_text()


def test_a_copy_of_a_bundled_scene_does_not_overwrite_a_copy_already_there(user_folder):
    ed = LayerEdit(resolve_scene("grating-5mm"))
    ed.select(0)
    ed.set("mu_low", 0.5)
    user_folder.mkdir(parents=True)
    (user_folder / ed.path.name).write_text("# the user's own\n")
    with pytest.raises(SaveConflict, match="is there already"):
        ed.save()
    assert (user_folder / ed.path.name).read_text() == "# the user's own\n"


@pytest.mark.parametrize("mode", [0o644, 0o640, 0o600, 0o664])
def test_a_save_keeps_the_files_permission_bits(tmp_path, mode):
    ed = edited(tmp_path)
    os.chmod(ed.path, mode)
    ed.save()
    assert stat.S_IMODE(os.stat(ed.path).st_mode) == mode
    assert [p.name for p in tmp_path.iterdir()] == ["lines.toml"]  # no temporary left


@pytest.mark.parametrize("umask", [0o022, 0o027, 0o077])
def test_a_new_copy_gets_the_mode_the_umask_gives(user_folder, umask):
    ed = LayerEdit(resolve_scene("grating-5mm"))
    ed.select(0)
    ed.set("mu_low", 0.5)
    old = os.umask(umask)
    try:
        path = ed.save()
    finally:
        os.umask(old)
    assert path.parent == user_folder
    assert stat.S_IMODE(os.stat(path).st_mode) == 0o666 & ~umask


def test_unsaved_edits_are_kept_on_a_file_taken_again(tmp_path):
    ed = edited(tmp_path)
    ed.set("duty", 0.4, group=1)
    ed.set("duty", 0.3, group=1)
    ed.end_group()
    by_hand = ed.path.read_text().replace("period_mm = 5", "period_mm = 6") + "# a note\n"
    ed.path.write_text(by_hand)
    assert ed.reread() == (2, 0)
    text = ed.text()
    assert "mu_low = 0.5" in text and "duty = 0.3" in text
    assert "period_mm = 6" in text and text.endswith("# a note\n")
    load_scene(ed.path, text=text)
    assert ed.unsaved == 2 and ed.dirty
    assert ed.undo() and "duty = 0.5" in ed.text() and "mu_low = 0.5" in ed.text()
    assert ed.undo() and ed.text() == by_hand and not ed.dirty
    ed.set("mu_low", 0.55)
    ed.save()  # the file as taken again is the one written onto
    assert ed.path.read_text() == by_hand.replace("mu_low = 0.6", "mu_low = 0.55")


def test_an_edit_the_changed_file_refuses_is_dropped_and_counted(tmp_path):
    ed = edited(tmp_path)
    ed.set("duty", 0.1)
    path, text = ed.path, ed.path.read_text()
    # a smooth edge 1 mm wide: fine with duty 0.5 (a 2.5 mm band), not with 0.1 (0.5 mm)
    path.write_text(text.replace('edge = "square"', 'edge = "smooth"\nedge_mm = 1.0'))
    assert ed.reread() == (1, 1)
    assert "mu_low = 0.5" in ed.text() and "duty = 0.5" in ed.text()
    load_scene(path, text=ed.text())


def test_edits_to_a_layer_no_longer_there_are_dropped(tmp_path):
    ed = edited(tmp_path)
    path, text = ed.path, ed.path.read_text()
    path.write_text(text.replace("angle_deg = 0 ", "angle_deg = 10"))
    assert ed.reread() == (1, 0)
    path.write_text(text.replace('name = "lines"', 'name = "other"'))
    assert ed.reread() == (0, 1)  # another layer now: the edit does not apply
    assert ed.text() == path.read_text() and not ed.dirty


def test_a_height_slider_covers_the_formats_range(tmp_path):
    path = tmp_path / "bump.toml"
    path.write_text(BUMP)
    ed = LayerEdit(path)
    ed.select(0)
    rise, spec = ed.control("rise_mm"), LAYER_KEYS["height"]["rise_mm"]
    assert isinstance(rise, Slider) and (rise.lo, rise.hi) == (spec.ge, spec.le)
    assert ed.set("rise_mm", spec.ge / 2) == spec.ge / 2  # a dip
    load_scene(path, text=ed.text())
    cx = ed.control("cx_mm")  # a position: the format's catch-all narrowed to the display
    assert (cx.lo, cx.hi) == (0.0, 108.0)


def test_every_slider_ends_at_a_bound_the_format_gives_tighter_than_its_catch_all(tmp_path):
    ed = LayerEdit(grating(tmp_path))
    ed.select(0)
    for c in ed.controls():
        if isinstance(c, Slider):
            spec = LAYER_KEYS["grating"].get(c.key)
            if spec is not None and spec.ge is not None and abs(spec.ge) < 1.0:
                assert c.lo == spec.ge or c.lo == pytest.approx(spec.ge + c.step)


def test_switching_a_grating_to_smooth_sets_a_usable_edge_width_and_back(tmp_path):
    ed = LayerEdit(grating(tmp_path))
    ed.select(0)
    assert "edge_mm" not in {c.key for c in ed.controls()}
    ed.set("edge", "smooth")
    load_scene(ed.path, text=ed.text())
    width = ed.control("edge_mm")
    table = ed.doc["layer"][0]
    narrow = min(table["duty"], 1 - table["duty"]) * table["period_mm"]
    assert width.written and width.value == pytest.approx(narrow / 2)
    ed.set("edge", "square")
    load_scene(ed.path, text=ed.text())
    assert "edge_mm" not in ed.text()
    assert ed.undo() and "edge_mm" in ed.text() and ed.undo() and not ed.dirty


def test_a_refused_change_leaves_no_undo_entry(tmp_path, monkeypatch):
    # the sliders over the format's ranges alone, so that one's end is refused
    monkeypatch.setattr(layer_edit, "loader_spans", lambda path, doc, index, controls: controls)
    ed = LayerEdit(grating(tmp_path))
    ed.select(0)
    ed.set("edge", "smooth")
    ed.end_group()
    entries = len(ed._undo)
    ed.set("edge_mm", ed.control("edge_mm").hi)  # wider than the band: the loader refuses
    with pytest.raises(ValueError, match="wider than the narrower band"):
        load_scene(ed.path, text=ed.text())
    ed.revert()
    assert len(ed._undo) == entries and 'edge = "smooth"' in ed.text()
    load_scene(ed.path, text=ed.text())
    ed.set("mu_low", 0.5, group=7)  # a drag: its refused later position keeps its entry
    ed.set("edge_mm", ed.control("edge_mm").hi, group=7)
    ed.revert()
    assert len(ed._undo) == entries + 1 and "mu_low = 0.5" in ed.text()
    assert ed.undo() and "mu_low = 0.6" in ed.text()


def test_the_panel_says_unsaved_changes_until_the_scene_is_the_file_again(tmp_path):
    ed = edited(tmp_path)
    assert panel_view(ed).dirty
    ed.save()
    assert not panel_view(ed).dirty
    ed.undo()  # back to the text before the save: not the file
    assert panel_view(ed).dirty and "mu_low = 0.6" in ed.text()


def test_a_key_changed_in_the_file_too_keeps_the_files_value(tmp_path):
    ed = edited(tmp_path)  # mu_low 0.6 -> 0.5 in the panel
    ed.set("mu_high", 0.9)
    text = ed.path.read_text()
    ed.path.write_text(text.replace("mu_low = 0.6", "mu_low = 0.55"))
    assert ed.reread() == (1, 1)
    assert "mu_low = 0.55" in ed.text() and "mu_high = 0.9" in ed.text()


def test_a_save_says_the_full_path_of_a_file_named_relative(tmp_path, monkeypatch, capfd):
    """A scene opened as ``lines.toml`` in the current folder: the panel and the terminal
    name the file saved by its full path, not 'lines.toml in .'."""
    from test_layer_panel_demo import run_demo, save_an_edit
    grating(tmp_path)
    monkeypatch.chdir(tmp_path)
    rec = tmp_path / "rec"
    rec.mkdir()

    def hand(window, loop, haptic):
        save_an_edit(window, loop)
        assert loop.panel_note == f"saved {tmp_path / 'lines.toml'}"

    run_demo(Path("lines.toml"), rec, hand)
    assert f"saved: {tmp_path / 'lines.toml'}\n" in capfd.readouterr().out


def test_a_save_over_a_deleted_file_says_so_and_writes_it_anew_when_saved_again(tmp_path):
    ed = edited(tmp_path)
    ed.path.unlink()
    with pytest.raises(SaveConflict, match="was deleted \\(or moved\\) since the panel read it: "
                                           "not saved. Ctrl\\+S again writes it anew") as refused:
        ed.save()
    assert "deleted or moved" in refused.value.banner and "changed on disk" not in str(refused.value)
    assert not ed.path.exists()
    ed.save()
    assert "mu_low = 0.5" in ed.path.read_text() and not ed.dirty


def test_a_save_is_on_disk_before_it_replaces_the_file(tmp_path, monkeypatch):
    """The new text is synced before the rename: a power cut after the save leaves the
    old file or the new one, never an empty one."""
    events = []
    real_fsync, real_replace = os.fsync, os.replace
    monkeypatch.setattr(layer_edit.os, "fsync", lambda fd: (events.append(
        ("fsync", os.readlink(f"/proc/self/fd/{fd}"))), real_fsync(fd)))
    monkeypatch.setattr(layer_edit.os, "replace", lambda a, b: (events.append(
        ("replace", str(a))), real_replace(a, b)))
    ed = edited(tmp_path)
    ed.save()
    synced = [path for kind, path in events if kind == "fsync"]
    replaced = [path for kind, path in events if kind == "replace"]
    assert len(replaced) == 1 and replaced[0] in synced
    assert events.index(("fsync", replaced[0])) < events.index(("replace", replaced[0]))
    assert "mu_low = 0.5" in (tmp_path / "lines.toml").read_text()

"""The layer panel's save changes only the lines it edits: a key it adds goes after the
layer's keys with no blank line before a sub-table, in the file's line ending; a file
with a byte order mark and CRLF line endings is edited and saved with both; a file
reached through a symbolic link is written where the link leads, and stays a link."""

import difflib

import pytest

from frictex.app.live.layer_edit import LayerEdit
from frictex.textures.loader import load_scene

DISPLAY = """format = 1
[display]
width_mm = 108.0   # width
height_mm = 64.8
width_px = 800
height_px = 480
"""

FILES = {
    "sub-table right after the keys": DISPLAY + """
[[layer]]
type = "grating"   # lines
period_mm = 5
mu_low = 0.6
[layer.visual]
color_low = "#123"
""",
    "a blank line before the sub-table": DISPLAY + """
[[layer]]
type = "grating"
period_mm = 7.3
mu_low = 0.6

[layer.visual]
color_low = "#123"
""",
    "two sub-tables and a second layer": DISPLAY + """[[layer]]
type = "grating"
period_mm = 5.0
mu_low = 0.6
[layer.visual]
color_low = "#123"
[layer.region]
cx_mm = 50
cy_mm = 30
radius_mm = 10
[[layer]]
type = "disc"
cx_mm = 50
cy_mm = 30
radius_mm = 10
mu = 0.7
""",
    "indented keys": DISPLAY + """[[layer]]
  type = "grating"
  period_mm = 5.0
  mu_low = 0.6
  [layer.visual]
  color_low = "#123"
""",
    "no sub-table, the next layer right after": DISPLAY + """[[layer]]
type = "grating"
period_mm = 5.0
mu_low = 0.6
[[layer]]
type = "disc"
cx_mm = 50
cy_mm = 30
radius_mm = 10
mu = 0.7
""",
}


def _changes(before: str, after: str) -> tuple[list[str], list[str]]:
    """(lines taken out, lines put in) from ``before`` to ``after``, line endings kept."""
    out, put = [], []
    matcher = difflib.SequenceMatcher(None, before.splitlines(True), after.splitlines(True),
                                      autojunk=False)
    for op, a0, a1, b0, b1 in matcher.get_opcodes():
        if op != "equal":
            out += before.splitlines(True)[a0:a1]
            put += after.splitlines(True)[b0:b1]
    return out, put


def _edit_and_save(path) -> None:
    """Set a key the first layer gives (mu_low, 0.6 in every file) and one it does not
    (blend); save."""
    editor = LayerEdit(path)
    editor.select(0)
    editor.set("mu_low", 0.55)
    editor.set("blend", "replace")
    editor.save()


@pytest.mark.parametrize("name", FILES)
def test_a_save_keeps_every_line_it_does_not_change_byte_for_byte(tmp_path, name):
    path = tmp_path / "scene.toml"
    path.write_text(FILES[name])
    _edit_and_save(path)
    before, after = FILES[name], path.read_text()
    out, put = _changes(before, after)
    indent = "  " if name == "indented keys" else ""
    assert out == [f"{indent}mu_low = 0.6\n"]
    assert put == [f"{indent}mu_low = 0.55\n", f'{indent}blend = "replace"\n']
    load_scene(path)


def test_a_key_added_to_a_layer_with_a_sub_table_goes_before_it_with_no_blank_line(tmp_path):
    path = tmp_path / "scene.toml"
    path.write_text(FILES["sub-table right after the keys"])
    _edit_and_save(path)
    assert 'mu_low = 0.55\nblend = "replace"\n[layer.visual]\n' in path.read_text()


BOM_CRLF = ("\ufeff" + DISPLAY + '[[layer]]\ntype = "grating"\nperiod_mm = 5.0\nmu_low = 0.6\n'
            '[layer.visual]\ncolor_low = "#123"\n').replace("\n", "\r\n")


def test_a_file_with_a_byte_order_mark_and_crlf_is_edited_and_saved_with_both(tmp_path):
    path = tmp_path / "scene.toml"
    path.write_bytes(BOM_CRLF.encode("utf-8"))
    load_scene(path)  # the loader takes it: so must the panel
    _edit_and_save(path)
    saved = path.read_bytes().decode("utf-8")
    assert saved.startswith("\ufeffformat = 1\r\n")
    assert "\n" not in saved.replace("\r\n", "")
    out, put = _changes(BOM_CRLF, saved)
    assert out == ["mu_low = 0.6\r\n"]
    assert put == ["mu_low = 0.55\r\n", 'blend = "replace"\r\n']
    load_scene(path)


def test_a_file_with_a_byte_order_mark_saves_twice_and_takes_a_change_on_disk(tmp_path):
    path = tmp_path / "scene.toml"
    path.write_bytes(BOM_CRLF.encode("utf-8"))
    editor = LayerEdit(path)
    editor.select(0)
    editor.set("mu_low", 0.55)
    editor.save()
    assert not editor.dirty
    path.write_bytes(path.read_bytes().replace(b"period_mm = 5.0", b"period_mm = 6.0"))
    assert editor.reread() == (0, 0)
    editor.set("mu_low", 0.5)
    editor.save()
    saved = path.read_bytes().decode("utf-8")
    assert saved.startswith("\ufeff") and "period_mm = 6.0\r\nmu_low = 0.5\r\n" in saved


def test_a_save_through_a_symbolic_link_writes_the_file_it_leads_to(tmp_path):
    real = tmp_path / "real.toml"
    real.write_text(FILES["sub-table right after the keys"])
    link = tmp_path / "link.toml"
    link.symlink_to(real.name)
    editor = LayerEdit(link)
    editor.select(0)
    editor.set("mu_low", 0.55)
    editor.save()
    assert link.is_symlink() and link.resolve() == real.resolve()
    assert "mu_low = 0.55\n" in real.read_text()
    editor.set("mu_low", 0.5)
    editor.save()  # the file as last written, read through the link: no conflict
    assert link.is_symlink() and "mu_low = 0.5\n" in real.read_text()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link.toml", "real.toml"]

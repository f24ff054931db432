"""The demo's layer panel without GL: its controls from the loader's key tables, values
clamped to their keys' ranges, undo, and saving that keeps every untouched line of a
texture file byte for byte (on every bundled scene), a bundled scene saved as a copy in
the user's folder; and the panel's layout and hit test."""

import math
from dataclasses import fields, is_dataclass
from pathlib import Path

import numpy as np

import pytest
from hypothesis import given, settings, strategies as st

from frictex.app.live.layer_edit import (EditError, LayerEdit, Menu, Slider, clamp, is_bundled,
                                         layer_controls, save_path)
from frictex.rendering.visual.layer_panel import (ControlView, PanelView, hit, panel_layout,
                                                  track_fraction)
from frictex.rendering.visual.viewport import frame_layout
from frictex.textures.keys import LAYER_KEYS
from frictex.textures.library import list_scenes, resolve_scene
from frictex.textures.loader import load_scene

BUNDLED = [entry.path for entry in list_scenes()]


@pytest.fixture(autouse=True)
def user_folder(tmp_path, monkeypatch):
    """The user's scene folder under the test's own folder."""
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "data"))
    return tmp_path / "data" / "frictex" / "scenes"


def grating(tmp_path, extra=""):
    path = tmp_path / "lines.toml"
    path.write_text(resolve_scene("grating-5mm").read_text() + extra)
    return path


def slider(ed, key) -> Slider:
    control = ed.control(key)
    assert isinstance(control, Slider)
    return control


def test_controls_follow_the_key_tables(tmp_path):
    ed = LayerEdit(grating(tmp_path))
    ed.select(0)
    keys = [c.key for c in ed.controls()]
    assert keys[:2] == ["blend", "render"] and "type" not in keys
    assert set(keys[2:]) <= set(LAYER_KEYS["grating"])
    mu_low = slider(ed, "mu_low")
    assert (mu_low.value, mu_low.written, mu_low.unit) == (0.6, True, "relative friction mu'")
    assert mu_low.allowed_hi == 1.0 and 0.0 < mu_low.allowed_lo <= mu_low.step
    assert mu_low.lo == mu_low.allowed_lo and mu_low.hi == 1.0  # (0, 1]: all of it draggable
    assert slider(ed, "period_mm").hi == 108.0  # lengths: up to the display's larger side
    edge = ed.control("edge")
    assert isinstance(edge, Menu) and edge.options == ("square", "smooth")
    assert (edge.value, edge.written) == ("square", True)


WAVEFORM = """format = 1
name = "w"
[display]
width_mm = 100.0
height_mm = 60.0
width_px = 1000
height_px = 600

[[layer]]
type = "waveform"
shape = "{shape}"
period_mm = 3.0
mu_min = 0.8
[layer.region]
cx_mm = 25.0
cy_mm = 30.0
radius_mm = 15.0

[[layer]]
type = "height"
shape = "bump"
rise_mm = 1.0
cx_mm = 50.0
cy_mm = 30.0
sigma_mm = 2.0

[[layer]]
type = "clip"
trigger = "down"
clip = "ramp"
duration_s = 0.05
[layer.region]
cx_mm = 80.0
cy_mm = 45.0
radius_mm = 8.0
"""


def offered(tmp_path, text, index) -> set[str]:
    path = tmp_path / "w.toml"
    path.write_text(text)
    ed = LayerEdit(path)
    ed.select(index)
    return {c.key for c in ed.controls()}


@pytest.mark.parametrize("shape", ["sine", "triangle", "sawtooth", "square"])
def test_a_waveform_offers_duty_only_where_the_loader_takes_it(tmp_path, shape):
    keys = offered(tmp_path, WAVEFORM.format(shape=shape), 0)
    assert {"period_mm", "mu_min", "mu_max", "angle_deg"} <= keys
    assert ("duty" in keys) == (shape == "square")
    assert "samples" not in keys and "shape" not in keys


def test_every_key_offered_unwritten_loads_when_written_at_its_default(tmp_path):
    """What the panel offers, the loader takes: each layer of the file, each key the
    file does not give, written at the value the panel shows."""
    for shape in ("sine", "square"):
        text = WAVEFORM.format(shape=shape)
        for index in range(3):
            path = tmp_path / "w.toml"
            path.write_text(text)
            ed = LayerEdit(path)
            ed.select(index)
            for c in ed.controls():
                if not c.written:
                    ed.set(c.key, c.value)
            load_scene(path, text=ed.text())


def test_a_height_or_clip_layer_offers_the_keys_of_its_shape_only(tmp_path):
    keys = offered(tmp_path, WAVEFORM.format(shape="sine"), 1)
    assert {"rise_mm", "cx_mm", "sigma_mm", "gain", "mu_rest"} <= keys
    assert not keys & {"radius_mm", "rim_mm", "chamfer_mm", "shape", "width_mm", "angle_deg"}
    keys = offered(tmp_path, WAVEFORM.format(shape="sine"), 2)
    assert {"depth", "duration_s", "level_from", "level_to"} <= keys
    assert not keys & {"intensity", "clip", "trigger"}


def test_a_square_grating_offers_no_edge_width(tmp_path):
    ed = LayerEdit(grating(tmp_path))
    ed.select(0)
    assert "edge_mm" not in {c.key for c in ed.controls()}


def test_an_unnamed_layer_is_listed_by_the_loaders_name_for_it(tmp_path):
    path = tmp_path / "w.toml"
    path.write_text(WAVEFORM.format(shape="sine"))
    names = LayerEdit(path).layer_names()
    loaded = [layer.name for layer in load_scene(path).layers]
    assert names == tuple(f"{name} ({kind})" for name, kind in
                          zip(loaded, ("waveform", "height", "clip")))
    assert names[0] == "waveform-1 (waveform)"


def test_a_refused_edit_is_said_at_the_line_of_the_file_on_disk(tmp_path):
    path = tmp_path / "w.toml"
    text = WAVEFORM.format(shape="square")
    path.write_text(text)
    lines = text.splitlines()
    ed = LayerEdit(path)
    ed.select(0)
    ed.set("duty", 0.3)  # a key the file does not give: a line more in the edited text
    ed.doc["layer"][1]["sigma_mm"] = -1.0  # refused, a line further down than on disk
    with pytest.raises(ValueError) as refused:
        load_scene(path, text=ed.text())
    assert refused.value.problems[0].line > lines.index("sigma_mm = 2.0") + 1  # edited text
    said = ed.refusal(refused.value)
    line = int(said.split(":")[1])
    assert lines[line - 1] == "sigma_mm = 2.0" and "layer[2].sigma_mm" in said
    ed.revert()  # the duty set
    ed.doc["layer"][1]["sigma_mm"] = 2.0
    ed.doc["layer"][0]["shape"] = "sine"
    ed.doc["layer"][0]["duty"] = 0.3
    with pytest.raises(ValueError) as refused:
        load_scene(path, text=ed.text())
    said = ed.refusal(refused.value)
    assert lines[int(said.split(":")[1]) - 1] == "[[layer]]" and "not in the file yet" in said


@settings(max_examples=200, derandomize=True)
@given(value=st.floats(allow_nan=False, allow_infinity=False, width=64))
def test_a_value_is_clamped_to_the_keys_range_and_rounded_to_the_step(tmp_path_factory, value):
    ed = LayerEdit(grating(tmp_path_factory.mktemp("g")))
    ed.select(0)
    for key in ("mu_low", "duty", "period_mm", "angle_deg"):
        s = slider(ed, key)
        written = ed.set(key, value)
        assert s.allowed_lo <= written <= s.allowed_hi
        on_step = written == pytest.approx(round(written / s.step) * s.step, abs=1e-9)
        assert on_step or written in (s.allowed_lo, s.allowed_hi)
        spec = LAYER_KEYS["grating"][key]
        if spec.gt is not None:
            assert written > spec.gt
        if spec.lt is not None:
            assert written < spec.lt
        load_scene(ed.path, text=ed.text())  # what the panel writes, the loader takes


def test_clamp_examples(tmp_path):
    ed = LayerEdit(grating(tmp_path))
    ed.select(0)
    mu = slider(ed, "mu_low")
    assert clamp(mu, 7.0) == 1.0 and clamp(mu, -3.0) == mu.step and clamp(mu, 0.4567) == 0.457
    with pytest.raises(EditError, match="mu_low = nan: expected a finite number"):
        clamp(mu, math.nan)
    with pytest.raises(EditError, match="'wavy' is not one of square, smooth"):
        ed.set("edge", "wavy")
    with pytest.raises(EditError, match="no key 'colour'"):
        ed.set("colour", 1.0)


def test_undo_takes_back_a_change_or_a_whole_drag(tmp_path):
    ed = LayerEdit(grating(tmp_path))
    ed.select(0)
    original = ed.text()
    assert not ed.can_undo and not ed.undo()
    ed.set("mu_low", 0.5)
    after_first = ed.text()
    for v in (0.4, 0.3, 0.2):  # one drag
        ed.set("mu_high", v + 0.5, group=1)
    ed.end_group()
    ed.set("edge", "smooth")
    assert ed.dirty and "mu_high = 0.7" in ed.text() and 'edge = "smooth"' in ed.text()
    assert ed.undo() and 'edge = "square"' in ed.text() and "mu_high = 0.7" in ed.text()
    assert ed.undo() and ed.text() == after_first  # the whole drag at once
    assert ed.undo() and ed.text() == original and not ed.dirty
    assert not ed.undo()


def test_a_value_set_again_is_no_change(tmp_path):
    ed = LayerEdit(grating(tmp_path))
    ed.select(0)
    ed.set("mu_low", 0.6)
    assert not ed.can_undo and not ed.dirty


def valid_nudges(ed):
    """Each number key written in the file moved by 10 of its slider's steps (inwards)
    where the loader takes the result, left set; the key's slider as it was."""
    for k in range(len(ed.layer_names())):
        ed.select(k)
        for c in ed.controls():
            if isinstance(c, Slider) and c.written:
                sign = 1.0 if c.value + 10 * c.step <= c.hi else -1.0
                assert ed.set(c.key, c.value + sign * 10 * c.step) != c.value
                try:
                    load_scene(ed.path, text=ed.text())
                except ValueError:
                    ed.revert()
                    continue
                yield c


def same(a, b) -> bool:
    """Scenes (or their parts) equal field by field, arrays by value, paths by file name
    (a copy's references lie in another folder)."""
    if is_dataclass(a):
        return type(a) is type(b) and all(same(getattr(a, f.name), getattr(b, f.name))
                                          for f in fields(a))
    if isinstance(a, np.ndarray):
        return isinstance(b, np.ndarray) and np.array_equal(a, b)
    if isinstance(a, (tuple, list)):
        return type(a) is type(b) and len(a) == len(b) and all(map(same, a, b))
    if isinstance(a, dict):
        return isinstance(b, dict) and a.keys() == b.keys() and all(same(a[k], b[k]) for k in a)
    if isinstance(a, Path):
        return isinstance(b, Path) and a.name == b.name
    return a == b


def changed_lines(before: str, after: str) -> list[tuple[str, str]]:
    a, b = before.splitlines(keepends=True), after.splitlines(keepends=True)
    assert len(a) == len(b)
    return [(x, y) for x, y in zip(a, b) if x != y]


@pytest.mark.parametrize("path", BUNDLED, ids=[p.stem for p in BUNDLED])
def test_every_bundled_scene_round_trips_a_change_of_one_value(path, user_folder):
    """Load, change one value written in the file, save, diff: one line differs (the key's,
    its comment kept), every other byte as it was; the saved copy (in the user's folder,
    never the bundled file) validates and loads to the scene the edit showed."""
    text = path.read_text()
    ed = LayerEdit(path)
    target = next(iter(valid_nudges(ed)), None)
    assert target is not None, f"{path.name}: no number key the panel can change"
    (old_line, new_line), = changed_lines(text, ed.text())
    key_part, _, comment = old_line.partition("#")
    assert old_line.lstrip().startswith(target.key) and new_line.lstrip().startswith(target.key)
    if comment:
        assert new_line.endswith("#" + comment)
    shown = load_scene(path, text=ed.text())
    saved = ed.save()
    assert saved == user_folder / path.name and path.read_text() == text
    assert saved.read_text() == ed.text() and not ed.dirty
    assert same(load_scene(saved), shown) and not same(load_scene(saved), load_scene(path))


def test_a_key_given_by_its_default_is_written_keeping_every_other_line(tmp_path):
    path = grating(tmp_path)
    ed = LayerEdit(path)
    ed.select(0)
    assert not slider(ed, "offset_mm").written
    ed.set("offset_mm", 1.3)
    lines = ed.text().splitlines(keepends=True)
    assert "offset_mm = 1.3\n" in lines
    it = iter(lines)
    assert all(line in it for line in path.read_text().splitlines(keepends=True))  # in order
    assert ed.save() == path and load_scene(path).layers[0].offset_mm == 1.3


def test_a_bundled_scene_is_saved_as_a_copy_with_the_files_it_names(user_folder):
    path = resolve_scene("raster-map")
    assert is_bundled(path) and save_path(path) == user_folder / "raster-map.toml"
    ed = LayerEdit(path)
    ed.select(0)
    ed.set("mu_black", 0.7)
    saved = ed.save()
    assert (user_folder / "raster-map.png").read_bytes() == (path.parent / "raster-map.png").read_bytes()
    assert load_scene(saved).layers[0].mu_black == 0.7
    assert ed.path == saved and not is_bundled(saved)  # edited from the copy from now on


def test_a_save_the_loader_refuses_writes_nothing(tmp_path):
    path = grating(tmp_path)
    text = path.read_text()
    ed = LayerEdit(path)
    ed.select(0)
    ed.set("mu_low", 0.9)
    ed.doc["layer"][0]["period_mm"] = -1.0  # as a hand edit could leave it
    with pytest.raises(ValueError, match="period_mm"):
        ed.save()
    assert path.read_text() == text


@pytest.mark.parametrize("text, match", [("format = 1\n[display\n", "is not TOML"),
                                         ("format = 1\n", "has no \\[\\[layer\\]\\]")])
def test_files_the_panel_cannot_edit_say_why(tmp_path, text, match):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(EditError, match=match):
        LayerEdit(path)
    with pytest.raises(EditError, match="cannot read missing.toml"):
        LayerEdit(tmp_path / "missing.toml")


def test_layout_and_hit_test_agree():
    view = PanelView(("a (grating)", "b (disc)"), 1,
                     (ControlView("slider", "mu", "mu = 0.5", 0.5),
                      ControlView("menu", "blend", "blend: multiply",
                                  options=("multiply", "min", "replace"))),
                     open_menu="blend", can_undo=True)
    rows = panel_layout(view, (0.0, 40.0, 300.0, 400.0), 24.0)
    kinds = [r.kind for r in rows]
    assert kinds == ["title", "layer", "layer", "slider", "menu", "option", "option", "option",
                     "undo", "save"]
    for row in rows:
        x, y, w, h = row.box
        found, _ = hit(rows, x + w / 2, y + h / 2)
        assert found is row
    s = rows[3]
    tx, ty, tw, th = s.track
    assert hit(rows, tx + 0.25 * tw, ty + 1)[1] == pytest.approx(0.25)
    assert track_fraction(s, tx - 50) == 0.0 and track_fraction(s, tx + tw + 50) == 1.0
    # the track's last pixel is the row's last: a press on it (or one short of it) sets
    # the end's value, which it could not before (0.99 of the way at most)
    assert hit(rows, tx + tw - 1, ty + 1)[1] == 1.0 == track_fraction(s, tx + tw - 2)
    assert hit(rows, tx + 1, ty + 1)[1] == 0.0
    assert hit(rows, 1.0, 41.0) is None  # the column's padding
    short = panel_layout(view, (0.0, 40.0, 300.0, 100.0), 24.0)
    assert [r.kind for r in short] == kinds[:3] and short[-1].box[1] + 24.0 <= 140.0


@pytest.mark.parametrize("size, left", [((800, 615), 240), ((640, 480), 400), ((1920, 1080), 360)])
def test_the_panel_column_is_kept_left_of_the_scene(size, left):
    """frame_layout's left column: the scene fitted right of it (never under it), the scope
    strip still across the frame; a column wider than half the frame is cut to half."""
    display = load_scene(resolve_scene("grating-5mm")).display
    vp, strip, _ = frame_layout(display, *size, True, 0, left_px=left)
    kept = min(left, size[0] // 2)
    assert vp.x0 >= kept and vp.x0 + vp.width_px <= size[0]
    assert strip[0] == 0.0 and strip[2] == size[0] and vp.y0 + vp.height_px <= strip[1]
    alone, _, _ = frame_layout(display, size[0] - kept, size[1], True)
    assert (vp.width_px, vp.height_px, vp.x0 - kept) == (alone.width_px, alone.height_px, alone.x0)


@pytest.mark.parametrize("table, period", [
    ({"type": "grating", "period_mm": 0.6}, 0.6),
    ({"type": "waveform", "shape": "sine", "period_mm": 0.8, "offset_mm": 0.3}, 0.8),
    ({"type": "grating", "period_mm": 5.0, "offset_mm": 7.5}, 7.5)])  # a value past a period
def test_a_periodic_layers_offset_spans_one_period(table, period):
    """The offset spanned the display (0-108 mm, step 0.1): a pixel of drag moved a 0.6 mm
    grating by 1.75 periods, and 0.123456 was written 0.1."""
    offset = next(c for c in layer_controls(table, 108.0) if c.key == "offset_mm")
    assert (offset.lo, offset.hi) == (0.0, period)
    assert offset.step <= period / 500
    assert clamp(offset, 0.123456) == pytest.approx(0.123456, abs=offset.step)


def test_an_integer_key_is_a_slider_of_whole_numbers():
    table = {"type": "recorded", "model": "model.json", "seed": 3}
    seed = next(c for c in layer_controls(table, 100.0) if c.key == "seed")
    assert isinstance(seed, Slider) and seed.integer and seed.step == 1.0
    assert (seed.lo, seed.allowed_lo, seed.allowed_hi) == (0.0, 0.0, 2.0**31 - 1)
    assert clamp(seed, 7.6) == 8.0 and clamp(seed, -4) == 0.0 and clamp(seed, 1e12) == 2**31 - 1


def test_a_full_column_leaves_out_the_last_controls_not_undo_save_and_the_news():
    view = PanelView(("a (grating)",), 0,
                     tuple(ControlView("slider", f"k{i}", f"k{i} = {i}", 0.5) for i in range(20)),
                     note="kept 1 unsaved panel value", can_undo=True, dirty=True)
    rows = panel_layout(view, (0.0, 0.0, 300.0, 6.0 + 10 * 24.0), 24.0)
    assert [r.kind for r in rows] == ["title", "layer"] + ["slider"] * 5 + ["undo", "save", "note"]
    assert [r.key for r in rows[2:7]] == ["k0", "k1", "k2", "k3", "k4"]
    assert rows[-2].text == "unsaved changes: Ctrl+S saves" and rows[-1].box[1] + 24.0 <= 6.0 + 240.0

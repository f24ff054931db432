"""A layer panel slider spans what the loader takes for its layer as it is: a key whose
limit the layer's other keys set (a rectangle's edge_mm at most the shorter side, a
disc's at most the diameter, a rectangle's sides at least its edge_mm) ends there, and a
value set past it is clamped to it, so no drag or click lands on a value the loader
refuses."""

from pathlib import Path

import pytest

from frictex.app.live.layer_edit import LayerEdit, Slider
from frictex.textures.library import resolve_scene
from frictex.textures.loader import load_scene

from test_texture_loader import HEAD

OBJECTS = HEAD + """
[[layer]]
type = "rectangle"
x_mm = 10
y_mm = 10
width_mm = 30
height_mm = 20
mu = 0.5
edge_mm = 2

[[layer]]
type = "disc"
cx_mm = 60
cy_mm = 30
radius_mm = 5
mu = 0.6
edge_mm = 1
"""


@pytest.fixture(autouse=True)
def user_folder(tmp_path, monkeypatch):
    """The user's scene folder under the test's own folder."""
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "data"))


def objects(tmp_path) -> Path:
    path = tmp_path / "scene.toml"
    path.write_text(OBJECTS)
    return path


@pytest.mark.parametrize("layer, limit", [(0, 20.0), (1, 10.0)])  # shorter side, diameter
def test_an_edge_width_slider_ends_at_the_loaders_limit(tmp_path, layer, limit):
    ed = LayerEdit(objects(tmp_path))
    ed.select(layer)
    edge = ed.control("edge_mm")
    assert edge.hi == pytest.approx(limit, abs=edge.step) and edge.hi <= limit
    assert edge.allowed_hi == edge.hi
    assert ed.set("edge_mm", edge.value_at(1.0)) == edge.hi
    load_scene(ed.path, text=ed.text())
    assert ed.set("edge_mm", 1000.0) == edge.hi  # typed past the end: clamped, no refusal


def test_a_side_slider_stops_at_the_edge_width(tmp_path):
    ed = LayerEdit(objects(tmp_path))
    ed.select(0)
    assert ed.control("height_mm").lo == pytest.approx(2.0)  # edge_mm = 2
    ed.set("edge_mm", 15.0)
    assert ed.control("height_mm").lo == pytest.approx(15.0)
    assert ed.control("edge_mm").hi == pytest.approx(20.0)
    ed.set("height_mm", 0.0)
    assert ed.doc["layer"][0]["height_mm"] == pytest.approx(15.0)
    assert ed.control("edge_mm").hi == pytest.approx(15.0)  # the shorter side now
    load_scene(ed.path, text=ed.text())


@pytest.mark.parametrize("scene", [None, "objects-bump-edge-disc"])
def test_both_ends_of_every_slider_load(tmp_path, scene):
    path = objects(tmp_path) if scene is None else resolve_scene(scene)
    ed = LayerEdit(path)
    for k in range(len(ed.layer_names())):
        ed.select(k)
        for c in [c for c in ed.controls() if isinstance(c, Slider)]:
            for fraction in (0.0, 1.0):
                ed.set(c.key, c.value_at(fraction))
                load_scene(path, text=ed.text())  # raises on a refused end
                ed.undo()


def test_a_drag_keeps_its_sliders_ends_and_asks_the_loader_again_when_it_ends(tmp_path,
                                                                               monkeypatch):
    """The ends take a few hundred loader checks; a drag sets a value every frame, so
    its sliders keep the ends they had as it began, each knob at its value of now, and
    the ends are worked out once the drag ends (edge_mm's upper end: the shorter side
    the drag left)."""
    import frictex.app.live.layer_edit as layer_edit
    ed = LayerEdit(objects(tmp_path))
    ed.select(0)
    assert ed.control("edge_mm").hi == pytest.approx(20.0)
    asked = []
    spans = layer_edit.loader_spans
    monkeypatch.setattr(layer_edit, "loader_spans", lambda *a: asked.append(1) or spans(*a))
    drag = object()
    for height in (19.0, 17.0, 12.0):
        ed.set("height_mm", height, group=drag)
        assert ed.control("height_mm").value == height
        assert ed.control("edge_mm").hi == pytest.approx(20.0)  # as the drag began
    assert asked == []
    ed.end_group()
    assert ed.control("edge_mm").hi == pytest.approx(12.0) and asked == [1]

"""The layer panel offers only what the loader takes for the layer as it is: every
position of every slider (a directional layer's angle_deg, which the loader takes only
at 0 or 180, stops there) and every option of every menu ("sht" needs a periodic layer;
a raster's one-to-one drops the sizes it refuses) loads, in every bundled scene."""

import pytest

from frictex.app.live.layer_edit import LayerEdit, Menu, Slider
from frictex.textures.library import list_scenes, resolve_scene
from frictex.textures.loader import load_scene

#: slider positions tried besides the ends (test_layer_edit_loader_spans tries those)
FRACTIONS = (0.1234, 0.5, 0.777)


@pytest.fixture(autouse=True)
def user_folder(tmp_path, monkeypatch):
    """The user's scene folder under the test's own folder."""
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "data"))


@pytest.mark.parametrize("name", [e.name for e in list_scenes() if e.kind == "scene"])
def test_every_slider_position_and_menu_option_offered_loads(name):
    path = resolve_scene(name)
    ed = LayerEdit(path)
    refused = []
    for k in range(len(ed.layer_names())):
        ed.select(k)
        for c in ed.controls():
            tries = c.options if isinstance(c, Menu) else [c.value_at(f) for f in FRACTIONS]
            for value in tries:
                ed.set(c.key, value)
                try:
                    load_scene(path, text=ed.text())
                except ValueError as exc:
                    refused.append(f"layer {k} {c.key} = {value}: {exc}")
                ed.undo()
    assert refused == []


@pytest.mark.parametrize("name", ["directional-beam", "directional-ring"])
def test_a_directional_angle_stops_at_the_directions_the_loader_takes(name):
    ed = LayerEdit(resolve_scene(name))
    ed.select(0)
    angle = ed.control("angle_deg")
    assert isinstance(angle, Slider) and angle.stops == (-180.0, 0.0, 180.0)
    assert angle.value_at(0.1234) == -180.0 and angle.value_at(0.777) == 180.0
    assert ed.set("angle_deg", 100.0) == 180.0  # typed between: the nearest stop
    load_scene(ed.path, text=ed.text())


def test_a_slider_the_loader_takes_throughout_has_no_stops():
    ed = LayerEdit(resolve_scene("grating-5mm"))
    ed.select(0)
    assert all(c.stops == () for c in ed.controls() if isinstance(c, Slider))


@pytest.mark.parametrize("name, layer", [("objects-bump-edge-disc", 0), ("raster-map", 0),
                                         ("slider-clips", 1)])
def test_a_layer_that_is_not_periodic_is_offered_no_periodic_rendering(name, layer):
    ed = LayerEdit(resolve_scene(name))
    ed.select(layer)
    assert ed.control("render").options == ("auto", "sho")


def test_a_raster_set_one_to_one_drops_its_size_and_loads():
    ed = LayerEdit(resolve_scene("raster-map"))
    ed.select(0)
    assert "one-to-one" in ed.control("mode").options
    ed.set("mode", "one-to-one")
    table = ed.doc["layer"][0]
    assert "width_mm" not in table and "height_mm" not in table
    load_scene(ed.path, text=ed.text())
    assert ed.control("mode").options == ("one-to-one",)  # stretch and tile need a size


def test_a_value_moved_off_a_stop_goes_to_the_next_stop_that_way():
    ed = LayerEdit(resolve_scene("directional-beam"))
    ed.select(0)
    assert ed.control("angle_deg").value == 0.0
    assert ed.set("angle_deg", 1.0) == 180.0  # a nudge: not back to 0
    assert ed.set("angle_deg", 179.0) == 0.0
    assert ed.set("angle_deg", -400.0) == -180.0
    assert ed.set("angle_deg", -200.0) == -180.0  # none past -180: kept

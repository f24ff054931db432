"""A Scene changed in code keeps the texture file's word keys and its unique layer names:
a choice the loader refuses, or two layers of one name, is one TextureError line as the
loader's, not a scene that renders as something else (an unknown edge rendered square)."""

import dataclasses

import pytest

import frictex
from frictex._inputs import checked_scene
from frictex.textures.errors import TextureError
from frictex.textures.library import list_scenes
from frictex.textures.model import DiscRegion


def with_layer(scene_name: str, **changes):
    scene = frictex.load_scene(scene_name)
    layers = (dataclasses.replace(scene.layers[0], **changes), *scene.layers[1:])
    return dataclasses.replace(scene, layers=layers)


@pytest.mark.parametrize("scene_name, field, value, message", [
    ("grating-5mm", "edge", "zigzag", '"zigzag" is not one of square, smooth'),
    ("grating-5mm", "edge", 1, "expected one of square, smooth, got the number 1"),
    ("raster-map", "mode", "stretched", '"stretched" is not one of'),
    ("grating-5mm", "render", "nope", '"nope" is not one of auto, sho, hybrid'),
    ("objects-bump-edge-disc", "render", "sht",
     '"sht" needs a periodic layer \\(grating or waveform\\); a Bump layer renders with "sho"'),
])
def test_a_choice_the_loader_refuses_is_refused_naming_layer_and_field(scene_name, field,
                                                                        value, message):
    scene = with_layer(scene_name, **{field: value})
    with pytest.raises(TextureError, match=r"^scene '[^']+', layer '[^']+': "
                                           rf"layers\[0\]\.{field}: {message}"):
        frictex.build_pipeline(scene)


def test_two_layers_of_one_name_are_refused_as_the_loader_refuses_them():
    scene = frictex.load_scene("grating-5mm")
    twice = dataclasses.replace(scene, layers=(scene.layers[0], scene.layers[0]))
    with pytest.raises(TextureError) as caught:
        frictex.replay(twice, frictex.synth_trace("swipe", duration_s=0.1))
    assert str(caught.value) == ("scene 'grating-5mm', layer 'lines': layers[1].name: "
                                 '"lines" is already the name of layers[0]')


def test_a_choice_kept_in_another_form_and_every_bundled_scene_pass():
    """A key click's first_push is written '+x' and kept as +1: not refused as a word."""
    assert with_layer("keyclick-ring", first_push=-1).layers[0].first_push == -1
    checked_scene(with_layer("keyclick-ring", first_push=-1))
    checked_scene(with_layer("grating-5mm", edge="smooth"))
    for entry in list_scenes():
        scene = frictex.load_scene(entry.name)
        assert checked_scene(scene) is scene


@pytest.mark.parametrize("scene_name, resolved", [("grating-5mm", "hybrid"),
                                                  ("objects-bump-edge-disc", "sho")])
def test_render_auto_is_the_renderer_the_loader_picks(scene_name, resolved):
    """``render = "auto"``, the key's default, was kept as the word and refused by the
    pipeline ("unknown renderer 'auto'"); it renders as the loader resolves it."""
    auto = with_layer(scene_name, render="auto")
    assert checked_scene(auto).layers[0].render == resolved
    trace = frictex.synth_trace("swipe", duration_s=0.5)
    got = frictex.replay(auto, trace).friction["mu_target"].to_numpy()
    loaded = frictex.replay(with_layer(scene_name, render=resolved), trace)
    assert (got == loaded.friction["mu_target"].to_numpy()).all()


@pytest.mark.parametrize("scene_name, field, value, message", [
    ("grating-5mm", "region", "x", "expected a RectRegion, a DiscRegion or None, got str"),
    ("grating-5mm", "visual", None, "expected a VisualHints, got NoneType"),
    ("keyclick-ring", "geometry", DiscRegion(10.0, 10.0, 5.0),
     "expected a RectRegion, got DiscRegion"),
    ("objects-bump-edge-disc", "geometry", None,
     "expected a RectRegion or a DiscRegion, got NoneType"),
    ("grating-5mm", "name", " ", "is empty; give the layer a name or leave the key out"),
])
def test_a_region_or_name_the_loader_cannot_give_is_refused(scene_name, field, value, message):
    """A region, outline or visual hints of another type failed deep in the first block
    ("'str' object has no attribute 'contains'"), and a blank name was taken; each is one
    line as the loader's."""
    scene = frictex.load_scene(scene_name)
    index = next(i for i, layer in enumerate(scene.layers) if hasattr(layer, field))
    layers = list(scene.layers)
    layers[index] = dataclasses.replace(layers[index], **{field: value})
    with pytest.raises(TextureError, match=rf"layers\[{index}\]\.{field}: {message}$"):
        frictex.replay(dataclasses.replace(scene, layers=tuple(layers)),
                       frictex.synth_trace("swipe", duration_s=0.1))


def test_a_format_this_frictex_does_not_read_is_refused_as_in_a_file():
    scene = dataclasses.replace(frictex.load_scene("grating-5mm"), format=2)
    with pytest.raises(TextureError, match=r"^scene 'grating-5mm': format: 2 is newer than "
                                           r"this frictex reads; this frictex reads format = 1$"):
        frictex.build_pipeline(scene)


def test_a_layer_class_whose_annotations_do_not_resolve_is_checked_without_its_parts():
    """Another package's layer may annotate a field with a name its module does not
    import: typing.get_type_hints raises NameError, which was no reason to refuse it."""
    namespace: dict = {}
    exec("from __future__ import annotations\n"
         "import dataclasses\n"
         "from frictex.textures.model import Grating\n"
         "@dataclasses.dataclass(frozen=True)\n"
         "class Odd(Grating):\n"
         "    extra: NotImportedHere = None\n", namespace)
    scene = frictex.load_scene("grating-5mm")
    odd = namespace["Odd"](**{f.name: getattr(scene.layers[0], f.name)
                              for f in dataclasses.fields(scene.layers[0])})
    checked_scene(dataclasses.replace(scene, layers=(odd,)))

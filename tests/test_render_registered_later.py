"""A layer's ``render`` and a protocol's renderers take the renderers registered when the
file is read, not those known when frictex was imported: ``render = "wob"`` after
``RENDERERS.register("wob", ...)`` was refused ('"wob" is not one of auto, sho, ...'),
and the refusal listed a package's renderer that cannot be loaded."""

from pathlib import Path

import numpy as np
import pytest

import frictex
from frictex.app.experiment.protocol import ProtocolError, load_protocol
from frictex.device.registry import _Unloaded
from frictex.textures.model import RENDERERS
from flat_renderer import FlatRenderer

ROOT = Path(__file__).resolve().parents[1]
GRATING = (ROOT / "textures" / "library" / "grating-5mm.toml").read_text(encoding="utf-8")


class Wob(FlatRenderer):
    """A renderer of mu' = 0.7 wherever the layer is."""

    MU = 0.7


class Unloadable:
    """An entry point whose package cannot be imported."""

    value = "broken_pkg:Renderer"

    def load(self):
        raise ImportError("No module named 'broken_pkg'")


def write(folder: Path, name: str, text: str) -> Path:
    (folder / name).write_text(text, encoding="utf-8")
    return folder / name


def scene_rendered_by(tmp_path, renderer: str) -> Path:
    """grating-5mm with its layer's ``render`` set to ``renderer``."""
    text = GRATING.replace('render = "auto"', f'render = "{renderer}"')
    assert f'render = "{renderer}"' in text
    return write(tmp_path, "wob.toml", text)


def test_a_renderer_registered_after_import_is_a_layers_render(tmp_path, in_process_renderers):
    frictex.load_scene("grating-5mm")  # frictex imported and a scene read before it
    RENDERERS.register("wob", Wob)
    scene = frictex.load_scene(scene_rendered_by(tmp_path, "wob"))
    result = frictex.replay(scene, frictex.synth_trace("swipe", duration_s=0.2))
    assert np.unique(np.asarray(result.friction.column("mu_target"))).tolist() == [0.7]


def test_a_protocols_renderers_take_one_registered_after_import(tmp_path,
                                                                in_process_renderers):
    head = 'format = 1\nmethod = "magnitude"\nrepetitions = 2\n'
    crossed = write(tmp_path, "crossed.toml", head + '[stimuli]\nscene = "grating-5mm"\n'
                    'renderers = ["sho", "wob"]\n')
    listed = write(tmp_path, "listed.toml", head + '[[stimulus]]\nname = "wobbled"\n'
                   'scene = "grating-15mm"\nrenderer = "wob"\n')
    for path in (crossed, listed):
        with pytest.raises(ProtocolError, match='"wob" is not one of'):
            load_protocol(path)
    RENDERERS.register("wob", Wob)
    assert {s.renderer for s in load_protocol(crossed).stimuli.listed} == {"sho", "wob"}
    assert [s.renderer for s in load_protocol(listed).stimuli.listed] == ["wob"]


def test_a_refused_render_lists_the_renderers_that_load_now(tmp_path, in_process_renderers):
    RENDERERS.register("wob", Wob)
    RENDERERS._add("broken", _Unloaded(Unloadable()), "frictex-broken (broken_pkg:Renderer)")
    with pytest.raises(frictex.FrictexError) as refused:
        frictex.load_scene(scene_rendered_by(tmp_path, "wub"))
    listed = str(refused.value).split('"wub" is not one of ')[1]
    assert listed.endswith(" (did you mean wob?)")
    assert set(listed.removesuffix(" (did you mean wob?)").split(", ")) == {
        "auto", "sho", "hybrid", "sho-held", "sho-predicted", "sht", "wob"}

"""Recorded-texture layers in texture files: the toolkit's XML models, line-located errors."""

import pytest
from numpy.testing import assert_allclose

from test_ar_texture import _model, _xml
from test_texture_loader import write
from textures.errors import TextureError
from textures.hatt import ArTextureLayer
from textures.loader import load_scene

BODY = '[[layer]]\ntype = "recorded"\nmodel = "wood.xml"\ngain = 0.03\n'


def test_a_toolkit_model_file_loads(tmp_path):
    (tmp_path / "wood.xml").write_text(_xml(), encoding="utf-8")
    layer = load_scene(write(tmp_path, BODY)).layers[0]
    assert isinstance(layer, ArTextureLayer) and (layer.gain, layer.mu_mean, layer.seed) == (0.03, 0.8, 0)
    assert_allclose(layer.model.at(110.0, 1.1)[0], _model().at(110.0, 1.1)[0], atol=1e-12)


@pytest.mark.parametrize("xml, extra, message", [
    (None, "", r"scene\.toml:9: layer\[1\]\.model: \"wood\.xml\""),
    (_xml(extra="<numMACoeff>2</numMACoeff>"), "", r"scene\.toml:9: layer\[1\]\.model: .*ARMA models"),
    (_xml(), "mu_mean = 0.5\n", r"scene\.toml:11: layer\[1\]\.mu_mean: mu_min 0\.6 < mu_mean 0\.5"),
    (_xml(), "seed = -1\n", r"scene\.toml:11: layer\[1\]\.seed"),
])
def test_problems_are_reported_at_their_line(tmp_path, xml, extra, message):
    if xml is not None:
        (tmp_path / "wood.xml").write_text(xml, encoding="utf-8")
    with pytest.raises(TextureError, match=message):
        load_scene(write(tmp_path, BODY + extra))

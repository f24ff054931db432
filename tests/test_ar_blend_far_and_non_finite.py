"""The AR blend never lets a NaN out: a non-finite speed or force is refused by the
blend and silent in the renderer (NaN weights, 0/0, before), and a point far outside the
model's range takes the nearest point of the triangulation, not a vertex the rounding of
huge squared distances picked ((50 mm/s, 1e9 N) took the vertex at 0 mm/s)."""

import numpy as np
import pytest

from frictex.rendering.layers.ar_texture import ArTextureRenderer
from frictex.textures.hatt import model_from_coefficients
from test_ar_texture import _block, _layer

# a square of speeds 0..100 mm/s and forces 0..1 N, a variance per vertex
SQUARE = model_from_coefficients([0, 100, 0, 100], [0, 0, 1, 1], [[0, 1, 2], [1, 3, 2]],
                                 [np.array([1.0, -0.5, 0.2])] * 4, [1.0, 2.0, 3.0, 4.0],
                                 rate_hz=10_000.0)


@pytest.mark.parametrize("far, nearest", [
    ((50.0, 1e9), (50.0, 1.0)), ((50.0, -1e9), (50.0, 0.0)), ((1e12, 0.5), (100.0, 0.5)),
    ((-1e300, 0.3), (0.0, 0.3)), ((1e300, 1e300), (100.0, 1.0)), ((30.0, 2e3), (30.0, 1.0))])
def test_a_far_point_blends_as_its_nearest_point_of_the_square(far, nearest):
    (vertices, weights), (want_vertices, want_weights) = SQUARE.weights(*far), SQUARE.weights(*nearest)
    blended = dict(zip(vertices.tolist(), weights))
    expected = dict(zip(want_vertices.tolist(), want_weights))
    for k in set(blended) | set(expected):
        assert blended.get(k, 0.0) == pytest.approx(expected.get(k, 0.0), abs=1e-9), (far, blended)
    assert SQUARE.at(*far)[1] == pytest.approx(SQUARE.at(*nearest)[1], abs=1e-9)


@pytest.mark.parametrize("speed, force", [(50.0, np.nan), (np.nan, 0.5), (np.inf, 0.5),
                                          (50.0, -np.inf)])
def test_the_blend_refuses_a_non_finite_speed_or_force(speed, force):
    with pytest.raises(ValueError, match="only at a finite speed and force"):
        SQUARE.weights(speed, force)
    with pytest.raises(ValueError, match="only at a finite speed and force"):
        SQUARE.at(speed, force)


@pytest.mark.parametrize("speed, force", [(100.0, np.nan), (np.inf, 0.5), (np.nan, 0.5)])
def test_a_non_finite_speed_or_force_renders_silence(speed, force):
    layer = _layer()
    renderer = ArTextureRenderer(layer, 10_000.0)
    mu, _, _ = renderer.render(_block(0, 500, speed, force), renderer.initial_state())
    assert (mu == layer.mu_mean).all()


def test_a_huge_finite_speed_plays_the_model_at_its_edge():
    layer = _layer()
    renderer = ArTextureRenderer(layer, 10_000.0)
    mu, _, _ = renderer.render(_block(0, 500, 1e200, 0.5), renderer.initial_state())
    assert np.isfinite(mu).all() and (mu != layer.mu_mean).any()

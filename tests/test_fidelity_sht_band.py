"""SHT and the hybrid above the output's Nyquist frequency play the texture's mean, not an
alias, and count those samples (``rendering.layers.band_limit``)."""

import numpy as np
import pytest

from frictex.rendering.input.trace_file import DOWN, MOVE, UP, make_trace
from frictex.rendering.pipeline import build_pipeline
from frictex.textures.loader import load_scene
from frictex.textures.library import resolve_scene
from scenes import grating_edges, straddling_samples


def _run(speed_mm_s: float, rate_hz: float, renderer: str = "sht", x0_mm: float = 2.0,
         duration_s: float = 0.26):
    """mu' of ``renderer`` on the 0.6 mm grating (0.6 / 1.0) under a finger swiping from
    ``x0_mm`` at ``speed_mm_s`` sampled at 50 Hz for ``duration_s`` (at 420 mm/s to 103 mm
    of the 108 mm display: a prediction held at its edge rests), at output rate
    ``rate_hz``, once the first fit gives a velocity; and the samples the layer counted
    as played as its mean."""
    scene = load_scene(resolve_scene("grating-0.6mm"))
    t = np.arange(0, duration_s, 0.02)
    ev = np.full(t.size, MOVE, np.int8)
    ev[0], ev[-1] = DOWN, UP
    trace = make_trace(t, np.zeros(t.size, int), x0_mm + speed_mm_s * t,
                       np.full(t.size, 30.0), np.full(t.size, 0.5), ev)
    pipeline = build_pipeline(scene, rate_hz=rate_hz, render_override=renderer,
                              sho_variant="sho-predicted")
    out, state = pipeline.process(0, trace, pipeline.initial_state(),
                                  n_blocks=int((duration_s - 0.02) * rate_hz) // pipeline.block_size)
    moving = out.contact[0] & (out.t_s >= 0.03)
    (layer_state,) = state.layers
    return out.mu_target[0][moving], layer_state.clipped


def _sht_mu(speed_mm_s: float, rate_hz: float) -> np.ndarray:
    return _run(speed_mm_s, rate_hz)[0]


def test_a_texture_above_nyquist_plays_its_mean():
    # 420 mm/s over 0.6 mm is 700 Hz; at 1 kHz output sampling it played 300 Hz
    mu = _sht_mu(420.0, 1000.0)
    np.testing.assert_allclose(mu, 0.8, atol=1e-3)


def test_a_texture_below_nyquist_is_played():
    """240 mm/s is 400 Hz, under 1 kHz's 500 Hz: each sample the mean over the 0.4 period
    it spans, so the output repeats every 5 samples (2 periods), 5 samples average to the
    grating's mean, and it is not that mean."""
    mu = _sht_mu(240.0, 1000.0)
    np.testing.assert_allclose(mu[5:], mu[:-5], rtol=0, atol=1e-9)
    windows = mu[:mu.size // 5 * 5].reshape(-1, 5).mean(axis=1)
    np.testing.assert_allclose(windows, 0.8, rtol=0, atol=1e-9)
    assert mu.std() > 0.1 and mu.min() >= 0.6 and mu.max() <= 1.0


@pytest.mark.parametrize("renderer", ["sht", "hybrid"])
def test_the_samples_played_as_the_mean_are_counted(renderer):
    """Every touching sample whose tracked velocity puts the texture past 500 Hz is
    counted; none at 10 kHz output (5 kHz)."""
    mu, counted = _run(420.0, 1000.0, renderer)
    assert counted >= mu.size and np.count_nonzero(np.isclose(mu, 0.8)) == mu.size
    mu, counted = _run(420.0, 10_000.0, renderer)
    assert counted == 0
    # 0.07 period per sample: 2 edges per period, 0.14 per sample, each within a sample
    # that plays both sides; SHT's phase, 0 at touch-down, meets an edge exactly at every
    # 50th sample boundary (3.5 periods on), 1 edge in 7 (the hybrid's is offset)
    edges = grating_edges(mu)
    assert abs(edges - 0.14 * mu.size) <= 2
    assert edges * 6 / 7 - 2 <= straddling_samples(mu) <= edges

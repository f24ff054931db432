"""SHO above the output's Nyquist frequency plays the texture's mean, not an alias, and
counts those samples as SHT and the hybrid do (``rendering.layers.band_limit``); below
it, and at a jump to a new touch sample under a slower finger, it plays as before."""

import numpy as np
import pytest

from frictex.rendering.layers.sho import HeldSho, PredictedSho
from scenes import grating_box_mean, grating_scene
from test_box_mean import _block
from test_fidelity_sht_band import _run as _swipe_run

RATE = 10_000.0
#: 20 um square grating: 150 mm/s is 7.5 kHz, past 10 kHz output's 5 kHz Nyquist
(FINE,) = grating_scene(0.02).layers


def _run(renderer: str):
    """``test_fidelity_sht_band._run`` of ``renderer`` at 560 mm/s from x = 5 mm for
    0.16 s (on the display throughout) at 1 kHz output."""
    return _swipe_run(560.0, 1000.0, renderer, x0_mm=5.0, duration_s=0.16)


def test_sho_predicted_plays_the_mean_of_a_texture_above_nyquist_and_counts_it():
    """560 mm/s on 0.6 mm is a 933 Hz texture against 1 kHz output's 500 Hz: SHO played
    a 67 Hz square wave 0.786-0.814 and counted nothing; now 0.8, counted as the hybrid
    counts it."""
    mu, counted = _run("sho-predicted")
    np.testing.assert_allclose(mu, 0.8, rtol=0, atol=1e-9)
    assert counted >= mu.size
    assert counted == _run("hybrid")[1]


def _render(renderer, x, vx, bounds):
    """mu' of ``renderer`` over the motion in calls split at ``bounds``, and its count."""
    state, parts = renderer.initial_state(), []
    for lo, hi in zip((0, *bounds), (*bounds, x.size)):
        mu, _, state = renderer.render(_block(x[lo:hi], vx[lo:hi], index0=lo), state)
        parts.append(mu[0])
    return np.concatenate(parts), state.clipped


def _swipe(speed_mm_s, n=2000):
    vx = np.full(n, speed_mm_s)
    return 5.0 + np.arange(n) * speed_mm_s / RATE, vx


@pytest.mark.parametrize("bounds", [(), (1,), (137, 138, 1500), tuple(range(7, 2000, 97))],
                         ids=["whole", "first", "odd", "many"])
def test_a_fine_grating_past_nyquist_plays_its_mean_whatever_the_split(bounds):
    """150 mm/s over 20 um at 10 kHz (0.75 cycle a sample): SHO played a 2.5 kHz alias at
    0.085; now every sample after the first (its point value) plays the mean, all
    counted, the same however the run is split into calls."""
    x, vx = _swipe(150.0)
    mu, counted = _render(PredictedSho(FINE, RATE), x, vx, bounds)
    assert mu[0] == FINE.profile(FINE.phase_at(x[:1], 30.0))[0]
    np.testing.assert_allclose(mu[1:], 0.8, rtol=0, atol=1e-9)
    assert counted == x.size - 1
    assert np.array_equal(mu, _render(PredictedSho(FINE, RATE), x, vx, ())[0])


def test_a_texture_just_below_nyquist_is_played_as_before():
    """99 mm/s over 20 um is 0.495 cycle a sample: each sample the box mean from the
    previous sample's phase, nothing counted, whatever the split."""
    x, vx = _swipe(99.0)
    phase = FINE.phase_at(x, 30.0)
    whole, counted = _render(PredictedSho(FINE, RATE), x, vx, ())
    np.testing.assert_allclose(whole[1:], grating_box_mean(FINE, phase[:-1], phase[1:]),
                               rtol=0, atol=5e-4)
    assert whole.std() > 0.05 and counted == 0
    split, _ = _render(PredictedSho(FINE, RATE), x, vx, (137, 138, 1500))
    assert np.array_equal(split, whole)


def test_a_jump_to_a_touch_sample_under_a_slow_finger_keeps_its_mean_over_the_jump():
    """SHO-held at 100 mm/s, touch samples 200 output samples apart: the position jumps
    2 mm (0.7 cycle of a 3 mm grating) at each, a step, not a texture past Nyquist (it
    is 33 Hz): the sample plays the mean over the jump, uncounted."""
    (layer,) = grating_scene(3.0).layers
    n = 1000
    x = 5.0 + np.floor(np.arange(n) / 200) * 2.0
    mu, counted = _render(HeldSho(layer, RATE), x, np.full(n, 100.0), (300,))
    phase = layer.phase_at(x, 30.0)
    jumps = np.flatnonzero(np.diff(x)) + 1
    np.testing.assert_allclose(mu[jumps], grating_box_mean(layer, phase[jumps - 1], phase[jumps]),
                               rtol=0, atol=5e-4)
    assert np.ptp(mu[jumps]) > 0.1 and counted == 0

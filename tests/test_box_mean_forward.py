"""Each output sample of SHT and the hybrid plays the texture's mean over the stretch the
finger crosses while the sample is held, [phase k, phase k + its own step], not the one
before it (``rendering.layers.band_limit``); the over-Nyquist count follows the phase
travel actually played; a non-finite phase rate holds the phase instead of spoiling it."""

from types import SimpleNamespace

import numpy as np

from frictex.rendering.layers.band_limit import BandLimit
from frictex.rendering.layers.hybrid import integrate_phase
from frictex.rendering.layers.sht import ShtRenderer
from frictex.rendering.tracking.tracks import FingerBlock
from frictex.textures.model import Grating, VisualHints

RATE = 10_000.0
#: 1 mm square grating, low band over the first half of each period
GRATING = Grating(name="lines", render="sht", region=None, blend="multiply",
                  visual=VisualHints(), period_mm=1.0, duty=0.5, mu_low=0.6, mu_high=1.0)


def _square_mean(a, b):
    """mu' of :data:`GRATING` averaged over phase [a, b] (cycles), b > a, computed here:
    the share of the interval inside the low bands, exactly."""
    low = lambda p: np.floor(p) * 0.5 + np.minimum(p - np.floor(p), 0.5)
    share = (low(b) - low(a)) / (b - a)
    return 1.0 + (0.6 - 1.0) * share


def _block(vx, index0):
    """One finger's FingerBlock moving along x at vx (mm/s) per sample, one touch."""
    n = vx.size
    row = lambda a: np.asarray(a, dtype=np.float64).reshape(1, n)
    return FingerBlock(index0=index0, t_s=(index0 + np.arange(n)) / RATE, ids=(0,),
                       contact=np.ones((1, n), bool), touch_id=np.ones((1, n), np.int64),
                       x_held=row(np.full(n, 5.0)), y_held=row(np.full(n, 30.0)),
                       x_pred=row(np.full(n, 5.0)), y_pred=row(np.full(n, 30.0)),
                       vx=row(vx), vy=row(np.zeros(n)), force=row(np.full(n, 0.5)),
                       touch_start=row(np.zeros(n)))


def test_sht_sample_plays_the_stretch_it_is_held_over_across_a_split():
    """SHT over a speed ramp, split into two calls: sample k plays the mean over [phi_k,
    phi_k+1] (phi from 0 at touch-down), the block's last sample and the next block's
    first joining without a seam."""
    n, split = 400, 137
    vx = np.linspace(100.0, 700.0, n)
    renderer, parts = ShtRenderer(GRATING, RATE), []
    state = renderer.initial_state()
    for lo, hi in ((0, split), (split, n)):
        mu, _, state = renderer.render(_block(vx[lo:hi], lo), state)
        parts.append(mu[0])
    mu = np.concatenate(parts)
    phase = np.concatenate(([0.0], np.cumsum(vx / GRATING.period_mm / RATE)))
    np.testing.assert_allclose(mu, _square_mean(phase[:-1], phase[1:]), rtol=0, atol=5e-4)


def test_the_sample_at_an_edge_plays_the_band_it_enters():
    """0.025 cycle per sample from phase 0.4: the sample at phase exactly 0.500 is held
    over [0.500, 0.525], all high band, and plays 1.0 (it played 0.6, the stretch before)."""
    n = 40
    steps = np.empty(n)
    phase, _ = integrate_phase(np.full(n, 250.0), 1.0 / RATE, np.zeros(n, np.int64), None,
                               steps)
    phase = phase + 0.4
    mu = BandLimit(GRATING).play_forward(phase[None], np.ones((1, n), bool), steps[None])
    assert abs(phase[4] - 0.5) < 1e-12
    assert mu[0, 4] == 1.0 and mu[0, 3] == 0.6


def test_nyquist_counts_the_phase_travel_played_not_the_trackers_velocity():
    """A sample whose phase moves 0.6 cycle (a correction on top of synthesis) while the
    tracker says 0.3 cycle per sample plays the mean and is counted."""
    band = BandLimit(GRATING)
    block = SimpleNamespace(vx=np.full((1, 2), 3000.0), vy=np.zeros((1, 2)),
                            contact=np.ones((1, 2), bool))
    mu = np.array([[0.6, 0.6]])
    counted = band.apply(mu, np.ones((1, 2), bool), block, np.array([[0.3, 0.6]]))
    assert counted == 1
    assert mu[0, 0] == 0.6 and mu[0, 1] == band.mean_mu


def test_a_non_finite_phase_rate_holds_the_phase():
    """[10, nan, 10, 10] cycles/s at 1e-4 s: the NaN step is 0 and the touch goes on."""
    steps = np.empty(4)
    phase, carry = integrate_phase(np.array([10.0, np.nan, 10.0, 10.0]), 1e-4,
                                   np.zeros(4, np.int64), None, steps)
    np.testing.assert_allclose(phase, [0.0, 0.001, 0.001, 0.002], rtol=0, atol=1e-15)
    assert np.isclose(carry, 0.003) and np.array_equal(steps, [0.001, 0.0, 0.001, 0.001])


def test_a_mean_never_leaves_the_profiles_range():
    """Stretches starting exactly on an edge (the low band's point value) and lying in the
    high band: their means round to 1.0 +- 1e-11, and a mean past 1 is a clamp the
    inversion counts (the refdata logs' SHT replays counted 1-7 such 'above_one'); each
    plays at most the high band's 1.0, at least the low band's 0.6, whatever the stretch."""
    rng = np.random.default_rng(7)
    n = 20_000
    start = np.where(rng.random(n) < 0.5, 0.5, 1.0) + rng.integers(0, 50, n)
    travel = rng.uniform(1.0 / 65536, 3.0, n) * rng.choice([-1.0, 1.0], n)
    mu = BandLimit(GRATING).play_forward(start[None], np.ones((1, n), bool), travel[None])
    assert mu.max() <= 1.0 and mu.min() >= 0.6
    inside = (np.mod(start, 1.0) == 0.5) & (travel > 0) & (travel <= 0.5)
    assert np.count_nonzero(inside) > 500
    np.testing.assert_allclose(mu[0, inside], 1.0, rtol=0, atol=1e-11)

"""Each output sample of a periodic layer plays the profile's mean over the phase interval
it spans (``rendering.layers.band_limit``): checked against the mean computed here, not
from the renderer's table, and on the alias that point sampling played."""

import numpy as np
import pytest
from scipy.integrate import quad

import frictex

from frictex.rendering.input.trace_file import DOWN, MOVE, UP, make_trace
from frictex.rendering.layers.sho import PredictedSho
from frictex.rendering.layers.sht import ShtRenderer
from frictex.rendering.tracking.tracks import FingerBlock
from frictex.textures.library import resolve_scene
from frictex.textures.model import Grating, VisualHints, Waveform
from scenes import grating_box_mean

RATE = 10_000.0
GRATING = Grating(name="lines", render="sht", region=None, blend="multiply",
                  visual=VisualHints(), period_mm=0.6, duty=0.4, offset_mm=1.3, mu_low=0.6,
                  mu_high=1.0)
SINE = Waveform(name="sine", render="sht", region=None, blend="multiply", visual=VisualHints(),
                period_mm=0.6, offset_mm=1.3, shape="sine", mu_min=0.6, mu_max=1.0)

#: renderer against box mean: the renderer's table places an edge to 1/65536 cycle, so a
#: mean over at least 0.02 cycle is off by at most 0.4 / 65536 / 0.02 = 3e-4
TOLERANCE = 5e-4


def _box_mean(layer, a, b):
    """The mean of ``layer``'s profile over phase [a, b] (cycles): exact for a square
    grating (the part of the interval inside low bands), scipy's quad otherwise."""
    if isinstance(layer, Grating):
        return grating_box_mean(layer, a, b)
    return np.array([quad(lambda p: float(layer.profile(p)), lo, hi, limit=200)[0] / (hi - lo)
                     for lo, hi in zip(a, b)])


def _block(x, vx, index0=0):
    """One finger's FingerBlock along x (mm) at velocity vx (mm/s), y 30 mm, one touch."""
    n = x.size
    row = lambda a: np.asarray(a, dtype=np.float64).reshape(1, n)
    return FingerBlock(index0=index0, t_s=(index0 + np.arange(n)) / RATE, ids=(0,),
                       contact=np.ones((1, n), bool), touch_id=np.ones((1, n), np.int64),
                       x_held=row(x), y_held=row(np.full(n, 30.0)), x_pred=row(x),
                       y_pred=row(np.full(n, 30.0)), vx=row(vx), vy=row(np.zeros(n)),
                       force=row(np.full(n, 0.5)), touch_start=row(np.zeros(n)))


def _render(renderer, x, vx, split):
    """mu' of ``renderer`` over the motion in two calls, split at sample ``split``."""
    state, parts = renderer.initial_state(), []
    for lo, hi in ((0, split), (split, x.size)):
        mu, _, state = renderer.render(_block(x[lo:hi], vx[lo:hi], index0=lo), state)
        parts.append(mu[0])
    return np.concatenate(parts)


def _motion(reversal):
    """Velocity (mm/s) and position (mm) per output sample: 300 mm/s constant, or 300 mm/s
    turning to -300 mm/s half way."""
    n = 400
    vx = np.where(np.arange(n) < n // 2, 300.0, -300.0) if reversal else np.full(n, 300.0)
    return vx, 5.0 + np.concatenate(([0.0], np.cumsum(vx[:-1]) / RATE))


@pytest.mark.parametrize("layer", [GRATING, SINE], ids=["grating", "sine"])
@pytest.mark.parametrize("reversal", [False, True], ids=["swipe", "reversal"])
@pytest.mark.parametrize("mode", ["sht", "sho-predicted"])
def test_each_sample_plays_the_mean_over_its_phase_interval(mode, reversal, layer):
    """SHT's phase from 0 at touch-down (the sum of its rate over the samples before) or
    SHO's at the finger's position; SHT's sample k plays the mean over [phase k,
    phase k+1] (the stretch crossed while it is held), SHO's over [phase k-1, phase k]
    (it knows no phase before it comes), its first its point value; whatever the split
    into calls."""
    vx, x = _motion(reversal)
    if mode == "sht":
        renderer = ShtRenderer(layer, RATE)
        phase = (x - x[0]) / layer.period_mm
    else:
        renderer = PredictedSho(layer, RATE)
        phase = (x - layer.offset_mm) / layer.period_mm
    mu = _render(renderer, x, vx, split=137)
    if mode == "sht":  # held over [phase k, phase k+1]
        played, expected = mu[:-1], _box_mean(layer, phase[:-1], phase[1:])
        assert np.abs(played - layer.profile(phase[:-1])).max() > 0.02  # not point values
    else:  # from the previous sample's phase; the first its point value
        assert mu[0] == layer.profile(phase[:1])[0]
        played, expected = mu[1:], _box_mean(layer, phase[:-1], phase[1:])
        assert np.abs(played - layer.profile(phase[1:])).max() > 0.02  # not point values
    np.testing.assert_allclose(played, expected, rtol=0, atol=TOLERANCE)


@pytest.mark.parametrize("mode", ["sht", "sho-predicted"])
def test_a_finger_at_rest_plays_the_point_value(mode):
    """A finger that moves, then rests on an edge (within a sample's travel of it): every
    sample at rest plays the profile at its phase, bit for bit."""
    n, stop = 300, 100
    vx = np.where(np.arange(n) < stop, 30.0, 0.0)
    x = 1.3 + 0.6 * 3 + np.concatenate(([0.0], np.cumsum(vx[:-1]) / RATE)) - 0.3
    renderer = ShtRenderer(GRATING, RATE) if mode == "sht" else PredictedSho(GRATING, RATE)
    mu = _render(renderer, x, vx, split=150)
    phase = (x - x[0]) / 0.6 if mode == "sht" else (x - 1.3) / 0.6
    assert np.array_equal(mu[stop + 1:], GRATING.profile(phase[stop + 1:]))


def _grating_toml() -> str:
    """The bundled 0.6 mm grating (seed 003's) with :data:`GRATING`'s duty and offset."""
    text = resolve_scene("grating-0.6mm").read_text()
    assert "duty = 0.5 " in text and "offset_mm" not in text
    return text.replace("duty = 0.5 ", "duty = 0.4\noffset_mm = 1.3\n", 1)


@pytest.mark.parametrize("mode", ["sht", "hybrid", "sho-predicted"])
def test_a_square_gratings_harmonics_do_not_fold_into_the_plates_band(tmp_path, mode):
    """0.6 mm, duty 0.4, under a 980 mm/s swipe (1 kHz touch samples) at 10 kHz output: a
    1633 Hz texture whose 6th harmonic (9800 Hz) point sampling folded to a 200 Hz line at
    0.168 of the fundamental; the box mean weights it by sinc(0.98), to about 0.003. Every
    line in 30-400 Hz (the plate's band, seed 003) stays under 0.01 of the fundamental."""
    path = tmp_path / "g.toml"
    path.write_text(_grating_toml())
    v = 980.0
    t = np.arange(0, 90 / v, 0.001)
    ev = np.full(t.size, MOVE, np.int8)
    ev[0], ev[-1] = DOWN, UP
    trace = make_trace(t, np.zeros(t.size, int), 5 + v * t, np.full(t.size, 32.4),
                       np.full(t.size, 0.5), ev)
    out = frictex.build_pipeline(frictex.load_scene(path), rate_hz=RATE,
                                 renderer=mode).process(trace)
    mu = out.mu_target[0][out.contact[0]][50:]
    spectrum = np.abs(np.fft.rfft((mu - mu.mean()) * np.hanning(mu.size)))
    freq = np.fft.rfftfreq(mu.size, 1 / RATE)
    band = (freq > 30) & (freq < 400)
    assert abs(freq[np.argmax(spectrum)] - v / 0.6) < 10
    assert spectrum[band].max() < 0.01 * spectrum.max()

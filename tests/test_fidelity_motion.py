"""The default renderer (``auto``: the hybrid) on constructed motions whose right answer
is known (issue 14): a constant-speed swipe sampled at 50 Hz (the prediction is exact),
a stop short of a grating edge (no overshoot past it by more than 0.5 mm), a reversal
(no phase jump the finger can feel, as a bound on the amplitude step per output sample);
and the synthetic human-varied strokes the report draws."""

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from frictex.rendering.input.trace_synth import Motion, make_motion, sample, truth
from frictex.rendering.layers.hybrid import SLIP, HybridRenderer
from frictex.rendering.metrics import accuracy, reference
from frictex.rendering.tracking.tracks import TrackerConfig, TrackerState, track
from scenes import grating_box_mean, grating_scene
from frictex.textures.model import VisualHints, Waveform

RATE = 10_000.0


def _tracks(trace, duration_s):
    return track(0, int(duration_s * RATE), trace, TrackerState(), TrackerConfig(rate_hz=RATE))[0]


def _line(*legs):
    """A motion along y = 30 mm through x positions, one minimum-jerk leg each
    ((t0, t1, x0, x1), s and mm), no pause between legs."""
    return Motion("human-varied", legs[-1][1], dict(segments=[
        (t0, t1, "line", (x0, 30.0, x1, 30.0, 0.0, 0.0)) for t0, t1, x0, x1 in legs]))


@pytest.mark.parametrize("period", [15.0, 5.0, 0.6])
def test_a_constant_speed_swipe_at_50_hz_is_rendered_exactly(period):
    """40 mm/s from x = 10 mm, 50 Hz, no noise: from the second sample on (the first
    velocity) the prediction is the true position (within 1e-9 mm) and the hybrid gives
    at every output sample after that the grating's mean between the true positions at
    the sample and at the one after it (``rendering.layers.band_limit``); 1e-6: 1e-9 mm of a
    4 um step across a 0.4 edge, and the edges (phases 0 and 0.5) are table points."""
    motion = make_motion("swipe", speed_mm_s=40.0, duration_s=1.0, x0_mm=10.0)
    fingers = _tracks(sample(motion, 50.0), 1.0)
    known = (fingers.t_s >= 0.02) & fingers.contact[0]
    x_true = 10.0 + 40.0 * fingers.t_s
    assert np.abs(fingers.x_pred[0, known] - x_true[known]).max() < 1e-9
    layer = grating_scene(period).layers[0]
    r = HybridRenderer(layer, RATE)
    mu, _, _ = r.render(fingers, r.initial_state())
    after = np.flatnonzero(known[1:] & known[:-1]) + 1
    phase = layer.phase_at(x_true, 30.0)
    expected = grating_box_mean(layer, phase[after - 1], phase[after])
    np.testing.assert_allclose(mu[0, after - 1], expected, rtol=0, atol=1e-6)


@pytest.mark.parametrize("seed", range(8))
def test_a_stop_short_of_an_edge_does_not_render_the_edge(seed):
    """A human-like stroke (minimum jerk, 60 mm/s peak) from 10 mm that stops 0.6 mm
    before the 15 mm grating's line at 37.5 mm and rests there, 50 Hz with 0.05 mm noise:
    the finger never reaches the line, so the band beyond it must never be rendered (an
    overshoot of the phase past the stop by 0.6 mm or more would render it)."""
    stop = 37.5 - 0.6
    duration = 1.875 * (stop - 10.0) / 60.0
    motion = _line((0.0, duration, 10.0, stop), (duration, duration + 0.4, stop, stop))
    fingers = _tracks(sample(motion, 50.0, noise_mm=0.05, seed=seed), duration + 0.4)
    layer = grating_scene(15.0).layers[0]
    r = HybridRenderer(layer, RATE)
    mu, _, _ = r.render(fingers, r.initial_state())
    beyond = layer.mu_at(37.5 + 0.1, 30.0)
    assert beyond != layer.mu_at(stop, 30.0)
    # from where the finger is 1 mm past the previous line (30 mm) on, in the low band
    x_true, _ = motion.position(fingers.t_s)
    on = fingers.contact[0] & (np.maximum.accumulate(x_true) > 31.0)
    assert on.sum() > 0.4 * RATE
    assert not np.any(mu[0, on] == beyond)


@pytest.mark.parametrize("period", [15.0, 5.0, 0.6])
def test_a_reversal_makes_no_phase_jump_the_finger_can_feel(period):
    """Out from 20 to 50 mm and straight back (minimum jerk, 94 mm/s peaks, no pause),
    50 Hz with 0.05 mm noise, on a sine texture (mu' 0.6-1.0, slope at most 0.4 pi / P
    per mm). Around the turn the amplitude step from one output sample to the next is
    bounded: on a fine layer (slewed) by the phase advancing at most (1 + SLIP) times the
    finger's speed; on a coarse layer (position-locked) by a jump of at most 0.5 mm, the
    stop test's tolerance, plus that advance."""
    motion = _line((0.0, 0.6, 20.0, 50.0), (0.6, 1.2, 50.0, 20.0))
    wave = Waveform(name="w", render="hybrid", region=None, blend="multiply",
                    visual=VisualHints(), period_mm=period, shape="sine", mu_min=0.6, mu_max=1.0)
    slope = 0.4 * np.pi / period  # mu' per mm
    v_max = 1.875 * 30.0 / 0.6 * 1.2  # true peak speed, 20 % for the tracker's noise
    advance = (1 + SLIP) * v_max / RATE  # mm per output sample
    jump = 0.5 if period >= 2.0 else 0.0
    for seed in range(8):
        fingers = _tracks(sample(motion, 50.0, noise_mm=0.05, seed=seed), 1.2)
        r = HybridRenderer(wave, RATE)
        mu, _, _ = r.render(fingers, r.initial_state())
        near_turn = (fingers.t_s[1:] > 0.45) & (fingers.t_s[1:] < 0.85)
        step = np.abs(np.diff(mu[0]))[near_turn]
        assert step.max() <= slope * (jump + advance), (seed, step.max())


@settings(max_examples=40, derandomize=True, deadline=None)
@given(seed=st.integers(0, 10_000))
def test_human_varied_strokes_are_continuous_and_stay_on_the_display(seed):
    """Every draw: a continuous path (no step over 0.06 mm between 10 kHz samples: 500
    mm/s, the fastest flick, moves 0.05 mm), inside the display, resting at the start of
    each part; its touch trace with 5 % dropped samples keeps the first and last."""
    motion = make_motion("human-varied", speed_mm_s=60.0, duration_s=3.0, seed=seed)
    path = truth(motion, RATE)
    step = np.hypot(np.diff(path.x_mm), np.diff(path.y_mm))
    assert step.max() < 0.06
    assert path.x_mm.min() >= 8.0 - 1e-9 and path.x_mm.max() <= 108.0 - 8.0 + 1e-9
    assert path.y_mm.min() >= 8.0 - 1e-9 and path.y_mm.max() <= 64.8 - 8.0 + 1e-9
    for t0, t1, kind, q in motion.params["segments"]:
        x0, y0 = motion.position(np.array([t0, t0 + 1e-4]))
        assert np.hypot(x0[1] - x0[0], y0[1] - y0[0]) < 1e-3  # starts from rest
    full = sample(motion, 50.0)
    dropped = sample(motion, 50.0, drop=0.05, seed=seed)
    assert dropped.t_s[0] == full.t_s[0] and dropped.t_s[-1] == full.t_s[-1]
    assert 0.8 * len(full) < len(dropped) <= len(full)
    assert set(dropped.t_s) <= set(full.t_s)


def test_a_varying_stroke_never_runs_backwards():
    """The ripple on a stroke's minimum-jerk progress is at most 0.8 of the bound that
    keeps its slope positive: the progress is non-decreasing for 1-3 ripples."""
    from frictex.rendering.input.trace_synth import _progress
    tau = np.linspace(0.0, 1.0, 100_001)
    for cycles in (1.0, 2.0, 3.0):
        ripple = 0.8 * 30.0 / (np.pi * cycles / 2 + 3)
        for sign in (1.0, -1.0):
            u = _progress(tau, sign * ripple, cycles)
            assert np.all(np.diff(u) >= -1e-15) and u[0] == 0.0 and abs(u[-1] - 1.0) < 1e-12


def _felt(layer, motion, duration_s, seed):
    """The hybrid's mu' and its accuracy (with chatter) for ``motion`` sampled at 50 Hz with
    0.05 mm noise (draw ``seed``), against the true path."""
    fingers = _tracks(sample(motion, 50.0, noise_mm=0.05, seed=seed), duration_s)
    r = HybridRenderer(layer, RATE)
    mu, _, _ = r.render(fingers, r.initial_state())
    scene = grating_scene(layer.period_mm)
    return accuracy(reference(scene, truth(motion, RATE)), fingers.t_s, mu[0], RATE, layer=layer)


@pytest.mark.parametrize("period", [15.0, 5.0])
@pytest.mark.parametrize("speed", [20.0, 60.0])
def test_a_noisy_constant_speed_swipe_never_feels_an_edge_twice(period, speed):
    """A swipe from 10.6 to 68.6 mm (no line within 0.5 mm of either end) sampled at
    50 Hz with 0.05 mm noise, 8 draws of the noise: the true path never turns back, so no
    edge may be crossed back (chatter 0), and the hybrid renders exactly the true path's
    edges (as many steps)."""
    motion = make_motion("swipe", speed_mm_s=speed, duration_s=58.0 / speed, x0_mm=10.6)
    layer = grating_scene(period).layers[0]
    for seed in range(8):
        acc = _felt(layer, motion, 58.0 / speed, seed)
        assert acc.chatter == 0, (seed, acc)
        assert acc.rendered_steps == acc.ideal_steps, (seed, acc)


@pytest.mark.parametrize("period", [15.0, 5.0])
def test_a_true_reversal_is_felt_at_exactly_the_true_crossings(period):
    """Out from 19.2 mm, turning 0.3 mm past the line at 45 mm, and back (minimum jerk,
    no pause), 50 Hz with 0.05 mm noise, 8 draws: the hybrid crosses each line as often
    as the finger does (4 lines each way on the 15 mm grating, 11 on the 5 mm one) and no
    edge is undone that the finger did not undo itself."""
    motion = _line((0.0, 0.6, 19.2, 45.3), (0.6, 1.2, 45.3, 19.2))
    layer = grating_scene(period).layers[0]
    for seed in range(8):
        acc = _felt(layer, motion, 1.2, seed)
        assert acc.ideal_steps == (8 if period == 15.0 else 22)
        assert acc.chatter == 0 and acc.rendered_steps == acc.ideal_steps, (seed, acc)

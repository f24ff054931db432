"""The hybrid renderer: phase at touch-down, bounded correction, no texture under a still
finger, lock on coarse gratings, and block-split invariance.

The tests on constructed tracks (``_block``) check the phase rules given the finger
model's estimates; they run with the tracker's own estimates in place of the filter
(``tracker_estimates``), so that the position and rate each rule sees are the ones the
test writes. The filter is tested in tests/test_hybrid_filter.py; the tests on sampled
motion run both together."""

from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from numpy.testing import assert_allclose

from frictex.rendering.input.trace_synth import make_motion, sample
import frictex.rendering.layers.hybrid as hybrid_module
from frictex.rendering.layers.band_limit import BandLimit
from frictex.rendering.layers.hybrid import (BACK_MM, COARSE_MM, GATE_SIGMAS, LOCK_MM, RELOCK_MM_S,
                                     SLIP, HybridRenderer, slew_offset)
from frictex.rendering.metrics import accuracy, reference
from frictex.rendering.pipeline import build_pipeline
from frictex.rendering.tracking.tracks import FingerBlock, apply_index
from scenes import grating_box_mean, grating_scene

RATE = 10_000.0


def _use_tracker_estimates(monkeypatch, sd_mm):
    """Make the hybrid take the tracker's predicted position and velocity along the
    layer's axis as the filtered ones, with ``sd_mm`` (mm) as the standard deviation of
    every position correction."""
    def estimates(t_s, touch, vx, vy, x_held, y_held, x_pred, y_pred, axis, before=None):
        return (axis[0] * x_pred + axis[1] * y_pred, axis[0] * vx + axis[1] * vy,
                np.full(len(t_s), sd_mm), None)
    monkeypatch.setattr(hybrid_module, "filter_axis", estimates)


@pytest.fixture
def tracker_estimates(monkeypatch):
    """The hybrid on the tracker's estimates, with no uncertainty of its own (the
    lost-lock threshold is ``LOCK_MM``)."""
    _use_tracker_estimates(monkeypatch, 0.0)


def _sawtooth(period_mm):
    """A waveform layer whose mu' reads the rendered phase back: 1 - phase mod 1."""
    from frictex.textures.model import VisualHints, Waveform
    return Waveform(name="saw", render="hybrid", region=None, blend="multiply",
                    visual=VisualHints(), period_mm=period_mm, shape="sawtooth", mu_min=0.0,
                    mu_max=1.0)


@pytest.fixture
def played(monkeypatch):
    """The phases (cycles, (F, n) per call) the renderers hand to
    ``BandLimit.play_forward``: the phase the hybrid renders, which a sample plays the box
    mean from (``rendering.layers.band_limit``), so mu' no longer reads it back point by
    point."""
    calls = []
    play = BandLimit.play_forward

    def recorded(self, phase, *args, **kwargs):
        calls.append(np.array(phase))
        return play(self, phase, *args, **kwargs)

    monkeypatch.setattr(BandLimit, "play_forward", recorded)
    return calls


def _wrapped(cycles):
    """Phase differences (cycles) the shorter way round, in [-0.5, 0.5)."""
    return (np.asarray(cycles) + 0.5) % 1.0 - 0.5


def _block(x_pred, vx, x_held=None, touch=None, index0=0):
    """One finger's FingerBlock along x (y fixed at 30 mm)."""
    n = x_pred.size
    row = lambda a: np.asarray(a, dtype=np.float64).reshape(1, n)
    return FingerBlock(index0=index0, t_s=(index0 + np.arange(n)) / RATE, ids=(0,),
                       contact=np.ones((1, n), bool),
                       touch_id=np.ones((1, n), np.int64) if touch is None else touch.reshape(1, n),
                       x_held=row(x_pred if x_held is None else x_held), y_held=row(np.full(n, 30.0)),
                       x_pred=row(x_pred), y_pred=row(np.full(n, 30.0)), vx=row(vx),
                       vy=row(np.zeros(n)), force=row(np.full(n, 0.5)), touch_start=row(np.zeros(n)))


def _run(scene, trace, mode, splits=()):
    p = build_pipeline(scene, rate_hz=RATE, render_override=mode, t0_s=float(trace.t_s[0]))
    applied = apply_index(trace.t_s, p.tracker_config)
    total = int(applied[-1] // p.block_size) + 1
    bounds = [0, *(s for s in splits if s < total), total]
    state, outs = p.initial_state(), []
    for lo, hi in zip(bounds[:-1], bounds[1:]):
        a, b = np.searchsorted(applied, [lo * p.block_size, hi * p.block_size])
        out, state = p.process(lo, trace.slice(a, b) if b > a else None, state, n_blocks=hi - lo)
        outs.append(out)
    return np.concatenate([o.mu_target for o in outs], axis=1)


def test_touch_down_starts_at_the_measured_phase_not_zero(tracker_estimates):
    """Plain SHT starts every touch at phase 0 (seed 003 4.4.2's drawback); the hybrid
    starts where the finger is: on the 15 mm grating at x = 20 mm that is the low band
    (phase 1.33), where SHT would give the start of a period too (phase 0: low) and at
    x = 29 mm (phase 1.93: high band) SHT is wrong."""
    layer = grating_scene(15.0).layers[0]
    for x0 in (20.0, 29.0):
        block = _block(np.full(10, x0), np.zeros(10))
        mu, covers, _ = HybridRenderer(layer, RATE).render(block, HybridRenderer(layer, RATE).initial_state())
        assert_allclose(mu[0], layer.mu_at(x0, 30.0))
        assert covers.all()


def test_a_still_finger_gets_no_correction(tracker_estimates):
    """Measurements jump (noise) while the velocity is 0: the phase must not move."""
    layer = grating_scene(0.6).layers[0]
    r = HybridRenderer(layer, RATE)
    _, _, state = r.render(_block(np.full(100, 10.0), np.zeros(100)), r.initial_state())
    held = np.repeat([10.0, 10.2, 10.4, 10.1], 50)
    mu, _, _ = r.render(_block(held, np.zeros(200), index0=100), state)
    assert np.ptp(mu) == 0.0 and mu[0, 0] == layer.mu_at(10.0, 30.0)


def test_a_lost_lock_under_a_crawling_finger_is_worked_off_at_the_relock_speed(tracker_estimates):
    """The finger crawls forward at 1 mm/s (a screen still reporting a resting finger);
    the measurements put it 3 mm back from where the phase is (more than the position
    lock takes at once), across a 15 mm grating's line (7.5 mm). Bounded by the finger's
    own speed the phase would need 0.5 mm / 0.9 mm/s = 0.56 s to get back over the line;
    at SLIP x RELOCK_MM_S it is there after 0.5 mm / 17 mm/s = 29 ms and the error is
    worked off down to the lock within 2.9 mm / 17 mm/s = 0.17 s."""
    layer = grating_scene(15.0).layers[0]
    assert 3.0 > BACK_MM
    r = HybridRenderer(layer, RATE)
    _, _, state = r.render(_block(np.full(100, 8.0), np.full(100, 1.0)), r.initial_state())
    n = 2000
    mu, _, _ = r.render(_block(np.full(n, 5.0), np.full(n, 1.0), index0=100), state)
    crossed = np.flatnonzero(mu[0] == layer.mu_at(5.0, 30.0))[0] / RATE
    # the phase moves back at SLIP x RELOCK less the finger's own 1 mm/s forward
    line_s = 0.5 / (SLIP * RELOCK_MM_S - 1.0)
    relock_s = (3.0 - LOCK_MM) / (SLIP * RELOCK_MM_S - 1.0)
    assert mu[0, 0] == layer.mu_at(8.0, 30.0)
    assert abs(crossed - line_s) < 2e-3
    assert (mu[0, int(relock_s * RATE) + 1:] == layer.mu_at(5.0, 30.0)).all()


def test_coarse_layers_take_small_errors_and_errors_ahead_at_once(tracker_estimates):
    """Position lock on a 15 mm grating, the finger moving at 40 mm/s across the line at
    7.5 mm: a measurement 0.8 mm or 3 mm ahead of the phase is taken at once, so is one
    1.5 mm behind (within BACK_MM) but for the 0.8 mm the finger covers within HOLD_S
    (held: the phase, 0.7 mm back, short of the line, waits for it); one 3 mm behind is
    not (slewed); the fine 0.6 mm grating takes no error at once."""
    coarse, fine = grating_scene(15.0).layers[0], grating_scene(0.6).layers[0]
    assert 1.5 < BACK_MM < 3.0 and 15.0 >= COARSE_MM > 0.6
    t = np.arange(400) / RATE
    # (layer, start, jump, taken): the phase reaches start + 0.8 mm, the measurement says
    # start + 0.8 + jump, in the other band (or half period) from it
    for layer, start, jump, taken in ((coarse, 6.2, 0.8, True), (coarse, 6.2, 3.0, True),
                                      (coarse, 6.9, -1.5, True), (coarse, 9.5, -3.0, False),
                                      (fine, 6.2, 0.25, False)):
        assert layer.mu_at(start + 0.8, 30.0) != layer.mu_at(start + 0.8 + jump, 30.0)
        r = HybridRenderer(layer, RATE)
        before = _block(start + 40.0 * t[:200], np.full(200, 40.0))
        _, _, state = r.render(before, r.initial_state())
        x = start + 40.0 * t[200:] + jump
        mu, _, _ = r.render(_block(x, np.full(200, 40.0), x_held=np.full(200, x[0]), index0=200),
                            state)
        # taken: the measured band from the first sample (one sample of rounding at the line)
        wrong = np.count_nonzero(mu[0] != layer.mu_at(x, 30.0))
        assert (wrong <= 1) if taken else (wrong > 20), (layer.period_mm, jump, wrong)


def test_correction_never_exceeds_slip_times_the_finger_phase_rate(tracker_estimates):
    """The velocity says 40 mm/s, the measurements say the finger is 1 mm further on each
    time: the rendered phase advances at most (1 + SLIP) and at least (1 - SLIP) times the
    velocity's phase rate, and never backwards."""
    layer = grating_scene(1.5).layers[0]
    assert layer.period_mm < COARSE_MM  # not position-locked
    r = HybridRenderer(layer, RATE)
    n = 2000
    t = np.arange(n) / RATE
    held = 10.0 + 40.0 * np.floor(t * 50) / 50 + np.where(np.floor(t * 50) % 2 == 1, 1.0, -0.5)
    x_pred = held + 40.0 * (t - np.floor(t * 50) / 50)
    block = _block(x_pred, np.full(n, 40.0), x_held=held)
    # read the phase back through a sawtooth waveform: mu' = 1 - phase mod 1 (see model)
    mu, _, _ = HybridRenderer(_sawtooth(1.5), RATE).render(block, r.initial_state())
    step = np.mod(-np.diff(mu[0]), 1.0)  # phase increments (cycles per sample)
    rate = 40.0 / 1.5 / RATE
    assert step.max() <= (1 + SLIP) * rate * (1 + 1e-9)
    assert step.min() >= (1 - SLIP) * rate * (1 - 1e-9)


@pytest.mark.parametrize("gap_mm, sd_mm", [(0.15, 0.08), (0.28, 0.08), (0.15, 0.0)])
def test_a_lost_lock_is_a_gap_beyond_the_filters_own_uncertainty(monkeypatch, played, gap_mm,
                                                                 sd_mm):
    """A 120 mm/s finger on a 0.6 mm texture (200 Hz), rendered exactly where it is;
    then a measurement puts it ``gap_mm`` further on. With the filter's position
    correction of standard deviation 0.08 mm (a steady swipe's at 50 Hz), the gate is
    max(LOCK_MM, 2.576 x 0.08) = 0.206 mm: a 0.15 mm gap is what the filter's own
    noise explains and is left alone (no frequency modulation), a 0.28 mm one is a lost
    lock, worked off at SLIP times the finger's phase rate down to the gate, i.e.
    gap(t) = max(gap - SLIP v t, gate); with no uncertainty (sd 0) the gate is LOCK_MM
    and the 0.15 mm gap is a lost lock too."""
    _use_tracker_estimates(monkeypatch, sd_mm)
    layer, v = _sawtooth(0.6), 120.0
    gate = max(LOCK_MM, GATE_SIGMAS * sd_mm)
    r = HybridRenderer(layer, RATE)
    t = np.arange(400) / RATE
    _, _, state = r.render(_block(10.0 + v * t[:200], np.full(200, v)), r.initial_state())
    x = 10.0 + v * t[200:] + gap_mm
    r.render(_block(x, np.full(200, v), x_held=np.full(200, x[0]), index0=200), state)
    rendered = played[-1][0]
    left = -_wrapped(rendered - layer.phase_at(x, 30.0)) * layer.period_mm  # mm behind
    after = t[200:] - t[200]
    want = gap_mm if gap_mm <= gate else np.maximum(gap_mm - SLIP * v * after, gate)
    assert_allclose(left, want, rtol=0, atol=1e-9)


def test_slew_offset_closed_form_against_a_sample_by_sample_loop():
    """The vectorised fill equals the obvious per-sample recurrence, position lock
    (jumps ahead of the finger's direction, and back up to ``back``) and hold (an error
    behind up to ``hold`` worked off at the ``travel`` allowance, the part of one up to
    ``back`` beyond it taken at once) included."""
    rng = np.random.default_rng(5)
    n = 3000
    fast = np.concatenate(([0.0], np.cumsum(rng.uniform(0, 2e-3, n))))
    slow = np.concatenate(([0.0], np.cumsum(rng.uniform(0, 1e-3, n) * (rng.random(n) < 0.5))))
    travel = np.concatenate(([0.0], np.cumsum(rng.uniform(0, 1e-3, n))))
    bounds = np.sort(rng.choice(np.arange(1, n), 40, replace=False))
    bounds = np.concatenate(([0], bounds))
    target = rng.uniform(-3, 3, bounds.size)
    restart = rng.random(bounds.size) < 0.1
    snap = rng.random(bounds.size) < 0.2
    jump = rng.choice([-1.0, 0.0, 1.0], bounds.size)
    back = 0.1
    hold = rng.choice([0.0, 0.3], bounds.size)
    lock = rng.choice([0.05, 0.12], bounds.size)  # per measurement (the filter's gate)
    got, end = slew_offset(bounds, target, restart, snap, fast, slow, 0.3, lock, jump, back,
                           hold, travel)
    off, seg, held, expected = 0.3, -1, False, []
    decided = {"held": 0, "taken": 0}
    for i in range(n + 1):
        if i > 0:  # the allowance of sample i - 1 -> i, towards the current target
            err = (target[seg] - off + 0.5) % 1.0 - 0.5
            if held:
                off += np.copysign(min(travel[i] - travel[i - 1], abs(err)), err)
            elif abs(err) > lock[seg] + 1e-12:  # rounding must not keep it in the fast mode
                off += np.copysign(min(fast[i] - fast[i - 1], abs(err) - lock[seg]), err)
            else:
                off += np.copysign(min(slow[i] - slow[i - 1], abs(err)), err)
        if i < n and seg + 1 < bounds.size and bounds[seg + 1] == i:
            seg += 1
            err = (target[seg] - off + 0.5) % 1.0 - 0.5
            held = False
            if (restart[seg] or (snap[seg] and abs(err) > lock[seg])
                    or (jump[seg] != 0 and err * jump[seg] > 0)):
                off = target[seg]
            elif jump[seg] != 0 and abs(err) <= max(hold[seg], back):
                excess = np.copysign(max(abs(err) - hold[seg], 0.0), err)
                off += excess
                held = True
                decided["taken" if excess else "held"] += 1
        if i < n:
            expected.append(off)
    assert decided["held"] >= 3 and decided["taken"] >= 1  # every branch is exercised
    # the loop switches from fast to slow at whole samples, the closed form within one:
    # they may differ by one sample's slow allowance (< 1e-3)
    assert_allclose(got, expected, atol=1e-3)
    assert abs(((end - off) + 0.5) % 1.0 - 0.5) < 1e-3


def test_a_noise_free_constant_speed_swipe_gets_no_correction(played):
    """The finger filter on a noise-free 120 mm/s swipe, 50 Hz, on a 0.6 mm texture: the
    filter is exact from the second touch sample on, so every gap is 0 and the rendered
    phase is the true position's at every output sample from then on."""
    layer = _sawtooth(0.6)
    motion = make_motion("swipe", speed_mm_s=120.0, duration_s=0.6, x0_mm=10.0)
    trace = sample(motion, 50.0)
    _run(replace(grating_scene(0.6), layers=(layer,)), trace, "hybrid")
    phase = played[-1][0]  # one call (the first is the pipeline's warm-up)
    t = np.arange(phase.size) / RATE
    known = (t >= 0.025) & (t < 0.55)  # the second sample takes effect from the next block
    x_true, y_true = motion.position(t[known])
    assert_allclose(_wrapped(phase[known] - layer.phase_at(x_true, y_true)), 0.0,
                    rtol=0, atol=1e-9)


def test_a_swipe_starts_at_the_measured_phase_once_its_velocity_is_known(tracker_estimates):
    """Before the second touch sample the velocity is unknown (0): at the first estimate
    the finger has already moved 2.4 mm (half a 5 mm period). The hybrid starts its
    synthesis where the finger then is, instead of slewing half a period in."""
    layer = grating_scene(5.0).layers[0]
    r = HybridRenderer(layer, RATE)
    n = 400
    t = np.arange(n) / RATE
    known = t >= 0.02
    x_held = np.where(known, 12.4, 10.0)
    x_pred = np.where(known, 12.4 + 120.0 * (t - 0.02), 10.0)
    mu, _, _ = r.render(_block(x_pred, np.where(known, 120.0, 0.0), x_held=x_held), r.initial_state())
    # each sample plays the box mean over its own stretch, up to the next sample's phase;
    # the jump to where the finger is is not crossed (rendering.layers.band_limit)
    phase = layer.phase_at(np.where(known, x_pred, 10.0), 30.0)
    moving = np.flatnonzero(known)
    step = 120.0 / layer.period_mm / RATE
    assert_allclose(mu[0, moving], grating_box_mean(layer, phase[moving], phase[moving] + step),
                    atol=1e-4)
    assert_allclose(mu[0, ~known], layer.mu_at(10.0, 30.0))


def test_coarse_grating_stays_aligned_where_sht_drifts():
    """Seed 003's coarse case: 15 mm grating, human-like strokes sampled at 50 Hz with
    0.05 mm noise. The hybrid's edges stay within 0.2 mm of where they are drawn on
    average (0.10 mm here; 0.52 mm before the hold of rendering.layers.hybrid, when one
    jump back over a line added an edge pair 2 ms apart); plain SHT's are millimetres
    off."""
    scene = grating_scene(15.0)
    motion = make_motion("human", speed_mm_s=60.0, duration_s=3.0, seed=7)
    trace = sample(motion, 50.0, noise_mm=0.05, seed=3)
    ref = reference(scene, sample(motion, 20_000.0))
    errs = {}
    for mode in ("hybrid", "sht"):
        mu = _run(scene, trace, mode)[0]
        t = np.arange(mu.size) / RATE
        errs[mode] = accuracy(ref, t, mu, RATE).alignment_error_mm
    assert errs["hybrid"] < 0.2 < 1.0 < errs["sht"]


@settings(max_examples=12, derandomize=True, deadline=None)
@given(splits=st.lists(st.integers(1, 300), max_size=6, unique=True).map(sorted),
       period=st.sampled_from([0.6, 5.0, 15.0]))
def test_any_split_into_blocks_equals_one_call(splits, period):
    motion = make_motion("human", speed_mm_s=60.0, duration_s=1.5, seed=4)
    trace = sample(motion, 120.0, noise_mm=0.05, seed=4)
    whole = _run(grating_scene(period), trace, "hybrid")
    parts = _run(grating_scene(period), trace, "hybrid", splits)
    assert_allclose(parts, whole, atol=1e-9)


def test_slip_outside_0_1_is_a_clear_error():
    layer = grating_scene(5.0).layers[0]
    with pytest.raises(ValueError, match=r"hybrid slip 1.5: expected a fraction in \(0, 1\)"):
        HybridRenderer(layer, RATE, slip=1.5)

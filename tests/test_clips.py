"""Effect clips: shapes of mu' against time, and their triggers' timing (rendering.layers.clips)."""

import math

import numpy as np
import pytest
from hypothesis import example, given, settings, strategies as st
from numpy.testing import assert_allclose

from frictex.device.profile import DeviceProfile
from frictex.rendering.input.trace_file import DOWN, MOVE, UP, make_trace
from frictex.rendering.pipeline import build_pipeline
from scenes import DISPLAY
from frictex.textures.clips import Clip, ClipEvent, ClipLayer
from frictex.textures.model import DiscRegion, RectRegion, Scene, VisualHints

RATE, BLOCK = 10_000.0, 50


def _layer(clip, trigger="down", region=None, **kw):
    return ClipLayer(name="c", render="sho", region=region, blend="multiply",
                     visual=VisualHints(), clip=clip, trigger=trigger, **kw)


TICK = Clip((ClipEvent("transient", 0.0, intensity=0.8, sharpness=0.0),), depth=0.5)


def test_a_tick_is_a_hann_pulse_of_30_ms_at_sharpness_0():
    mu, clipped = TICK.sample(RATE)
    k = np.arange(mu.size)
    expected = 1.0 - 0.5 * 0.8 * np.sin(np.pi * np.minimum(k / RATE, 0.03) / 0.03) ** 2
    assert_allclose(mu, expected, atol=1e-12)
    assert mu.size == 301 and not clipped.any() and mu[-1] == 1.0


def test_sharper_ticks_are_shorter():
    sharp = Clip((ClipEvent("transient", 0.0, sharpness=1.0),), depth=0.5)
    assert (sharp.sample(RATE)[0] < 1.0).sum() == pytest.approx(0.005 * RATE, abs=2)


def test_a_smooth_ramp_follows_its_envelope():
    ramp = Clip((ClipEvent("continuous", 0.01, 1.0, 0.0, 0.1, ((0.0, 0.0), (0.1, 1.0))),), 0.4)
    mu, _ = ramp.sample(RATE)
    t = np.arange(mu.size) / RATE
    played = (t - 0.01 >= 0.0) & (t - 0.01 < 0.1)  # an event plays for [start, start + length)
    expected = 1.0 - 0.4 * np.clip((t - 0.01) / 0.1, 0.0, 1.0) * played
    assert_allclose(mu, expected, atol=1e-9)
    assert mu[-1] == 1.0 and played.sum() == 1000


def test_a_held_event_of_a_whole_number_of_samples_ends_back_at_1():
    held = Clip((ClipEvent("continuous", 0.0, 1.0, 0.0, 0.5),), 0.5)
    mu, _ = held.sample(RATE)
    assert mu.size == 5001 and (mu[:5000] == 0.5).all() and mu[-1] == 1.0


@pytest.mark.parametrize("rate_hz", [RATE, 44_100.0, 8_000.0])
def test_events_end_to_end_share_no_sample(rate_hz):
    """0.1 + 0.2 is 3000.0000000000005 samples at 10 kHz: the first event played one sample
    into the second, whose levels added to 2 there and were counted as clipped."""
    starts_and_lengths = ((0.1, 0.2), (0.3, 0.1), (0.4, 0.3))  # as an author writes them
    clip = Clip(tuple(ClipEvent("continuous", a, 1.0, 0.0, n) for a, n in starts_and_lengths),
                depth=0.4)
    mu, clipped = clip.sample(rate_hz)
    t = np.arange(mu.size) / rate_hz
    played = (t >= 0.1 - 1e-12) & (t < 0.7 - 1e-12)  # independent: the union of [start, end)
    assert not clipped.any()
    assert_allclose(mu, np.where(played, 0.6, 1.0), atol=1e-12)


def test_sharpness_sets_the_carrier_and_levels_that_add_past_1_are_counted():
    buzz = Clip((ClipEvent("continuous", 0.0, 1.0, 1.0, 1.0),), depth=0.3)
    mu, _ = buzz.sample(RATE)
    spectrum = np.abs(np.fft.rfft(mu[:10_000] - mu[:10_000].mean()))
    assert np.argmax(spectrum) == 250  # 1 Hz bins: the 250 Hz carrier
    both = Clip((ClipEvent("continuous", 0.0, 0.7, 0.0, 0.01), ClipEvent("continuous", 0.0, 0.7, 0.0, 0.01)), 0.3)
    mu, clipped = both.sample(RATE)
    assert mu.min() == pytest.approx(0.7) and clipped.sum() == 100  # 10 ms at 10 kHz
    assert (mu[clipped] == 0.7).all() and clipped[:100].all()


def _scene(*layers):
    return Scene(1, "clips", "", DISPLAY, DeviceProfile(), layers)


def _replay(scene, trace, splits=()):
    p = build_pipeline(scene, rate_hz=RATE, block_size=BLOCK, t0_s=0.0)
    total = int(math.ceil(trace.t_s[-1] * RATE / BLOCK)) + 2
    bounds = [0, *sorted({s for s in splits if 0 < s < total}), total]
    applied = np.ceil(trace.t_s * RATE / BLOCK - 1e-9) * BLOCK  # next block boundary at or after
    state = p.initial_state()
    mu = np.ones((int(trace.finger.max()) + 1, total * BLOCK))  # 1 where a finger is absent
    for lo, hi in zip(bounds[:-1], bounds[1:]):
        a, b = np.searchsorted(applied, [lo * BLOCK, hi * BLOCK])
        out, state = p.process(lo, trace.slice(a, b) if b > a else None, state, n_blocks=hi - lo)
        for row, fid in enumerate(out.finger_ids):
            mu[fid, lo * BLOCK: hi * BLOCK] = out.mu_target[row]
    return mu


def _first_use(t_s):
    """Output index from which a touch sample at t_s is used: the next block boundary."""
    return int(math.ceil(round(t_s * RATE, 9) / BLOCK)) * BLOCK


def test_touch_down_inside_starts_the_clip_on_the_next_output_sample():
    clip_mu, _ = TICK.sample(RATE)
    layer = _layer(TICK, region=DiscRegion(50.0, 30.0, 10.0))
    trace = make_trace([0.0123, 0.03, 0.06, 0.1], [0] * 4, [52.0] * 4, [30.0] * 4,
                       event=[DOWN, MOVE, MOVE, UP])
    mu = _replay(_scene(layer), trace)[0]
    k = _first_use(0.0123)
    assert (mu[: k + 1] == 1.0).all()
    assert_allclose(mu[k + 1: k + 1 + clip_mu.size], clip_mu)
    assert 0 < (k + 1) - 0.0123 * RATE <= BLOCK + 1  # live: within one block of the touch
    outside = make_trace([0.0123, 0.1], [0, 0], [70.0, 70.0], [30.0, 30.0], event=[DOWN, UP])
    assert (_replay(_scene(layer), outside) == 1.0).all()


def _crossing_trace():
    """One finger: down at x = 20.013, a swipe over x = 50 at 100 mm/s, a press through 1 N."""
    t = np.arange(0.0, 0.8, 0.01) + 0.0037
    x = np.minimum(20.013 + 100.0 * (t - t[0]), 80.0)
    force = np.where(t > 0.6, 1.5, 0.5)
    ev = np.full(t.size, MOVE)
    ev[0], ev[-1] = DOWN, UP
    return make_trace(t, np.zeros(t.size, int), x, np.full(t.size, 30.0), force, ev)


def test_crossing_an_edge_and_pressing_through_a_threshold():
    trace = _crossing_trace()
    clip_mu, _ = TICK.sample(RATE)
    edge = _layer(TICK, "edge", x_mm=50.0, y_mm=0.0, angle_deg=0.0)
    mu = _replay(_scene(edge), trace)[0]
    # the predicted position (exact at constant speed) reaches 50 mm at t0 + 0.29987 s:
    # the crossing is the first output sample at or past it
    k = int(math.ceil((trace.t_s[0] + (50.0 - 20.013) / 100.0) * RATE))
    assert (mu[: k + 1] == 1.0).all()
    assert_allclose(mu[k + 1: k + 1 + clip_mu.size], clip_mu)
    press = _layer(TICK, "force", force_n=1.0)
    mu = _replay(_scene(press), trace)[0]
    first_above = float(trace.t_s[np.flatnonzero(trace.force_n >= 1.0)[0]])
    k = _first_use(first_above)
    assert (mu[: k + 1] == 1.0).all()
    assert_allclose(mu[k + 1: k + 1 + clip_mu.size], clip_mu)


def test_noise_about_the_force_threshold_fires_once_until_the_force_falls_below_rearm():
    """A press released through 0.7 N with 0.03 N of noise (0.75, 0.69, 0.72) fired a
    second tick; the trigger re-arms only below FORCE_REARM x force_n (0.56 N)."""
    press = _layer(TICK, "force", force_n=0.7)
    force = [0.3, 0.75, 0.69, 0.72, 0.60, 0.71, 0.55, 0.74, 0.2, 0.9, 0.9]
    t = 0.0013 + 0.1 * np.arange(len(force))
    ev = [DOWN] + [MOVE] * (len(force) - 2) + [UP]
    trace = make_trace(t, [0] * t.size, [30.0] * t.size, [30.0] * t.size, force, ev)
    mu = _replay(_scene(press), trace)[0]
    clip_mu, _ = TICK.sample(RATE)
    expected = np.ones_like(mu)
    for i in (1, 7, 9):  # risen through 0.7 N from below 0.56 N (or from the touch's start)
        k = _first_use(t[i])
        expected[k + 1: k + 1 + clip_mu.size] = clip_mu
    assert_allclose(mu, expected, rtol=0, atol=0)
    assert list(press.force_level([0.55, 0.56, 0.6999, 0.7, np.nan])) == [-1, 0, 0, 1, 0]


def test_a_lift_inside_plays_under_the_finger_still_touching():
    layer = _layer(TICK, "lift", region=RectRegion(0.0, 0.0, 40.0, 64.8))
    t = [0.001, 0.002, 0.05, 0.0871, 0.2]
    trace = make_trace(t, [0, 1, 0, 0, 1], [20.0, 80.0, 20.0, 20.0, 80.0], [30.0] * 5,
                       event=[DOWN, DOWN, MOVE, UP, UP])
    mu = _replay(_scene(layer), trace)
    k = _first_use(0.0871)  # finger 0's last output sample touching is k - 1
    clip_mu, _ = TICK.sample(RATE)
    assert (mu[1, : k + 1] == 1.0).all()
    assert_allclose(mu[1, k + 1: k + 1 + clip_mu.size], clip_mu)


@given(st.lists(st.integers(1, 200), max_size=6))
@settings(derandomize=True, max_examples=25, deadline=None)
def test_any_split_into_blocks_gives_the_same_output(splits):
    """Live runs one block per call, replay many: the clips land on the same samples."""
    trace = _crossing_trace()
    scene = _scene(_layer(TICK, "edge", x_mm=50.0, angle_deg=0.0),
                   _layer(Clip((ClipEvent("continuous", 0.0, 1.0, 0.6, 0.05),), 0.3), "force",
                          force_n=1.0))
    whole = _replay(scene, trace)
    assert_allclose(_replay(scene, trace, splits), whole, rtol=0, atol=0)
    assert (whole < 1.0).any()


def _one_sample_at_a_time(trigger, contact, touch_id, inside, flag, prev, index0, start, samples,
                          clipped):
    """The renderer's block, sample by sample from the module docstring's rules: mu',
    coverage, the clip's start after the block, the clipped samples played under a
    touching finger and each finger's last sample."""
    fingers, n = contact.shape
    mu, covers = np.ones((fingers, n)), np.zeros((fingers, n), bool)
    played_clipped = 0
    last = [tuple(int(v) for v in row) for row in prev]
    for j in range(n):
        fired = False
        for i in range(fingers):
            c0, t0, in0, f0 = (bool(last[i][0]), last[i][1], bool(last[i][2]), last[i][3])
            c, t, inn, f = (bool(contact[i, j]), int(touch_id[i, j]), bool(inside[i, j]),
                            int(flag[i, j]))
            same = c and c0 and t == t0
            fired |= (c and not same and inn, c0 and not same and in0,
                      same and 0 != f != f0 != 0 and inn, same and f == 1 and f0 != 1 and inn
                      )[trigger]
            # on the edge line, or between the force's re-arm level and threshold
            as_it_came = trigger in (2, 3) and same and f == 0
            last[i] = (int(c), t, int(inn), f0 if as_it_came else f)
        if start >= 0 and index0 + j - start < samples.size:
            mu[:, j], covers[:, j] = samples[index0 + j - start], contact[:, j]
            played_clipped += int(contact[:, j].sum()) * bool(clipped[index0 + j - start])
        if fired:
            start = index0 + j + 1
    return mu, covers, start, played_clipped, np.array(last, dtype=np.int64).reshape(fingers, 4)


@pytest.mark.parametrize("seed", range(40))
def test_a_block_is_the_clip_played_sample_by_sample(seed):
    """Events anywhere (restarts while playing, on a block's first and last samples), a
    clip started in an earlier block, one to three fingers."""
    from frictex.rendering.layers.clips import render_block
    rng = np.random.default_rng(seed)
    fingers, n = int(rng.integers(1, 4)), int(rng.integers(1, 300))
    rate = rng.choice([0.002, 0.02, 0.2])  # how often the inputs change
    change = lambda: rng.random((fingers, n)) < rate  # noqa: E731
    contact = np.cumsum(change(), axis=1) % 2 == 0
    touch_id = np.cumsum(change(), axis=1) + 10 * np.arange(fingers)[:, None]
    inside, flag = np.cumsum(change(), axis=1) % 2 == 0, np.cumsum(change(), axis=1) % 2 == 1
    side = (np.cumsum(change(), axis=1) % 3 - 1).astype(np.int8)  # edge: -1, 0 (on the line), 1
    prev = np.column_stack([rng.integers(0, 2, fingers), rng.integers(-1, 2, fingers),
                            rng.integers(0, 2, fingers), rng.integers(-1, 2, fingers)])
    samples = rng.uniform(0.5, 1.0, int(rng.integers(1, 400)))
    clipped = rng.random(samples.size) < 0.3
    index0 = int(rng.integers(0, 1000))
    start = int(rng.choice([-1, index0, index0 - rng.integers(0, 500)]))
    for trigger in range(4):
        # edge and force: -1, 0 (on the line; between re-arm and threshold), 1
        flags, last_flag = (side, prev[:, 3]) if trigger in (2, 3) else (flag, prev[:, 3] != 0)
        args = (trigger, contact, touch_id, inside, flags,
                np.column_stack([prev[:, :3], last_flag]).astype(np.int64), index0, start,
                samples, clipped)
        idle = (np.ones(contact.shape), np.zeros(contact.shape, bool))
        got, want = render_block(*args, idle), _one_sample_at_a_time(*args)
        assert got[0].tobytes() == want[0].tobytes() and (got[1] == want[1]).all()
        assert got[2:4] == want[2:4] and (got[4] == want[4]).all()


def test_the_edge_side_is_the_sign_of_the_distance_to_the_line():
    layer = _layer(TICK, "edge", x_mm=50.0, y_mm=30.0, angle_deg=120.0)
    rng = np.random.default_rng(5)
    x, y = rng.uniform(0.0, 100.0, (3, 400)), rng.uniform(0.0, 60.0, 400)
    a = math.radians(120.0)
    distance = math.cos(a) * (x - 50.0) + math.sin(a) * (y - 30.0)
    assert (layer.side(x, y) == np.sign(distance)).all() and layer.side(x, y).shape == (3, 400)
    assert layer.side(50.0, 30.0).shape == () and layer.side(50.0, 30.0) == 0  # on the line


@pytest.mark.parametrize("ends_in_block", [True, False])
def test_a_clip_from_an_earlier_block_plays_to_its_last_sample_and_no_further(ends_in_block):
    """No event in the block: the clip's last sample still plays on its first sample; one
    that ended just before gives the idle block itself."""
    from frictex.rendering.layers.clips import render_block
    samples, index0, n = np.linspace(0.5, 0.9, 10), 100, 30
    contact, touch_id = np.ones((1, n), bool), np.full((1, n), 5)
    start = index0 - 9 if ends_in_block else index0 - 10
    idle = (np.ones((1, n)), np.zeros((1, n), bool))
    mu, covers, after, clipped, _ = render_block(0, contact, touch_id, contact, ~contact,
                                                 np.array([[1, 5, 1, 0]]), index0, start,
                                                 samples, samples < 0.6, idle)
    assert after == start and clipped == 0  # only the last sample (0.9) plays
    if ends_in_block:
        assert mu[0, 0] == samples[-1] and (mu[0, 1:] == 1.0).all()
        assert covers[0, 0] and not covers[0, 1:].any()
    else:
        assert mu is idle[0] and covers is idle[1]


@settings(max_examples=300, deadline=None)
@example(duration_s=1.8809, rate_hz=1e6 / 7)
@given(duration_s=st.floats(1e-3, 5.0), rate_hz=st.floats(100.0, 1e6))
def test_a_clips_last_sample_is_back_at_1_at_any_rate(duration_s, rate_hz):
    """A 1.8809 s event at 1e6/7 Hz: duration x rate rounded down past an integer, so
    the last sample fell 3e-16 s inside the event and played it at full depth (0.6)."""
    clip = Clip((ClipEvent("continuous", 0.0, 1.0, 0.0, duration_s,
                           ((0.0, 1.0), (duration_s, 1.0))),), 0.4)
    mu, _ = clip.sample(rate_hz)
    assert mu[-1] == 1.0
    assert (mu.size - 1) / rate_hz >= duration_s > (mu.size - 3) / rate_hz


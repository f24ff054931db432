"""Finger tracking: velocity from noisy samples, prediction, touch events, hard cases."""

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from numpy.testing import assert_allclose

from frictex.rendering.input.trace_file import DOWN, MOVE, UP, make_trace
from frictex.rendering.tracking.tracks import TrackerConfig, TrackerState, apply_index, track

CFG = TrackerConfig(rate_hz=10_000.0, quantum=50)


def _run(trace, n_out, cfg=CFG):
    return track(0, n_out, trace, TrackerState(), cfg)


def _swipe(rate_hz=50.0, speed=40.0, duration=1.0, noise=0.0, seed=0):
    t = np.arange(0, duration + 1e-12, 1 / rate_hz)
    rng = np.random.default_rng(seed)
    x = 10 + speed * t + rng.normal(0, noise, t.size)
    return make_trace(t, np.zeros(t.size, int), x, np.full(t.size, 30.0))


def test_constant_speed_velocity_and_prediction_are_exact():
    trace = _swipe()
    block, _ = _run(trace, 10_100)
    live = block.contact[0] & (block.t_s > 0.1)
    assert_allclose(block.vx[0, live], 40.0, rtol=1e-9)
    # prediction between 50 Hz samples follows the true line exactly (after the fit fills)
    assert_allclose(block.x_pred[0, live], 10 + 40.0 * block.t_s[live], atol=1e-9)
    # held position lags by up to one touch period (20 ms = 0.8 mm) plus one block
    lag = (10 + 40.0 * block.t_s[live]) - block.x_held[0, live]
    assert lag.min() >= -1e-9 and lag.max() <= 40.0 * (0.02 + 0.005) + 1e-9


def test_noisy_samples_give_a_sane_velocity():
    trace = _swipe(rate_hz=120.0, noise=0.1, duration=2.0)
    block, _ = _run(trace, 20_000)
    live = block.contact[0] & (block.t_s > 0.1)
    # a 50 ms line fit over 6 samples with 0.1 mm noise: error well under 10 mm/s
    assert np.abs(block.vx[0, live] - 40.0).max() < 10.0


def test_samples_take_effect_at_the_next_block_boundary():
    cfg = TrackerConfig(rate_hz=1000.0, quantum=10)
    assert list(apply_index(np.array([0.0, 0.001, 0.0099, 0.010, 0.0101]), cfg)) == [0, 10, 10, 10, 20]


def test_duplicate_rereports_do_not_swing_the_velocity():
    # refdata phone-two-finger-drag: the same position re-reported 0.57 ms later
    t = np.repeat(np.arange(0, 1, 1 / 60), 2)
    t[1::2] += 0.00057
    x = np.repeat(10 + 50.0 * np.arange(0, 1, 1 / 60), 2)
    trace = make_trace(t, np.zeros(t.size, int), x, np.full(t.size, 20.0))
    block, _ = _run(trace, 10_000)
    live = block.contact[0] & (block.t_s > 0.15)
    assert np.abs(block.vx[0, live] - 50.0).max() < 5.0
    assert np.all(np.isfinite(block.vx)) and np.all(np.isfinite(block.x_pred))


def test_equal_timestamps_keep_finite_output():
    t = np.array([0.0, 0.01, 0.01, 0.01, 0.02])
    trace = make_trace(t, np.zeros(5, int), [0, 1, 1.5, 2, 3], np.zeros(5))
    block, _ = _run(trace, 400)
    for arr in (block.vx, block.vy, block.x_pred, block.y_pred):
        assert np.all(np.isfinite(arr))


def test_jump_is_a_lift_and_a_new_touch():
    t = np.arange(0, 0.2, 0.02)
    x = np.where(t < 0.1, 10 + 40 * t, 80 + 40 * t)  # 70 mm away in 20 ms
    trace = make_trace(t, np.zeros(t.size, int), x, np.full(t.size, 30.0))
    block, state = _run(trace, 2_000)
    assert state.jumps == 1
    assert len(np.unique(block.touch_id[0][block.contact[0]])) == 2
    # the velocity restarts: never the 3500 mm/s the jump implies
    assert np.abs(block.vx).max() < 100.0


def test_zero_speed_and_reversal():
    t = np.arange(0, 1.0, 0.01)
    x = 30 + 20 * np.sin(2 * np.pi * 1.0 * t)  # reverses at 0.25 s and 0.75 s
    x[60:] = x[60]  # then rests
    trace = make_trace(t, np.zeros(t.size, int), x, np.full(t.size, 30.0))
    block, _ = _run(trace, 10_000)
    v_true = 2 * np.pi * 20 * np.cos(2 * np.pi * block.t_s)
    moving = (block.t_s > 0.06) & (block.t_s < 0.55)
    # a line fit lags by half its window; the sample is held up to one touch period and
    # applied up to one block late: error <= peak acceleration x that lag
    lag = CFG.velocity_window_s / 2 + 0.01 + CFG.quantum / CFG.rate_hz
    accel = (2 * np.pi) ** 2 * 20
    assert np.abs(block.vx[0, moving] - v_true[moving]).max() < accel * lag
    resting = block.t_s > 0.7
    assert np.abs(block.vx[0, resting]).max() < 1e-9


def test_finger_that_stops_reporting_rests_after_the_horizon():
    trace = _swipe(duration=0.2)
    events = trace.event.copy()
    events[-1] = MOVE  # never lifted: the screen just stops reporting
    trace = make_trace(trace.t_s, trace.finger, trace.x_mm, trace.y_mm, trace.force_n, events)
    block, _ = _run(trace, 5_000)
    late = block.t_s > 0.2 + CFG.predict_horizon_s + 0.005
    assert block.contact[0, late].all()
    assert np.all(block.vx[0, late] == 0.0)
    assert np.ptp(block.x_pred[0, late]) == 0.0


@pytest.mark.parametrize("speed", [200.0, -200.0])
def test_a_prediction_stays_on_the_display(speed):
    # towards an edge at 200 mm/s, then silent for 90 ms before the lift (a phone's
    # two-finger drag): the fit alone runs 12 mm on, past the 140 mm plate's edge
    t = np.arange(0.0, 0.3001, 0.0165)
    x = (131.0 if speed > 0 else 9.0) + speed * (t - t[-1])
    times = np.append(t, t[-1] + 0.09)
    xs = np.append(x, x[-1])
    events = np.full(times.size, MOVE)
    events[0], events[-1] = DOWN, UP
    trace = make_trace(times, np.zeros(times.size, int), xs, np.full(times.size, 30.0),
                       None, events)
    free, _ = _run(trace, 4_000)
    held, _ = _run(trace, 4_000, TrackerConfig(rate_hz=10_000.0, quantum=50,
                                               area_mm=(140.0, 140.0)))
    touching = free.contact[0]
    assert free.x_pred[0, touching].max() > 140.0 or free.x_pred[0, touching].min() < 0.0
    assert 0.0 <= held.x_pred[0, touching].min() and held.x_pred[0, touching].max() <= 140.0
    inside = (free.x_pred[0] >= 0.0) & (free.x_pred[0] <= 140.0)
    assert_allclose(held.x_pred[0, inside], free.x_pred[0, inside], rtol=0, atol=0)
    # velocity is the fit's while the prediction is on the display, 0 where it is held
    assert_allclose(held.vx[0, inside], free.vx[0, inside], rtol=0, atol=0)
    assert (~inside & touching).any() and (held.vx[0, ~inside] == 0.0).all()


def test_down_and_up():
    t = np.array([0.0, 0.01, 0.02, 0.05, 0.06])
    ev = np.array([DOWN, MOVE, UP, DOWN, UP], dtype=np.int8)
    trace = make_trace(t, np.zeros(5, int), [0, 1, 2, 50, 51], np.zeros(5), None, ev)
    block, _ = _run(trace, 1_000)
    idx = np.arange(1_000)
    contact = block.contact[0]
    assert contact[0] and contact[199] and not contact[200] and not contact[499]
    assert contact[500] and not contact[600]
    assert block.touch_id[0, 500] == block.touch_id[0, 0] + 1
    assert np.all(block.vx[0, ~contact] == 0)
    del idx


def test_out_of_order_live_samples_are_dropped_and_counted():
    first = make_trace([0.0, 0.02], [0, 0], [0.0, 1.0], [0.0, 0.0])
    _, state = track(0, 400, first, TrackerState(), CFG)
    late = make_trace([0.01], [0], [99.0], [0.0])
    block, state = track(400, 50, late, state, CFG)
    assert state.out_of_order == 1
    assert np.all(block.x_held[0] == 1.0)


def test_two_fingers_are_tracked_independently():
    t = np.repeat(np.arange(0, 0.5, 0.02), 2)
    finger = np.tile([0, 1], t.size // 2)
    x = np.where(finger == 0, 10 + 40 * t, 90 - 20 * t)
    trace = make_trace(t, finger, x, np.full(t.size, 30.0))
    block, _ = _run(trace, 5_000)
    assert block.ids == (0, 1)
    live = block.t_s > 0.1
    assert_allclose(block.vx[0, live], 40.0, rtol=1e-9)
    assert_allclose(block.vx[1, live], -20.0, rtol=1e-9)


# -- cost bounded by the samples, however closely they crowd --------------------------------

def _crowded(m, span_s=1e-4, seed=0):
    """One finger's ``m`` samples within ``span_s`` (moving at 40 mm/s plus 1 um noise)."""
    t = np.linspace(0.0, span_s, m)
    rng = np.random.default_rng(seed)
    return (t, 10 + 40.0 * t + rng.normal(0, 1e-3, m), 20 - 30.0 * t + rng.normal(0, 1e-3, m),
            np.full(m, 0.5), np.r_[DOWN, np.full(m - 1, MOVE)].astype(np.int8))


def _summed_rows(monkeypatch, m, cap):
    """Run the step kernel as Python over ``m`` crowded samples with fits of at most
    ``cap`` rows, counting the values its sums add: (number of sums, values summed)."""
    from frictex.rendering.tracking import tracks
    calls = []
    real = tracks._pairwise
    monkeypatch.setattr(tracks, "_pairwise", lambda a, lo, n: calls.append(n) or real(a, lo, n))
    t, x, y, f, ev = _crowded(m)
    tracks._steps_kernel.py_func((False, 0, -np.inf, 0.0, 0.0, 0.0, 0.0, np.inf), np.empty((0, 3)),
                                 t, x, y, f, ev, (0.05, 0.1, 2000.0, 10.0), cap)
    return len(calls), sum(calls)


def test_fit_work_is_linear_in_crowded_samples(monkeypatch):
    # 6 sums per sample (t, t^2, x, y, t x, t y), each over at most `cap` rows: doubling
    # the samples doubles the work
    for m in (400, 800):
        sums, values = _summed_rows(monkeypatch, m, cap=16)
        assert sums == 6 * m and values == 6 * m * 16
    # without the cap every fit spans the touch so far: the work the cap removes
    sums, values = _summed_rows(monkeypatch, 200, cap=10**9)
    assert sums == 6 * 200 and values == 6 * 200 * 200


def test_capped_fit_is_the_line_through_the_latest_samples():
    # brute force: np.polyfit through each sample's last `cap` samples (all within 50 ms;
    # the samples crowd into 3 ms, so the least span a fit needs is lifted)
    from frictex.rendering.tracking.tracks import FingerState, _finger_steps
    cap = 8
    t, x, y, f, ev = _crowded(300, span_s=0.003)
    counters = {"jumps": 0, "out_of_order": 0}
    table, keep, _ = _finger_steps(FingerState(), t, x, y, f, ev,
                                   TrackerConfig(fit_samples=cap, min_fit_span_s=0.0), counters)
    assert keep.all() and counters == {"jumps": 0, "out_of_order": 0}
    for k in range(1, t.size):
        rows = slice(max(0, k - cap + 1), k + 1)
        vx, x0 = np.polyfit(t[rows] - t[k], x[rows], 1)
        vy, y0 = np.polyfit(t[rows] - t[k], y[rows], 1)
        assert_allclose(table[7:9, k], [vx, vy], rtol=1e-6, err_msg=f"sample {k}")
        assert_allclose(table[5:7, k], [x0, y0], rtol=1e-12, atol=1e-9, err_msg=f"sample {k}")


def test_capped_fit_carries_across_blocks():
    # the same crowded samples in one call or in 7 blocks: same tracks (the history
    # carried is the cap's rows, not the whole window)
    t, x, y, f, ev = _crowded(2000, span_s=0.01)
    trace = make_trace(t, np.zeros(t.size, int), x, y, f, ev)
    cfg = TrackerConfig(rate_hz=10_000.0, quantum=1, fit_samples=32)
    whole, _ = track(0, 120, trace, TrackerState(), cfg)
    applied = apply_index(trace.t_s, cfg)
    state, parts, i = TrackerState(), [], 0
    for lo in range(0, 120, 20):
        j = int(np.searchsorted(applied, lo + 20))
        block, state = track(lo, 20, trace.slice(i, j) if j > i else None, state, cfg)
        parts.append(block.vx)
        i = j
    assert_allclose(np.concatenate(parts, axis=1), whole.vx, rtol=1e-9, atol=1e-9)


def test_many_short_touches_in_one_block_track_each_finger():
    # 400 touches (down, move, up) within 1 ms: each finger's rows as if tracked alone
    m = 400
    fid = np.repeat(np.arange(m), 3)
    t = np.linspace(0, 1e-3, 3 * m)
    ev = np.tile([DOWN, MOVE, UP], m).astype(np.int8)
    x = 5 + 0.01 * np.arange(3 * m)
    trace = make_trace(t, fid, x, np.full(3 * m, 7.0), None, ev)
    block, state = track(0, 50, trace, TrackerState(), CFG)
    assert block.ids == tuple(range(m)) and state.fingers == {}
    for k in (0, 137, m - 1):
        alone, _ = track(0, 50, trace.slice(3 * k, 3 * k + 3), TrackerState(), CFG)
        assert_allclose(block.x_held[k], alone.x_held[0]) and (block.touch_id[k] == alone.touch_id[0]).all()


@pytest.mark.parametrize("rate_hz", [60.0, 120.0, 240.0])
@pytest.mark.parametrize("speed_mm_s", [1950.0, 2000.0, 2500.0, 4000.0])
def test_a_fast_swipe_is_no_jump_and_a_jump_out_of_it_is_one(rate_hz, speed_mm_s):
    """A swipe reaching 2-4 m/s at the largest acceleration of a finger (20 m/s^2,
    0.1-0.2 s), then steady, with 0.05 mm of noise: its steps
    are 8-67 mm, at or beyond 2 m/s times the interval, yet none is a jump (at 2 m/s
    and 120 Hz 3 of 6 samples were). The same swipe whose last samples are a finger
    resting 50 mm aside (another touch reported under its id) has one jump."""
    rng = np.random.default_rng(3)
    ramp_s = speed_mm_s / TrackerConfig.accel_max_mm_s2
    t = np.arange(int((ramp_s + 0.15) * rate_hz)) / rate_hz
    x = 5.0 + speed_mm_s * np.where(t < ramp_s, t ** 2 / (2 * ramp_s), t - ramp_s / 2)
    x += rng.normal(0.0, 0.05, t.size)
    y = 30.0 + rng.normal(0.0, 0.05, t.size)
    finger = np.zeros(t.size, int)
    _, state = _run(make_trace(t, finger, x, y), 10_000)
    assert state.jumps == 0
    aside = t.size - 3
    x[aside:], y[aside:] = x[aside], y[aside:] + 50.0
    _, state = _run(make_trace(t, finger, x, y), 10_000)
    assert state.jumps == 1


@settings(max_examples=40, deadline=None, derandomize=True)
@given(steps=st.lists(st.floats(-60.0, 60.0), min_size=3, max_size=40),
       dts=st.lists(st.sampled_from([0.0006, 0.004, 0.0083, 0.0167, 0.04]), min_size=40,
                    max_size=40),
       cut=st.integers(1, 30))
def test_jumps_are_the_same_in_one_call_or_in_blocks(steps, dts, cut):
    """Steps of up to 60 mm (jumps among them) at intervals of 0.6-40 ms: the touches and
    jumps found in one call are those found block by block (the motion a jump is judged
    against is carried in the history)."""
    t = np.cumsum(dts[:len(steps)])
    x = 50.0 + np.cumsum(steps)
    trace = make_trace(t, np.zeros(t.size, int), x, np.full(t.size, 30.0))
    cfg = TrackerConfig(rate_hz=1000.0, quantum=1)
    n = int(t[-1] * 1000) + 3
    whole, whole_state = track(0, n, trace, TrackerState(), cfg)
    applied = apply_index(trace.t_s, cfg)
    state, i = TrackerState(), 0
    for lo in range(0, n, cut):
        size = min(cut, n - lo)
        j = int(np.searchsorted(applied, lo + size))
        block, state = track(lo, size, trace.slice(i, j) if j > i else None, state, cfg)
        if block.touch_id.shape[0]:  # the finger is known from its first sample on
            np.testing.assert_array_equal(block.touch_id, whole.touch_id[:, lo:lo + size])
        i = j
    assert (state.jumps, state.touches) == (whole_state.jumps, whole_state.touches)


@pytest.mark.parametrize("epoch_s", [1e5, 1e6, 1e9])
def test_where_the_clock_starts_changes_no_block_a_sample_is_used_from(epoch_s):
    """A 50 Hz log's samples fall on 5 ms block boundaries. With its clock reading 1e5 s
    or more, the rounding of each time put some of them a block later (24 of 151 at
    1e5 s, 72 at 1e9 s): the predicted finger moved by up to 2 mm and mu' by up to 0.4
    against the same log starting at 0. Now only the rounding of the output's own times
    is left: at 1e9 s (a Unix time) 1.2e-7 s, 60 mm/s of it 1e-5 mm."""
    import frictex
    base = frictex.synth_trace("back-and-forth", rate_hz=50, duration_s=3, speed_mm_s=60,
                               x0_mm=60)
    later = frictex.make_trace(base.t_s + epoch_s, base.finger, base.x_mm, base.y_mm,
                               base.force_n, base.event)
    at_zero, at_epoch = (frictex.build_pipeline("grating-5mm").process(trace)
                         for trace in (base, later))
    assert np.abs(at_zero.x_mm - at_epoch.x_mm).max() < 1e-4
    assert np.abs(at_zero.mu_target - at_epoch.mu_target).max() < 1e-3


@pytest.mark.parametrize("t0_s", [0.0, 1e4 + 0.0123])
@pytest.mark.parametrize("x_mm, y_mm", [(50.0, 30.0), (0.1, 70.3), (1e3, 123.456), (-4321.5, 1e4)])
def test_a_finger_at_rest_has_exactly_zero_velocity(x_mm, y_mm, t0_s):
    """The fit summed raw positions: for x = 50 mm the large terms left +-7.4e-13 mm/s on
    2400 of 20,000 samples of a still finger, and its prediction drifted off 50.0."""
    rng = np.random.default_rng(1)
    t = t0_s + np.cumsum(rng.uniform(0.001, 0.02, 200))  # irregular, as a real screen
    trace = make_trace(t, np.zeros(t.size, int), np.full(t.size, x_mm), np.full(t.size, y_mm))
    cfg = TrackerConfig(rate_hz=10_000.0, quantum=50, t0_s=t0_s)
    block, _ = _run(trace, int((t[-1] - t0_s) * 1e4) + 100, cfg)
    touching = block.contact[0]
    assert touching.sum() > 1000
    assert np.all(block.vx[0] == 0.0) and np.all(block.vy[0] == 0.0)
    assert np.all(block.x_pred[0, touching] == x_mm) and np.all(block.y_pred[0, touching] == y_mm)


@pytest.mark.parametrize("x_mm", [50.0, 61.37])
def test_sht_plays_a_constant_command_under_a_still_finger(x_mm):
    """A finger held still at 50 mm on the 0.6 mm grating (an edge: SHT restarts phase at
    0 there) had its commanded amplitude step 1.508981 -> 0 -> 1.508981 um at t = 0.1001,
    0.14 and 0.1801 s: a velocity of -7.4e-13 mm/s wrapped the phase to 0.99999."""
    import frictex
    t = np.arange(100) / 50.0
    trace = make_trace(t, np.zeros(t.size, int), np.full(t.size, x_mm), np.full(t.size, 30.0),
                       np.full(t.size, 0.5))
    out = frictex.build_pipeline("grating-0.6mm", renderer="sht").process(trace)
    commands = out.commands_um[out.contact[0]]  # (samples touching, channels)
    assert commands.shape[0] > 10_000 and np.all(commands > 0.0)
    assert np.all(commands == commands[0])

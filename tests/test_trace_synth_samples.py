"""trace synth: how many samples a motion gives, their timestamps under jitter, and the
speed of human-varied arcs."""

import numpy as np
import pytest

from frictex.app.commands.cli import main
from frictex.rendering.input.press_synth import TOUCH_N, press_trace
from frictex.rendering.input.trace_file import DOWN, UP, read_trace
from frictex.rendering.input.trace_synth import make_motion, sample, sample_count


def test_a_duration_of_whole_intervals_ends_on_its_last_sample():
    """0.57 s at 100 Hz is 56.999... intervals in floating point: the trace ended at
    0.56 s; 69 of 1000 durations from 0.01 to 10 s at 100 Hz lost their last sample."""
    trace = sample(make_motion("swipe", duration_s=0.57), 100.0)
    assert len(trace) == 58 and trace.t_s[-1] == pytest.approx(0.57)
    durations = np.round(np.arange(1, 1001) * 0.01, 2)
    assert all(sample_count(d, 100.0) == round(d * 100) + 1 for d in durations)


def test_a_duration_between_samples_ends_with_a_sample_at_its_end():
    """--rate 3 --duration 1.01 wrote 4 samples, the lift at 1.0 s: the stroke was cut short."""
    assert sample_count(0.575, 100.0) == 59
    trace = sample(make_motion("swipe", duration_s=1.01), 3.0)
    assert trace.t_s.tolist() == pytest.approx([0.0, 1 / 3, 2 / 3, 1.0, 1.01], abs=1e-12)
    assert trace.t_s[-1] == 1.01 and trace.event[-1] == UP


@pytest.mark.parametrize("options, end_s", [(["swipe", "--duration", "0.001"], 0.001),
                                            (["human", "--duration", "1e-6"], 1e-6),
                                            (["swipe", "--rate", "0.001"], 2.0)])
def test_a_motion_shorter_than_an_interval_is_a_touch_and_a_lift_at_its_end(tmp_path, capsys,
                                                                            options, end_s):
    """Such a trace was one row whose event was a lift, with no touch; then refused; now
    its end is sampled like any other's."""
    out = tmp_path / "t.csv"
    assert main(["trace", "synth", *options, "-o", str(out)]) == 0
    trace = read_trace(out)
    assert trace.event.tolist() == [DOWN, UP] and trace.t_s[-1] == pytest.approx(end_s, rel=1e-12)


def test_a_press_at_a_low_rate_lifts_at_its_end_and_touch_force():
    """--rate 3 --force-noise 0: each 1.3 s press ended at 1.0 s and lifted at 0.55 N
    (the whole trace 4.2 s instead of 4.5 s)."""
    trace = press_trace(rate_hz=3.0, noise_n=0.0)
    ups = np.flatnonzero(trace.event == UP)
    assert trace.t_s[ups] == pytest.approx([1.3, 2.9, 4.5], abs=1e-12)
    assert trace.force_n[ups] == pytest.approx([TOUCH_N] * 3, abs=1e-12)


def test_whole_interval_durations_keep_their_samples():
    """A press at the bundled 100 Hz (1.3 s: 130.00000000000003 intervals) gets no extra
    sample at its end."""
    trace = press_trace(noise_n=0.0, peaks_n=(1.0,))
    assert len(trace) == 131 and np.array_equal(trace.t_s, np.arange(131) / 100.0)


def test_jittered_timestamps_stay_strictly_increasing():
    """--jitter 0.004 --rate 100 --duration 20 (under the 0.005 s refused): 88 of 2001
    samples shared a timestamp with the one before."""
    t = sample(make_motion("swipe", speed_mm_s=1.0, duration_s=20.0), 100.0,
               jitter_s=0.004).t_s
    assert t.size == 2001 and np.diff(t).min() >= 0.1 / 100 * (1 - 1e-9)


def test_a_slow_speed_gives_slow_arcs():
    """human-varied's arcs were played at 40 mm/s peak or faster whatever --speed said:
    at --speed 5 every arc ran at 40 mm/s and more."""
    motion = make_motion("human-varied", speed_mm_s=5.0, duration_s=200.0, seed=3)
    arcs = [(t1 - t0, q[2] * abs(q[4] - q[3]))  # (s, mm): radius x sweep
            for t0, t1, kind, q in motion.params["segments"] if kind == "arc"]
    assert arcs
    peaks = [1.875 * length / seconds for seconds, length in arcs if seconds > 0.1]
    assert peaks and max(peaks) <= 5.0 * 1.8 + 1e-9

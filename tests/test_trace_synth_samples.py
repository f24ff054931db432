"""trace synth: how many samples a motion gives, their timestamps under jitter, and the
speed of human-varied arcs."""

import numpy as np
import pytest

from frictex.app.commands.cli import main
from frictex.rendering.input.trace_synth import make_motion, sample, sample_count


def test_a_duration_of_whole_intervals_ends_on_its_last_sample():
    """0.57 s at 100 Hz is 56.999... intervals in floating point: the trace ended at
    0.56 s; 69 of 1000 durations from 0.01 to 10 s at 100 Hz lost their last sample."""
    trace = sample(make_motion("swipe", duration_s=0.57), 100.0)
    assert len(trace) == 58 and trace.t_s[-1] == pytest.approx(0.57)
    durations = np.round(np.arange(1, 1001) * 0.01, 2)
    assert all(sample_count(d, 100.0) == round(d * 100) + 1 for d in durations)


def test_a_duration_between_samples_still_ends_at_the_last_whole_one():
    assert sample_count(0.575, 100.0) == 58


@pytest.mark.parametrize("options", [["swipe", "--duration", "0.001"],
                                     ["human", "--duration", "1e-6"],
                                     ["swipe", "--rate", "0.001"]])
def test_a_motion_of_fewer_than_two_samples_is_refused(tmp_path, capsys, options):
    """Such a trace was one row whose event was a lift, with no touch (exit 0)."""
    out = tmp_path / "t.csv"
    assert main(["trace", "synth", *options, "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert "gives 1 sample; a trace needs at least 2 (a touch and a lift)" in err
    assert "\n" not in err and not out.exists()


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

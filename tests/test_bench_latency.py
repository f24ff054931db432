"""frictex bench latency's bookkeeping: when a device played a sample, which sample first
carried a touch, and the TUIO datagrams it sends (read back by frictex's own decoder)."""

import numpy as np
import pytest

from frictex.app.measure.bench_latency import PlayedTimes, _latencies, tuio_frame
from frictex.rendering.input.trace_file import DOWN, UP
from frictex.rendering.input.tuio import TuioDecoder


def test_each_sample_is_timed_back_from_its_batch():
    played = PlayedTimes(10_000.0)
    played.note(np.arange(100, 150), 2.0)           # 149 played at 2.0 s
    played.note(np.array([150, 151, 160, 161]), 3.0)  # a gap: 161 at 3.0 s, 151 a tick before 160
    assert played.time_of(149) == pytest.approx(2.0)
    assert played.time_of(100) == pytest.approx(2.0 - 49e-4)
    assert played.time_of(161) == pytest.approx(3.0)
    assert played.time_of(160) == pytest.approx(3.0 - 1e-4)
    assert played.time_of(151) == pytest.approx(3.0 - 10e-4)
    assert played.time_of(155) is None and played.time_of(99) is None


def test_a_touch_is_timed_to_the_first_rise_played_after_it():
    commands = np.zeros(1000)
    commands[300:400] = 1.5  # the first touch
    commands[700:800] = 1.5  # the second
    played = PlayedTimes(1000.0)
    played.note(np.arange(0, 1000), 10.0)  # sample i played at 9.001 + i / 1000 s
    latency, early = _latencies([9.25, 9.6], commands, played, int)
    np.testing.assert_allclose(latency, [9.001 + 0.3 - 9.25, 9.001 + 0.7 - 9.6])
    assert early == 0


def test_a_rise_that_never_played_leaves_its_touch_out_not_the_next_touchs_rise():
    commands = np.zeros(100)
    commands[10:20] = commands[50:60] = 1.0
    played = PlayedTimes(100.0)
    played.note(np.arange(40, 100), 5.0)  # 0-39 never played (flushed)
    latency, early = _latencies([4.0, 4.3], commands, played, int)
    np.testing.assert_allclose(latency, [5.0 - 0.49 - 4.3])
    assert early == 0


def test_tuio_frames_decode_to_a_down_at_the_position_and_an_up():
    decoder = TuioDecoder()
    down = decoder.feed(tuio_frame(1, (0.25, 0.5)), 1.0)
    up = decoder.feed(tuio_frame(2, None), 2.0)
    assert [(s.event, round(s.x, 6), round(s.y, 6)) for s in down] == [(DOWN, 0.25, 0.5)]
    assert [s.event for s in up] == [UP]


def test_a_rise_in_a_skipped_block_is_timed_at_the_sample_played_in_its_stead():
    from frictex.device.link.catch_up import IndexMap
    commands = np.zeros(200)
    commands[55:] = 1.0
    index = IndexMap()
    index.skip(50, 25)  # host samples 50-74 never went out; 75 went out as the device's 50
    played = PlayedTimes(1000.0)
    played.note(np.arange(0, 175), 1.0)  # device sample d played at 1.0 - (174 - d) / 1000
    np.testing.assert_allclose(_latencies([0.8], commands, played, index.device_index)[0],
                               [1.0 - 0.124 - 0.8])


def test_a_rise_dated_before_its_touch_is_counted_apart_from_the_lost():
    """A batch played in a catch-up burst is dated back one period a sample from its
    arrival, so its rise can come out before the touch: left out as before, but counted
    and said apart from the lost (it was counted lost, 'flushed or late')."""
    from frictex.app.measure.bench_latency import _figures
    commands = np.zeros(100)
    commands[10:20] = commands[50:60] = 1.0
    played = PlayedTimes(100.0)
    played.note(np.arange(0, 100), 5.0)  # sample i dated 4.01 + i / 100 s
    latency, early = _latencies([4.2, 4.3], commands, played, int)  # rise 10 at 4.11 < 4.2
    np.testing.assert_allclose(latency, [4.51 - 4.3])
    assert early == 1
    [p50, *_] = _figures("trace", latency, 3, early=early)
    assert p50.label == ("trace: p50 of 1 played of 3 touches (1 lost, 1 dated at or before "
                         "their touch (a batch played in a catch-up burst), not in it)")

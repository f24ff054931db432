"""A live link's catch-up (PROTOCOL.md 6.1): the index map, checked against a plain list
of which host sample went out as which device sample; when a block is skipped; and a
live stream whose device fell behind brought back to its lead, every sample accounted."""

import io
import time

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from frictex.device.link.catch_up import IndexMap, behind
from frictex.device.link.host import CommandSink
from frictex.device.link.ledger import Snapshot
from frictex.device.link.simport import SimDevice, sim_config

RATE = 10_000.0
BLOCK = 25


@settings(max_examples=200, deadline=None)
@given(st.lists(st.booleans(), min_size=1, max_size=60), st.integers(1, 40))
def test_the_map_agrees_with_a_list_of_what_went_out(skips, n):
    """Blocks of ``n`` host samples, each sent or skipped: every sent host sample maps to
    the device number it went out as, and back; a skipped one to the next sent one's."""
    index = IndexMap(keep=1000)
    sent_as: dict[int, int] = {}
    device_next = 0
    for k, skipped in enumerate(skips):
        start = k * n
        if skipped:
            index.skip(start, n)
            continue
        assert index.to_device(start) == device_next
        for h in range(start, start + n):
            sent_as[h] = device_next
            device_next += 1
    for h, d in sent_as.items():
        assert index.device_index(h) == d
        assert index.host_index(d) == h
    for h in range(len(skips) * n):
        if h not in sent_as:
            later = [sent_as[g] for g in range(h, len(skips) * n) if g in sent_as]
            assert index.device_index(h) == (later[0] if later else device_next)
    # any run of device samples splits into runs of consecutive host samples
    for d0 in range(0, device_next, 7):
        m = min(13, device_next - d0)
        runs = index.host_runs(d0, m)
        assert runs[0][1] == 0 and runs[-1][2] == m
        for host, lo, hi in runs:
            assert [sent_as[host + j] for j in range(hi - lo)] == list(range(d0 + lo, d0 + hi))


def _snapshot(play, end, playing=True, t_s=0.0):
    return Snapshot(t_s, play, end, end - play, playing, end, end)


def test_behind_a_playing_device_holding_its_prefill_or_more():
    assert behind(_snapshot(100, 150), 0.0, RATE, 150, 50)
    assert not behind(_snapshot(100, 149), 0.0, RATE, 149, 50)
    assert not behind(None, 0.0, RATE, 0, 50)
    # 2.5 ms later the device has played 25 more: 75 ahead, then 50
    assert behind(_snapshot(100, 175), 0.0, RATE, 175, 50)
    assert not behind(_snapshot(100, 175), 0.0026, RATE, 175, 50)


def test_a_device_that_stopped_reporting_is_not_taken_to_play_on_for_ever():
    """Reports 0.1 s old: the device is taken to have played 4 prefills past its last
    report, not 1000 samples, so 200 samples sent since are ahead of it."""
    assert behind(_snapshot(100, 150), 0.1, RATE, 350, 50)
    assert not behind(_snapshot(100, 150), 0.1, RATE, 349, 50)


def test_behind_a_waiting_device_only_with_three_prefills_held_or_on_their_way():
    """A device waiting for its prefill starts as soon as it holds it; the Status saying
    so may come two blocks later: only three prefills held or sent mean it is late
    (a transport that delivers slowly), however long ago it reported."""
    assert not behind(_snapshot(100, 200, playing=False), 5.0, RATE, 200, 50)
    assert not behind(_snapshot(100, 100, playing=False), 5.0, RATE, 249, 50)
    assert behind(_snapshot(100, 100, playing=False), 5.0, RATE, 250, 50)


def test_behind_when_fresher_blocks_wait_behind_it():
    """Blocks queued at the host (a port that took no bytes for a while): once those
    behind a block make up the prefill, it is stale, whatever the device reported."""
    assert behind(None, 0.0, RATE, 0, 50, queued=50)
    assert not behind(None, 0.0, RATE, 0, 50, queued=49)
    assert behind(_snapshot(100, 100, playing=False), 0.0, RATE, 100, 50, queued=75)


def test_a_live_stream_whose_device_fell_behind_comes_back_to_its_lead():
    """Blocks of 2.5 ms at the wall clock's pace, as the haptic thread makes them: after a
    30 ms pause it sends the blocks it owes at once. The device ran dry in the pause and
    plays again once it holds its prefill, so without catch-up the stream would play
    about 30 ms later from then on (the blocks owed sit in its buffer). The link skips
    blocks until the device is back to its lead; every sample is accounted for (played or
    skipped)."""
    device = SimDevice(sim_config([], 1, RATE, False))
    sink = CommandSink(device.open, 1, RATE, paced=False, stderr=io.StringIO(),
                       on_close=device.close, simulated=True, prefill_s=2 * BLOCK / RATE,
                       catch_up=True)
    t0 = time.perf_counter()
    k = 0
    for k in range(400):
        pause = t0 + k * BLOCK / RATE - time.perf_counter()
        if pause > 0:
            time.sleep(pause)
        if k == 100:
            time.sleep(0.030)
        sink.send(k * BLOCK, np.full((BLOCK, 1), 1.0))
    sink.close()
    status = sink.status()
    assert status["underruns"] >= 1
    # 12 blocks owed after the pause, the device holding at most 2 when it resumes: at
    # least 8 skipped however the threads were scheduled (more after other underruns)
    assert status["skipped_blocks"] >= 8, status
    assert status["unplayed_by_cause"]["skipped"] == BLOCK * status["skipped_blocks"]
    assert status["commanded_samples"] == status["played_samples"] + status["unplayed_samples"]
    # a link thread starved past the queue's 64 blocks drops the blocks it had no room for
    assert status["blocks_sent"] + status["skipped_blocks"] + status["dropped_blocks"] == 400
    assert status["unplayed_by_cause"]["queue_full"] == BLOCK * status["dropped_blocks"]

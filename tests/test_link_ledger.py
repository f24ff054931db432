"""The host's estimate of the device's buffer and its count of unplayed samples (pure)."""

import pytest
from hypothesis import given, settings, strategies as st

from frictex.device.link import protocol as p
from frictex.device.link.ledger import Ledger, Pacing, Snapshot, unwrap
from frictex.device.link.protocol import DeviceState as S

RATE = 10_000.0
U64 = st.integers(0, 2**64 - 1)


def status(play, level, state=S.PLAYING, end=None, played=0, flushed=0, late=0, overflow=0):
    """A version 2 Status (``end`` None: a version 1 Status, no accounting)."""
    extra = {} if end is None else {"buffer_end": end % 2**64, "played_samples": played,
                                    "flushed_samples": flushed, "flushes": 0}
    return p.Status(1, state, play % 2**64, level, late_samples=late,
                    overflow_samples=overflow, **extra)


@settings(derandomize=True, max_examples=200, deadline=None)
@given(U64, st.integers(-2**70, 2**70))
def test_unwrap_is_the_congruent_number_nearest_the_reference(device_index, near):
    got = unwrap(device_index, near)
    assert (got - device_index) % 2**64 == 0
    assert -2**63 <= got - near < 2**63


PACING = Pacing(RATE, target=200, prefill=100, window=2048)


def test_after_a_watchdog_flush_the_empty_buffer_takes_the_next_block():
    # the host sent up to 1200; the device flushed 200 samples and waits at 1000
    for st_ in (status(1000, 0, S.BUFFERING, end=1000), status(1000, 0, S.BUFFERING)):
        snap = Snapshot.from_status(st_, t_s=0.0, mark_end=1200, mark_count=1200)
        assert snap.room(PACING, 1.0, 1200, 1200, 1200, 50)
    # the same sent position with the samples still held (and playing): 1250 - 1000 > 200
    held = Snapshot.from_status(status(1000, 200, S.PLAYING, end=1200), 0.0, 1200, 1200)
    assert not held.room(PACING, 0.0, 1200, 1200, 1200, 50)


def test_a_device_without_an_origin_in_this_session_is_placed_where_the_host_is():
    """A device reused by a new host reports, until this session's first block reaches
    it, the play index its last session ended at (20000): with nothing held, played or
    flushed since the Hello it has no origin yet. Taken as empty at 20000, every block
    up to 20000 + window had room; it is taken as empty where the host is, and gets
    blocks up to the target (then its prefill is on its way)."""
    snap = Snapshot.from_status(status(20000, 0, S.BUFFERING, end=20000), 0.0, mark_end=0,
                                mark_count=0)
    sent = 0
    while sent < 30000 and snap.room(PACING, 0.0, sent, sent, sent, 50):
        sent += 50
    assert sent == PACING.target
    # once it holds, played or flushed something, its index is this session's again
    placed = Snapshot.from_status(status(20000, 0, S.BUFFERING, end=20000, flushed=50), 0.0,
                                  mark_end=20100, mark_count=100)
    assert placed.play_index == 20000


def test_a_playing_device_drains_at_its_rate_from_the_report():
    snap = Snapshot.from_status(status(1000, 200, end=1200), t_s=10.0, mark_end=1200,
                                mark_count=1200)
    # 5 ms at 10 kHz: 50 played, so 1250 - 1050 = 200 samples would be held
    assert snap.room(PACING, 10.005, 1200, 1200, 1200, 50)
    tighter = Pacing(RATE, target=199, prefill=100, window=2048)
    assert not snap.room(tighter, 10.005, 1200, 1200, 1200, 50)
    assert snap.level(10.005, RATE, 1200) == (1050, 1200)
    # it never plays past what it holds
    assert snap.level(99.0, RATE, 1200) == (1200, 1200)


def test_without_fresh_reports_nothing_goes_beyond_the_window():
    """A device reported playing at 1000 and then fell silent: the host streams on at
    the device's rate, but never past play + window, where the device would overflow."""
    snap = Snapshot.from_status(status(1000, 200, end=1200), t_s=0.0, mark_end=1200,
                                mark_count=1200)
    sent = 1200
    for k in range(200):  # 2 s of 10 ms turns with no new Status
        while snap.room(PACING, k * 0.01, sent, sent, sent, 50):
            sent += 50
    assert sent - 1000 <= PACING.window
    assert sent - 1000 > PACING.window - 50


def test_blocks_sent_after_the_heartbeat_are_in_flight_not_lost():
    # the Status says empty, but 200 samples went out after its heartbeat
    snap = Snapshot.from_status(status(1000, 0, S.PLAYING, end=1000), 0.0, mark_end=1000,
                                mark_count=1000)
    assert snap.level(0.0, RATE, 1200) == (1000, 1200)
    assert not snap.room(PACING, 0.0, 1200, 1200, 1200, 50)
    assert snap.room(PACING, 0.0, 1000, 1000, 1000, 50)


def test_a_device_short_of_its_prefill_across_a_hole_gets_blocks_within_the_window():
    """Blocks 1050..1400 were lost on the wire: the device holds 50 samples (1000..1050),
    below its prefill of 100, and waits; the host's next block starts at 1400. Held to
    the target the host would wait too (1450 - 1000 > 200): the old deadlock."""
    snap = Snapshot.from_status(status(1000, 50, S.BUFFERING, end=1050), 0.0, 1400, 1400)
    assert snap.room(PACING, 0.0, 1400, 1400, 1400, 50)
    # once 50 more are on their way it has its prefill: back to the target
    assert not snap.room(PACING, 0.0, 1450, 1450, 1450, 50)
    # and never beyond the window, where the device would refuse it (overflow)
    assert not snap.room(PACING, 0.0, 1400, 1400, 3100, 50)


def test_a_flushed_message_empties_the_buffer_at_the_restart_index():
    snap = Snapshot.flushed(2**64 - 5, t_s=3.0, sent_end=2**64 + 100, sent_count=500)
    assert snap.play_index == snap.end == 2**64 - 5  # mapped onto the host's numbering
    assert snap.room(PACING, 3.0, 2**64 + 100, 500, 2**64 + 100, 50)


def test_the_ledger_settles_every_commanded_sample():
    led = Ledger()
    led.command(1000)
    led.drop("disconnected", 100)
    led.start_session()
    # the session's first Status is the baseline: late 5 is from an earlier session
    led.status(status(0, 0, S.BUFFERING, end=0, late=5), mark=0)
    assert led.reporting
    led.sent(600)
    led.status(status(450, 100, end=550, played=300, flushed=100, late=55), mark=600)
    # 600 sent before that heartbeat: 300 played, 100 flushed, 50 late, 100 held, 50 lost
    assert led.breakdown() == {"disconnected": 100, "queue_full": 0, "stalled": 0, "skipped": 0,
                               "flushed": 100, "late": 50, "overflow": 0, "lost": 50}
    assert led.played == 300 and led.unplayed == 300
    led.sent(300)
    led.end_session()  # the link failed: 900 sent, 450 settled, the rest unknown
    assert led.breakdown()["lost"] == 900 - 300 - 100 - 50
    assert led.played + led.unplayed == led.commanded == 1000


def test_device_counters_that_wrap_at_2_32_still_add_up():
    led = Ledger()
    led.start_session()
    led.status(status(0, 0, end=0, played=2**32 - 10), mark=0)
    led.sent(30)
    led.status(status(30, 0, S.BUFFERING, end=30, played=20), mark=30)
    assert led.played == 30 and led.unplayed == 0
    # a counter that goes back restarted (a device that reset it): counted from 0
    led.sent(40)
    led.status(status(70, 0, S.BUFFERING, end=70, played=15), mark=70)
    assert led.played == 45


def test_a_version_1_device_leaves_played_flushed_lost_and_unplayed_unknown():
    """Unplayed summed the known causes alone: a version 1 device's watchdog trips dropped
    samples that nothing counted, and the run read 0 unplayed. It is unknown now."""
    led = Ledger()
    led.command(500)
    led.start_session()
    led.status(status(0, 0, S.BUFFERING), mark=0)
    led.sent(500)
    led.status(status(400, 0, S.BUFFERING, late=20), mark=500)
    b = led.breakdown()
    assert b["flushed"] is None and b["lost"] is None and b["late"] == 20
    assert led.played is None and led.unplayed is None


@pytest.mark.parametrize("cause", ["flushed", "late", "lost", "other"])
def test_only_host_causes_are_dropped_by_the_host(cause):
    with pytest.raises(ValueError, match=f"cause '{cause}': the host drops for disconnected"):
        Ledger().drop(cause, 1)

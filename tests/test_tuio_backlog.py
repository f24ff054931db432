"""A served sender that stops is lifted SILENCE_S after its last frame by the clock,
however many of its datagrams wait in the queue; a backlog is dropped, counted."""

import time

from frictex.rendering.input.trace_file import DOWN, MOVE, UP
from frictex.rendering.input.tuio import MAX_QUEUED_S, POLL_DATAGRAMS, SILENCE_S, TuioListener
from test_tuio import frame, osc_bundle, osc_message, received, sender

JUNK = 50  # well-formed OSC, not TUIO: read, but no frame


def until_counted(listener, accepted):
    """Wait (bounded) until the listener's thread has queued ``accepted`` datagrams,
    polling none of them."""
    deadline = time.monotonic() + 60.0
    while listener.datagrams < accepted and time.monotonic() < deadline:
        time.sleep(0.002)
    assert listener.datagrams == accepted


def test_a_sender_that_stops_is_lifted_by_the_clock_not_by_its_backlog():
    """Issue: silence was judged from each queued datagram's arrival and from the clock
    only once the queue was empty; a sender that queued 1,024 non-TUIO datagrams (7 ms
    each to decode, one a poll) and stopped stayed pressed 7 s, not 1.5 s."""
    now, lines = [0.0], []
    junk = osc_bundle(*[osc_message("/a")] * 40)
    with TuioListener(0, width_mm=100.0, height_mm=100.0, clock=lambda: now[0],
                      warn=lines.append) as listener, sender("127.0.0.1") as tablet:
        to = ("127.0.0.1", listener.port)
        tablet.sendto(frame(1, [3], [(3, 0.25, 0.5)]), to)
        samples = received(listener, 1, 0)
        for _ in range(JUNK):
            tablet.sendto(junk, to)
        until_counted(listener, 1 + JUNK)
        now[0] = SILENCE_S + MAX_QUEUED_S  # the clock: the tablet is silent, its junk stale
        samples += listener.poll()  # one poll
        counts = listener.counters()
    assert [(s.x_mm, s.event) for s in samples] == [(25.0, DOWN), (25.0, UP)]
    assert samples[-1].t_s == SILENCE_S + MAX_QUEUED_S and len(lines) == 1
    # all but the newest dropped unread; the newest decoded
    assert counts["stale"] == JUNK - 1 and listener.wait(0.0) is False


def test_a_stale_frame_is_still_decoded():
    """A frame that waited past MAX_QUEUED_S behind a newer one may carry a touch's only
    `set` (a sender may send one only as the cursor moves): it is decoded, not dropped;
    only the junk between is."""
    now = [0.0]
    junk = osc_bundle(*[osc_message("/a")] * 40)
    with TuioListener(0, width_mm=100.0, height_mm=100.0, clock=lambda: now[0],
                      warn=lambda line: None) as listener, sender("127.0.0.1") as tablet:
        to = ("127.0.0.1", listener.port)
        tablet.sendto(frame(1, [3], [(3, 0.25, 0.5)]), to)
        tablet.sendto(junk, to)
        tablet.sendto(frame(2, [3], []), to)  # the cursor alive, not moved: no set
        until_counted(listener, 3)
        now[0] = MAX_QUEUED_S  # all three queued this long
        samples = listener.poll()
        counts = listener.counters()
    assert [(s.x_mm, s.event) for s in samples] == [(25.0, DOWN)]
    assert counts["stale"] == 1


def queue_frames(listener, tablet, count, period_s, now):
    """Send ``count`` one-finger frames from ``tablet``, frame k with the clock ``now`` at
    k * ``period_s`` (s), and wait until all are queued, none polled; the last one's
    clock time (s)."""
    to = ("127.0.0.1", listener.port)
    for k in range(1, count + 1):
        now[0] = k * period_s
        tablet.sendto(frame(k, [3], [(3, 0.25, 0.5)]), to)
        until_counted(listener, k)  # stamped by the clock of its own k
    return now[0]


def test_a_backlog_of_frames_does_not_lift_and_press_again():
    """Issue: 40 queued frames (16 ms apart) and a poll 1.51 s after the last by the clock:
    poll 1 ended with an UP though 8 frames were still queued, poll 2 began with a DOWN
    (a new touch: clips fire again) and 'lifted 1 finger' was said twice. The sender is
    not silent while a frame of its waits in the queue."""
    now, lines = [0.0], []
    with TuioListener(0, width_mm=100.0, height_mm=100.0, clock=lambda: now[0],
                      warn=lines.append) as listener, sender("127.0.0.1") as tablet:
        last = queue_frames(listener, tablet, 40, 0.016, now)
        now[0] = last + SILENCE_S + 0.01  # the polling thread stalled; the tablet stopped
        first = listener.poll()
        second = listener.poll()
    assert len(first) == POLL_DATAGRAMS and UP not in [s.event for s in first]
    events = [s.event for s in first + second]
    assert events == [DOWN] + [MOVE] * 39 + [UP] and len(lines) == 1
    assert second[-1].t_s == now[0]


def test_a_backlog_of_junk_does_not_keep_a_silent_sender_pressed():
    """A sender whose last frame was SILENCE_S ago by the clock, with 50 fresh datagrams
    that are no TUIO frame still queued (more than one poll decodes): lifted by the clock
    at once, not when its junk is drained."""
    now, lines = [0.0], []
    junk = osc_bundle(*[osc_message("/a")] * 40)
    with TuioListener(0, width_mm=100.0, height_mm=100.0, clock=lambda: now[0],
                      warn=lines.append) as listener, sender("127.0.0.1") as tablet:
        queue_frames(listener, tablet, 1, 0.0, now)
        samples = listener.poll()
        now[0] = SILENCE_S - 0.01  # the junk comes just before the silence
        for _ in range(JUNK):
            tablet.sendto(junk, ("127.0.0.1", listener.port))
        until_counted(listener, 1 + JUNK)
        now[0] = SILENCE_S
        samples += listener.poll()  # fresh junk: none stale, POLL_DATAGRAMS decoded
        still_queued = listener.wait(0.0)
    assert [s.event for s in samples] == [DOWN, UP] and samples[-1].t_s == SILENCE_S
    assert still_queued and len(lines) == 1

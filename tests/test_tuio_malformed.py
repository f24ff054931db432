"""Malformed TUIO: one bad cursor does not throw its frame away, each kind of problem is
said once with its reason and counted by kind, a silence says what came meanwhile, a
sender the listener cannot hear is refused, and the queue is bounded in bytes."""

import math
import time
from dataclasses import replace

import pytest

from frictex.app.commands.demo import tuio_line
from frictex.app.live.inputs import parse_input
from frictex.device.errors import InputError
from frictex.rendering.input.trace_file import DOWN, MOVE
from frictex.rendering.input.tuio import SILENCE_S, TuioListener, parse_sender
from test_tuio import STILL, frame, received, sender


class Clock:
    """A clock the test moves (s)."""

    def __init__(self) -> None:
        self.t = 100.0

    def __call__(self) -> float:
        return self.t


def test_one_cursor_off_the_screen_leaves_the_other_playing():
    """Issue: two cursors a frame, cursor 2 at x = 1.6, 60 frames/s for 2.4 s: every frame
    counted malformed, cursor 1 frozen, and after 1.5 s both lifted as 'no message'."""
    clock, lines = Clock(), []
    with TuioListener(0, width_mm=100.0, height_mm=100.0, clock=clock,
                      warn=lines.append) as listener, sender("127.0.0.1") as tablet:
        to = ("127.0.0.1", listener.port)
        tablet.sendto(frame(1, [1, 2], [(1, 0.5, 0.5), (2, 0.6, 0.5)]), to)
        samples = received(listener, 1, 0)
        for k in range(2, 150):
            clock.t += 1 / 60
            tablet.sendto(frame(k, [1, 2], [(1, 0.5 + k / 1000, 0.5), (2, 1.6, 0.5)]), to)
            samples += received(listener, k, 0)
        counts = listener.counters()
    assert [s.event for s in samples] == [DOWN, DOWN] + [MOVE] * 148
    assert samples[-1].finger == 0 and samples[-1].x_mm == pytest.approx(64.9, abs=1e-3)
    assert (counts["bad_packets"], counts["bad_sets"]) == (0, 148)
    assert counts["malformed"] == {"cursor position off the screen": 148}
    assert lines == [f"TUIO: cursor skipped in a frame from {counts['sender']}: /tuio/2Dcur "
                     "set 2: position (1.6, 0.5) is off the screen, expected -0.5 to 1.5 "
                     "(normalised) (the frame's other cursors played, this one kept where it "
                     "was); further ones counted"]
    assert "148 cursor sets skipped (cannot be played), by kind (datagrams and cursor sets " \
           "together): 148 cursor position off the screen" in tuio_line(counts)


def test_each_kind_of_malformed_datagram_is_said_once_and_counted():
    """Issue: NaN positions and junk were dropped without a word while the demo ran, and
    its closing line said only '118 malformed datagrams dropped'."""
    lines = []
    nan_frame = frame(2, [1], [(1, math.nan, 0.5)])
    with TuioListener(0, width_mm=100.0, height_mm=100.0, clock=STILL,
                      warn=lines.append) as listener, sender("127.0.0.1") as tablet:
        to = ("127.0.0.1", listener.port)
        tablet.sendto(frame(1, [1], [(1, 0.5, 0.5)]), to)
        for data in (b"junk", nan_frame, b"junk", nan_frame, b"/abc"):
            tablet.sendto(data, to)
        received(listener, 6, 0)
        counts = listener.counters()
    origin = counts["sender"]
    assert lines == [f"TUIO: malformed datagram from {origin}: OSC string at byte 0 has no "
                     "NUL terminator; further ones counted",
                     f"TUIO: cursor skipped in a frame from {origin}: /tuio/2Dcur set 1: "
                     "position (nan, 0.5) is not finite (the frame's other cursors played, "
                     "this one kept where it was); further ones counted"]
    assert counts["malformed"] == {"not OSC": 3, "cursor position not finite": 2}
    assert tuio_line(counts).endswith(
        "3 malformed datagrams dropped, 2 cursor sets skipped (cannot be played), "
        "by kind (datagrams and cursor sets together): 3 not OSC, 2 cursor position not "
        "finite")


def test_a_silence_of_malformed_datagrams_says_they_came():
    """Issue: a sender whose every datagram was malformed was said silent, 'no message
    ... for 1.5 s', though one came every 16 ms."""
    clock, lines = Clock(), []
    with TuioListener(0, width_mm=100.0, height_mm=100.0, clock=clock,
                      warn=lines.append) as listener, sender("127.0.0.1") as tablet:
        to = ("127.0.0.1", listener.port)
        tablet.sendto(frame(1, [1], [(1, 0.5, 0.5)]), to)
        received(listener, 1, 0)
        for k in range(2, 5):
            tablet.sendto(b"junk", to)
            received(listener, k, 0)
        clock.t += SILENCE_S
        listener.poll()
        origin = listener.counters()["sender"]
    assert lines[-1] == (f"TUIO: no valid frame from {origin} for {SILENCE_S:g} s "
                         "(3 datagrams, 3 malformed): lifted 1 finger")


def test_a_silence_with_nothing_received_says_no_message():
    clock, lines = Clock(), []
    with TuioListener(0, width_mm=100.0, height_mm=100.0, clock=clock,
                      warn=lines.append) as listener, sender("127.0.0.1") as tablet:
        tablet.sendto(frame(1, [1], [(1, 0.5, 0.5)]), ("127.0.0.1", listener.port))
        received(listener, 1, 0)
        clock.t += SILENCE_S
        listener.poll()
        origin = listener.counters()["sender"]
    assert lines == [f"TUIO: no message from {origin} for {SILENCE_S:g} s: lifted 1 finger"]


@pytest.mark.parametrize("text", ["0.0.0.0", "0.0.0.0:5000", "255.255.255.255", "224.0.0.1"])
def test_no_sender_has_the_any_broadcast_or_multicast_address(text):
    """Issue: --tuio-from 0.0.0.0 was accepted, though no datagram comes from it."""
    with pytest.raises(InputError, match="no sender has that address"):
        parse_sender(text)


def test_ipv6_any_is_refused():
    with pytest.raises(InputError, match="expected ADDR or ADDR:PORT, an IPv4 address"):
        parse_sender("::")


def test_a_network_sender_for_a_loopback_listener_is_an_error():
    """Issue: --tuio-from 192.168.1.20 with the listener on 127.0.0.1 said 'accepting
    from 192.168.1.20:* only' and waited for a tablet that could never reach it."""
    _, loopback = parse_input("tuio:3333")
    with pytest.raises(InputError, match=r"TUIO from 192.168.1.20: the listener is on loopback "
                                         r"\(127.0.0.1\), .* --input tuio:0.0.0.0:PORT"):
        replace(loopback, accept_from=parse_sender("192.168.1.20"))
    assert replace(loopback, accept_from=parse_sender("127.0.0.2:5000")).accept_from == \
        ("127.0.0.2", 5000)
    _, everywhere = parse_input("tuio:0.0.0.0:3333")
    assert replace(everywhere, accept_from=parse_sender("192.168.1.20")).host == "0.0.0.0"


def test_the_queue_is_bounded_in_bytes_and_the_drop_said_once():
    """Issue: 64 kB datagrams from the served sender filled a 1024-entry queue (64 MB)."""
    lines = []
    big = b"\0" * 2000
    with TuioListener(0, width_mm=1.0, height_mm=1.0, clock=STILL, max_bytes=4096,
                      warn=lines.append) as listener, sender("127.0.0.1") as tablet:
        to = ("127.0.0.1", listener.port)
        tablet.sendto(frame(1, [1], [(1, 0.5, 0.5)]), to)
        for _ in range(5):
            tablet.sendto(big, to)
        deadline = time.monotonic() + 60.0
        while listener.datagrams < 6 and time.monotonic() < deadline:
            time.sleep(0.005)
        counts = listener.counters()
    assert counts["dropped"] == 4  # the frame and one 2000-byte datagram fit in 4096
    assert lines == [f"TUIO: datagrams from {counts['sender']} come faster than they are "
                     "decoded (1024 datagrams or 4 kB queued): dropping; further ones counted"]


def test_a_served_senders_oversized_datagram_is_counted_unparsed():
    """A flood of 64 kB bundles from the sender served was parsed whole, 10 ms each, in the
    haptic process (439 deadline misses in 12 s against 9): a datagram over
    MAX_FRAME_BYTES is counted 'too large' and not decoded; the frames around it play."""
    from frictex.rendering.input.tuio import MAX_FRAME_BYTES, TuioDecoder, OscError
    sets = [(k, 0.5, 0.5) for k in range(1, 600)]  # 31 kB
    huge = frame(2, [1], sets)
    assert len(huge) > MAX_FRAME_BYTES
    with pytest.raises(OscError, match=r"bytes, over the 16,384 a TUIO frame needs") as said:
        TuioDecoder().feed(huge, 0.0)
    assert said.value.kind == "too large"
    lines = []
    with TuioListener(0, width_mm=100.0, height_mm=100.0, clock=STILL,
                      warn=lines.append) as listener, sender("127.0.0.1") as tablet:
        to = ("127.0.0.1", listener.port)
        tablet.sendto(frame(1, [1], [(1, 0.5, 0.5)]), to)
        tablet.sendto(huge, to)
        tablet.sendto(frame(3, [1], [(1, 0.6, 0.5)]), to)
        samples = received(listener, 3, 0)
        while listener.wait(0.0):  # a poll stops after the big one: the rest waits
            samples += listener.poll()
        counts = listener.counters()
    assert [s.event for s in samples] == [DOWN, MOVE]
    assert counts["malformed"] == {"too large": 1}
    assert len(lines) == 1 and "over the 16,384 a TUIO frame needs (not decoded)" in lines[0]

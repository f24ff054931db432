"""TUIO 1.1 2Dcur: the OSC parser, the alive/set/fseq semantics and the UDP listener."""

import math
import queue
import socket
import struct
import threading
import time

import pytest
from hypothesis import given, settings, strategies as st

from frictex.rendering.input.trace_file import DOWN, MOVE, UP, TraceError
from test_evdev_decode import check_event_sequence
from frictex.device.errors import InputError
from frictex.rendering.input.tuio import (MAX_CURSORS, MAX_SOURCES, SILENCE_S, OscError,
                                         SenderGate, TuioDecoder,
                                         TuioListener, exposure_warning, is_tuio_frame,
                                         parse_message, parse_packet, parse_sender)


# an OSC 1.0 encoder written from the specification, independent of the parser under test
def osc_string(s: str) -> bytes:
    b = s.encode() + b"\0"
    return b + b"\0" * (-len(b) % 4)


def osc_message(address: str, *args) -> bytes:
    tags, data = ",", b""
    for a in args:
        if isinstance(a, str):
            tags, data = tags + "s", data + osc_string(a)
        elif isinstance(a, int):
            tags, data = tags + "i", data + struct.pack(">i", a)
        elif isinstance(a, float):
            tags, data = tags + "f", data + struct.pack(">f", a)
        else:
            tags, data = tags + "b", data + struct.pack(">i", len(a)) + a + b"\0" * (-len(a) % 4)
    return osc_string(address) + osc_string(tags) + data


def osc_bundle(*elements: bytes) -> bytes:
    return b"#bundle\0" + struct.pack(">Q", 1) + b"".join(struct.pack(">i", len(e)) + e for e in elements)


def frame(fseq, alive, sets=(), source=None):
    """A TUIO 1.1 2Dcur bundle: sets are (session, x, y)."""
    msgs = [osc_message("/tuio/2Dcur", "source", source)] if source else []
    msgs.append(osc_message("/tuio/2Dcur", "alive", *alive))
    msgs += [osc_message("/tuio/2Dcur", "set", s, x, y, 0.0, 0.0, 0.0) for s, x, y in sets]
    msgs.append(osc_message("/tuio/2Dcur", "fseq", fseq))
    return osc_bundle(*msgs)


#: a clock standing still: nothing queued goes stale, no source falls silent, however
#: late the test's thread runs
STILL = lambda: 0.0  # noqa: E731


def test_message_with_every_common_type():
    data = (osc_string("/a/b") + osc_string(",ifsbhdTFN") + struct.pack(">i", -7)
            + struct.pack(">f", 0.25) + osc_string("hey") + struct.pack(">i", 3) + b"xyz\0"
            + struct.pack(">q", -2 ** 40) + struct.pack(">d", math.pi))
    assert parse_message(data) == ("/a/b", [-7, 0.25, "hey", b"xyz", -2 ** 40, math.pi, True, False, None])


def test_nested_bundles_flatten_in_order():
    inner = osc_bundle(osc_message("/x", 1), osc_message("/y", 2))
    assert parse_packet(osc_bundle(osc_message("/w", 0), inner)) == [("/w", [0]), ("/x", [1]), ("/y", [2])]


@pytest.mark.parametrize("data, message", [
    (b"/abc", "no NUL terminator"),
    (osc_string("abc") + osc_string(",i") + b"\0\0\0\1", "does not start with '/'"),
    (osc_string("/a"), "has no type tag string"),
    (osc_string("/a") + osc_string("i"), "do not start with ','"),
    (osc_string("/a") + osc_string(",i") + b"\0\0", r"'i' argument at byte 8 needs 4 bytes, only 2 left"),
    (osc_string("/a") + osc_string(",q"), "type tag 'q' is not supported"),
    (osc_string("/a") + osc_string(",b") + struct.pack(">i", -1), "blob size -1 is negative"),
    (b"#bundle\0" + b"\0" * 8 + struct.pack(">i", 6) + b"\0" * 6, "has size 6"),
    (b"#bundle\0\0\0", "bundle time tag"),
    (osc_string("/\xe9") [:2] + b"\xff\0\0", "not UTF-8"),
])
def test_malformed_packets_raise_osc_errors(data, message):
    with pytest.raises(OscError, match=message):
        parse_packet(data)


def test_osc_error_is_a_trace_error():
    assert issubclass(OscError, TraceError) and issubclass(OscError, ValueError)


_arg = st.one_of(st.integers(-2 ** 31, 2 ** 31 - 1), st.floats(width=32, allow_nan=False),
                 st.text(st.characters(min_codepoint=1, max_codepoint=0x7FF), max_size=12),
                 st.binary(max_size=9))
_msg = st.tuples(st.text("abcxyz/", min_size=0, max_size=10).map(lambda s: "/" + s), st.lists(_arg, max_size=6))


@settings(max_examples=150, derandomize=True, deadline=None)
@given(st.lists(_msg, min_size=1, max_size=4), st.booleans())
def test_parser_inverts_the_encoder(messages, bundled):
    packets = [osc_message(a, *args) for a, args in messages]
    data = osc_bundle(*packets) if bundled else packets[0]
    expected = messages if bundled else messages[:1]
    assert parse_packet(data) == [(a, list(args)) for a, args in expected]


@settings(max_examples=300, derandomize=True, deadline=None)
@given(st.binary(max_size=64) | st.lists(_msg, min_size=1, max_size=3).flatmap(
    lambda ms: st.integers(0, 200).map(lambda cut: osc_bundle(*[osc_message(a, *x) for a, x in ms])[:cut])))
def test_any_bytes_parse_or_raise_osc_error(data):
    try:
        parse_packet(data)
    except OscError:
        pass


@settings(max_examples=150, derandomize=True, deadline=None)
@given(st.lists(st.tuples(st.integers(-3, 8), st.lists(st.integers(0, 4), max_size=3),
                          st.lists(st.tuples(st.integers(0, 5), st.floats(-0.5, 1.5), st.floats(0, 1)),
                                   max_size=3)), max_size=10))
def test_random_frames_give_consistent_samples(frames):
    dec = TuioDecoder()
    samples = [s for k, (fseq, alive, sets) in enumerate(frames)
               for s in dec.feed(frame(fseq, alive, sets), float(k))]
    check_event_sequence(samples)


# -- 2Dcur semantics ------------------------------------------------------------------------
def _short(samples):
    return [(s.finger, round(s.x, 6), round(s.y, 6), s.event) for s in samples]


def test_alive_set_fseq():
    dec = TuioDecoder()
    assert _short(dec.feed(frame(1, [7], [(7, 0.5, 0.25)]), 0.0)) == [(0, 0.5, 0.25, DOWN)]
    assert _short(dec.feed(frame(2, [7, 9], [(7, 0.5, 0.3), (9, 0.1, 0.1)]), 0.01)) == \
        [(0, 0.5, 0.3, MOVE), (1, 0.1, 0.1, DOWN)]
    # 7 unmoved: no set, no sample; 9 moves
    assert _short(dec.feed(frame(3, [7, 9], [(9, 0.2, 0.1)]), 0.02)) == [(1, 0.2, 0.1, MOVE)]
    # 7 leaves the alive list: lifted where it was last seen; its id is reused
    assert _short(dec.feed(frame(4, [9], []), 0.03)) == [(0, 0.5, 0.3, UP)]
    assert _short(dec.feed(frame(5, [9, 11], [(11, 0.9, 0.9)]), 0.04)) == [(0, 0.9, 0.9, DOWN)]
    assert dec.frames == 5 and dec.late == 0


def test_late_frames_are_dropped_and_restarts_accepted():
    dec = TuioDecoder()
    dec.feed(frame(200, [1], [(1, 0.5, 0.5)]), 0.0)
    assert dec.feed(frame(199, [1], [(1, 0.6, 0.5)]), 0.01) == [] and dec.late == 1
    assert _short(dec.feed(frame(200, [1], [(1, 0.7, 0.5)]), 0.02)) == [(0, 0.7, 0.5, MOVE)]
    # more than 100 frames back: the tracker restarted
    assert _short(dec.feed(frame(3, [1], [(1, 0.8, 0.5)]), 0.03)) == [(0, 0.8, 0.5, MOVE)]
    # fseq -1: always accepted
    assert len(dec.feed(frame(-1, [1], [(1, 0.9, 0.5)]), 0.04)) == 1


def test_sources_scope_session_ids_and_stray_sets_are_counted():
    dec = TuioDecoder()
    a = dec.feed(frame(1, [1], [(1, 0.1, 0.1)], source="tableA"), 0.0)
    b = dec.feed(frame(1, [1], [(1, 0.9, 0.9), (2, 0.5, 0.5)], source="tableB"), 0.0)
    assert [s.finger for s in a + b] == [0, 1] and dec.stray == 1
    assert _short(dec.feed(frame(2, [], source="tableA"), 0.1)) == [(0, 0.1, 0.1, UP)]


def test_what_the_decoder_keeps_is_bounded_whatever_a_sender_claims():
    """A frame claiming 1,000 cursors alive, 200 of them set (16 kB, under the frame
    size decoded), gives MAX_CURSORS fingers; frames of a 9th source and on are ignored;
    both counted."""
    dec = TuioDecoder()
    ids = list(range(1_000))
    down = dec.feed(frame(1, ids, [(i, 0.5, 0.5) for i in ids[:200]]), 0.0)
    assert len(down) == MAX_CURSORS and dec.over_limit == 200 - MAX_CURSORS
    assert sorted(s.finger for s in down) == list(range(MAX_CURSORS))
    for k in range(1, 20):
        dec.feed(frame(1, [], source=f"table{k}"), 0.0)
    assert len(dec._alive) == MAX_SOURCES
    assert dec.over_limit == 200 - MAX_CURSORS + 19 - (MAX_SOURCES - 1)
    up = dec.feed(frame(2, []), 0.1)  # all lift: the fingers are free again
    assert len(up) == MAX_CURSORS and not dec._pos and not dec._fingers


def test_bad_sets_are_skipped_and_said():
    """A set that cannot be played is skipped alone (bad_sets), with its reason; the
    cursor, still alive, keeps its last good position."""
    skipped = []
    dec = TuioDecoder(on_bad_set=lambda error, origin: skipped.append(str(error)))
    dec.feed(frame(1, [1], [(1, 0.25, 0.25)]), 0.0)
    bad = osc_bundle(osc_message("/tuio/2Dcur", "alive", 1), osc_message("/tuio/2Dcur", "set", 1, "x", 0.5),
                     osc_message("/tuio/2Dcur", "fseq", 2))
    assert dec.feed(bad, 0.01) == []
    assert dec.feed(frame(3, [1], [(1, math.nan, 0.5)]), 0.02) == []
    # one frame far off the screen ended the live demo (its x in mm out of the trace's range)
    for x, y in ((1000.0, 0.5), (0.5, -0.6), (1.51, 0.5)):
        assert dec.feed(frame(3, [1], [(1, x, y)]), 0.02) == []
    assert dec.bad_sets == 5 and dec._pos == {("", 1): (0.25, 0.25)}
    assert "set: position is 'x', expected float" in skipped[0]
    assert "position (nan, 0.5) is not finite" in skipped[1]
    assert all("is off the screen, expected -0.5 to 1.5" in line for line in skipped[2:])
    assert dec.feed(frame(4, [1], []), 0.03) == []  # finger 1 still alive, nothing lifted
    assert dec.feed(osc_message("/tuio/2Dobj", "alive"), 0.04) == []  # other profiles skipped


def test_a_frame_whose_alive_or_fseq_cannot_be_read_changes_nothing():
    dec = TuioDecoder()
    dec.feed(frame(1, [1], [(1, 0.25, 0.25)]), 0.0)
    for bad in (osc_bundle(osc_message("/tuio/2Dcur", "alive", "one"), osc_message("/tuio/2Dcur", "fseq", 2)),
                osc_bundle(osc_message("/tuio/2Dcur", "alive"), osc_message("/tuio/2Dcur", "fseq", 0.5))):
        with pytest.raises(OscError, match="expected int") as caught:
            dec.feed(bad, 0.01)
        assert caught.value.kind == "2Dcur arguments wrong"
    assert dec._pos == {("", 1): (0.25, 0.25)}


# -- over real UDP --------------------------------------------------------------------------
def test_listener_receives_udp_on_localhost():
    with TuioListener(0, width_mm=200.0, height_mm=100.0, host="127.0.0.1",
                      clock=lambda: 100.0) as listener:
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as tx:
            tx.sendto(frame(1, [3], [(3, 0.25, 0.5)]), ("127.0.0.1", listener.port))
            tx.sendto(b"garbage", ("127.0.0.1", listener.port))
            tx.sendto(frame(2, [], []), ("127.0.0.1", listener.port))
            samples = []
            deadline = time.monotonic() + 60.0
            while len(samples) < 2 and time.monotonic() < deadline:
                samples += listener.poll()
                time.sleep(0.005)
        assert [(s.finger, s.x_mm, s.y_mm, s.force_n, s.event) for s in samples] == \
            [(0, 50.0, 50.0, 0.5, DOWN), (0, 50.0, 50.0, 0.5, UP)]
        # stamped on the listener's clock (100 s, standing still) less the time each
        # waited in the socket since the kernel received it
        assert all(40.0 < s.t_s <= 100.0 for s in samples)
        assert listener.bad_packets == 1 and "no NUL terminator" in listener.last_error


def test_listener_queue_is_bounded():
    with TuioListener(0, width_mm=1.0, height_mm=1.0, host="127.0.0.1", max_packets=2,
                      clock=STILL) as listener:
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as tx:
            for k in range(6):
                tx.sendto(frame(k + 1, [1], [(1, 0.5, 0.5)]), ("127.0.0.1", listener.port))
            deadline = time.monotonic() + 60.0
            while listener.dropped < 4 and time.monotonic() < deadline:
                time.sleep(0.005)
        assert listener.dropped == 4 and len(listener.poll()) == 2


def test_listener_port_in_use_is_a_clear_error():
    with TuioListener(0, width_mm=1.0, height_mm=1.0, host="127.0.0.1") as first:
        with pytest.raises(OSError, match=rf"TUIO: cannot listen on UDP 127.0.0.1:{first.port}"):
            TuioListener(first.port, width_mm=1.0, height_mm=1.0, host="127.0.0.1")


def test_a_datagram_is_stamped_when_it_arrived_not_when_it_was_read():
    """The receiving thread is held (its clock blocks) while a second frame arrives:
    that frame's stamp is the kernel's receive time, before the thread read it."""
    held, release = threading.Event(), threading.Event()

    def clock():
        if not held.is_set():  # the first datagram's stamp: hold the thread here
            held.set()
            release.wait()
        return time.monotonic()

    with TuioListener(0, width_mm=100.0, height_mm=100.0, host="127.0.0.1", clock=clock) as listener:
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as tx:
            tx.sendto(frame(1, [3], [(3, 0.25, 0.5)]), ("127.0.0.1", listener.port))
            assert held.wait(60.0)
            tx.sendto(frame(2, [3], [(3, 0.5, 0.5)]), ("127.0.0.1", listener.port))
            sent = time.monotonic()  # loopback: received by the kernel within sendto
            time.sleep(0.1)
            released = time.monotonic()
            release.set()
            samples = []
            deadline = time.monotonic() + 60.0
            while len(samples) < 2 and time.monotonic() < deadline:
                samples += listener.poll()
                time.sleep(0.005)
    assert [s.x_mm for s in samples] == [25.0, 50.0]
    assert samples[1].t_s <= sent + 1e-3 < released  # not when the thread got to it


# -- who may send ---------------------------------------------------------------------------
def sender(address):
    """A UDP socket sending from ``address`` (127.0.0.2 is a second loopback host)."""
    tx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    tx.bind((address, 0))
    return tx


def received(listener, accepted, refused):
    """Wait (bounded) until the listener counted ``accepted`` and ``refused`` datagrams;
    the samples it decoded meanwhile."""
    samples, deadline = [], time.monotonic() + 60.0
    while ((listener.datagrams, listener.refused) != (accepted, refused)
           and time.monotonic() < deadline):
        samples += listener.poll()
        time.sleep(0.005)
    assert (listener.datagrams, listener.refused) == (accepted, refused)
    return samples + listener.poll()


class LateQueue(queue.Queue):
    """A queue whose writer is descheduled for 50 ms before each put, as a receive
    thread on a loaded machine may be."""

    def put_nowait(self, item):
        time.sleep(0.05)
        super().put_nowait(item)


def test_a_counted_datagram_can_be_polled_however_late_its_thread_runs():
    with TuioListener(0, width_mm=100.0, height_mm=100.0) as listener, \
            sender("127.0.0.1") as tablet:
        listener._queue = LateQueue(listener._queue.maxsize)
        tablet.sendto(frame(1, [3], [(3, 0.25, 0.5)]), ("127.0.0.1", listener.port))
        deadline = time.monotonic() + 60.0
        while listener.datagrams < 1 and time.monotonic() < deadline:
            time.sleep(0.001)
        assert listener.wait(0.0)
        assert [(s.x_mm, s.event) for s in listener.poll()] == [(25.0, DOWN)]


def test_listener_binds_loopback_by_default():
    with TuioListener(0, width_mm=1.0, height_mm=1.0) as listener:
        assert listener._sock.getsockname()[0] == "127.0.0.1"
        assert listener.counters()["listen"] == f"127.0.0.1:{listener.port}"


def test_only_the_first_sender_moves_fingers_and_the_others_are_counted():
    with TuioListener(0, width_mm=100.0, height_mm=100.0) as listener, \
            sender("127.0.0.1") as first, sender("127.0.0.2") as stranger, \
            sender("127.0.0.1") as neighbour:
        to = ("127.0.0.1", listener.port)
        first.sendto(frame(1, [3], [(3, 0.25, 0.5)]), to)
        samples = received(listener, 1, 0)
        stranger.sendto(frame(1, [7], [(7, 0.9, 0.9)]), to)  # another host
        neighbour.sendto(frame(1, [8], [(8, 0.9, 0.9)]), to)  # another process, same host
        first.sendto(frame(2, [3], [(3, 0.5, 0.5)]), to)
        samples += received(listener, 2, 2)
        counts, first_port = listener.counters(), first.getsockname()[1]
    assert [(s.x_mm, s.event) for s in samples] == [(25.0, DOWN), (50.0, MOVE)]
    assert counts["sender"] == f"127.0.0.1:{first_port}"
    assert (counts["datagrams"], counts["refused"], counts["dropped"]) == (2, 2, 0)


def test_accept_from_an_address_takes_its_first_port_and_nothing_else():
    with TuioListener(0, width_mm=100.0, height_mm=100.0, host="0.0.0.0",
                      accept_from=("127.0.0.2", None)) as listener, \
            sender("127.0.0.1") as local, sender("127.0.0.2") as a, sender("127.0.0.2") as b:
        to = ("127.0.0.1", listener.port)
        local.sendto(frame(1, [1], [(1, 0.1, 0.1)]), to)  # first, but not the one accepted
        a.sendto(frame(1, [3], [(3, 0.25, 0.5)]), to)
        samples = received(listener, 1, 1)
        b.sendto(frame(2, [3], [(3, 0.5, 0.5)]), to)  # another port while a speaks
        a.sendto(frame(2, [3], [(3, 0.5, 0.5)]), to)
        samples += received(listener, 2, 2)
        assert listener.counters()["sender"] == f"127.0.0.2:{a.getsockname()[1]}"
    assert [(s.x_mm, s.event) for s in samples] == [(25.0, DOWN), (50.0, MOVE)]


def test_only_a_tuio_frame_claims_the_first_sender_slot():
    """Garbage, a lone OSC message and a bundle of another profile, from another host
    first, claim nothing: the tablet that then sends a 2Dcur frame is served."""
    stray = [b"\x00garbage\xff" * 3, osc_message("/tuio/2Dcur", "fseq", 1),
             osc_bundle(osc_message("/tuio/2Dobj", "alive"), osc_message("/tuio/2Dobj", "fseq", 1)),
             osc_bundle(osc_message("/tuio/2Dcur", "alive", 1)),  # no fseq: not a frame
             b"#bundle\0" + b"\x00" * 7]
    assert not any(is_tuio_frame(d) for d in stray) and is_tuio_frame(frame(1, []))
    with TuioListener(0, width_mm=100.0, height_mm=100.0) as listener, \
            sender("127.0.0.2") as stranger, sender("127.0.0.1") as tablet:
        to = ("127.0.0.1", listener.port)
        for data in stray:
            stranger.sendto(data, to)
        received(listener, 0, len(stray))
        tablet.sendto(frame(1, [3], [(3, 0.25, 0.5)]), to)
        samples = received(listener, 1, len(stray))
        assert listener.counters()["sender"] == f"127.0.0.1:{tablet.getsockname()[1]}"
    assert [(s.x_mm, s.event) for s in samples] == [(25.0, DOWN)]


@pytest.mark.parametrize("host, accept_from, warned", [
    ("127.0.0.1", None, False), ("127.0.0.5", None, False), ("0.0.0.0", None, True),
    ("192.168.1.4", None, True), ("0.0.0.0", ("10.0.0.7", None), False)])
def test_exposure_warning_beyond_loopback_without_a_named_sender(host, accept_from, warned):
    line = exposure_warning(host, accept_from)
    assert (line is not None) == warned
    if warned:
        assert "\n" not in line and host in line and "--tuio-from" in line


@pytest.mark.parametrize("text, expect", [("10.0.0.7", ("10.0.0.7", None)),
                                          ("127.0.0.2:5000", ("127.0.0.2", 5000))])
def test_parse_sender(text, expect):
    assert parse_sender(text) == expect


@pytest.mark.parametrize("text", ["", "host", "10.0.0", "10.0.0.7:0", "10.0.0.7:70000",
                                  "10.0.0.7:x", "::1", "10.0.0.7\x1b[2J"])
def test_bad_sender_is_an_input_error(text):
    with pytest.raises(InputError, match="expected ADDR or ADDR:PORT"):
        parse_sender(text)


def test_the_demos_line_says_when_nothing_came():
    """It said 'from None' when no datagram came."""
    from frictex.app.commands.demo import tuio_line
    with TuioListener(0, width_mm=200.0, height_mm=100.0, host="127.0.0.1") as listener:
        line = tuio_line(listener.counters())
    assert "from no sender (nothing came): 0 datagrams" in line and "None" not in line


# -- silence: a sender that vanishes, a sender that comes back ------------------------------
def test_a_silent_source_is_lifted_once_and_forgotten():
    dec = TuioDecoder()
    dec.feed(frame(150, [1, 2], [(1, 0.1, 0.4), (2, 0.3, 0.6)]), 0.0, "127.0.0.1:5000")
    assert dec.expire(SILENCE_S - 0.01) == ([], [])  # not silent long enough
    up, gone = dec.expire(SILENCE_S)
    assert _short(up) == [(0, 0.1, 0.4, UP), (1, 0.3, 0.6, UP)] and all(s.t_s == SILENCE_S for s in up)
    assert gone == [("127.0.0.1:5000", "", 2)]
    assert dec.expire(10.0) == ([], [])  # said once
    # the restarted sender counts from 1 again: not taken for a late frame of the old one
    assert _short(dec.feed(frame(1, [1], [(1, 0.5, 0.5)]), 10.1)) == [(0, 0.5, 0.5, DOWN)]
    assert dec.late == 0


def test_each_source_name_falls_silent_on_its_own():
    dec = TuioDecoder()
    dec.feed(frame(1, [1], [(1, 0.1, 0.1)], source="old"), 0.0, "h:1")
    for k in range(20):  # a new source name from the same sender keeps speaking
        dec.feed(frame(k + 1, [4], [(4, 0.9, 0.9)], source="new"), 0.1 * k, "h:1")
    up, gone = dec.expire(1.95)
    assert _short(up) == [(0, 0.1, 0.1, UP)] and gone == [("h:1", "old", 1)]


def test_the_gate_serves_one_sender_and_the_newest_after_silence():
    a, b = ("127.0.0.1", 4000), ("127.0.0.1", 4001)
    gate, tick = SenderGate(), frame(1, [])
    assert gate.admit(*b, 0.0, b"junk") is None  # junk claims nothing
    assert gate.admit(*a, 0.0, tick) == "new" and gate.sender == a
    t = 0.0
    for k in range(1000):  # b floods while a keeps speaking every 10 ms: all refused
        t = 0.01 * k
        assert gate.admit(*b, t, tick) is None
        assert gate.admit(*a, t, tick) == "same"
    assert gate.admit(*b, t + SILENCE_S - 0.01, tick) is None  # a: not silent long enough
    assert gate.admit(*b, t + SILENCE_S, b"junk") is None  # junk takes nothing over
    assert gate.admit(*b, t + SILENCE_S, tick) == "new" and gate.sender == b
    assert gate.admit(*a, t + SILENCE_S + 0.01, tick) is None and gate.takeovers == 1


def test_a_named_address_is_served_on_its_first_port_and_a_new_port_after_silence():
    """Issue: with no port named, every port of the address was served at once, each
    taking the slot from the other: two trackers moved one finger between them."""
    gate, tick = SenderGate(("127.0.0.2", None)), frame(1, [])
    assert gate.admit("127.0.0.1", 4000, 0.0, tick) is None
    assert gate.admit("127.0.0.2", 4000, 0.0, b"any") == "new"
    for k in range(1, 100):  # 4001 speaks as often as 4000: refused while 4000 speaks
        assert gate.admit("127.0.0.2", 4001, 0.01 * k, tick) is None
        assert gate.admit("127.0.0.2", 4000, 0.01 * k, b"any") == "same"
    assert gate.admit("127.0.0.2", 4002, 0.99 + SILENCE_S, b"any") == "new"
    assert gate.sender == ("127.0.0.2", 4002) and gate.takeovers == 1


def test_listener_lifts_a_vanished_sender_and_serves_the_one_that_comes_back():
    """Issue: a sender that exits without an empty alive left two fingers touching for
    good, and a restarted sender (a new port) was refused."""
    now, lines = [0.0], []
    with TuioListener(0, width_mm=100.0, height_mm=100.0, clock=lambda: now[0],
                      warn=lines.append) as listener, \
            sender("127.0.0.1") as old, sender("127.0.0.1") as new:
        to = ("127.0.0.1", listener.port)
        old.sendto(frame(150, [1, 2], [(1, 0.1, 0.4), (2, 0.3, 0.6)]), to)
        samples = received(listener, 1, 0)
        new.sendto(frame(1, [1], [(1, 0.5, 0.5)]), to)  # the old one still counts as speaking
        samples += received(listener, 1, 1)
        now[0] = SILENCE_S + 0.5  # a fake clock: the old sender has now been silent
        samples += listener.poll() + listener.poll()
        new.sendto(frame(1, [1], [(1, 0.5, 0.5)]), to)
        samples += received(listener, 2, 1)
        counts = listener.counters()
        old_port, new_port = old.getsockname()[1], new.getsockname()[1]
    assert [(s.finger, round(s.x_mm, 4), s.event) for s in samples] == [
        (0, 10.0, DOWN), (1, 30.0, DOWN), (0, 10.0, UP), (1, 30.0, UP), (0, 50.0, DOWN)]
    assert lines == [f"TUIO: no message from 127.0.0.1:{old_port} for {SILENCE_S:g} s: lifted 2 fingers",
                     f"TUIO: taking frames from 127.0.0.1:{new_port} (127.0.0.1:{old_port} was "
                     f"silent for {SILENCE_S:g} s or more)"]
    assert counts["sender"] == f"127.0.0.1:{new_port}" and counts["takeovers"] == 1


def test_a_silent_sources_name_is_said_escaped_and_cut():
    """A sender's 60,000-character source name (an ESC first) went into the silence
    warning whole: a 60,084-character line written from the haptic thread (15,000
    characters here, within the frame size decoded)."""
    from frictex.device.safe_text import MAX_SHOWN
    now, lines = [0.0], []
    # named: a frame this long claims nothing from an unnamed sender (MAX_CLAIM_BYTES)
    with TuioListener(0, width_mm=100.0, height_mm=100.0, clock=lambda: now[0],
                      accept_from=("127.0.0.1", None), warn=lines.append) as listener, \
            sender("127.0.0.1") as tracker:
        tracker.sendto(frame(1, [1], [(1, 0.1, 0.4)], source="\x1b" + "S" * 15_000),
                       ("127.0.0.1", listener.port))
        received(listener, 1, 0)
        now[0] = SILENCE_S + 0.5
        listener.poll()
    (line,) = lines
    assert "(source \"\\x1bSSS" in line and "\x1b" not in line
    assert len(line) < 120 + MAX_SHOWN

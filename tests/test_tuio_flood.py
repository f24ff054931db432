"""A TUIO flood cannot hold the thread that polls: an ``alive`` is read no further than
MAX_ALIVE_IDS ids, and one poll() decodes a bounded share of what is queued.

The bounds are checked by what is decoded (ids, datagrams, bytes), never by time.
"""

import socket
import struct
import time

from frictex.rendering.input.trace_file import DOWN, MOVE
from frictex.rendering.input.tuio import (MAX_ALIVE_IDS, MAX_CURSORS, MAX_FRAME_BYTES,
                                         POLL_BYTES, POLL_DATAGRAMS, TuioDecoder,
                                         TuioListener)
from test_tuio import STILL, frame, osc_bundle, osc_message, osc_string

#: the flood's shape: an alive of 1,000 ids and 180 sets in each 14,880-byte bundle, the
#: largest a served sender has decoded being MAX_FRAME_BYTES (16 kB)
FLOOD_IDS, FLOOD_SETS = 1000, 180


def flood_bundle(fseq: int) -> bytes:
    sets = [osc_message("/tuio/2Dcur", "set", i, 0.5, 0.5, 0.0, 0.0, 0.0)
            for i in range(FLOOD_SETS)]
    return osc_bundle(osc_message("/tuio/2Dcur", "alive", *range(FLOOD_IDS)), *sets,
                      osc_message("/tuio/2Dcur", "fseq", fseq))


FLOOD_BYTES = len(flood_bundle(1))
assert POLL_BYTES / 2 < FLOOD_BYTES <= MAX_FRAME_BYTES


def test_an_alive_is_read_no_further_than_max_alive_ids():
    """Its type tags claim 8,000 ids but only MAX_ALIVE_IDS follow: read further, the
    message would be malformed (an OscError)."""
    ids = struct.pack(f">{MAX_ALIVE_IDS}i", *range(MAX_ALIVE_IDS))
    alive = (osc_string("/tuio/2Dcur") + osc_string(",s" + "i" * FLOOD_IDS)
             + osc_string("alive") + ids)
    sets = [osc_message("/tuio/2Dcur", "set", i, 0.5, 0.5, 0.0, 0.0, 0.0) for i in (0, 1)]
    decoder = TuioDecoder()
    down = decoder.feed(osc_bundle(alive, *sets, osc_message("/tuio/2Dcur", "fseq", 1)), 0.0)
    assert [s.event for s in down] == [DOWN, DOWN]
    assert decoder.unread == FLOOD_IDS - MAX_ALIVE_IDS


def test_a_flood_bundle_gives_max_cursors_fingers_and_counts_what_it_refused():
    decoder = TuioDecoder()
    down = decoder.feed(flood_bundle(1), 0.0)
    assert len(flood_bundle(1)) == FLOOD_BYTES
    assert len(down) == MAX_CURSORS and decoder.unread == FLOOD_IDS - MAX_ALIVE_IDS
    assert decoder.over_limit == FLOOD_SETS - MAX_CURSORS


def counting(listener) -> list:
    """Wrap the listener's decoder so that each datagram it decodes is listed by size."""
    sizes, feed = [], listener.decoder.feed

    def counted(data, *args):
        sizes.append(len(data))
        return feed(data, *args)
    listener.decoder.feed = counted
    return sizes


def delivered(listener, datagrams, chunk):
    """Send ``datagrams`` to ``listener`` over loopback, ``chunk`` at a time, waiting
    (bounded) until it has queued each chunk: more at once may overflow the socket's
    buffer while its thread waits for a core."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as tx:
        expected = listener.datagrams
        for k, data in enumerate(datagrams, 1):
            tx.sendto(data, ("127.0.0.1", listener.port))
            expected += 1
            if k % chunk == 0 or k == len(datagrams):
                until(lambda: listener.datagrams >= expected)
    assert listener.dropped == 0


def until(condition):
    deadline = time.monotonic() + 60.0
    while not condition():
        assert time.monotonic() < deadline, "datagrams not delivered over loopback in 60 s"
        time.sleep(0.002)


def polls(listener, sizes) -> tuple[list, list]:
    """Poll until nothing is queued: the touches, and the sizes decoded by each poll."""
    touches, per_poll = [], []
    while listener.wait(0.0):
        before = len(sizes)
        touches += listener.poll()
        per_poll.append(sizes[before:])
    return touches, per_poll


def test_one_poll_decodes_one_flood_bundle_and_the_rest_waits():
    # named: a bundle this large claims nothing from an unnamed sender (MAX_CLAIM_BYTES)
    with TuioListener(0, width_mm=100.0, height_mm=100.0, accept_from=("127.0.0.1", None),
                      clock=STILL, warn=lambda line: None) as listener:
        sizes = counting(listener)
        delivered(listener, [flood_bundle(k + 1) for k in range(8)], chunk=1)
        touches, per_poll = polls(listener, sizes)
    # a poll stops once POLL_BYTES are decoded: two bundles, the rest waits
    assert per_poll == [[FLOOD_BYTES] * 2] * 4
    assert [t.event for t in touches] == [DOWN] * MAX_CURSORS + [MOVE] * MAX_CURSORS * 7


def test_an_ordinary_stream_is_decoded_whole_in_bounded_polls():
    """300 frames of one finger queued at once: every touch comes out, in order, no poll
    decoding more than POLL_DATAGRAMS datagrams or POLL_BYTES bytes and one datagram."""
    xs = [0.1 + 0.8 * k / 300 for k in range(300)]
    with TuioListener(0, width_mm=100.0, height_mm=100.0, clock=STILL,
                      warn=lambda line: None) as listener:
        sizes = counting(listener)
        delivered(listener, [frame(k + 1, [5], [(5, x, 0.5)]) for k, x in enumerate(xs)],
                  chunk=50)
        touches, per_poll = polls(listener, sizes)
    assert [round(t.x_mm, 3) for t in touches] == [round(100.0 * x, 3) for x in xs]
    assert [t.event for t in touches] == [DOWN] + [MOVE] * 299
    assert max(len(p) for p in per_poll) == POLL_DATAGRAMS and len(per_poll) >= 300 / POLL_DATAGRAMS
    assert all(sum(p[:-1]) < POLL_BYTES for p in per_poll)

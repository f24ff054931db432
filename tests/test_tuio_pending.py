"""What a TUIO decoder keeps while commands wait for an fseq that never comes is bounded:
a sender's set messages of ever new cursors, or of ever new sources, without an fseq."""

import tracemalloc

from frictex.rendering.input.tuio import MAX_CURSORS, MAX_SOURCES, SILENCE_S, TuioDecoder
from test_tuio import frame, osc_bundle, osc_message

#: datagrams sent without an fseq; what they leave behind grows with them when unbounded
FLOOD = 20_000
#: the most the flood may add to what the decoder holds (bytes): without a bound it adds
#: several hundred bytes a datagram, about 4 MB
MOST_KEPT = 200_000


def kept_after(datagrams) -> tuple[int, TuioDecoder]:
    """Bytes allocated and still held after a decoder that has seen one frame is fed
    ``datagrams``, and the decoder."""
    decoder = TuioDecoder()
    decoder.feed(frame(1, [1], [(1, 0.5, 0.5)]), 0.0)
    tracemalloc.start()
    try:
        before = tracemalloc.get_traced_memory()[0]
        for k, datagram in enumerate(datagrams):
            decoder.feed(datagram, 0.001 * k)
        return tracemalloc.get_traced_memory()[0] - before, decoder
    finally:
        tracemalloc.stop()


def set_message(sid: int) -> bytes:
    return osc_message("/tuio/2Dcur", "set", sid, 0.5, 0.5, 0.0, 0.0, 0.0)


def test_sets_of_new_cursors_without_fseq_keep_at_most_max_cursors():
    kept, decoder = kept_after(set_message(sid) for sid in range(2, FLOOD + 2))
    assert kept < MOST_KEPT
    assert decoder.over_limit == FLOOD - MAX_CURSORS


def test_sets_of_new_sources_without_fseq_keep_at_most_max_sources():
    kept, decoder = kept_after(osc_bundle(osc_message("/tuio/2Dcur", "source", f"s{k}"),
                                          set_message(1)) for k in range(FLOOD))
    assert kept < MOST_KEPT
    assert decoder.over_limit == FLOOD - MAX_SOURCES


def test_commands_that_waited_the_silence_for_an_fseq_are_dropped():
    """Eight sources that never end a frame hold no place from a ninth for ever."""
    decoder = TuioDecoder()
    for k in range(MAX_SOURCES):
        decoder.feed(osc_bundle(osc_message("/tuio/2Dcur", "source", f"s{k}"), set_message(1)),
                     0.0)
    decoder.expire(SILENCE_S)
    down = decoder.feed(frame(1, [3], [(3, 0.25, 0.5)], source="late"), SILENCE_S)
    assert [(s.finger, s.x) for s in down] == [(0, 0.25)] and decoder.over_limit == 0

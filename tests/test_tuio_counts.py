"""Every TUIO drop is counted in ``counters()`` (so in summary.json's input_counts) and
said, with its reason, on the demo's closing line."""

from frictex.app.commands.demo import tuio_line
from frictex.rendering.input.tuio import MAX_CURSORS, TuioListener
from test_tuio import STILL, frame, osc_bundle, osc_message, received, sender


def test_every_drop_is_counted_and_said():
    """Issue: 5 cursors over the limit, 1 late frame and 1 set of a dead session were
    counted by the decoder, but counters() had no late or stray and the closing line
    said '0 refused ..., 0 dropped (queue full), 0 malformed' and nothing else."""
    dead_set = osc_bundle(osc_message("/tuio/2Dcur", "alive", 1, 2, 3),
                          osc_message("/tuio/2Dcur", "set", 99, 0.5, 0.5, 0.0, 0.0, 0.0),
                          osc_message("/tuio/2Dcur", "fseq", 11))
    ids = list(range(MAX_CURSORS + 5))
    with TuioListener(0, width_mm=100.0, height_mm=100.0, clock=STILL) as listener, \
            sender("127.0.0.1") as tablet:
        to = ("127.0.0.1", listener.port)
        tablet.sendto(frame(10, ids, [(i, 0.5, 0.5) for i in ids]), to)
        tablet.sendto(frame(5, [1], [(1, 0.9, 0.9)]), to)  # out of order
        tablet.sendto(dead_set, to)
        received(listener, 3, 0)
        counts = listener.counters()
    assert (counts["over_limit"], counts["late"], counts["stray"]) == (5, 1, 1)
    line = tuio_line(counts)
    assert line.endswith(": 3 datagrams; 1 late frame dropped (out of order), 1 stray set "
                         "ignored (cursor not alive), 5 cursor or source commands ignored "
                         "(over the limit)")


def counts(**nonzero):
    base = {"listen": "0.0.0.0:3333", "sender": "10.0.0.7:5000", "datagrams": 1, "refused": 0,
            "kernel_dropped": 0, "dropped": 0, "stale": 0, "bad_packets": 0, "bad_sets": 0, "malformed": {},
            "late": 0, "stray": 0,
            "over_limit": 0, "unread": 0, "takeovers": 0}
    return base | nonzero


def test_the_line_says_each_nonzero_count_with_its_reason_and_no_zero():
    assert tuio_line(counts()) == ("demo: TUIO on 0.0.0.0:3333 from 10.0.0.7:5000: 1 datagram; "
                                   "nothing dropped")
    line = tuio_line(counts(refused=2, dropped=3, stale=4, bad_packets=1, unread=81, takeovers=1))
    assert line.endswith("1 datagram; 2 datagrams refused (other senders, or before one was "
                         "served), 3 datagrams dropped (queue full), 4 datagrams dropped unread "
                         "(stale, a newer one queued), 1 malformed datagram dropped, "
                         "81 arguments unread (over the limit of one message), "
                         "1 takeover after a silence")
    assert " 0 " not in line


def test_the_line_says_no_sender_was_served_when_none_was():
    """Issue: before any sender was served, the refused were said as 'refused from other
    senders' ('798 refused ... from no sender')."""
    line = tuio_line(counts(sender=None, datagrams=0, refused=798))
    assert line == ("demo: TUIO on 0.0.0.0:3333 from no sender (none was served): 0 datagrams; "
                    "798 datagrams refused (none claimed the input)")
    assert "other senders" not in line

"""Refusing a stranger before any sender is served costs a bounded, small amount of work
per datagram: no full parse of a large bundle, one parse per sender (address and port)
per interval."""

import pytest

import frictex.rendering.input.tuio as tuio
from frictex.rendering.input.tuio import (CLAIM_INTERVAL_S, MAX_CLAIM_BYTES, SenderGate,
                                         is_tuio_frame)
from test_tuio import frame, osc_bundle, osc_message

STRANGER, TABLET = ("10.0.0.9", 5000), ("10.0.0.7", 6000)


@pytest.fixture
def parses(monkeypatch):
    """The datagrams whose 2Dcur commands were parsed, in order."""
    seen = []
    real = tuio._commands

    def counting(packet):
        seen.append(packet)
        return real(packet)

    monkeypatch.setattr(tuio, "_commands", counting)
    return seen


def test_a_large_bundle_is_refused_unparsed(parses):
    """Issue: a 64 kB bundle of 5,400 tiny non-TUIO messages was parsed whole (10 ms)
    to refuse it, in the haptic process, made its 2.5 ms blocks late by up to 17 ms."""
    junk = osc_bundle(*[osc_message("/a")] * 5400)
    disguised = osc_bundle(osc_message("/tuio/2Dcur", "alive", 1), *[osc_message("/a")] * 5400,
                           osc_message("/tuio/2Dcur", "fseq", 1))
    gate = SenderGate()
    for k in range(100):
        assert gate.admit(*STRANGER, k * 1.0, junk) is None
        assert gate.admit(*STRANGER, k * 1.0 + 0.5, disguised) is None
    assert parses == [] and len(disguised) > MAX_CLAIM_BYTES
    assert not is_tuio_frame(disguised)


def test_one_claim_parse_per_sender_per_interval(parses):
    """A stranger's small bundles that start as a 2Dcur frame but are none: one of them
    parsed per CLAIM_INTERVAL_S, however many come; the tablet then claims at once."""
    almost = osc_bundle(osc_message("/tuio/2Dcur", "alive", 1))  # no fseq: not a frame
    gate = SenderGate()
    for k in range(1000):
        assert gate.admit(*STRANGER, k * CLAIM_INTERVAL_S / 100, almost) is None
    assert len(parses) == 10
    assert gate.admit(*TABLET, 10 * CLAIM_INTERVAL_S, frame(1, [3], [(3, 0.5, 0.5)])) == "new"
    assert gate.sender == TABLET


def test_a_full_tuio_frame_still_claims():
    twenty = frame(1, list(range(20)), [(k, 0.5, 0.5) for k in range(20)], source="tablet@host")
    assert len(twenty) <= MAX_CLAIM_BYTES and is_tuio_frame(twenty)
    assert SenderGate().admit(*TABLET, 0.0, twenty) == "new"


def test_one_local_senders_junk_does_not_delay_anothers_claim(parses):
    """Issue: claim parses were rate-limited per address, and on loopback every process
    is 127.0.0.1: a process sending 2Dcur-looking bundles that are no frame every 1 ms
    kept the real tracker (60 Hz, first frame at 3 ms) from being served for 2 s; every
    10 ms, its first claim waited until 0.153 s. Each address and port has its own."""
    almost = osc_bundle(osc_message("/tuio/2Dcur", "alive", 1))  # no fseq: not a frame
    junk = [(k * 0.001, ("127.0.0.1", 9999), almost) for k in range(2000)]
    tracker = [(0.003 + k / 60, ("127.0.0.1", 3334), frame(k + 1, [3], [(3, 0.5, 0.5)]))
               for k in range(120)]
    gate, served = SenderGate(), []
    for t_s, (address, port), data in sorted(junk + tracker, key=lambda event: event[0]):
        if gate.admit(address, port, t_s, data) == "new":
            served.append((t_s, port))
    assert served == [(0.003, 3334)]
    assert len(parses) == 2  # the junk's first datagram, the tracker's first frame


def test_what_the_claim_rate_limit_remembers_is_bounded(monkeypatch):
    """One sender on each of 99 ports: at most _CLAIM_ADDRESSES of them remembered."""
    monkeypatch.setattr(tuio, "_CLAIM_ADDRESSES", 8)
    almost = osc_bundle(osc_message("/tuio/2Dcur", "alive", 1))
    gate = SenderGate()
    for port in range(1, 100):
        gate.admit("127.0.0.1", port, 0.0, almost)
    assert len(gate._claim_t) <= 8

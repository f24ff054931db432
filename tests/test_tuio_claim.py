"""Refusing a stranger before any sender is served costs a bounded, small amount of work
per datagram: no full parse of a large bundle, one parse per address per interval."""

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


def test_one_claim_parse_per_address_per_interval(parses):
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

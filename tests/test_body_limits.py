"""Frames the receivers must refuse by their decoded content (PROTOCOL.md 2, 4.3, 4.5),
in both the C core and the Python device: they are dropped, counted, and change nothing."""

import zlib

import pytest

from frictex.device.link import protocol as p
from frictex.device.link.simdevice import DeviceConfig
from link_checks import CORES, core_class


def raw_frame(version, mtype, seq, payload):
    """A frame around any payload, its CRC right (bypasses the encoder's checks)."""
    body = bytes([version, mtype]) + seq.to_bytes(2, "little") + payload
    return p.cobs_encode(body + zlib.crc32(body).to_bytes(4, "little")) + b"\x00"


def zero_block(start, n):
    """A one-channel Block of ``n`` zero samples: zeros stuff cheaply, so even 2039
    samples (a 4098-byte body) fit in the 4113 stuffed bytes a receiver collects."""
    return start.to_bytes(8, "little") + n.to_bytes(2, "little") + b"\1\0" + bytes(2 * n)


@pytest.mark.parametrize("kind", CORES)
def test_a_body_over_4096_bytes_is_oversize(kind):
    core = core_class(kind)(DeviceConfig())
    core.receive(p.encode(p.Hello(1), 0), 0.0)
    core.receive(raw_frame(1, p.Block.TYPE, 1, zero_block(0, 2039)), 0.0)
    counts = core.decoder.counts
    assert (counts.oversize, counts.frames_ok, core.level) == (1, 1, 0)
    core.receive(raw_frame(1, p.Block.TYPE, 2, zero_block(0, 2038)), 0.0)
    assert (core.decoder.counts.frames_ok, core.level) == (2, 2038)


@pytest.mark.parametrize("kind", CORES)
def test_a_stop_with_drain_above_1_is_a_bad_payload(kind):
    """Drain 7 used to be taken as a drained Stop; it is dropped and changes nothing."""
    core = core_class(kind)(DeviceConfig())
    core.receive(p.encode(p.Hello(1), 0), 0.0)
    assert core.receive(raw_frame(1, p.Stop.TYPE, 1, b"\7"), 0.0) == b""
    assert (core.decoder.counts.bad_payload, core.stopped) == (1, False)

"""A new host's Hello restarts the sequence count (PROTOCOL.md 2): however far the old
host had counted, no frames are counted lost. Both the C core and the Python device."""

import pytest

from frictex.device.link import protocol as p
from frictex.device.link.simdevice import DeviceConfig
from link_checks import CORES, core_class


@pytest.mark.parametrize("kind", CORES)
def test_a_new_hosts_hello_at_seq_0_counts_no_lost_frames(kind):
    """The old host reached seq 40000 (more than half of 65536 past 0); the new one's Hello
    at seq 0 used to count 25535 lost frames."""
    core = core_class(kind)(DeviceConfig())
    core.receive(p.encode(p.Hello(1), 0) + p.encode(p.Heartbeat(0), 40000), 0.0)
    lost_before = core.decoder.counts.lost_frames
    core.receive(p.encode(p.Hello(1), 0) + p.encode(p.Heartbeat(0), 1), 0.001)
    assert core.decoder.counts.lost_frames == lost_before


def test_the_decoder_counts_no_loss_across_a_hello():
    decoder = p.Decoder()
    frames = decoder.feed(p.encode(p.Heartbeat(0), 40000) + p.encode(p.Hello(1), 0))
    assert [f.lost for f in frames] == [0, 0]
    assert decoder.counts.lost_frames == 0

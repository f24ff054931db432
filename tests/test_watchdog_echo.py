"""The device's own frames echoed back (a half-duplex RS-485 adapter, a loopback fault)
must not feed the watchdog (PROTOCOL.md 5.3): both the C core and the Python reference."""

import numpy as np
import pytest

from frictex.device.link import protocol as p
from frictex.device.link.simdevice import DeviceConfig
from device_recorder import Recorder
from link_checks import CORES, core_class

ECHOED_STATUS = p.Status(0, int(p.DeviceState.PLAYING), 0, 2000, buffer_end=2000,
                         played_samples=0, flushed_samples=0, flushes=0)


@pytest.mark.parametrize("kind", CORES)
def test_echoed_device_frames_do_not_keep_the_output_up(kind):
    """One 2000-sample Block, then only echoes of a Status every ms: the watchdog trips
    25 ms (250 ticks) after the Block and the 20 ms ramp ends by tick 450."""
    rec = Recorder()
    core = core_class(kind)(DeviceConfig(limits_um=(1000 * p.AMPLITUDE_STEP_UM,)),
                            log=rec.log, plate_log=rec.plate_log)
    core.receive(p.encode(p.Hello(1), 0), 0.0)
    core.receive(p.encode(p.Block(0, np.full((2000, 1), 1000, dtype=np.uint16)), 1, 2), 0.0)
    for ms in range(1, 300):
        core.advance_to(ms / 1000)
        core.receive(p.encode(ECHOED_STATUS, ms), ms / 1000)
    _, setpoint, _ = rec.ticks()
    last_on = int(np.flatnonzero(setpoint[:, 0] > 0)[-1])
    assert last_on < 450, f"output on until tick {last_on}"
    assert core.counters.watchdog_trips == 1


def _block(start: int) -> p.Block:
    return p.Block(start, np.full((50, 1), 100, dtype=np.uint16))


@pytest.mark.parametrize("kind", CORES)
def test_an_echoed_device_frame_does_not_hide_a_lost_block(kind):
    """A version-4 host sends Block seq 1, its device's Status seq 40 comes back as an
    echo, then Block seq 3: seq 2 is lost, counted once and asked for again by Missing
    (PROTOCOL.md 4.10), as without the echo. Counting the echo's seq made that 38 lost
    and no Missing."""
    core = core_class(kind)(DeviceConfig())
    out = core.receive(p.encode(p.Hello(1), 0, 4), 0.0)
    out += core.receive(p.encode(_block(0), 1, 4), 0.001)
    out += core.receive(p.encode(ECHOED_STATUS, 40, 4), 0.0015)
    out += core.receive(p.encode(_block(100), 3, 4), 0.002)
    out += core.receive(p.encode(p.Heartbeat(5), 4, 4), 0.003)
    replies = [f.message for f in p.Decoder().feed(out)]
    assert [m.seqs for m in replies if isinstance(m, p.Missing)][:1] == [(2,)]
    assert core.decoder.counts.lost_frames == 1
    assert core.decoder.counts.frames_ok == 5  # the echo too (PROTOCOL.md 5.3)


@pytest.mark.parametrize("kind", CORES)
def test_an_echo_far_ahead_adds_no_lost_frames(kind):
    """An echo numbered 5000 between host frames 1 and 2 used to add 4998 lost frames."""
    core = core_class(kind)(DeviceConfig())
    core.receive(p.encode(p.Hello(1), 0), 0.0)
    core.receive(p.encode(p.Heartbeat(1), 1), 0.001)
    core.receive(p.encode(ECHOED_STATUS, 5000), 0.002)
    core.receive(p.encode(p.Heartbeat(2), 2), 0.003)
    assert core.decoder.counts.lost_frames == 0


def test_the_host_side_still_counts_the_device_frames_it_misses():
    """The host's receiver is numbered by the device: a Status gap is a loss there."""
    host = p.Decoder()
    host.feed(p.encode(ECHOED_STATUS, 1, 4) + p.encode(ECHOED_STATUS, 40, 4))
    assert host.counts.lost_frames == 38


def test_the_host_side_does_not_count_its_own_frames_echoed_back():
    """The host's receiver (``on_device=False``) is numbered by the device only: its own
    Heartbeat echoed between two Statuses (seq 7 and 8) adds no lost frames, where a
    decoder counting every frame counts 42 (seq 8 to 49, skipped before the echo's 50)."""
    host = p.Decoder(on_device=False)
    frames = host.feed(p.encode(ECHOED_STATUS, 7, 4) + p.encode(p.Heartbeat(3), 50, 4)
                       + p.encode(ECHOED_STATUS, 8, 4))
    assert [f.lost for f in frames] == [0, 0, 0]
    assert host.counts.lost_frames == 0
    assert host.counts.frames_ok == 3
    every = p.Decoder()
    every.feed(p.encode(ECHOED_STATUS, 7, 4) + p.encode(p.Heartbeat(3), 50, 4)
               + p.encode(ECHOED_STATUS, 8, 4))
    assert every.counts.lost_frames == 42

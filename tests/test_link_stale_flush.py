"""A device reused by a second host trips its watchdog before the new session's first
block: the Flushed it sends names the play index its last session ended at, and the host
must not take it for where the device plays (PROTOCOL.md 5.1, 6.1).

The host session (sans I/O) and the device core (the Python reference and the C firmware)
are driven by hand on a clock of their own, so the starvation that made this happen under
load (the host's thread silent past the watchdog, then the device's thread slow to read
what the host wrote) happens here whatever the scheduler does.
"""

from __future__ import annotations

import io

import numpy as np
import pytest

from frictex.device.link import protocol as p
from frictex.device.link.session import HostSession
from frictex.device.link.simdevice import DeviceConfig
from link_checks import CORES, core_class

RATE = 10_000.0
#: the host's turn on the test's clock (s)
TURN_S = 0.001
BLOCK = 50


def _queue(host: HostSession, first: int, last: int) -> None:
    """Queue blocks of samples ``first .. last - 1`` (1 um each), as ``CommandSink.send``."""
    for start in range(first, last, BLOCK):
        counts, _ = p.amplitude_to_wire(np.full((BLOCK, 1), 1.0), host.limits_um)
        with host.cond:
            host.ledger.command(BLOCK)
            host.queue.append((start, counts, None))


def _lockstep(host: HostSession, core, t: float, until) -> float:
    """Host and device take turns, the device answering at once, from ``t`` until
    ``until()``; returns the time."""
    while not until():
        t += TURN_S
        reply = core.receive(host.poll(t), t)
        host.data_received(reply + core.advance_to(t), t)
        assert t < 60.0, "the session did not get there in 60 s"
    return t


def _session(core, t: float) -> tuple[HostSession, float]:
    """A new host's session on ``core``, handshaken and reported on; returns it and the time."""
    host = HostSession(1, RATE, phases=False, paced=True, label="test", stderr=io.StringIO())
    host.connection_made(t)
    return host, _lockstep(host, core, t, lambda: host.ledger.reporting)


@pytest.mark.parametrize("kind", CORES)
def test_a_flushed_before_the_first_block_does_not_place_the_device_at_its_last_session(kind):
    """The third host of a run of replays overflowed 421 samples: its thread starved past
    the device's 25 ms watchdog, the device's Flushed said it would play 5000 next (where
    the previous host's session ended), and the host, taking the buffer for empty at 5000,
    sent everything up to 5000 while the device, slow to read, took the first block at 0
    as its origin. A device plays nothing it was not sent: the host now takes it as empty
    where the host is, and sends no more than the target until a Status places it."""
    core = core_class(kind)(DeviceConfig())
    first, t = _session(core, 0.0)
    _queue(first, 0, 5000)
    t = _lockstep(first, core, t, lambda: not first.queue)
    first.close_requested = True
    t = _lockstep(first, core, t, lambda: first.done)
    assert core.play_index == 5000

    second, t = _session(core, t)
    overflow0 = core.counters.overflow_samples
    t += 0.030  # the host's thread starved: the device's watchdog trips
    said = core.advance_to(t)
    flushed = [f.message for f in p.Decoder(on_device=False).feed(said)]
    assert [type(m) for m in flushed] == [p.Flushed] and flushed[0].play_index == 5000
    second.data_received(said, t)
    _queue(second, 0, 5000)
    wire = bytearray()
    for _ in range(5):  # the host turns while the device's thread does not read
        t += TURN_S
        wire += second.poll(t)
    assert second.sent_end <= second.target
    second.data_received(core.receive(bytes(wire), t) + core.advance_to(t), t)
    t = _lockstep(second, core, t, lambda: not second.queue)
    second.close_requested = True
    _lockstep(second, core, t, lambda: second.done)
    assert core.counters.overflow_samples == overflow0
    breakdown = second.ledger.breakdown()
    assert breakdown["overflow"] == 0 and breakdown["lost"] == 0, breakdown
    assert second.ledger.played == 5000

"""A Status that arrives out of order is ignored, counted and said once (PROTOCOL.md 6.1).

The byte stream keeps order, so only a faulty device sends Statuses out of order. One that
held every 3 Statuses and sent them shuffled (its frames' sequence numbers still rising)
made a replay of 20,050 samples report 1,004,588 played and none unplayed: a Status whose
counters were older than the last one read as counters that wrapped at 2**32, so their
whole count was added again, and ``--max-unplayed`` could not see unplayed samples.

The device is the Python reference core, called in-process by a host session on a clock
the test advances (no thread, no wall clock). Between them, the device's Statuses are held
in threes and sent back newest first: whole (their echoes out of order too), or with only
their counters out of order (each keeps the echo of its place: read as a device that
reset its counters, but never as more played than was sent).
"""

import dataclasses
import io

import numpy as np
import pytest

from frictex.device.link import protocol as p
from frictex.device.link.ledger import Ledger
from frictex.device.link.session import HostSession
from frictex.device.link.simdevice import DeviceConfig, DeviceCore

RATE = 10_000.0
STEP_S = 0.001
BLOCK = 50
SAMPLES = 2000


class ShufflingWire:
    """A paced host session and a device core joined by a byte stream on the test's clock;
    ``shuffle``: None (in order), ``"whole"`` or ``"counters"`` (see the module docstring)."""

    def __init__(self, shuffle: str | None):
        self.err = io.StringIO()
        self.session = HostSession(1, RATE, phases=False, paced=True, label="test",
                                   stderr=self.err)
        self.core = DeviceCore(DeviceConfig(rate_hz=RATE))
        self.shuffle = shuffle
        self.decoder = p.Decoder()
        self.held: list[p.Status] = []
        self.seq = 0
        self.t = 0.0
        self.session.connection_made(self.t)

    def step(self) -> None:
        """One turn of 1 ms: the host's bytes to the device, the device's back."""
        self.t += STEP_S
        to_device = self.session.poll(self.t)
        back = self.core.receive(to_device, self.t) if to_device else b""
        self.session.data_received(self._pass(back + self.core.advance_to(self.t)), self.t)

    def _pass(self, data: bytes) -> bytes:
        """The device's frames as they reach the host, sequence numbers rising."""
        out = bytearray()
        for frame in self.decoder.feed(data):
            if self.shuffle is None or not isinstance(frame.message, p.Status):
                out += self._encode(frame.message, frame.version)
                continue
            self.held.append(frame.message)
            if len(self.held) == 3:
                shuffled = self.held[::-1]
                if self.shuffle == "counters":
                    shuffled = [dataclasses.replace(st, echo=held.echo)
                                for st, held in zip(shuffled, self.held)]
                for st in shuffled:
                    out += self._encode(st, frame.version)
                self.held = []
        return bytes(out)

    def _encode(self, msg, version: int) -> bytes:
        self.seq = (self.seq + 1) & 0xFFFF
        return p.encode(msg, self.seq, version)

    def stream_and_close(self, wrap: bool) -> HostSession:
        """Stream :data:`SAMPLES` samples paced, then close; ``wrap``: the device's
        since-Hello ``played_samples`` and its ``frames_ok`` start just short of 2**32,
        so both wrap during the stream."""
        s = self.session
        while s.phase != "session":
            self.step()
        if wrap:  # before the session's first Status, the counters' baseline
            self.core.session.played = 2**32 - 700
            self.core.decoder.counts.frames_ok = 2**32 - 30
        with s.cond:
            for start in range(0, SAMPLES, BLOCK):
                s.ledger.command(BLOCK)
                s.queue.append((start, np.full((BLOCK, 1), 100, np.uint16), None))
        for _ in range(2000):
            if not s.queue:
                break
            self.step()
        assert not s.queue, "the stream went out"
        s.close_requested = True
        for _ in range(2000):
            if s.done:
                break
            self.step()
        assert s.done and s.stop_confirmed, "the close ended with the device silent"
        return s


@pytest.mark.parametrize("wrap", [False, True])
def test_statuses_out_of_order_are_ignored_and_every_sample_is_accounted_for(wrap):
    wire = ShufflingWire("whole")
    s = wire.stream_and_close(wrap)
    assert wire.core.counters.played_samples == SAMPLES  # what the device really played
    assert s.ledger.played == SAMPLES and s.ledger.unplayed == 0
    assert s.ledger.commanded == SAMPLES
    assert s.counts["stale_statuses"] > 0
    said = [line for line in wire.err.getvalue().splitlines() if "out of order" in line]
    assert len(said) == 1, wire.err.getvalue()
    assert "stale_statuses" in said[0]


@pytest.mark.parametrize("wrap", [False, True])
def test_counters_that_go_back_under_echoes_in_order_never_count_more_than_was_sent(wrap):
    """Counters that go back under an echo in order read as a device that reset them
    (PROTOCOL.md 6.3), as one that restarted on a port that stayed open: not ignored. A
    device that shuffles them so could make the ledger count 28,410 of 2,000 samples
    played; it counts at most what was sent."""
    wire = ShufflingWire("counters")
    s = wire.stream_and_close(wrap)
    assert s.ledger.commanded == SAMPLES and s.ledger.played <= SAMPLES
    assert s.counts["stale_statuses"] == 0


def test_counters_that_wrap_at_2_32_in_order_are_not_out_of_order():
    wire = ShufflingWire(None)
    s = wire.stream_and_close(wrap=True)
    assert s.ledger.played == SAMPLES and s.ledger.unplayed == 0
    assert s.counts["stale_statuses"] == 0 and "out of order" not in wire.err.getvalue()


def test_the_ledger_never_counts_more_played_than_was_sent_before_the_heartbeat():
    led = Ledger()
    led.command(100)
    led.start_session()
    led.status(p.Status(1, p.DeviceState.BUFFERING, 0, 0, buffer_end=0, played_samples=0,
                        flushed_samples=0, flushes=0), mark=0)
    led.sent(100)
    led.status(p.Status(2, p.DeviceState.PLAYING, 500, 0, buffer_end=500,
                        played_samples=500, flushed_samples=0, flushes=0), mark=100)
    assert led.played == 100 and led.unplayed == 0


def test_statuses_out_of_order_are_a_warning_of_the_run():
    from frictex.app.engine.device_changes import device_warnings
    said = device_warnings({"stale_statuses": 3, "commanded_samples": 100}, 1.0)
    assert said == ["the device sent 3 Statuses out of order (answering a heartbeat older "
                    "than one already answered), which were ignored: a faulty device or "
                    "firmware (PROTOCOL.md 6.1)"]
    assert device_warnings({"stale_statuses": 0, "commanded_samples": 100}, 1.0) == []

"""A close is bounded by what the host sent, not by what the device declares, and says
when the device never confirmed its Stop (PROTOCOL.md 4.5, 6.2).

A device that declared a buffer of 2**32 - 1 samples and, after the Stop, answered every
Heartbeat DRAINING with its play index one further (on and on) held the host's close for days: the
close waited twice that buffer's drain (4.3e5 s at 10 kHz), each step forward pushing it
on. A close that ended on its bound with the device still DRAINING said nothing and
wrote ``device_state: draining``, no more.

The session is driven here by hand, on a clock of its own (``HostSession`` is sans I/O),
against a fake device that plays at its rate until the Stop and creeps after it.
"""

from __future__ import annotations

import io
import threading
import time

import numpy as np

from frictex.device.link import protocol as p
from frictex.device.link.host import CommandSink
from frictex.device.link.session import CLOSE_STRETCH, STOP_MARGIN_S, TARGET_S, HostSession

RATE = 10_000.0
WATCHDOG_MS, RAMP_MS = 25, 20
#: the host's turn on the fake clock (s)
TURN_S = 0.001


class CreepingDevice:
    """A device that plays at its rate until a Stop, then answers every Heartbeat
    DRAINING with its play index one further, on and on, never SILENT (``buffer``: the samples its
    Info declares)."""

    def __init__(self, buffer: int):
        self.buffer = buffer
        self.decoder = p.Decoder(on_device=True)
        self.seq = 0
        self.end = 0           # one past the last sample received
        self.started = None    # when the first block came (s)
        self.stopped_at = None  # the play index at the Stop
        self.play = 0

    def _frame(self, msg) -> bytes:
        self.seq += 1
        return p.encode(msg, self.seq)

    def answer(self, data: bytes, now: float) -> bytes:
        """The device's frames in answer to the host's ``data`` at time ``now`` (s)."""
        out = b""
        for frame in self.decoder.feed(data):
            msg = frame.message
            if isinstance(msg, p.Hello):
                out += self._frame(p.Info(1, RATE, (4.0,), self.buffer, WATCHDOG_MS, RAMP_MS))
            elif isinstance(msg, p.Block):
                self.end = max(self.end, msg.start_index + len(msg.amplitudes))
                self.started = now if self.started is None else self.started
            elif isinstance(msg, p.Stop):
                self.stopped_at = self.play
            elif isinstance(msg, p.Heartbeat):
                out += self._frame(self._status(msg.token, now))
        return out

    def _status(self, token: int, now: float) -> p.Status:
        if self.stopped_at is not None:  # on and on, past what it was sent
            self.play += 1
            state = p.DeviceState.DRAINING
        else:
            clock = 0 if self.started is None else int((now - self.started) * RATE)
            self.play = min(clock, self.end)
            state = p.DeviceState.PLAYING if self.end > self.play else p.DeviceState.IDLE
        end = max(self.end, self.play)
        return p.Status(token, state, self.play, end - self.play, buffer_end=end,
                        played_samples=min(self.play, self.end), flushed_samples=0, flushes=0)


def _stream_then_close(device: CreepingDevice, samples: int, err: io.StringIO,
                       give_up_s: float = 60.0) -> tuple[HostSession, float]:
    """A paced session to ``device`` on the fake clock: ``samples`` sent in blocks of 50,
    then closed. Returns the session and how long its close took on that clock (s), or
    ``give_up_s`` if it had not ended by then."""
    s = HostSession(1, RATE, phases=False, paced=True, label="creeper", stderr=err)
    now = 0.0
    s.connection_made(now)
    for start in range(0, samples, 50):
        counts, _ = p.amplitude_to_wire(np.full((50, 1), 2.0), np.array([4.0]))
        s.ledger.command(50)
        s.queue.append((start, counts, None))

    def turn():
        s.data_received(device.answer(s.poll(now), now), now)
    while (s.queue or s.snapshot is None) and now < 10.0:
        turn()
        now += TURN_S
    assert not s.queue, "the stream did not go out"
    s.close_requested = True
    began = now
    while not s.done and now - began < give_up_s:
        turn()
        now += TURN_S
    return s, now - began


def test_a_huge_declared_buffer_does_not_lengthen_the_close():
    """Declared 2**32 - 1 samples, creeping after the Stop: the close ends within twice
    the drain of the host's target level, the ramp and the margin, as with 4096."""
    bound_s = CLOSE_STRETCH * (TARGET_S + RAMP_MS * 1e-3 + STOP_MARGIN_S) + 2 * TURN_S
    for buffer in (2**32 - 1, 4096):
        device = CreepingDevice(buffer)
        s, took_s = _stream_then_close(device, 2000, io.StringIO())
        assert s.done, f"buffer {buffer}: the close had not ended after {took_s:.0f} s"
        assert took_s <= bound_s, f"buffer {buffer}: the close took {took_s:.3f} s"
        assert device.stopped_at is not None  # the Stop went out, and the close waited on it
        assert s.close_limit_s() <= bound_s


def test_a_close_that_ends_on_its_bound_says_the_watchdog_stops_the_plate():
    """The device never reports SILENT: one warning naming its last state and its
    watchdog, and ``stop_confirmed`` false."""
    err = io.StringIO()
    s, _ = _stream_then_close(CreepingDevice(4096), 2000, err)
    assert s.done and s.stop_confirmed is False
    warned = [line for line in err.getvalue().splitlines() if "confirm" in line]
    assert warned == ["frictex: warning: creeper: the device did not confirm it stopped "
                      f"(last state draining); relying on its watchdog ({WATCHDOG_MS} ms)"]


class FakePort:
    """A port whose far end is a :class:`CreepingDevice` answering on the wall clock."""

    def __init__(self, device: CreepingDevice):
        self.device = device
        self.pending = b""
        self.lock = threading.Lock()

    def write(self, data: bytes) -> None:
        with self.lock:
            self.pending += self.device.answer(data, time.monotonic())

    def read(self, size: int = 1) -> bytes:
        with self.lock:
            data, self.pending = self.pending[:size], self.pending[size:]
        if not data:
            time.sleep(TURN_S)  # a real port waits its timeout for the first byte
        return data

    @property
    def in_waiting(self) -> int:
        return len(self.pending)

    def close(self) -> None:
        pass


def test_the_unconfirmed_stop_is_in_the_links_status():
    """What summary.json's ``device`` section takes: ``stop_confirmed`` false after a
    close on its bound, null while the link is open. Nothing is sent, so however the
    host's thread runs the device is still DRAINING when the close gives up."""
    err = io.StringIO()
    sink = CommandSink(lambda: FakePort(CreepingDevice(4096)), 1, RATE, paced=True,
                       stderr=err)
    assert sink.status()["stop_confirmed"] is None
    sink.close()
    status = sink.status()
    assert status["stop_confirmed"] is False and status["device_state"] == "draining"
    assert "relying on its watchdog (25 ms)" in err.getvalue()

"""A device that closes the link during the first handshake is said to, with the port's
last error, and one that closes it every time fails the handshake after
``session.HANDSHAKE_CLOSES`` closes in a row, not after the whole wait (PROTOCOL.md 6.2).

A TCP listener that accepted and closed at once was reported after 10.5 s as "no answer
to the handshake within 10.1 s (0 Hellos)", though it had closed the link 33 times. The
device here is an in-process port whose reads fail as a closed socket's do; the reopen
period (0.25 s) sets the pace, so 5 closes take about 1.25 s.
"""

import io
import time

import pytest
import serial

from frictex.device.link import protocol as p
from frictex.device.link.host import CommandSink
from frictex.device.link.protocol import LinkError
from frictex.device.link.session import HANDSHAKE_CLOSES

RATE = 10_000.0
INFO = p.encode(p.Info(1, RATE, (4.0,), 4096, 25, 20, name="half"), 0, 1)


class ClosingPort:
    """A port that hands over ``first`` (bytes) and then fails every read, as a socket
    the device closed does."""

    def __init__(self, first: bytes = b""):
        self.pending = first

    @property
    def in_waiting(self) -> int:
        return len(self.pending)

    def read(self, n: int = 1) -> bytes:
        if not self.pending:
            raise ConnectionResetError(104, "Connection reset by peer")
        data, self.pending = self.pending[:n], self.pending[n:]
        return data

    def write(self, data: bytes) -> int:
        return len(data)

    def close(self) -> None:
        pass


def _open_failing(opener, handshake_s: float) -> tuple[str, float]:
    """The handshake's error on the ports ``opener`` opens, and how long it took (s)."""
    t0 = time.monotonic()
    with pytest.raises(LinkError) as failed:
        CommandSink(opener, 1, RATE, paced=True, stderr=io.StringIO(),
                    label="socket://127.0.0.1:9", handshake_s=handshake_s)
    return str(failed.value), time.monotonic() - t0


@pytest.mark.parametrize("first", [b"", INFO[:len(INFO) // 2]], ids=["closes", "half-info"])
def test_a_device_that_closes_the_link_every_time_fails_the_handshake_early(first):
    said, took_s = _open_failing(lambda: ClosingPort(first), handshake_s=60.0)
    assert said.startswith(f"socket://127.0.0.1:9: the device closed the link "
                           f"{HANDSHAKE_CLOSES} times during the handshake, in ")
    assert said.endswith("(last: ConnectionResetError: [Errno 104] Connection reset by "
                         "peer); is it a frictex device?")
    assert "\n" not in said
    assert took_s < 30.0  # about 1.25 s; the handshake's own bound here is 60 s


def test_a_device_that_sends_frames_between_closes_gets_the_whole_wait():
    """A valid frame between closes is a device that answers: only the wait's own bound
    ends the handshake, and the closes are still said."""
    report = p.encode(p.ErrorReport(0, 0), 0, 1)
    said, took_s = _open_failing(lambda: ClosingPort(report), handshake_s=2.0)
    assert took_s >= 2.0
    closes = int(said.split("closed the link ")[1].split(" times")[0])
    assert closes > HANDSHAKE_CLOSES, said


def test_a_silent_device_still_gets_the_whole_wait_and_is_said_silent():
    said, took_s = _open_failing(lambda: serial.serial_for_url("loop://", timeout=0.005),
                                 handshake_s=1.0)
    assert took_s >= 1.0
    assert "no answer to the handshake within" in said and "Hellos)" in said


def test_a_device_that_closed_the_link_once_is_said_to_have_closed_it_once():
    """A port that fails once, then stays silent: 'closed the link once' (it said '1 times')."""
    ports = iter([ClosingPort()])
    said, _ = _open_failing(lambda: next(ports, None) or serial.serial_for_url("loop://", timeout=0.005),
                            handshake_s=1.0)
    assert "the device closed the link once during the handshake, in " in said, said


class AnsweringPort(ClosingPort):
    """A port that hands over the device's Info, then stays quiet."""

    def read(self, n: int = 1) -> bytes:
        data, self.pending = self.pending[:n], self.pending[n:]
        return data


def test_a_link_lost_during_the_first_handshake_and_then_answered_is_counted_and_said():
    """An unplug during the first handshake left only last_error: no count, no warning
    (disconnects counts sessions lost, and there was none yet)."""
    ports = iter([ClosingPort(), AnsweringPort(INFO)])
    said = io.StringIO()
    sink = CommandSink(lambda: next(ports), 1, RATE, paced=True, stderr=said,
                       label="socket://127.0.0.1:9", handshake_s=30.0)
    try:
        status = sink.status()
        assert (status["handshake_closes"], status["disconnects"], status["reconnects"]) == (1, 0, 0)
        assert ("frictex: warning: socket://127.0.0.1:9: the link closed 1 time(s) during the "
                "first handshake (last: ConnectionResetError: [Errno 104] Connection reset by "
                "peer) before the device answered\n") in said.getvalue()
    finally:
        sink.abort()

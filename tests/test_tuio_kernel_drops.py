"""Datagrams the kernel drops (the socket's receive buffer full) are counted and said."""

import fcntl
import socket
import sys
import termios
import threading
import time

import pytest

from frictex.app.commands.demo import tuio_line
from frictex.rendering.input.tuio import TuioListener
from test_tuio import frame, sender

SENT = 300  # frames sent while the receiving thread is held: far more than a tiny buffer holds


def until(condition, what: str) -> None:
    """Wait (bounded) until ``condition()`` holds."""
    deadline = time.monotonic() + 60.0
    while not condition() and time.monotonic() < deadline:
        time.sleep(0.005)
    assert condition(), what


def unread_bytes(sock: socket.socket) -> int:
    """Size of the next datagram waiting in ``sock`` (0: none)."""
    return int.from_bytes(fcntl.ioctl(sock.fileno(), termios.FIONREAD, bytes(4)), sys.byteorder)


@pytest.mark.skipif(not sys.platform.startswith("linux"),
                    reason="SO_RXQ_OVFL, the kernel's count of a socket's dropped datagrams, "
                           "is Linux's only")
def test_datagrams_the_kernel_dropped_are_counted_and_said():
    """Issue: a flood of 200,000 frames raised the kernel's RcvbufErrors by 52,247, and the
    closing line said only '147753 datagrams; 146223 datagrams dropped (queue full)'.
    Here the receiving thread is held (its clock blocks) while frames fill a tiny receive
    buffer; once the thread has read everything, a last frame carries the final count."""
    release = threading.Event()

    def held_clock() -> float:
        release.wait(60.0)
        return 0.0

    with TuioListener(0, width_mm=100.0, height_mm=100.0, clock=held_clock,
                      warn=lambda line: None) as listener, sender("127.0.0.1") as tablet:
        try:
            listener._sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1)  # the least
            to = ("127.0.0.1", listener.port)
            for k in range(1, SENT + 1):
                tablet.sendto(frame(k, [1], [(1, 0.5, 0.5)]), to)
        finally:
            release.set()
        until(lambda: unread_bytes(listener._sock) == 0, "the buffer was never read empty")
        tablet.sendto(frame(SENT + 1, [1], [(1, 0.5, 0.5)]), to)  # room for it now
        sent = SENT + 1
        until(lambda: listener.datagrams + listener.refused + (listener.kernel_dropped or 0)
              == sent, f"counts {listener.counters()} do not add up to {sent} sent")
        counts = listener.counters()
    assert counts["kernel_dropped"] > 0
    assert counts["kernel_dropped"] == sent - counts["datagrams"] - counts["refused"]
    assert (f"{counts['kernel_dropped']} datagrams dropped by the kernel (socket receive "
            "buffer full)") in tuio_line(counts)


def test_nothing_is_said_where_the_system_does_not_count_kernel_drops(monkeypatch):
    from frictex.rendering.input import tuio
    monkeypatch.setattr(tuio, "_SO_RXQ_OVFL", None)
    with TuioListener(0, width_mm=100.0, height_mm=100.0) as listener:
        counts = listener.counters()
    assert counts["kernel_dropped"] is None
    assert tuio_line(counts).endswith(": 0 datagrams; nothing dropped")

"""Opening a link by URL, pyserial's way, and reading what has arrived.

``open_port(url)`` takes what pyserial's ``serial_for_url`` takes (a device path such as
``/dev/ttyACM0``, ``/dev/pts/N`` or ``COM3``, ``socket://HOST:PORT``, ``loop://``,
``spy://...``) and returns a pyserial port whose reads wait at most
:data:`READ_WAIT_S`. ``socket://`` gets :class:`TcpPort` (TCP_NODELAY, a true
``in_waiting``). ``sim://`` is not a port of pyserial's: the simulated device opens it
(``device.link.simport``), in this process.

A device path is opened exclusively (pyserial's ``exclusive``: an advisory ``flock`` on
POSIX): a second host, another frictex or a stale one reconnecting to a path whose
number a new pseudo-terminal took, is refused while one holds the port, rather than both
streaming frames into one plate.
"""

from __future__ import annotations

import errno
import socket
import struct

import serial
from serial.urlhandler import protocol_socket

try:
    import fcntl
    import termios
except ImportError:  # Windows: in_waiting stays pyserial's (0 or 1)
    fcntl = termios = None

from frictex.device.link.protocol import LinkError

#: longest a read waits for its first byte (s): the port thread's turn
READ_WAIT_S = 0.002
#: what a UART link is opened at (baud; USB CDC devices ignore it)
BAUD = 921_600
#: longest a write may block (s)
WRITE_WAIT_S = 0.5


class TcpPort(protocol_socket.Serial):
    """pyserial's ``socket://`` port with TCP_NODELAY (without it small frames wait for
    the peer's delayed ACK, tens of ms, longer than the device's watchdog), and an
    ``in_waiting`` that counts the bytes waiting (pyserial's says 0 or 1, so draining
    ``in_waiting`` bytes would read one byte per call and fall behind the device)."""

    def open(self):
        super().open()
        self._socket.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)

    @property
    def in_waiting(self) -> int:
        if fcntl is None or not self.is_open:
            return super().in_waiting
        return struct.unpack("i", fcntl.ioctl(self._socket, termios.FIONREAD, b"\0" * 4))[0]


def open_port(url: str):
    """Open a pyserial port or URL (see the module docstring); raises :class:`LinkError`
    naming it when it cannot be opened."""
    options = {"baudrate": BAUD, "timeout": READ_WAIT_S, "write_timeout": WRITE_WAIT_S}
    try:
        if url.startswith("socket://"):
            port = TcpPort(None, **options)
            port.port = url
            port.open()
        elif "://" in url:
            port = serial.serial_for_url(url, **options)
        else:
            port = serial.serial_for_url(url, exclusive=True, **options)
    except (serial.SerialException, ValueError, OSError) as exc:
        if getattr(exc, "errno", None) in (errno.EAGAIN, errno.EWOULDBLOCK):  # the lock
            raise LinkError(f"cannot open device port {url!r}: another program holds it "
                            "(a port is opened for one host at a time)") from None
        raise LinkError(f"cannot open device port {url!r}: {exc}") from None
    return port


def read_available(port) -> bytes:
    """What has arrived on ``port``, waiting at most its read timeout for the first byte."""
    data = port.read(1)
    waiting = port.in_waiting if data else 0
    return data + port.read(waiting) if waiting else data

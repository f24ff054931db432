"""Opening a link by URL, pyserial's way, and reading what has arrived.

``open_port(url)`` takes what pyserial's ``serial_for_url`` takes (a device path such as
``/dev/ttyACM0``, ``/dev/pts/N`` or ``COM3``, ``socket://HOST:PORT``, ``loop://``,
``spy://...``) and returns a pyserial port whose reads wait at most
:data:`READ_WAIT_S`. ``socket://`` gets :class:`TcpPort` (TCP_NODELAY, a true
``in_waiting``). ``sim://`` is not a port of pyserial's: the simulated device opens it
(``device.link.simport``), in this process.

A URL is checked before pyserial sees it (:func:`check_url`): its scheme is one of
:data:`URL_SCHEMES`, a ``socket://`` or ``rfc2217://`` URL names a host and a port 1 to
65535, and every ``?option`` is one that scheme takes, with a value it understands; any
other URL is an :class:`~device.errors.InputError` of one line saying what was expected
(pyserial's own messages for these are Python internals, and ``loop://?logging=x`` was
a traceback).

A device path is opened exclusively (pyserial's ``exclusive``: an advisory ``flock`` on
POSIX): a second host, another frictex or a stale one reconnecting to a path whose
number a new pseudo-terminal took, is refused while one holds the port, rather than both
streaming frames into one plate.
"""

from __future__ import annotations

import errno
import math
import os
import stat
import re
import socket
import struct
from urllib.parse import unquote_plus, urlsplit

import serial
from serial.urlhandler import protocol_socket

try:
    import fcntl
    import termios
except ImportError:  # Windows: in_waiting stays pyserial's (0 or 1)
    fcntl = termios = None

from frictex.device.errors import InputError
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


_LEVELS = ("debug", "info", "warning", "error")


def _level(text: str) -> bool:
    return text in _LEVELS


def _flag(text: str) -> bool:
    return text == ""  # pyserial sets the flag whatever follows '=': 'raw=0' is raw too


def _seconds(text: str) -> bool:
    try:
        return 0 < float(text) and math.isfinite(float(text))
    except ValueError:
        return False


#: option -> (accepts its value, what the value must be)
_LOGGING = {"logging": (_level, "|".join(_LEVELS))}
#: the pyserial URL schemes frictex opens: scheme -> (form, whether it names HOST:PORT,
#: its options)
URL_SCHEMES = {
    "socket": ("socket://HOST:PORT[?logging=LEVEL]", True, _LOGGING),
    "rfc2217": ("rfc2217://HOST:PORT[?logging=LEVEL][&ign_set_control][&poll_modem]"
                "[&timeout=S]", True,
                {**_LOGGING, "ign_set_control": (_flag, "no value"),
                 "poll_modem": (_flag, "no value"),
                 "timeout": (_seconds, "a positive number of seconds")}),
    "loop": ("loop://[?logging=LEVEL]", False, _LOGGING),
    "spy": ("spy://PATH[?file=FILE][&color][&raw][&all] (PATH a device path)", False,
            {"file": (bool, "a file name"), "color": (_flag, "no value"),
             "raw": (_flag, "no value"), "all": (_flag, "no value")}),
}
_HOST = re.compile(r"[\w.%:-]+")


def _url_problem(url: str) -> str | None:
    """What is wrong with ``url`` (``SCHEME://...``) for :func:`check_url`, or None."""
    try:
        parts = urlsplit(url)
    except ValueError:  # the only one urlsplit raises: an unbalanced '[' or ']'
        return "unbalanced [ ] around the host (an IPv6 address is written [ADDRESS])"
    try:
        port = parts.port
    except ValueError:  # not a whole number, or out of 0..65535
        port = parts.netloc.rpartition(":")[2]
    form, host_port, options = URL_SCHEMES[parts.scheme]
    target = parts.netloc + parts.path
    if parts.fragment:
        return f"unexpected '#{parts.fragment}'"
    if host_port:
        if "@" in parts.netloc or parts.path not in ("", "/"):
            return "expected HOST:PORT and nothing else before '?'"
        if not parts.hostname:
            return "no host"
        if not _HOST.fullmatch(parts.hostname):
            return f"host {parts.hostname!r}: expected a host name or address"
        if port is None:
            return "no port"
        if not isinstance(port, int) or not 1 <= port <= 65535:
            return f"port {port!r}: expected a whole number 1 to 65535"
    elif parts.scheme == "loop" and target:
        return f"unexpected {target!r} after loop://"
    elif parts.scheme == "spy" and (not target or "://" in target):
        return f"expected a device path to watch (got {target!r}; spy:// wraps a port path, "\
               "not a URL)"
    seen = set()
    for field in filter(None, parts.query.split("&")):  # pyserial skips empty ones too
        name, _, value = (unquote_plus(x) for x in field.partition("="))
        if name not in options:
            known = ", ".join(options)
            return f"unknown option {name!r} (known: {known})"
        if name in seen:
            return f"option {name!r} given twice"
        seen.add(name)
        accepts, expected = options[name]
        if not accepts(value):
            return f"option {name}={value!r}: expected {expected}"
    return None


def check_url(url: str) -> None:
    """Refuse a malformed pyserial URL before it is opened (see the module docstring):
    :class:`~device.errors.InputError` of one line naming the URL and the form expected.
    A device path (no ``://``) passes unchecked; opening it tells."""
    scheme, sep, _ = url.partition("://")
    if not sep:
        return
    if scheme not in URL_SCHEMES:
        known = ", ".join(f"{name}://" for name in URL_SCHEMES)
        raise InputError(f"device URL {url!r}: unknown scheme {scheme!r}; expected one of "
                         f"{known} or a port path")
    problem = _url_problem(url)
    if problem is not None:
        raise InputError(f"device URL {url!r}: {problem} (form: {URL_SCHEMES[scheme][0]})")


def open_port(url: str):
    """Open a pyserial port or URL (see the module docstring); raises
    :class:`~device.errors.InputError` for a malformed URL (:func:`check_url`) and
    :class:`LinkError` naming it when it cannot be opened."""
    check_url(url)
    options = {"baudrate": BAUD, "timeout": READ_WAIT_S, "write_timeout": WRITE_WAIT_S}
    if "://" not in url:
        _check_character_device(url)
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
        raise LinkError(f"cannot open device port {url!r}: {_reason(exc)}") from None
    return port


def _check_character_device(path: str) -> None:
    """:class:`LinkError` where ``path`` names a file that is no character device (a
    serial port, a pty): pyserial would say 'Could not configure port: (25, ...)'. A
    name that is no file (a Windows COM port) is left to pyserial."""
    try:
        mode = os.stat(path).st_mode
    except (OSError, ValueError):
        return
    if not stat.S_ISCHR(mode):
        kind = "folder" if stat.S_ISDIR(mode) else "regular file" if stat.S_ISREG(mode) else "file"
        raise LinkError(f"cannot open device port {path!r}: not a serial port (a {kind}); "
                        "expected a serial device such as /dev/ttyACM0")


def _reason(exc: BaseException) -> str:
    """Why a port did not open, said once: the text of the system error under pyserial's
    (which repeats it: '[Errno 2] could not open port X: [Errno 2] No such file or
    directory: X'), else pyserial's own."""
    cause = exc
    while cause is not None:
        if isinstance(getattr(cause, "errno", None), int):
            return os.strerror(cause.errno)
        cause = cause.__cause__ or cause.__context__
    return str(exc)


def read_available(port) -> bytes:
    """What has arrived on ``port``, waiting at most its read timeout for the first byte."""
    data = port.read(1)
    waiting = port.in_waiting if data else 0
    return data + port.read(waiting) if waiting else data

"""The thread that owns a link's port and only moves bytes (pyserial's ``ReaderThread``).

It reads what has arrived and hands it to its protocol, writes what the protocol asks
for, and when the port fails tells the protocol and reopens it every
:data:`RECONNECT_PERIOD_S` until it returns. The protocol
(``device.link.session.HostSession``) decides everything else: what the bytes mean,
what to send and when the link is done.
"""

from __future__ import annotations

import threading
import time

import serial

from frictex.device.link.port import read_available

#: how often a lost port is reopened (s)
RECONNECT_PERIOD_S = 0.25
#: the thread's wait between tries while it has no port (s)
_IDLE_S = 0.005


class PortThread(threading.Thread):
    """Moves bytes between ``port`` (already open; reopened through ``opener``) and
    ``protocol``, which has ``connection_made(now)``, ``data_received(data, now)``,
    ``poll(now) -> bytes``, ``connection_lost(exc)``, ``finish_without_port()``,
    ``close_requested`` and ``done``. ``on_crash(exc)``: told of anything else the
    protocol raises, before the thread ends."""

    def __init__(self, port, opener, protocol, *, name: str, on_crash, clock=time.monotonic):
        super().__init__(name=name, daemon=True)
        self._port = port
        self._opener = opener
        self._protocol = protocol
        self._on_crash = on_crash
        self._clock = clock
        self.stop_event = threading.Event()

    def run(self) -> None:
        proto = self._protocol
        try:
            proto.connection_made(self._clock())
            next_try = 0.0
            while not proto.done and not self.stop_event.is_set():
                if self._port is None:
                    if proto.close_requested:
                        proto.finish_without_port()
                        break
                    if self._clock() >= next_try:
                        next_try = self._clock() + RECONNECT_PERIOD_S
                        self._reopen()
                    self.stop_event.wait(_IDLE_S)
                    continue
                try:
                    data = read_available(self._port)
                    if data:
                        proto.data_received(data, self._clock())
                    out = proto.poll(self._clock())
                    if out:
                        self._port.write(out)
                except (OSError, serial.SerialException) as exc:  # LinkError is an OSError
                    self._close_port()
                    proto.connection_lost(exc)
        except Exception as exc:  # noqa: BLE001 -- a dead thread must not hang the caller
            self._on_crash(exc)
        finally:
            self._close_port()

    def _reopen(self) -> None:
        try:
            port = self._opener()
        except (OSError, serial.SerialException):
            return
        self._port = port
        self._protocol.connection_made(self._clock())

    def _close_port(self) -> None:
        port, self._port = self._port, None
        if port is not None:
            try:
                port.close()
            except Exception:  # noqa: BLE001 -- the port is already gone; nothing to save
                pass

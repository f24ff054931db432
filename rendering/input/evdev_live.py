"""A live Linux input device (``/dev/input/eventN``) as a touch source for the demo.

The device is read non-blocking: :meth:`EvdevReader.poll` returns at once with the samples
of the frames completed since the last call; :meth:`EvdevReader.wait` blocks until
there is something to read. Bytes are ``struct input_event`` records::

    struct input_event { struct timeval time; __u16 type; __u16 code; __s32 value; };
    # native layout: "llHHi" (24 bytes on 64-bit Linux, 16 on 32-bit)

A record split across two reads (a pipe, or a short read) is kept until it is whole.
The axis ranges come from the device (``EVIOCGABS``) unless given; on something that is
not an evdev device (a pipe, a file of packed events) they must be given. The reader asks
the kernel for ``CLOCK_MONOTONIC`` timestamps (``EVIOCSCLOCKID``), the clock of
``time.monotonic()``; where that is refused the events keep the device's clock.
"""

from __future__ import annotations

import errno
import fcntl
import os
import select
import struct
import time
from pathlib import Path

from frictex.rendering.input.evdev_decode import (ABS_MT_POSITION_X, ABS_MT_POSITION_Y, AbsInfo, EvdevDecoder,
                                    Event, ScreenSpec, TouchSample, screen_map)

INPUT_EVENT = struct.Struct("llHHi")
_ABSINFO = struct.Struct("6i")  # value, minimum, maximum, fuzz, flat, resolution
_READ_BYTES = INPUT_EVENT.size * 512
#: Most reads of _READ_BYTES one poll makes (32768 records, 786 kB on 64-bit Linux): far
#: more than a touch screen writes between two frames, and a bound on what one call
#: takes from a large file of events, or from something that never ends (/dev/zero).
_READS_PER_POLL = 64


def _ioc(direction: int, number: int, size: int) -> int:
    """Linux ``_IOC('E', number, size)``; direction 1 = write, 2 = read."""
    return (direction << 30) | (size << 16) | (ord("E") << 8) | number


def eviocgabs(code: int) -> int:
    """The ``EVIOCGABS(code)`` request number."""
    return _ioc(2, 0x40 + code, _ABSINFO.size)


EVIOCSCLOCKID = _ioc(1, 0xA0, 4)


def unpack_events(data: bytes) -> tuple[list[Event], bytes]:
    """Whole ``input_event`` records of ``data`` (times in s) and the incomplete rest."""
    n = len(data) // INPUT_EVENT.size
    events = [Event(sec + usec * 1e-6, etype, code, value)
              for sec, usec, etype, code, value in INPUT_EVENT.iter_unpack(data[:n * INPUT_EVENT.size])]
    return events, data[n * INPUT_EVENT.size:]


def read_absinfo(fd: int, code: int) -> AbsInfo | None:
    """The device's range of axis ``code``, or None when ``fd`` is not an evdev device."""
    try:
        raw = fcntl.ioctl(fd, eviocgabs(code), bytes(_ABSINFO.size))
    except OSError:
        return None
    _, lo, hi, _, _, res = _ABSINFO.unpack(raw)
    return AbsInfo(lo, hi, res)


class EvdevReader:
    """Non-blocking multi-touch reader: ``poll()`` -> list of :class:`TouchSample` (mm, N, s).

    Parameters
    ----------
    path : the device (``/dev/input/event5``), or any readable file of packed events.
    spec : screen size, ranges and orientation; what it leaves out comes from the device
        (ranges and resolution); without a device (a pipe) ranges and sizes must be given.
    """

    def __init__(self, path: str | Path, spec: ScreenSpec = ScreenSpec()) -> None:
        self.path = str(path)
        try:
            self._fd = os.open(self.path, os.O_RDONLY | os.O_NONBLOCK)
        except OSError as exc:
            hint = " (add yourself to the 'input' group)" if exc.errno == errno.EACCES else ""
            raise OSError(f"{self.path}: cannot open input device ({exc.strerror}){hint}") from None
        try:
            try:
                fcntl.ioctl(self._fd, EVIOCSCLOCKID, struct.pack("i", time.CLOCK_MONOTONIC))
            except OSError:
                pass  # not an evdev device, or an old kernel: keep the device's clock
            absinfo = {code: info for code in (ABS_MT_POSITION_X, ABS_MT_POSITION_Y)
                       if (info := read_absinfo(self._fd, code)) is not None}
            self.screen, _ = screen_map(spec, absinfo, where=self.path)
        except Exception:
            os.close(self._fd)
            raise
        self.decoder = EvdevDecoder(self.path)
        self._rest = b""
        self._ended = False  # the last read found the end of a file or of a pipe's writers

    def wait(self, timeout_s: float) -> bool:
        """Block until the device has bytes to read, at most ``timeout_s`` s; True if it
        has. At the end of a file (always "readable") it sleeps ``timeout_s`` instead."""
        if self._ended:
            time.sleep(timeout_s)
            return False
        return bool(select.select([self._fd], [], [], timeout_s)[0])

    def poll(self) -> list[TouchSample]:
        """Samples of the frames completed since the last call; never blocks. Reads at
        most _READS_PER_POLL x _READ_BYTES bytes: the rest waits for the next call."""
        chunks = []
        for _ in range(_READS_PER_POLL):
            try:
                data = os.read(self._fd, _READ_BYTES)
            except BlockingIOError:
                self._ended = False
                break
            except OSError as exc:
                raise OSError(f"{self.path}: read failed ({exc.strerror})") from None
            self._ended = not data
            if not data:
                break  # end of a file or pipe
            chunks.append(data)
        events, self._rest = unpack_events(self._rest + b"".join(chunks))
        return self.screen.touches(self.decoder.feed(events))

    def close(self) -> None:
        os.close(self._fd)

    def __enter__(self) -> EvdevReader:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

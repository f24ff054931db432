"""Fault injection between host and device, for tests and for trying a link by hand.

:func:`inject` damages a byte string (bit flips, dropped bytes, bursts of garbage) with a
seeded generator; :class:`FaultyPort` wraps a pyserial port and damages both directions,
can stall writes and can "unplug" (every call fails, and reopening fails, until it is
plugged back).
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass

import numpy as np
import serial


@dataclass(frozen=True)
class Faults:
    """Per-byte probabilities of damage, and stalls.

    flip : a byte gets one random bit flipped. drop : a byte is lost.
    garbage : a burst of 1..garbage_len random bytes is inserted before a byte.
    stall : a write waits ``stall_s`` before going out.
    """

    flip: float = 0.0
    drop: float = 0.0
    garbage: float = 0.0
    garbage_len: int = 32
    stall: float = 0.0
    stall_s: float = 0.050


def inject(data: bytes, faults: Faults, rng: np.random.Generator) -> bytes:
    """``data`` with the byte faults of ``faults`` applied (stalls are not byte faults)."""
    if not data:
        return data
    buf = np.frombuffer(data, dtype=np.uint8).copy()
    n = len(buf)
    flips = rng.random(n) < faults.flip
    buf[flips] ^= (1 << rng.integers(0, 8, int(flips.sum()))).astype(np.uint8)
    keep = rng.random(n) >= faults.drop
    bursts = np.flatnonzero(rng.random(n) < faults.garbage)
    if not bursts.size:
        return buf[keep].tobytes()
    pieces, prev = [], 0
    for at in bursts:
        pieces.append(buf[prev:at][keep[prev:at]].tobytes())
        pieces.append(rng.integers(0, 256, int(rng.integers(1, faults.garbage_len + 1)),
                                   dtype=np.uint8).tobytes())
        prev = at
    pieces.append(buf[prev:][keep[prev:]].tobytes())
    return b"".join(pieces)


class FaultyPort:
    """A pyserial-like port that damages what passes through ``port`` in both directions."""

    def __init__(self, port, faults: Faults, seed: int = 0):
        self._port = port
        self.faults = faults
        self._rng = np.random.default_rng(seed)
        self._lock = threading.Lock()
        self.unplugged = False

    def _check(self):
        if self.unplugged:
            raise serial.SerialException("device unplugged (fault injection)")

    @property
    def in_waiting(self) -> int:
        self._check()
        return self._port.in_waiting

    def read(self, size: int = 1) -> bytes:
        self._check()
        data = self._port.read(size)
        with self._lock:
            return inject(data, self.faults, self._rng)

    def write(self, data: bytes) -> int:
        self._check()
        with self._lock:
            stall = self._rng.random() < self.faults.stall
            damaged = inject(bytes(data), self.faults, self._rng)
        if stall:
            time.sleep(self.faults.stall_s)
        self._port.write(damaged)
        return len(data)

    def close(self) -> None:
        self._port.close()


class Plug:
    """An opener for :class:`~device.link.host.CommandSink` whose port can be pulled and put back.

    ``opener()`` opens the underlying port through ``open_port`` wrapped in a
    :class:`FaultyPort`; while unplugged it raises, and the open port fails on every call.
    """

    def __init__(self, open_port, faults: Faults = Faults(), seed: int = 0):
        self._open_port = open_port
        self.faults = faults
        self._seed = seed
        self.port: FaultyPort | None = None
        self.unplugged = False

    def __call__(self) -> FaultyPort:
        if self.unplugged:
            raise serial.SerialException("could not open port: device unplugged")
        self._seed += 1
        self.port = FaultyPort(self._open_port(), self.faults, self._seed)
        return self.port

    def unplug(self) -> None:
        self.unplugged = True
        if self.port is not None:
            self.port.unplugged = True

    def plug(self) -> None:
        self.unplugged = False

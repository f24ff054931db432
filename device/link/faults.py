"""Fault injection between host and device, for tests and for trying a link by hand.

:func:`inject` damages a byte string (bit flips, dropped bytes, bursts of garbage) with a
seeded generator; :class:`FaultyPort` wraps a pyserial port and damages both directions,
can stall writes, and plays timed events (host stalls, watchdog trips, unplugging);
:class:`Plug` is an opener whose port can be pulled and put back. :func:`parse_faults`
reads the ``--faults`` grammar into a :class:`FaultPlan`, which ``open_sink(...,
faults=plan)`` applies.

Grammar of ``--faults SPEC`` (items separated by commas, any order, events may repeat;
times in s after the link opens)::

    spec    = item { "," item }
    item    = rate | event | seed
    rate    = ("corrupt" | "drop" | "garbage") "=" PROBABILITY   per byte, both ways, [0, 1)
    event   = "stall=" SECONDS "@" SECONDS     the host's link thread stops for SECONDS
            | "trip@" SECONDS                  the device hears nothing for TRIP_S: its
                                               watchdog trips (it is at most 49 ms)
            | "unplug=" SECONDS "@" SECONDS    the port fails and cannot be reopened
    seed    = "seed=" INTEGER                  the damage generator's seed (default 0)

``corrupt`` flips one random bit of a byte, ``drop`` loses a byte, ``garbage`` inserts
1 to 32 random bytes before one. Example: ``corrupt=0.001,stall=0.2@1.5,trip@3,unplug=2@4``.
"""

from __future__ import annotations

import math
import threading
import time
from dataclasses import dataclass, field

import numpy as np
import serial

from frictex.device.errors import InputError

#: how long a ``trip@T`` event silences the host (s): past any watchdog (<= 49 ms)
TRIP_S = 0.1
#: longest stall or unplug a spec may ask for (s)
MAX_EVENT_S = 3600.0


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


@dataclass(frozen=True)
class Event:
    """A timed fault: ``kind`` ("stall", "trip" or "unplug") from ``at_s`` for
    ``duration_s`` (s, counted from when the link opens)."""

    kind: str
    at_s: float
    duration_s: float

    @property
    def end_s(self) -> float:
        return self.at_s + self.duration_s

    @property
    def text(self) -> str:
        """The event in the ``--faults`` grammar (``trip@3``, ``stall=0.2@1.5``)."""
        return f"trip@{self.at_s:g}" if self.kind == "trip" else \
            f"{self.kind}={self.duration_s:g}@{self.at_s:g}"


@dataclass(frozen=True)
class FaultPlan:
    """What :func:`parse_faults` reads: byte damage, timed events and a seed."""

    faults: Faults = Faults()
    events: tuple[Event, ...] = ()
    seed: int = 0

    def __str__(self) -> str:
        """The plan in the ``--faults`` grammar: its rates, its events in time order, its
        seed where not 0."""
        rates = [f"{name}={getattr(self.faults, field):g}" for name, field in _RATES.items()
                 if getattr(self.faults, field)]
        events = [e.text for e in self.events]
        return ",".join(rates + events + ([f"seed={self.seed}"] if self.seed else []))

    def opener(self, open_port) -> Plug:
        """An opener for ``CommandSink`` that applies this plan to the ports
        ``open_port()`` returns; event times count from this call."""
        return Plug(open_port, self.faults, self.seed, Schedule(self.events))


class FaultSpecError(InputError):
    """A ``--faults`` spec that does not follow the grammar (one line, names the item)."""


_RATES = {"corrupt": "flip", "drop": "drop", "garbage": "garbage"}
_FORMS = {"corrupt": "corrupt=PROBABILITY", "drop": "drop=PROBABILITY",
          "garbage": "garbage=PROBABILITY", "stall": "stall=SECONDS@SECONDS",
          "trip": "trip@SECONDS", "unplug": "unplug=SECONDS@SECONDS", "seed": "seed=INTEGER"}


def parse_faults(spec: str) -> FaultPlan:
    """Read a ``--faults`` spec (grammar in the module docstring) into a :class:`FaultPlan`.

    Raises :class:`FaultSpecError` (a ValueError) with one line naming the bad item.
    """
    rates, events, seed = {}, [], 0
    items = [item.strip() for item in spec.split(",")]
    if not spec.strip():
        raise FaultSpecError("empty fault spec; expected items such as "
                             "'corrupt=0.001,stall=0.2@1.5,trip@3,unplug=2@4'")
    for item in items:
        name, at = item.partition("@")[0], None
        name, _, value = name.partition("=")
        if "@" in item:
            at = item.partition("@")[2]
        name = name.strip()
        if name not in _FORMS:
            raise FaultSpecError(f"fault {item!r}: unknown name {name!r}; expected one of "
                                 f"{', '.join(_FORMS)}")
        form = _FORMS[name]
        wants_at, wants_value = "@" in form, "=" in form
        if (at is not None) != wants_at or bool(value) != wants_value:
            raise FaultSpecError(f"fault {item!r}: expected {form}")
        if name in _RATES:
            rates[_RATES[name]] = _number(item, value, "probability", 0.0, 1.0, form,
                                          top_open=True)
        elif name == "seed":
            try:
                seed = int(value)
            except ValueError:
                raise FaultSpecError(f"fault {item!r}: {value!r} is not an integer; "
                                     f"expected {form}") from None
            if seed < 0:
                raise FaultSpecError(f"fault {item!r}: seed must be >= 0")
        else:
            start = _number(item, at, "start time", 0.0, math.inf, form)
            duration = TRIP_S if name == "trip" else _number(
                item, value, "duration", 0.0, MAX_EVENT_S, form, bottom_open=True)
            events.append(Event(name, start, duration))
    return FaultPlan(Faults(**rates), tuple(sorted(events, key=lambda e: e.at_s)), seed)


def _number(item: str, text: str, what: str, low: float, high: float, form: str,
            top_open: bool = False, bottom_open: bool = False) -> float:
    """A number of the spec in [low, high] (bounds open as asked), or one clear line."""
    try:
        x = float(text)
    except ValueError:
        raise FaultSpecError(f"fault {item!r}: {what} {text!r} is not a number; expected "
                             f"{form}") from None
    ok = (math.isfinite(x) and (x > low if bottom_open else x >= low)
          and (x < high if top_open else x <= high))
    if not ok:
        interval = f"{'(' if bottom_open else '['}{low:g}, {high:g}{')' if top_open else ']'}"
        raise FaultSpecError(f"fault {item!r}: {what} {text} is outside {interval}")
    return x


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


@dataclass
class Schedule:
    """Timed events on ``clock`` (s), counted from when the schedule was made."""

    events: tuple[Event, ...] = ()
    clock: object = time.monotonic
    t0: float = field(default=None)

    def __post_init__(self):
        if self.t0 is None:
            self.t0 = self.clock()

    def active(self, kind: str) -> Event | None:
        """The event of ``kind`` under way now, if any."""
        now = self.clock() - self.t0
        return next((e for e in self.events if e.kind == kind and e.at_s <= now < e.end_s),
                    None)

    def not_reached(self, at: float) -> list[Event]:
        """The events not yet begun at time ``at`` (on ``clock``)."""
        return [e for e in self.events if e.at_s > at - self.t0]

    def sleep_through(self, kind: str) -> None:
        """If an event of ``kind`` is under way, wait until it ends (a stalled thread)."""
        event = self.active(kind)
        if event is not None:
            time.sleep(max(self.t0 + event.end_s - self.clock(), 0.0))


class FaultyPort:
    """A pyserial-like port that damages what passes through ``port`` in both directions
    and plays the ``schedule``'s events (stall: every call waits for its end; trip:
    writes vanish; unplug: every call fails)."""

    def __init__(self, port, faults: Faults, seed: int = 0, schedule: Schedule | None = None):
        self._port = port
        self.faults = faults
        self._rng = np.random.default_rng(seed)
        self._lock = threading.Lock()
        self._schedule = schedule or Schedule()
        self.unplugged = False

    def _check(self):
        if self.unplugged or self._schedule.active("unplug") is not None:
            raise serial.SerialException("device unplugged (fault injection)")
        self._schedule.sleep_through("stall")

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
        if self._schedule.active("trip") is not None:
            return len(data)  # the device hears nothing
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
    :class:`FaultyPort`; while unplugged (by :meth:`unplug` or a scheduled event) it
    raises, and the open port fails on every call.
    """

    def __init__(self, open_port, faults: Faults = Faults(), seed: int = 0,
                 schedule: Schedule | None = None):
        self._open_port = open_port
        self.faults = faults
        self._seed = seed
        self._schedule = schedule or Schedule()
        self.port: FaultyPort | None = None
        self.unplugged = False

    def __call__(self) -> FaultyPort:
        if self.unplugged or self._schedule.active("unplug") is not None:
            raise serial.SerialException("could not open port: device unplugged")
        self._seed += 1
        self.port = FaultyPort(self._open_port(), self.faults, self._seed, self._schedule)
        return self.port

    def events_not_reached(self, at: float) -> list[str]:
        """The scheduled events (``--faults`` text) not begun by time ``at`` (s, on the
        schedule's clock, ``time.monotonic``: when the link closed)."""
        return [e.text for e in self._schedule.not_reached(at)]

    def unplug(self) -> None:
        self.unplugged = True
        if self.port is not None:
            self.port.unplugged = True

    def plug(self) -> None:
        self.unplugged = False

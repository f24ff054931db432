"""What paces the run: nothing (replay), the wall clock (live), or the device (streaming).

A clock is asked to ``wait(k)`` before block ``k`` is computed and told ``finished(k, n)``
once blocks ``k .. k + n - 1`` have reached the sinks. Clocks that pace in real time
count deadline misses; every wait has a bound.

The :class:`Clock` protocol is an extension point: :data:`CLOCKS` holds the clocks'
factories by name (``virtual``, ``wall``, ``device``), and another package adds one under
entry-point group ``frictex.clocks``::

    [project.entry-points."frictex.clocks"]
    lazy = "mypkg.lazy:open_lazy"   # open_lazy(arg, request) -> a Clock

A factory is called ``factory(arg, request)``: ``arg`` the text after ``NAME:`` of
``--clock NAME[:ARG]`` ("" when none), ``request`` a :class:`ClockRequest`.
:func:`build_clock` builds one (replay's ``--clock``); another package's is wrapped so that
what it raises is a ``PluginError`` naming it (exit 1).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any, Protocol

from frictex.device.errors import InputError
from frictex.device.registry import Expect, Registry, build_entry, guarded


class Clock(Protocol):
    """What paces a run (see the module docstring)."""

    def wait(self, k: int) -> None:
        """Return when block ``k`` may be computed (a bounded wait)."""

    def finished(self, k: int, n: int) -> None:
        """Blocks ``k .. k + n - 1`` have reached the sinks."""


@dataclass(frozen=True)
class ClockRequest:
    """What a clock is built for: the second argument of a :data:`CLOCKS` factory.

    Attributes
    ----------
    block_s : float
        The duration of one block of output (s): block ``k`` covers
        ``[k * block_s, (k + 1) * block_s)`` of output time.
    deadline_s : float
        How long after its start a block may reach the sinks before it is late (s).
    link : OutputDevice or None
        The output device the run streams to (the ``device`` clock's), or None.
    """

    block_s: float
    deadline_s: float
    link: Any = None


#: ``factory(arg, request) -> Clock``, by name
CLOCKS: Registry[Any] = Registry("clock", "frictex.clocks",
                                 expect=Expect.factory("a factory(arg, request) returning a "
                                                       "Clock"))


def clock_name(spec: str | Clock) -> tuple[str, str]:
    """NAME and ARG of a ``NAME[:ARG]`` clock spec; NAME registered (else
    ``UnknownName`` listing the known). A :class:`Clock` object given instead of a spec
    (``frictex.replay(clock=...)``): its type's name and ""."""
    if not isinstance(spec, str):
        return type(spec).__name__, ""
    return CLOCKS.named(spec)


def build_clock(spec: str | Clock, request: ClockRequest) -> Clock:
    """The clock ``NAME[:ARG]`` of :data:`CLOCKS` built for ``request``: frictex's own as
    its factory returns it, another package's checked and wrapped in a
    :class:`PluginClock`. A :class:`Clock` object (the API's caller's own, checked there)
    is used as it is, as the API's Sink objects are."""
    if not isinstance(spec, str):
        return spec
    name, arg = clock_name(spec)
    return build_entry(CLOCKS, "clock", name, arg, request, doing="building",
                       members=("wait()", "finished()"),
                       contract="a Clock (frictex.app.engine.clocks.Clock)", wrap=PluginClock)


class PluginClock:
    """Another package's clock (``inner``): what it raises, but frictex's own errors, is a
    ``PluginError`` naming it (``registry.guarded``)."""

    def __init__(self, inner: Clock, who: str):
        self.inner = inner
        self._who = who

    def wait(self, k: int) -> None:
        guarded(self._who, "in wait()", self.inner.wait, k)

    def finished(self, k: int, n: int) -> None:
        guarded(self._who, "in finished()", self.inner.finished, k, n)


class VirtualClock:
    """Replay: every block may run at once; output time advances exactly n / rate."""

    def wait(self, k: int) -> None:
        """No wait."""

    def finished(self, k: int, n: int) -> None:
        """Nothing to count."""

    @classmethod
    def open(cls, arg: str, request: ClockRequest) -> VirtualClock:
        """Its :data:`CLOCKS` factory."""
        CLOCKS.refuse_arg("virtual", arg)
        return cls()


@dataclass
class DeadlineStats:
    """Blocks sent after their deadline, and the worst lateness past a block's end (s)."""

    misses: int = 0
    worst_lateness_s: float = 0.0


class WallClock:
    """Live: block ``k`` starts at ``t0 + k * block_s`` on ``now`` (s) and is due
    ``deadline_s`` after its start (the device's jitter-buffer prefill); a block handed
    over later is a miss. A late loop catches up without sleeping.

    ``now`` and ``sleep`` are injectable so tests drive the clock themselves.
    """

    def __init__(self, block_s: float, deadline_s: float, now=time.perf_counter,
                 sleep=time.sleep):
        self.block_s = float(block_s)
        self.deadline_s = float(deadline_s)
        self.now = now
        self.sleep = sleep
        self.t0 = now()
        self.stats = DeadlineStats()

    def restart(self) -> None:
        """Block 0 starts now."""
        self.t0 = self.now()

    def wait(self, k: int) -> None:
        pause = self.t0 + k * self.block_s - self.now()
        if pause > 0:
            self.sleep(pause)

    def finished(self, k: int, n: int) -> None:
        start = self.t0 + k * self.block_s
        now = self.now()
        self.stats.worst_lateness_s = max(self.stats.worst_lateness_s,
                                          now - (start + n * self.block_s))
        if now > start + max(n * self.block_s, self.deadline_s):
            self.stats.misses += 1

    @classmethod
    def open(cls, arg: str, request: ClockRequest) -> WallClock:
        """Real time from now on, at ``request``'s block duration and deadline (its
        factory)."""
        CLOCKS.refuse_arg("wall", arg)
        return cls(request.block_s, request.deadline_s)


class DevicePacedClock:
    """Streaming to a device: block ``k`` runs when the device's link can take it, so the
    device's own sample clock paces the run. Each wait is bounded by ``timeout_s``; a wait
    that runs out is counted as a stall and the block goes ahead (the link counts what it
    cannot deliver), so a device that stops taking data never freezes the run.
    """

    def __init__(self, link, timeout_s: float = 0.5):
        self.link = link
        self.timeout_s = float(timeout_s)
        self.stalls = 0

    def wait(self, k: int) -> None:
        if not self.link.wait_for_room(self.timeout_s):
            self.stalls += 1

    def finished(self, k: int, n: int) -> None:
        """The device's clock, not this one, says when blocks play."""

    @classmethod
    def open(cls, arg: str, request: ClockRequest) -> DevicePacedClock:
        """Paced by ``request.link`` (its factory)."""
        CLOCKS.refuse_arg("device", arg)
        if request.link is None:
            raise InputError("clock 'device' is paced by an output device, and the run has "
                             "none: choose one (--device, device=)")
        return cls(request.link)


CLOCKS.register("virtual", VirtualClock.open)
CLOCKS.register("wall", WallClock.open)
CLOCKS.register("device", DevicePacedClock.open)

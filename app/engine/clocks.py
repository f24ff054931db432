"""What paces the run: nothing (replay), the wall clock (live), or the device (streaming).

A clock is asked to ``wait(k)`` before block ``k`` is computed and told ``finished(k, n)``
once blocks ``k .. k + n - 1`` have reached the sinks. Clocks that pace in real time
count deadline misses; every wait has a bound.

The :class:`Clock` protocol is an extension point: :data:`CLOCKS` holds the clocks by
name (``virtual``, ``wall``, ``device``), and another package adds one under entry-point
group ``frictex.clocks``. Each is built with its own arguments (a clock class).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Protocol

from frictex.device.registry import Registry


class Clock(Protocol):
    """What paces a run (see the module docstring)."""

    def wait(self, k: int) -> None:
        """Return when block ``k`` may be computed (a bounded wait)."""

    def finished(self, k: int, n: int) -> None:
        """Blocks ``k .. k + n - 1`` have reached the sinks."""


#: clocks by name (their classes)
CLOCKS: Registry[type] = Registry("clock", "frictex.clocks")


@CLOCKS.register("virtual")
class VirtualClock:
    """Replay: every block may run at once; output time advances exactly n / rate."""

    def wait(self, k: int) -> None:
        """No wait."""

    def finished(self, k: int, n: int) -> None:
        """Nothing to count."""


@dataclass
class DeadlineStats:
    """Blocks sent after their deadline, and the worst lateness past a block's end (s)."""

    misses: int = 0
    worst_lateness_s: float = 0.0


@CLOCKS.register("wall")
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


@CLOCKS.register("device")
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

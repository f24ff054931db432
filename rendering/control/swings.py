"""Swings of the closed loop's log gain: how an oscillation of the gain is told apart from a
loop that settles.

A swing is the gain's move between two turning points (successive steps of one sign,
summed). An oscillation that grows, holds or rings keeps making large swings, each about
as large as the one before; a damped loop's swings shrink by more than half each time,
and a loop that tracks a finger's drift moves by a few percent per block. So the loop
counts successive swings each over ``SWING`` (a 25 % change of the gain) and at least
half the one before; ``OSCILLATION_STEPS`` of them in a row (three periods) is an
oscillation. At the stated gain margins the report's population of 20 fingers never
made more than 3 in a row in 60 s runs (issue 16's report); a loop 1.5x past its gain
margin makes tens (``tests/test_closed_loop.py``), as do loops with ki 0.5-1e6 per
block (20-79 swings in 4 s, the gain pinned at its limits).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

#: a swing counts when it changes the gain by more than this fraction
SWING = 0.25
#: this many successive counted swings, each at least half the one before: an oscillation
OSCILLATION_STEPS = 6
_LOG_SWING = math.log1p(SWING)


@dataclass(frozen=True)
class Swings:
    """The count so far: the swing under way (log gain, signed), the last finished one's
    size, the run of counted swings up to it, the longest run, and how many times a run
    reached ``OSCILLATION_STEPS`` (oscillations seen)."""

    current: float = 0.0
    previous: float = math.inf
    run: int = 0
    longest: int = 0
    oscillations: int = 0

    def step(self, d_log: float) -> Swings:
        """After one step of the log gain by ``d_log`` (0: no step)."""
        if d_log == 0.0:
            return self
        if self.current == 0.0 or (d_log > 0) == (self.current > 0):
            return Swings(self.current + d_log, self.previous, self.run, self.longest,
                          self.oscillations)
        return Swings(d_log, *self._finish())

    def _finish(self) -> tuple[float, int, int, int]:
        """(previous, run, longest, oscillations) once the swing under way is finished."""
        size = abs(self.current)
        big = size > _LOG_SWING
        run = self.run + 1 if big and size >= self.previous / 2 else int(big)
        entered = run == OSCILLATION_STEPS
        return size, run, max(self.longest, run), self.oscillations + int(entered)

    def longest_with_current(self) -> int:
        """The longest run, the swing under way counted as finished (a run's last swing
        has no turn after it)."""
        return self._finish()[2] if self.current else self.longest


def longest_run(log_c) -> int:
    """The longest run of counted swings (module docstring) of a sequence of log gains,
    the last swing counted as finished; 0 when the gain never swung that far."""
    swings = Swings()
    for a, b in zip(log_c[:-1], log_c[1:]):
        swings = swings.step(float(b) - float(a))
    return swings.longest_with_current()

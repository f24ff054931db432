"""Where touch samples come from: a trace (recorded or synthetic) or live touch input.

A source hands the driver, for blocks ``k .. k + n - 1``, the touch samples that take
effect in them (a sample takes effect at the first block boundary at or after its time:
``rendering.tracking.tracks.apply_index``) and says how many of those blocks to run:

    samples, n_run = source.take(k, n)      # Trace or None; 1 <= n_run <= n
    source.done                              # nothing more to run

A trace source ends with the block after its last sample (so every sample, and the
last touch's end, is in the output); a live source runs until the driver is stopped.
"""

from __future__ import annotations

import queue

import numpy as np

from rendering.input.trace_file import Trace, make_trace
from rendering.tracking.tracks import apply_index


class TraceSource:
    """Samples of a trace given as an iterator of chunks (``rendering.input.trace_file.
    iter_trace``, or ``iter([trace])``), read ahead only as far as the blocks asked for.

    ``until_s``: run the output to this time (s, on the trace's clock) instead of to the
    block after the last sample (a synthetic motion scored over a fixed span).
    """

    def __init__(self, chunks, until_s: float | None = None):
        self.chunks = chunks
        self.until_s = until_s
        self.pending: Trace | None = None
        self.applied = np.zeros(0, dtype=np.int64)
        self.config = None
        self.ended = False
        self.end_index: int | None = None
        self.next_index = 0
        self.stats = TraceStats()

    def first_time(self) -> float:
        """Time (s) of the first sample: where the output clock starts."""
        if self.pending is None:
            self._read_more()
        if self.pending is None:
            raise ValueError("the trace has no samples")
        return float(self.pending.t_s[0])

    def start(self, tracker_config) -> None:
        """Begin handing out samples for a pipeline with this tracker configuration."""
        self.config = tracker_config
        self.first_time()
        self.applied = apply_index(self.pending.t_s, tracker_config)
        if self.until_s is not None:
            quantum = tracker_config.quantum
            span = (self.until_s - tracker_config.t0_s) * tracker_config.rate_hz / quantum
            self.end_index = int(np.ceil(span - 1e-9)) * quantum

    def _read_more(self) -> None:
        chunk = next(self.chunks, None)
        if chunk is None:
            self.ended = True
            return
        self.stats.add(chunk)
        self.pending = chunk if self.pending is None else self.pending.then(chunk)
        if self.config is not None:
            self.applied = apply_index(self.pending.t_s, self.config)

    def take(self, k: int, n: int) -> tuple[Trace | None, int]:
        block = self.config.quantum
        end = (k + n) * block
        while not self.ended and (self.applied.size == 0 or self.applied[-1] < end):
            self._read_more()
        hi = int(np.searchsorted(self.applied, end))
        taken = self.pending.slice(0, hi) if hi else None
        if hi:
            self.pending = self.pending.slice(hi, len(self.pending))
            self.applied = self.applied[hi:]
        if self.end_index is not None:
            n_run = min(n, -(-(self.end_index - k * block) // block))
        elif self.ended and self.applied.size == 0:
            last = int(apply_index(taken.t_s[-1:], self.config)[0]) if taken is not None else -1
            n_run = max(1, min(n, last // block + 1 - k))
        else:
            n_run = n
        self.next_index = (k + n_run) * block
        return taken, n_run

    @property
    def done(self) -> bool:
        if self.end_index is not None:
            return self.next_index >= self.end_index
        return self.ended and self.applied.size == 0


class TraceStats:
    """What a summary says about a trace, gathered chunk by chunk."""

    MAX_STEPS = 100_000  # the touch rate is the median over the first steps

    def __init__(self):
        self.samples = 0
        self.fingers: set[int] = set()
        self.first_t = self.last_t = None
        self.steps: list[np.ndarray] = []
        self.n_steps = 0

    def add(self, chunk: Trace) -> None:
        times = chunk.t_s if self.last_t is None else np.concatenate(([self.last_t], chunk.t_s))
        if self.n_steps < self.MAX_STEPS:
            steps = np.diff(times)
            steps = steps[steps > 0][: self.MAX_STEPS - self.n_steps]
            self.steps.append(steps)
            self.n_steps += steps.size
        self.samples += len(chunk)
        self.fingers.update(chunk.fingers)
        self.first_t = float(chunk.t_s[0]) if self.first_t is None else self.first_t
        self.last_t = float(chunk.t_s[-1])

    def report(self, path) -> dict:
        steps = np.concatenate(self.steps) if self.steps else np.zeros(0)
        return {"path": str(path) if path else None, "samples": self.samples,
                "fingers": sorted(self.fingers), "duration_s": self.last_t - self.first_t,
                "touch_rate_hz": float(1.0 / np.median(steps)) if steps.size else None}


class QueueSource:
    """Live touch samples from a queue of ``(t_s, finger, x_mm, y_mm, force_n, event)``
    tuples stamped on the output clock (s since the run's start); a sample is handed out
    with the first block starting at or after its stamp. Never ends by itself."""

    done = False

    def __init__(self, touches: queue.Queue, block_s: float):
        self.touches = touches
        self.block_s = block_s
        self._pending: list[tuple] = []

    def take(self, k: int, n: int) -> tuple[Trace | None, int]:
        while True:
            try:
                self._pending.append(self.touches.get_nowait())
            except queue.Empty:
                break
        start_s = k * self.block_s
        due = [s for s in self._pending if s[0] <= start_s]
        if not due:
            return None, n
        self._pending = self._pending[len(due):]
        t, finger, x, y, force, event = (np.array(c) for c in zip(*due))
        return make_trace(t, finger, x, y, force, event, where="live touch", normalise=False), n

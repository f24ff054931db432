"""A pipeline stage timed block by block, as the live haptic process runs it: one block
per call on a virtual clock, the garbage collector frozen once the pipeline is built
(and unfrozen when the timing ends, since the timing process goes on to other work);
each call's wall and thread CPU time (s). ``frictex bench pipeline`` and the report's
matrix time their live blocks with it."""

from __future__ import annotations

import gc
import time

import numpy as np


class _Timed:
    """A stage that keeps the wall and thread CPU time (s) of each of its pipeline calls
    (CPU time leaves out what other processes on a busy machine take meanwhile)."""

    def __init__(self, stage):
        self.stage = stage
        self.seconds: list[float] = []
        self.cpu_seconds: list[float] = []

    def process(self, k, samples, n):
        t, c = time.perf_counter(), time.thread_time()
        result = self.stage.process(k, samples, n)
        self.cpu_seconds.append(time.thread_time() - c)
        self.seconds.append(time.perf_counter() - t)
        return result


def time_blocks(stage, trace, duration: float, sinks=()) -> tuple[np.ndarray, np.ndarray]:
    """Run ``trace`` through ``stage`` (a pipeline stage) one block per call, virtual
    clock, for ``duration`` s, the garbage collector frozen meanwhile; per-call (wall,
    thread CPU) seconds."""
    from frictex.app.engine.clocks import VirtualClock
    from frictex.app.engine.driver import drive
    from frictex.app.engine.sources import TraceSource
    timed = _Timed(stage)
    source = TraceSource(iter([trace]), until_s=duration)
    source.start(stage.pipeline.tracker_config)
    gc.freeze()  # as the live haptic process does once its pipeline is built
    try:
        drive(timed, source, list(sinks), VirtualClock(), chunk_blocks=1)
    finally:
        gc.unfreeze()
    return np.array(timed.seconds), np.array(timed.cpu_seconds)

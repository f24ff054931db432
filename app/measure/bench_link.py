"""``frictex bench link``: the host link to the simulated device (``--device sim``).

The device runs in this process (``device.link.simport``), so "host CPU" includes the
simulated device's (when it ran as a ``frictex sim-device`` process before, it did not).
Two runs paced by the device as in replay
(timed from the first block until the device has played the last and stopped):
at the seed 003 rate (10 kHz, blocks of 50) for host CPU per second of output and the
heartbeat round trip; and at 1 MHz (the device's clock no longer limits) for the sustained
frame and block rates the link itself manages. A third run, live (the wall clock paces
the blocks, as the demo's haptic thread does), to a device whose simulated finger sends
force reports (the in-process ``sim`` device): how many blocks after a block ends its
report is in the host's hands (``rendering.control.loop``'s delay D; the report's
closed-loop section simulates it).
"""

from __future__ import annotations

import time

import numpy as np

from frictex.app.measure.figure import Figure
from frictex.device.link.host import open_sink

BLOCK = 50


def _stream(rate_hz: float, seconds: float) -> tuple[dict, float, float]:
    """Stream ``seconds`` of output; returns (status, wall s, host CPU s)."""
    n_blocks = int(seconds * rate_hz / BLOCK)
    block = np.abs(np.sin(np.arange(BLOCK) / 7.0))[:, None] * 2.0
    sink = open_sink("sim", channels=1, rate_hz=rate_hz, paced=True)
    try:
        wall0, cpu0 = time.perf_counter(), time.process_time()
        for b in range(n_blocks):
            sink.send(b * BLOCK, block, None)
    finally:
        sink.close()  # drains: the device has played everything when it returns
    wall, cpu = time.perf_counter() - wall0, time.process_time() - cpu0
    return sink.status(), wall, cpu


def _report_delays(seconds: float, rate_hz: float = 10_000.0) -> np.ndarray:
    """Live blocks to a simulated finger for ``seconds``: for each block, the whole blocks
    from its end to the first block computed with its force report come (the first
    tenth left out: the device's prefill)."""
    from frictex.rendering.control.loop import LoopConfig
    wait = LoopConfig().max_wait_s * rate_hz  # samples the loop waits for a report
    sink = open_sink("sim:finger=3", channels=1, rate_hz=rate_hz, paced=False)
    block = np.full((BLOCK, 1), 1.0)
    delays, pending = [], []
    n_blocks = int(seconds * rate_hz / BLOCK)
    try:
        t0 = time.perf_counter()
        for b in range(n_blocks):
            while time.perf_counter() < t0 + b * BLOCK / rate_hz:
                time.sleep(2e-4)
            now = b * BLOCK
            come = [i for i in pending if sink.force_report(i, BLOCK) is not None]
            delays += [(now - i - BLOCK) // BLOCK for i in come]
            # given up when the loop would give up on it
            pending = [i for i in pending if i not in come and now - i - BLOCK <= wait]
            sink.send(now, block, None)
            pending.append(now)
    finally:
        sink.close()
    return np.array(delays[n_blocks // 10:], dtype=float)


def run(quick: bool) -> list[Figure]:
    seconds = 1.0 if quick else 5.0
    status, wall, cpu = _stream(10_000.0, seconds)
    figs = [Figure("link", "host and device CPU per s of output (10 kHz)",
                   cpu / seconds * 1e3, "ms/s"),
            Figure("link", "heartbeat round trip p50", status["latency_ms_p50"], "ms"),
            Figure("link", "heartbeat round trip p99", status["latency_ms_p99"], "ms"),
            Figure("link", "underruns at 10 kHz", float(status["underruns"] or 0), "count")]
    fast, wall, _ = _stream(1_000_000.0, seconds / 5)
    figs += [Figure("link", "sustained frames/s (1 MHz device)", fast["frames_sent"] / wall, "1/s"),
             Figure("link", "sustained blocks/s (1 MHz device)", fast["blocks_sent"] / wall, "1/s"),
             Figure("link", "sustained samples/s (1 MHz device)",
                    fast["blocks_sent"] * BLOCK / wall, "1/s")]
    delays = _report_delays(seconds)
    if delays.size == 0:
        return figs + [Figure("link", "force reports: none came back (live, 5 ms blocks)",
                              float("nan"), "")]
    figs += [Figure("link", "force report delay p50 (live, 5 ms blocks)",
                    float(np.percentile(delays, 50)), "blocks"),
             Figure("link", "force report delay max (live, 5 ms blocks)",
                    float(delays.max()), "blocks")]
    return figs

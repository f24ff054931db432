"""``frictex bench link``: the host link to the simulated device (``--device sim``).

The device runs in this process (``device.link.simport``), so "host CPU" includes the
simulated device's (when it ran as a ``frictex sim-device`` process before, it did not).
Two runs paced by the device as in replay
(timed from the first block until the device has played the last and stopped):
at the seed 003 rate (10 kHz, blocks of 50) for host CPU per second of output and the
heartbeat round trip; and at 1 MHz (the device's clock no longer limits) for the sustained
frame and block rates the link itself manages. A third run, live (the wall clock paces
the blocks, as the demo's haptic thread does), to a device whose simulated finger sends
force reports (the in-process ``sim`` device), with no busy processes added and beside one
busy process per core, each with the machine's load at its end (another job's processes
count in it too):
how many blocks after a block ends its report is in the host's hands
(``rendering.control.loop``'s delay D; ``app.measure.link_report_delays``, which the
report's closed-loop section measures and replays).
"""

from __future__ import annotations

import time

import numpy as np

from frictex.app.measure.figure import Figure
from frictex.app.measure.link_report_delays import measure as measure_delays
from frictex.app.measure.processes import cores, load
from frictex.app.measure.tail import P99_SAMPLES, tail
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


def run(quick: bool) -> list[Figure]:
    seconds = 1.0 if quick else 5.0
    status, wall, cpu = _stream(10_000.0, seconds)
    figs = [Figure("link", "host and device CPU per s of output (10 kHz)",
                   cpu / seconds * 1e3, "ms/s"),
            *heartbeat_figures(status),
            Figure("link", "underruns at 10 kHz", float(status["underruns"] or 0), "count")]
    fast, wall, _ = _stream(1_000_000.0, seconds / 5)
    figs += [Figure("link", "sustained frames/s (1 MHz device)", fast["frames_sent"] / wall, "1/s"),
             Figure("link", "sustained blocks/s (1 MHz device)", fast["blocks_sent"] / wall, "1/s"),
             Figure("link", "sustained samples/s (1 MHz device)",
                    fast["blocks_sent"] * BLOCK / wall, "1/s")]
    for busy in (0, cores()):
        delays = measure_delays(max(seconds, 2.0), 10_000.0, BLOCK, busy)
        figs += delay_figures(delays.come(), len(delays.blocks), busy, load())
    return figs


def heartbeat_figures(status: dict) -> list[Figure]:
    """The heartbeat round trip's median and tail (ms) from a link's ``status``, each
    label with the number of round trips; the tail is the max where they are too few for
    a 99th percentile (``app.measure.tail``)."""
    n = status["latency_samples"]
    name, value = (("max", status["latency_ms_max"]) if n < P99_SAMPLES
                   else ("p99", status["latency_ms_p99"]))
    return [Figure("link", f"heartbeat round trip p50 of {n}", status["latency_ms_p50"], "ms"),
            Figure("link", f"heartbeat round trip {name} of {n}", value, "ms")]


def delay_figures(come: np.ndarray, sent: int, busy: int, load_1min: float) -> list[Figure]:
    """The force reports' delays (blocks) of a live run of ``sent`` blocks beside ``busy``
    busy processes, ``come`` those of the reports that came back: p50, p99 (the max under
    101 reports, ``app.measure.tail``) and max, each label counting the reports and
    giving the machine's load measured at the run's end (``load_1min``, 1-minute
    average), and how many were lost."""
    added = f"beside {busy} busy processes" if busy else "no busy processes added"
    where = f"live, 5 ms blocks, {added}, load {load_1min:.1f}"
    if come.size == 0:
        return [Figure("link", f"force reports: none came back of {sent} ({where})",
                       float("nan"), "")]
    high, value = tail(come)
    # under 101 reports the tail is the max itself: one row, not two
    rows = {"p50": float(np.median(come)), high: value, "max": float(come.max())}
    return [Figure("link", f"force report delay {name} of {come.size} reports ({where})",
                   got, "blocks") for name, got in rows.items()] + [
        Figure("link", f"force reports lost ({where})", float(sent - come.size),
               f"of {sent}")]

"""The device's force reports as the host keeps them: per output sample, by sample number.

A wire :class:`~device.link.protocol.ForceReport` carries one value per ``decimation``
samples; :func:`per_sample` holds each value over its samples, so a report reads as
lateral and normal force (N) for every output sample it covers, numbered as the host
numbers its samples. :class:`ForceHistory` keeps the recent ones (pure: no clock, no I/O)
and cuts out any range of samples they cover.
"""

from __future__ import annotations

import collections
from dataclasses import dataclass

import numpy as np

from device.link import protocol as p
from device.link.ledger import unwrap

#: samples of reports the host keeps (1 s at 10 kHz)
HISTORY_SAMPLES = 10_000


@dataclass(frozen=True, eq=False)
class ForceReport:
    """What the device's force sensors measured over output samples ``index0 ..
    index0 + m - 1``: lateral (tangential) and normal force (N), each (m,) float64.
    What the closed loop (``rendering.control.loop``) reads, from a device or a simulated
    finger.
    """

    index0: int
    lateral_n: np.ndarray
    normal_n: np.ndarray


def per_sample(msg: p.ForceReport, near: int) -> ForceReport:
    """``msg`` as one value per output sample (each value held over its ``decimation``
    samples), its start mapped onto the host's sample numbers nearest ``near``."""
    k = msg.decimation
    return ForceReport(unwrap(msg.start_index, near),
                       np.repeat(np.asarray(msg.lateral_n, dtype=np.float64), k),
                       np.repeat(np.asarray(msg.normal_n, dtype=np.float64), k))


class ForceHistory:
    """The last ``keep`` samples' worth of reports, newest last."""

    def __init__(self, keep: int = HISTORY_SAMPLES):
        self.keep = int(keep)
        self._reports: collections.deque[ForceReport] = collections.deque()
        self._held = 0

    def add(self, report: ForceReport) -> None:
        self._reports.append(report)
        self._held += report.lateral_n.size
        while self._held - self._reports[0].lateral_n.size >= self.keep:
            self._held -= self._reports.popleft().lateral_n.size

    def latest(self) -> ForceReport | None:
        return self._reports[-1] if self._reports else None

    def window(self, index0: int, n: int) -> ForceReport | None:
        """The forces over samples ``index0 .. index0 + n - 1``, or None unless the kept
        reports cover every one of them (where reports overlap, the newer wins)."""
        if n < 1:
            return None
        lateral = np.full(n, np.nan)
        normal = np.full(n, np.nan)
        for r in self._reports:
            lo, hi = max(r.index0, index0), min(r.index0 + r.lateral_n.size, index0 + n)
            if lo < hi:
                lateral[lo - index0:hi - index0] = r.lateral_n[lo - r.index0:hi - r.index0]
                normal[lo - index0:hi - index0] = r.normal_n[lo - r.index0:hi - r.index0]
        if np.isnan(lateral).any():
            return None
        return ForceReport(index0, lateral, normal)

"""The device's force reports as the host keeps them: per output sample, by sample number.

A wire :class:`~device.link.protocol.ForceReport` carries one value per ``decimation``
samples; :func:`per_sample` holds each value over its samples, so a report reads as
lateral and normal force (N) for every output sample it covers, numbered as the host
numbers its samples. :class:`ForceHistory` keeps the recent ones (pure: no clock, no I/O)
and cuts out any range of samples they cover.
"""

from __future__ import annotations

import bisect
from dataclasses import dataclass

import numpy as np

from frictex.device.link import protocol as p
from frictex.device.link.ledger import unwrap

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
    """The last ``keep`` samples' worth of reports, newest last.

    Reports normally arrive in order of their first sample: :meth:`window` then finds
    the few that can overlap a range by bisection on their starts, instead of looking at
    every report kept (about 250 at 10 kHz). While any kept report starts before the
    one kept before it (a device that restarted its numbering), it looks at all of them.
    """

    def __init__(self, keep: int = HISTORY_SAMPLES):
        self.keep = int(keep)
        # kept: [_head:] of both lists, oldest first; the popped prefix is cut now and then
        self._reports: list[ForceReport] = []
        self._starts: list[int] = []
        self._head = 0
        self._held = 0
        self._descents = 0  # kept neighbours whose start goes back
        self._longest = 0   # samples of the longest report ever added

    def add(self, report: ForceReport) -> None:
        if len(self._starts) > self._head and report.index0 < self._starts[-1]:
            self._descents += 1
        self._reports.append(report)
        self._starts.append(report.index0)
        self._held += report.lateral_n.size
        self._longest = max(self._longest, report.lateral_n.size)
        while self._held - self._reports[self._head].lateral_n.size >= self.keep:
            h = self._head
            if self._starts[h + 1] < self._starts[h]:
                self._descents -= 1
            self._held -= self._reports[h].lateral_n.size
            self._head += 1
        if self._head > 64 and 2 * self._head > len(self._reports):
            del self._reports[:self._head], self._starts[:self._head]
            self._head = 0

    def latest(self) -> ForceReport | None:
        return self._reports[-1] if len(self._reports) > self._head else None

    def window(self, index0: int, n: int) -> ForceReport | None:
        """The forces over samples ``index0 .. index0 + n - 1``, or None unless the kept
        reports cover every one of them (where reports overlap, the newer wins)."""
        got = self._gather(index0, n)
        if got is None or not got[2].all():
            return None
        return ForceReport(index0, got[0], got[1])

    def covered(self, index0: int, n: int) -> tuple[np.ndarray, np.ndarray]:
        """(lateral, normal) forces (N) of those of samples ``index0 .. index0 + n - 1``
        the kept reports cover, in sample order (a device drops the report it was building
        when it underruns, PROTOCOL.md 4.9); empty arrays if none."""
        got = self._gather(index0, n)
        if got is None:
            return np.zeros(0), np.zeros(0)
        lateral, normal, covered = got
        return lateral[covered], normal[covered]

    def _gather(self, index0: int, n: int):
        """(lateral, normal, covered) over samples ``index0 .. index0 + n - 1``, each (n,),
        or None when no kept report reaches into them."""
        if n < 1:
            return None
        if self._descents:
            lo, hi = self._head, len(self._reports)
        else:  # those starting in (index0 - longest, index0 + n), in arrival order
            lo = bisect.bisect_right(self._starts, index0 - self._longest, self._head)
            hi = bisect.bisect_left(self._starts, index0 + n, lo)
        if lo == hi:
            return None  # not come yet: the loop asks for every block sent until it has
        lateral = np.empty(n)
        normal = np.empty(n)
        covered = np.zeros(n, dtype=bool)  # not NaN as the mark: a sensor may send NaN
        for k in range(lo, hi):
            r = self._reports[k]
            lo_, hi_ = max(r.index0, index0), min(r.index0 + r.lateral_n.size, index0 + n)
            if lo_ < hi_:
                lateral[lo_ - index0:hi_ - index0] = r.lateral_n[lo_ - r.index0:hi_ - r.index0]
                normal[lo_ - index0:hi_ - index0] = r.normal_n[lo_ - r.index0:hi_ - r.index0]
                covered[lo_ - index0:hi_ - index0] = True
        return lateral, normal, covered

"""A live link's catch-up (PROTOCOL.md 6.1): blocks skipped so that a delay the device
took on comes back out, and the map from the host's sample numbers to the device's that
the skipped blocks leave.

A live stream's samples play a fixed lead after the pipeline made them only while the
device never runs dry. A device that underran holds its play position (PROTOCOL.md 5.1)
and plays again once it holds its prefill, so from then on every sample plays later by
the time it waited, and nothing in the device takes that delay back: a touch is felt
later for the rest of the run. The host takes it back (:func:`behind`). When a live
block is due to go out while the device, playing, still holds its prefill or more (at
least one block more than it holds at the stream's steady pace), the block is not sent
(its samples count as unplayed, cause ``skipped``) and the next block takes its sample
numbers: one block less queued, one block less of delay, and no gap in what the device
plays. The same holds for blocks that wait at the host (a port that took no bytes for a
while) or on their way (a device that reads its transport slowly): the newest go out,
the older are skipped.

Pure bookkeeping on the numbers it is given (no clock, no I/O).
"""

from __future__ import annotations

import bisect

from frictex.device.link.ledger import Snapshot

#: skips remembered for mapping sample numbers back (10 s of 2.5 ms blocks skipped back
#: to back; older samples map as if nothing before them was skipped)
KEEP_SKIPS = 4096
#: a device waiting for its prefill is behind once it holds, or has on its way, this many
#: prefills: more than it needs to start, so what arrives later would play later (a
#: device starved by a slow transport; at a stream's start the Status that says it
#: started playing may come two blocks after it did)
WAITING_PREFILLS = 3
#: a playing device is taken to have played on at its rate since its last report for at
#: most this many prefills (20 ms at the live default, four heartbeats): past that, it
#: is taken to have stopped where the estimate reached (its reports are not coming, so
#: neither, maybe, are the blocks), and what is sent meanwhile counts as ahead of it
HORIZON_PREFILLS = 4


def behind(snapshot: Snapshot | None, now_s: float, rate_hz: float, sent_end: int,
           prefill: int, queued: int = 0) -> bool:
    """Is a live stream's next block late before it leaves? Yes when ``queued`` samples
    (the blocks queued behind it) already make up the ``prefill``: they are fresher and
    enough for the device; when the device, as last reported and extrapolated to
    ``now_s`` (s; at most :data:`HORIZON_PREFILLS` prefills past the report), plays at
    least ``prefill`` samples (held or on their way) before the block; or when it waits
    for its prefill and holds or has on its way :data:`WAITING_PREFILLS` of them."""
    if queued >= prefill:
        return True
    if snapshot is None:
        return False
    played, end = snapshot.level(now_s, rate_hz, sent_end, horizon=HORIZON_PREFILLS * prefill)
    return end - played >= (prefill if snapshot.playing else WAITING_PREFILLS * prefill)


class IndexMap:
    """The host's sample numbers (the pipeline's) and the device's, after skips: a
    sample ``h`` goes out as ``h - skipped``, ``skipped`` being the samples skipped
    before it."""

    def __init__(self, keep: int = KEEP_SKIPS):
        self.keep = int(keep)
        self.skipped = 0
        # one entry per skip, oldest first: host start and end of the skipped samples,
        # the device number the next sample took, the samples skipped up to its end
        self._host_start: list[int] = []
        self._host_end: list[int] = []
        self._device_from: list[int] = []
        self._total: list[int] = []
        self._base = 0  # samples skipped by the skips no longer remembered

    def to_device(self, host_start: int) -> int:
        """The device's number for a block the host sends now (after every skip so far)."""
        return host_start - self.skipped

    def skip(self, host_start: int, n: int) -> None:
        """Host samples ``host_start .. host_start + n - 1`` are not sent."""
        self._host_start.append(host_start)
        self._host_end.append(host_start + n)
        self._device_from.append(host_start - self.skipped)
        self.skipped += n
        self._total.append(self.skipped)
        if len(self._total) > self.keep:
            cut = len(self._total) - self.keep // 2
            self._base = self._total[cut - 1]
            for column in (self._host_start, self._host_end, self._device_from, self._total):
                del column[:cut]

    def device_index(self, host: int) -> int:
        """The device's number of host sample ``host``; a skipped sample's is that of the
        first sample sent after it (the first one played in its stead)."""
        k = bisect.bisect_right(self._host_start, host) - 1
        if k < 0:
            return host - self._base
        if host < self._host_end[k]:
            return self._device_from[k]
        return host - self._total[k]

    def host_index(self, device: int) -> int:
        """The host's number of device sample ``device`` (the inverse of
        :meth:`device_index` on the samples sent)."""
        k = bisect.bisect_right(self._device_from, device) - 1
        return device + (self._total[k] if k >= 0 else self._base)

    def host_runs(self, device_start: int, n: int) -> list[tuple[int, int, int]]:
        """Device samples ``device_start ..`` (``n`` of them) as runs of consecutive host
        numbers: ``(host start, first, end)`` with ``first:end`` slicing the ``n``."""
        runs, lo = [], 0
        k = bisect.bisect_right(self._device_from, device_start)
        while k < len(self._device_from) and self._device_from[k] - device_start < n:
            cut = self._device_from[k] - device_start
            if cut > lo:
                runs.append((self.host_index(device_start + lo), lo, cut))
                lo = cut
            k += 1
        runs.append((self.host_index(device_start + lo), lo, n))
        return runs

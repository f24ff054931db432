"""CPU time a virtual machine's host took from it (``steal`` in Linux's /proc/stat).

A haptic block that misses its deadline on a virtual machine may have had no CPU at
all: on this project's 2-core VM the host took up to 60 % of the time in some seconds,
and misses came in bursts then, in thread and process mode alike. The demo reports the
share over its run beside its deadline misses, so a reader can tell the two apart.
"""

from __future__ import annotations

from pathlib import Path

PROC_STAT = Path("/proc/stat")


def cpu_times(stat: Path = PROC_STAT) -> tuple[int, int] | None:
    """(steal, total) jiffies summed over all CPUs since boot, or None where the file is
    missing or has no steal column (not Linux, or a kernel before 2.6.11)."""
    try:
        with stat.open(encoding="ascii") as f:
            fields = f.readline().split()
    except OSError:
        return None
    if len(fields) < 9 or fields[0] != "cpu":
        return None
    # user nice system idle iowait irq softirq steal [guest guest_nice: already in user, nice]
    jiffies = [int(v) for v in fields[1:9]]
    return jiffies[7], sum(jiffies)


class StealMeter:
    """Share (%) of CPU time stolen between construction and :meth:`percent`."""

    def __init__(self, stat: Path = PROC_STAT):
        self.stat = stat
        self.start = cpu_times(stat)

    def percent(self) -> float | None:
        """Steal since construction, % of all CPU time; None if not measurable."""
        end = cpu_times(self.stat)
        if self.start is None or end is None or end[1] <= self.start[1]:
            return None
        return 100.0 * (end[0] - self.start[0]) / (end[1] - self.start[1])

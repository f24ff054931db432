"""Whole processes timed as a user runs them, and the machine's load beside the figures.

``frictex bench``'s sections time commands in fresh processes (interpreter start,
imports, kernels, work and exit), the way ``/usr/bin/time -v`` does: wall time from
fork to exit and the child's user + system CPU from ``wait4``. Several commands compared
with each other run alternated, one of each per round (``alternated``), so that a change
in the machine's load during the measurement falls on all of them alike.
"""

from __future__ import annotations

import os
import subprocess
import sys
import time
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Run:
    """One finished process: wall time (s), user + system CPU (s), peak memory (MiB)
    and its exit code."""

    wall_s: float
    cpu_s: float
    peak_mib: float
    code: int


def load() -> float:
    """The machine's load: the 1-minute average of runnable processes (``os.getloadavg``;
    NaN where the system has none)."""
    try:
        return os.getloadavg()[0]
    except OSError:
        return float("nan")


def cores() -> int:
    """The cores this process may run on."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()


class BusyProcesses:
    """``count`` processes that keep a core busy each, for at most ``seconds`` (each ends
    itself, so none outlives a crashed parent by long), killed on leaving the ``with``."""

    def __init__(self, count: int, seconds: float):
        code = f"import time\nend = time.monotonic() + {seconds!r}\nwhile time.monotonic() < end: pass"
        self.procs = [subprocess.Popen([sys.executable, "-c", code]) for _ in range(count)]

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        for proc in self.procs:
            proc.kill()
            proc.wait(timeout=5.0)


def run_process(argv: list[str]) -> Run:
    """Run ``argv`` to its end, its output discarded; earlier processes' unwritten file
    data is written out first (``os.sync``, not timed), so that no run pays for the
    write-back of the one before."""
    os.sync()
    start = time.perf_counter()
    proc = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - start
    return Run(wall, usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024,
               os.waitstatus_to_exitcode(status))


def frictex_argv(*args: str) -> list[str]:
    """``frictex ARGS`` as this interpreter runs it."""
    return [sys.executable, "-m", "frictex", *args]


def alternated(commands: dict[str, list[str]], rounds: int) -> dict[str, list[Run]]:
    """Each command run ``rounds`` times, one of each per round, in turn; the order within
    a round is reversed every other round (A B, B A, ...) so that neither side always runs
    after the other."""
    runs: dict[str, list[Run]] = {name: [] for name in commands}
    names = list(commands)
    for k in range(rounds):
        for name in (names if k % 2 == 0 else names[::-1]):
            runs[name].append(run_process(commands[name]))
    return runs


def failed_note(failed: int, total: int) -> str:
    """", k of N failed" where ``failed`` of ``total`` runs (or rounds) failed and their
    figures leave them out; "" where none did."""
    return f", {failed} of {total} failed" if failed else ""


def median(runs: list[Run], field: str) -> float:
    """The median of one field over the runs that succeeded (NaN if none did)."""
    values = [getattr(r, field) for r in runs if r.code == 0]
    return float(np.median(values)) if values else float("nan")

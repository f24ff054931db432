"""Whole processes timed as a user runs them, and the machine's load beside the figures.

``frictex bench``'s sections time commands in fresh processes (interpreter start,
imports, kernels, work and exit), the way ``/usr/bin/time -v`` does: wall time from
fork to exit and the child's user + system CPU and peak memory from ``wait4``. Each
command starts from a small launcher process (``LAUNCHER``), not from this one: on Linux
a child's peak resident memory (``ru_maxrss``) starts at its parent's (the parent's
high-water mark is kept across fork and exec), so a command forked from a report holding 200 MiB
would report at least 200 MiB. From the launcher, a peak counts from the launcher's few
MiB at most (``Run.floor_mib``). Several commands compared
with each other run alternated, one of each per round (``alternated``), so that a change
in the machine's load during the measurement falls on all of them alike.
"""

from __future__ import annotations

import os
import subprocess
import sys
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Run:
    """One finished process: wall time (s), user + system CPU (s), peak memory (MiB),
    its exit code and the most of that peak the command can have inherited (MiB): the
    launcher's resident memory when it forked the command (NaN where the system does not
    say)."""

    wall_s: float
    cpu_s: float
    peak_mib: float
    code: int
    floor_mib: float = float("nan")


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
    itself, so none outlives a crashed parent by long), killed on leaving the ``with``.
    ``started`` counts every one this process has started (a bench section's child
    processes include them)."""

    started = 0

    def __init__(self, count: int, seconds: float):
        BusyProcesses.started += count
        code = f"import time\nend = time.monotonic() + {seconds!r}\nwhile time.monotonic() < end: pass"
        self.procs = [subprocess.Popen([sys.executable, "-c", code]) for _ in range(count)]

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        for proc in self.procs:
            proc.kill()
            proc.wait(timeout=5.0)


#: the program of the launcher that forks each measured command (``python -I -S``: no
#: site packages, so it holds a few MiB) and prints, once the command has ended, the
#: command's wall time (s) from fork to exit, user + system CPU (s) and peak resident
#: memory (KiB) from ``wait4``, its exit code, and its own resident memory (KiB, "nan"
#: where /proc does not say) when it forked
LAUNCHER = """
import os, sys, time
def resident_kib():
    try:
        with open('/proc/self/status') as status:
            return next(line.split()[1] for line in status if line.startswith('VmRSS:'))
    except (OSError, StopIteration):
        return 'nan'
floor = resident_kib()
start = time.perf_counter()
pid = os.fork()
if pid == 0:
    try:
        null = os.open(os.devnull, os.O_RDWR)
        os.dup2(null, 1)
        os.dup2(null, 2)
        os.execvp(sys.argv[1], sys.argv[1:])
    finally:
        os._exit(127)
_, status, usage = os.wait4(pid, 0)
wall = time.perf_counter() - start
print(wall, usage.ru_utime + usage.ru_stime, usage.ru_maxrss,
      os.waitstatus_to_exitcode(status), floor)
"""


def run_process(argv: list[str]) -> Run:
    """Run ``argv`` to its end from the launcher (``LAUNCHER``), its output discarded;
    earlier processes' unwritten file data is written out first (``os.sync``, not timed),
    so that no run pays for the write-back of the one before. 127 is the code of a
    command that could not be started."""
    os.sync()
    done = subprocess.run([sys.executable, "-I", "-S", "-c", LAUNCHER, *argv],
                          stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, check=True,
                          text=True)
    wall, cpu, peak_kib, code, floor_kib = done.stdout.split()
    return Run(float(wall), float(cpu), float(peak_kib) / 1024, int(code),
               float(floor_kib) / 1024)


def frictex_argv(*args: str) -> list[str]:
    """``frictex ARGS`` as this interpreter runs it."""
    return [sys.executable, "-m", "frictex", *args]


def alternated(commands: dict[str, list[str]], rounds: int,
               before=None) -> dict[str, list[Run]]:
    """Each command run ``rounds`` times, one of each per round, in turn; the order within
    a round is reversed every other round (A B, B A, ...) so that neither side always runs
    after the other. ``before(name)``, untimed, just before each run of command ``name``
    (None: nothing)."""
    runs: dict[str, list[Run]] = {name: [] for name in commands}
    names = list(commands)
    for k in range(rounds):
        for name in (names if k % 2 == 0 else names[::-1]):
            if before is not None:
                before(name)
            runs[name].append(run_process(commands[name]))
    return runs


def failed_note(failed: int, total: int) -> str:
    """", k of N failed" where ``failed`` of ``total`` runs (or rounds) failed and their
    figures leave them out; "" where none did."""
    return f", {failed} of {total} failed" if failed else ""


def medians_of(runs: list[Run]) -> str:
    """"median of K" over the runs that succeeded (those ``median`` keeps), with
    ``failed_note`` where some failed."""
    ok = sum(r.code == 0 for r in runs)
    return f"median of {ok}{failed_note(len(runs) - ok, len(runs))}"


def median(runs: list[Run], field: str) -> float:
    """The median of one field over the runs that succeeded (NaN if none did)."""
    values = [getattr(r, field) for r in runs if r.code == 0]
    return float(np.median(values)) if values else float("nan")

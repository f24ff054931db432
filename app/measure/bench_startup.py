"""``frictex bench startup``: what each command costs as a whole process.

Every command a user types, each in a fresh process from the interpreter's start to its
exit (``app.measure.processes``): ``--version``, ``library``, ``validate``, and a
one-second replay into each output format, beside two floors measured in the same rounds:
the interpreter alone (``python -c pass``) and the interpreter importing numpy. The
commands run alternated, one of each per round (15 rounds; 5 with ``--quick``), and each
figure is the median over the rounds: wall time (what a user waits) and user + system
CPU (what the machine's load does not change much); ``frictex bench`` prints the
machine's load before and after. ``python -X importtime -m frictex ...`` says where a command's
start-up goes. With ``PYTHONDONTWRITEBYTECODE`` set, Python caches no compiled modules and
every command compiles frictex's again: the section says so.

Targets (issue 31): ``frictex --version`` under 0.15 s; a one-second replay under 0.5 s
of wall time on a quiet machine.
"""

from __future__ import annotations

import os
import sys
import tempfile
from pathlib import Path

from frictex.app.measure.bench_replay import SCENE, human_trace
from frictex.app.measure.figure import Figure
from frictex.app.measure.processes import alternated, frictex_argv, median
from frictex.rendering.input.trace_file import write_trace


def commands(tmp: Path) -> dict[str, list[str]]:
    """name -> argv of every command timed, the floors first."""
    trace = tmp / "one-second.csv"
    write_trace(trace, human_trace(1.0))
    found = {"python -c pass (floor)": [sys.executable, "-c", "pass"],
             "python -c 'import numpy' (floor)": [sys.executable, "-c", "import numpy"],
             "frictex --version": frictex_argv("--version"),
             "frictex library": frictex_argv("library"),
             "frictex validate grating-5mm": frictex_argv("validate", "grating-5mm")}
    for fmt in ("parquet", "npz", "csv"):
        found[f"frictex replay, one second, {fmt}"] = frictex_argv(
            "replay", SCENE, str(trace), "--out", str(tmp / f"out-{fmt}"), "--format", fmt,
            "--quiet")
    return found


def run(quick: bool) -> list[Figure]:
    if os.environ.get("PYTHONDONTWRITEBYTECODE"):
        # measured here: about 70 frictex modules compiled again by every one-second
        # replay, 80 ms of its 0.52-0.60 s
        print("frictex: bench startup: PYTHONDONTWRITEBYTECODE is set, so every command "
              "compiles frictex's modules from source again; unset it for the start-up a "
              "user gets", file=sys.stderr)
    rounds = 5 if quick else 15
    with tempfile.TemporaryDirectory(prefix="frictex-startup-") as name:
        runs = alternated(commands(Path(name)), rounds)
    figures = []
    for label, got in runs.items():
        failed = sum(r.code != 0 for r in got)
        note = f", {failed} of {rounds} failed" if failed else ""
        figures += [Figure("startup", f"{label}, wall (median of {rounds}, alternated{note})",
                           median(got, "wall_s"), "s"),
                    Figure("startup", f"{label}, CPU user + system (median of {rounds})",
                           median(got, "cpu_s"), "s")]
    return figures

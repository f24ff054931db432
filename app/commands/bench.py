"""``frictex bench``: speed figures, measured here and now (never asserted in tests).

Each section is a module ``app.measure.bench_<name>`` with ``run(quick: bool) -> list[Figure]``.
A section whose optional dependency is missing reports why instead of failing the rest.
Every section's figures are printed between the machine's load (the 1-minute average)
at its start and at its end, and followed by the section's whole wall time and CPU, this
process's apart from its child processes' (which include the busy processes some
sections start as load), so that a figure is read with the load it was measured under.

Plain text is printed section by section as each ends, so that the figures of finished
sections stay on the screen when a later section is interrupted (Ctrl-C) or crashes.
``--json`` prints one JSON document, a list of every figure, once the sections end, or
are interrupted or crash (the figures of the finished ones); a figure that is not a
number (NaN: every run it is over failed) is ``null`` there. The exit status is 1 where
a section's figures include failed runs (a NaN figure or a label saying how many runs
failed), each such section named on one line of standard error.
"""

from __future__ import annotations

import argparse
import importlib
import json
import math
import resource
import sys
import time
from dataclasses import asdict

from frictex.app.engine.summary import finite_json
from frictex.app.measure.figure import Figure
from frictex.device.errors import InputError

#: section name -> module
SECTIONS = {
    "pipeline": "frictex.app.measure.bench_pipeline",
    "replay": "frictex.app.measure.bench_replay",
    "link": "frictex.app.measure.bench_link",
    "visual": "frictex.app.measure.bench_visual",
    "modal": "frictex.app.measure.bench_modal",
    "startup": "frictex.app.measure.bench_startup",
    "baseline": "frictex.app.measure.bench_baseline",
    "latency": "frictex.app.measure.bench_latency",
}


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("sections", nargs="*", metavar="SECTION",
                        help=f"sections to run (default: all of {', '.join(SECTIONS)})")
    parser.add_argument("--quick", action="store_true", help="shorter runs (less precise figures)")
    parser.add_argument("--json", action="store_true",
                        help="print the figures as one JSON document once the sections end "
                             "(NaN as null); plain text is printed as each section ends")


def _cpu_s(who: int) -> float:
    """User + system CPU seconds so far of ``who`` (``resource.RUSAGE_SELF`` or
    ``RUSAGE_CHILDREN``: the waited-for child processes)."""
    usage = resource.getrusage(who)
    return usage.ru_utime + usage.ru_stime


def _children_label(loaded: bool) -> str:
    """The label of a section's child processes' CPU: what those children are (``loaded``:
    the section started busy processes as load, ``processes.BusyProcesses``)."""
    which = ("the commands it ran and the busy processes it started as load"
             if loaded else "the commands it ran")
    return f"the whole section, CPU user + system of its child processes ({which})"


def _measured(name: str, section, quick: bool) -> list[Figure]:
    """A section's figures between the machine's load before and after it, the whole
    section's wall time and CPU (user + system, s) of this process and, apart, of the
    child processes it ran."""
    from frictex.app.measure.processes import BusyProcesses, load

    busy0 = BusyProcesses.started
    own0, children0 = _cpu_s(resource.RUSAGE_SELF), _cpu_s(resource.RUSAGE_CHILDREN)
    before, wall0 = load(), time.perf_counter()
    figures = section(quick)
    wall = time.perf_counter() - wall0
    own = _cpu_s(resource.RUSAGE_SELF) - own0
    children = _cpu_s(resource.RUSAGE_CHILDREN) - children0
    return [Figure(name, "machine load at the start (1-minute average)", before, ""),
            *figures,
            Figure(name, "machine load at the end (1-minute average)", load(), ""),
            Figure(name, "the whole section, wall", wall, "s"),
            Figure(name, "the whole section, CPU user + system of this process", own, "s"),
            Figure(name, _children_label(BusyProcesses.started > busy0), children, "s")]


def failed_figures(figures: list[Figure]) -> list[Figure]:
    """The figures that include failed runs (``Figure.failed``) or are not a number (NaN:
    nothing was measured)."""
    return [f for f in figures if f.failed or not math.isfinite(f.value)]


def print_text(figures: list[Figure]) -> None:
    """One line per figure: section, label (padded to the longest), value, unit."""
    width = max((len(f.label) for f in figures), default=10)
    for f in figures:
        print(f"{f.section:9s} {f.label:<{width}s} {f.value:14.4g} {f.unit}", flush=True)


def json_text(figures: list[Figure]) -> str:
    """The figures as one JSON list, each non-finite value written as null."""
    return json.dumps(finite_json([asdict(f) for f in figures]), indent=2, allow_nan=False)


def run(args: argparse.Namespace) -> int:
    unknown = [s for s in args.sections if s not in SECTIONS]
    if unknown:
        raise InputError(f"unknown bench section(s) {', '.join(unknown)}; "
                         f"expected some of {', '.join(SECTIONS)}")
    figures: list[Figure] = []
    failed_sections = 0
    try:
        for name in args.sections or list(SECTIONS):
            try:
                module = importlib.import_module(SECTIONS[name])
            except ModuleNotFoundError as exc:
                print(f"frictex: bench {name}: not available ({exc})", file=sys.stderr)
                continue
            section = _measured(name, module.run, args.quick)
            figures.extend(section)
            if not args.json:
                print_text(section)
            failed = failed_figures(section)
            if failed:
                failed_sections += 1
                print(f"frictex: bench {name}: {len(failed)} figure(s) include failed runs: "
                      f"{'; '.join(f.label for f in failed)}", file=sys.stderr)
    finally:
        if args.json:
            print(json_text(figures))
    return 1 if failed_sections else 0

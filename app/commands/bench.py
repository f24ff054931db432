"""``frictex bench``: speed figures, measured here and now (never asserted in tests).

Each section is a module ``app.measure.bench_<name>`` with ``run(quick: bool) -> list[Figure]``.
A section whose optional dependency is missing reports why instead of failing the rest.
Every section's figures are printed between the machine's load (the 1-minute average)
at its start and at its end, and followed by the section's whole wall time and CPU, this
process's apart from its child processes' (which include the busy processes some
sections start as load), so that a figure is read with the load it was measured under.
"""

from __future__ import annotations

import argparse
import importlib
import json
import resource
import sys
import time
from dataclasses import asdict

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
    parser.add_argument("--json", action="store_true", help="print the figures as JSON")


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


def run(args: argparse.Namespace) -> int:
    unknown = [s for s in args.sections if s not in SECTIONS]
    if unknown:
        raise InputError(f"unknown bench section(s) {', '.join(unknown)}; "
                         f"expected some of {', '.join(SECTIONS)}")
    figures: list[Figure] = []
    for name in args.sections or list(SECTIONS):
        try:
            module = importlib.import_module(SECTIONS[name])
        except ModuleNotFoundError as exc:
            print(f"frictex: bench {name}: not available ({exc})", file=sys.stderr)
            continue
        figures.extend(_measured(name, module.run, args.quick))
    if args.json:
        print(json.dumps([asdict(f) for f in figures], indent=2))
    else:
        width = max((len(f.label) for f in figures), default=10)
        for f in figures:
            print(f"{f.section:9s} {f.label:<{width}s} {f.value:14.4g} {f.unit}")
    return 0

"""``frictex bench``: speed figures, measured here and now (never asserted in tests).

Each section is a module ``app.measure.bench_<name>`` with ``run(quick: bool) -> list[Figure]``.
A section whose optional dependency is missing reports why instead of failing the rest.
"""

from __future__ import annotations

import argparse
import importlib
import json
import sys
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
}


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("sections", nargs="*", metavar="SECTION",
                        help=f"sections to run (default: all of {', '.join(SECTIONS)})")
    parser.add_argument("--quick", action="store_true", help="shorter runs (less precise figures)")
    parser.add_argument("--json", action="store_true", help="print the figures as JSON")


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
        figures.extend(module.run(args.quick))
    if args.json:
        print(json.dumps([asdict(f) for f in figures], indent=2))
    else:
        width = max((len(f.label) for f in figures), default=10)
        for f in figures:
            print(f"{f.section:9s} {f.label:<{width}s} {f.value:14.4g} {f.unit}")
    return 0

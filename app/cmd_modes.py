"""``frictex modes beam|plate|ring``: natural frequencies, wavelengths and nodes of a structure.

Each structure is a module of ``app`` (table :data:`STRUCTURES`) with
``add_arguments(parser)`` and ``run(args) -> int``; a structure whose module is not
installed answers "not available". The helpers here print the common table or JSON,
``{"modes": [{"order", "frequency_hz", "wavelength_mm", "nodes_mm"}, ...]}`` (a
structure may add keys to each mode, e.g. the plate's ``axis``), and save plots.
"""

from __future__ import annotations

import argparse
import importlib
import json

STRUCTURES = {"beam": "app.modes_beam", "plate": "app.modes_plate", "ring": "app.modes_ring"}


def add_arguments(parser: argparse.ArgumentParser) -> None:
    sub = parser.add_subparsers(dest="structure", metavar="STRUCTURE", required=True)
    for name, module_name in STRUCTURES.items():
        try:
            module = importlib.import_module(module_name)
        except ModuleNotFoundError as exc:
            if exc.name != module_name:
                raise
            # no option syntax, so whatever follows reaches run() and its one-line answer
            missing = sub.add_parser(name, help="not available in this installation",
                                     prefix_chars="\0", add_help=False)
            missing.add_argument("rest", nargs="*")
            missing.set_defaults(structure_run=_not_available(name, module_name))
            continue
        summary = (module.__doc__ or name).strip().splitlines()[0]
        structure = sub.add_parser(name, help=summary, description=module.__doc__,
                                   formatter_class=argparse.RawDescriptionHelpFormatter)
        module.add_arguments(structure)
        structure.set_defaults(structure_run=module.run)


def _not_available(name: str, module_name: str):
    def run(args: argparse.Namespace) -> int:
        raise ValueError(f"modes {name}: not available (module {module_name} is not installed)")
    return run


def run(args: argparse.Namespace) -> int:
    return args.structure_run(args)


def add_output_arguments(parser: argparse.ArgumentParser) -> None:
    """--json and --plot, shared by every structure."""
    parser.add_argument("--json", action="store_true",
                        help='print {"modes": [{"order", "frequency_hz", "wavelength_mm", '
                             '"nodes_mm"}, ...]} instead of a table')
    parser.add_argument("--plot", metavar="PNG",
                        help="also write a plot of the modes and of det Phi over finger positions")


def print_modes(title: str, modes: list[dict], as_json: bool) -> None:
    """Print ``modes`` (dicts with order, frequency_hz, wavelength_mm, nodes_mm) as JSON or a table."""
    if as_json:
        print(json.dumps({"modes": modes}, indent=2))
        return
    print(title)
    extra = [k for k in modes[0] if k not in ("order", "frequency_hz", "wavelength_mm", "nodes_mm")]
    print("".join(f"{k:>6s} " for k in extra) + "order  frequency_hz  wavelength_mm  nodes  nodes_mm")
    for m in modes:
        nodes = " ".join(f"{x:.2f}" for x in m["nodes_mm"])
        print("".join(f"{str(m[k]):>6s} " for k in extra)
              + f"{m['order']:5d}  {m['frequency_hz']:12.1f}  {m['wavelength_mm']:13.3f}  "
                f"{len(m['nodes_mm']):5d}  {nodes}")


def save_figure(fig, path: str) -> None:
    """Write ``fig`` to ``path`` (PNG) and say where; OSError becomes a one-line error."""
    fig.savefig(path, dpi=110)
    print(f"plot written to {path}")

"""``frictex modes beam|plate|ring``: natural frequencies, wavelengths and nodes of a structure.

Each structure is a module of ``app.commands`` (table :data:`STRUCTURES`) with
``add_arguments(parser)`` and ``run(args) -> int``; a structure whose module is not
installed answers "not available". ``app.commands.modes_output`` prints the common table or JSON,
``{"modes": [{"order", "frequency_hz", "wavelength_mm", "nodes_mm"}, ...]}`` (a
structure may add keys to each mode, e.g. the plate's ``axis``), and save plots.

Each structure refuses, in one line naming the option, what its model cannot describe
(an order above 100 or given twice, a wavelength under the thickness, a beam thicker
than long, a ring thicker than its radius) and warns where the model still computes but
leaves its validity (a wavelength under 6 thicknesses for the theories without shear).
"""

from __future__ import annotations

import argparse
import importlib

from frictex.device.errors import FrictexError

STRUCTURES = {"beam": "frictex.app.commands.modes_beam", "plate": "frictex.app.commands.modes_plate", "ring": "frictex.app.commands.modes_ring"}


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
        raise FrictexError(f"modes {name}: not available (module {module_name} is not installed)")
    return run


def run(args: argparse.Namespace) -> int:
    return args.structure_run(args)

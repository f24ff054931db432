"""What ``frictex modes`` prints for every structure: a table or JSON of the modes, and plots."""

from __future__ import annotations

import argparse
import json


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

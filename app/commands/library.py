"""``frictex library``: the bundled scenes, traces and experiment protocols, and the
scenes saved from the demo's layer panel, one line each."""

from __future__ import annotations

import argparse

from frictex.app.experiment import PROTOCOLS_DIR
from frictex.textures.library import (list_saved_scenes, list_scenes, list_toml_files,
                                      list_traces)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--paths", action="store_true", help="also print each file's path "
                        "(always for a saved scene, which opens by its path)")


def run(args: argparse.Namespace) -> int:
    entries = (list_scenes() + list_saved_scenes() + list_traces()
               + list_toml_files(PROTOCOLS_DIR, "protocol"))
    width = max((len(e.name) for e in entries), default=0)
    kind_width = max((len(e.kind) for e in entries), default=0)
    for e in entries:
        line = f"{e.name:<{width}}  {e.kind:<{kind_width}}  {e.description}"
        print(f"{line}  [{e.path}]" if args.paths or e.kind == "saved" else line)
    return 0

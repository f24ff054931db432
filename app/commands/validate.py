"""``frictex validate FILE...``: check texture files and report every problem.

For each file: ``ok FILE (n layers)`` on stdout, or every problem as one line on stderr,
``frictex: error: FILE:LINE: field: message`` (the README's form for every error);
warnings (legal but probably unintended, such as a mu' the device cannot reach at its
nominal force) as ``frictex: warning: FILE:LINE: field: message``. Exit 0 if every file
is good (warnings allowed), 2 if any is bad.
"""

from __future__ import annotations

import argparse
import sys

from frictex.textures.errors import TextureError
from frictex.textures.library import resolve_scene
from frictex.textures.loader import check_scene
from frictex.textures.outside import add_allow_outside


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("files", nargs="+", metavar="FILE",
                        help="texture file (.toml), or a bundled scene name (see frictex library)")
    add_allow_outside(parser)


def run(args: argparse.Namespace) -> int:
    bad = 0
    for name in args.files:
        try:
            path = resolve_scene(name)
        except TextureError as exc:
            print(f"frictex: error: {exc}", file=sys.stderr)
            bad += 1
            continue
        scene, problems, warnings = check_scene(path)
        for problem in problems:
            print(f"frictex: error: {problem}", file=sys.stderr)
        for warning in warnings:
            print(f"frictex: warning: {warning}", file=sys.stderr)
        if scene is None:
            bad += 1
        else:
            n = len(scene.layers)
            print(f"ok {path} ({n} layer{'s' * (n != 1)})")
    if bad and len(args.files) > 1:
        print(f"frictex: error: {bad} of {len(args.files)} files have problems", file=sys.stderr)
    return 2 if bad else 0

"""``frictex validate FILE...``: check texture files and report every problem.

For each file: ``ok FILE (n layers)`` on stdout, or every problem as one line on stderr,
``frictex: error: FILE:LINE: field: message`` (the README's form for every error);
warnings (legal but probably unintended) as ``frictex: warning: FILE:LINE: field:
message``. Two kinds of warning concern reach, at the scene's nominal normal force
(``[device] normal_force_n``): a layer asking on its own for a mu' below the device's
floor (the loader's, with the line of its key), and layers whose *product* goes below it
(``rendering.reach``: the share of the display's area and of a typical stroke run
through the scene's pipeline, and the layers that cause it).

Exit 0 if every file is good (warnings allowed), 2 if any is bad. ``--strict`` counts a
file with warnings as bad: exit 2, because a warning is about what the file asks for
(bad input for a session that must render it as written); 1 stays for failures of the
program's surroundings (device, link, output space).
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
    parser.add_argument("--strict", action="store_true",
                        help="a file with warnings fails too (exit 2), e.g. a scene whose "
                             "layers together ask for a friction below the device's floor")
    add_allow_outside(parser)


def _share(fraction: float) -> str:
    """A share as a percentage, never rounding a share above 0 to "0.0%"."""
    return "under 0.1%" if 0.0 < fraction < 0.0005 else f"{fraction:.1%}"


def reach_warning(path, scene) -> str | None:
    """The warning for a scene whose layers together ask for mu' below the device's floor
    (``rendering.reach.scene_reach``), or None."""
    from frictex.device.safe_text import escape_path
    from frictex.rendering.reach import STROKE_S, scene_reach

    reach = scene_reach(scene)
    if not reach.below:
        return None
    causes = ", ".join(f'"{name}"' for name in reach.causes) or "the layers together"
    return (f"{escape_path(path)}: layers: {_share(reach.stroke_share)} of a typical stroke "
            f"({STROKE_S:g} s) and {_share(reach.area_share)} of the display ask for mu' below the "
            f"device's floor {reach.floor:.4g} at the nominal {reach.force_n:g} N (down to "
            f"{reach.lowest:.3g}): the product of layers {causes}; those targets will be "
            f"clamped to the floor")


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
        notes = [str(w) for w in warnings]
        reach = reach_warning(path, scene) if scene is not None else None
        notes += [reach] if reach is not None else []
        for note in notes:
            print(f"frictex: warning: {note}", file=sys.stderr)
        if scene is None:
            bad += 1
        elif args.strict and notes:
            print(f"frictex: error: {path}: {len(notes)} warning{'s' * (len(notes) != 1)} "
                  f"(--strict)", file=sys.stderr)
            bad += 1
        else:
            n = len(scene.layers)
            print(f"ok {path} ({n} layer{'s' * (n != 1)})")
    if bad and len(args.files) > 1:
        print(f"frictex: error: {bad} of {len(args.files)} files have problems", file=sys.stderr)
    return 2 if bad else 0

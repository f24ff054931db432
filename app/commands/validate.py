"""``frictex validate FILE...``: check texture files and report every problem.

For each file: ``ok FILE (n layers)`` on stdout, or every problem as one line on stderr,
``frictex: error: FILE:LINE: field: message`` (the README's form for every error);
warnings (legal but probably unintended) as ``frictex: warning: FILE:LINE: field:
message``. Two kinds of warning concern reach, at the scene's nominal normal force
(``[device] normal_force_n``): a layer asking on its own for a mu' below the device's
floor (the loader's, with the line of its key), and layers whose *product* goes below it
(``rendering.reach``: the share of the display's area and of a typical stroke run
through the scene's pipeline, and the layers that cause it; ``textures.overlap``: the
lowest product where layers overlap, and those layers). On a travelling-wave scene also
forces (``rendering.reach.force_reach``): the share of typical strokes (over the display
and each directional or guidance layer's region), and of a press on each key-click
button, asking for a force out of the wave's reach.

A layer's ``render`` may name another package's renderer (entry-point group
``frictex.renderers``); the name is checked by the loader, and the renderer is imported
here as a replay would import it, so that one that cannot be loaded (a module or object
that is not there, an import that fails) is a problem of the file's layer, naming the
entry point, not a replay's failure later.

Exit 0 if every file is good (warnings allowed), 2 if any is bad. ``--strict`` counts a
file with warnings as bad: exit 2, because a warning is about what the file asks for
(bad input for a session that must render it as written); 1 stays for failures of the
program's surroundings (device, link, output space).

``--perception`` adds what a finger can feel (``rendering.perception``, each threshold
with its source): a scene's features below the published thresholds, and for an
experiment protocol (a file with a top-level ``method``, or a bundled protocol's name
where no file and no bundled scene has that name) its scenes and its stimuli compared
pair by pair (``app.experiment.perception_check``); a protocol's ok line counts its
perception warnings and, apart from them, its rendering notes. These are printed as
``frictex: warning: FILE: perception: ...``, and a periodic layer finer than the touch
samples can place (a limit of rendering, not of perception: what the layer's renderer
makes of it) as ``frictex: warning: FILE: rendering: ...``. They never fail a file, not
even with ``--strict``: they say what a finger will not tell apart or how a layer
renders, not what the file asks for.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from frictex.device.safe_text import printable
from frictex.device.safe_text import escape_path

from frictex.device.registry import PluginError
from frictex.textures.errors import Locator, Problem, TextureError
from frictex.textures.library import resolve_scene
from frictex.textures.loader import check_scene
from frictex.textures.model import RENDERERS, SHO
from frictex.textures.outside import add_allow_outside


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("files", nargs="+", metavar="FILE",
                        help="texture file (.toml), or a bundled scene name (see frictex "
                             "library); with --perception also an experiment protocol: a file "
                             "with a top-level 'method', or a bundled protocol's name (a name "
                             "is looked up among the scenes first, then the protocols)")
    parser.add_argument("--strict", action="store_true",
                        help="a file with warnings fails too (exit 2), e.g. a scene whose "
                             "layers together ask for a friction below the device's floor")
    parser.add_argument("--perception", action="store_true",
                        help="also report features a finger cannot feel (published thresholds, "
                             "each with its source) and periods finer than the touch samples "
                             "can place (what the layer's renderer makes of them); FILE may be "
                             "an experiment protocol (file or bundled name), whose stimuli are "
                             "compared pair by pair; warnings only, perception warnings counted "
                             "apart from rendering notes")
    add_allow_outside(parser)


def _share(fraction: float) -> str:
    """A share as a percentage, never rounding a share above 0 to "0.0%"."""
    return "under 0.1%" if 0.0 < fraction < 0.0005 else f"{fraction:.1%}"


def _names(names) -> str:
    """``layers "a", "b"`` or ``layer "a"``."""
    return f"layer{'s' * (len(names) != 1)} " + ", ".join(f'"{name}"' for name in names)


def reach_warning(path, scene) -> str | None:
    """The warning for a scene whose layers together ask for mu' below the device's floor
    (``rendering.reach.scene_reach``), or None. It names the layers that lower mu' where
    the typical stroke and the display's map fall below the floor (``Reach.causes``), and
    the lowest product of the layers' lowest mu' where their extents overlap, with the
    layers that overlap there (``textures.overlap``), for a finger touching alone."""
    from frictex.rendering.reach import STROKE_S, scene_reach

    reach = scene_reach(scene)
    if not reach.below:
        return None
    causes = f"from {_names(reach.causes)}" if reach.causes else "from the layers together"
    overlap = reach.overlap
    where = (f"the product of {_names(overlap.names)}" if len(overlap.names) > 1
             else f"{_names(overlap.names)} alone")
    return (f"{escape_path(path)}: layers: {_share(reach.stroke_share)} of a typical stroke "
            f"({STROKE_S:g} s) and {_share(reach.area_share)} of the display ask for mu' below the "
            f"device's floor {reach.floor:.4g} at the nominal {reach.force_n:g} N, {causes}; lowest "
            f"where layers overlap: {overlap.lowest:.3g}, {where}; those targets will be clamped "
            f"to the floor")


def force_reach_warnings(path, scene) -> list[str]:
    """The warnings for a travelling-wave scene whose typical stroke, or a press on one of
    its key-click buttons, asks for forces out of the wave's reach
    (``rendering.reach.force_reach``)."""
    from frictex.rendering.reach import PRESS_PEAK, STROKE_S, force_reach

    reach = force_reach(scene)
    if reach is None:
        return []
    why = ("beyond what the actuators give within the amplifier's limit or, on a finite "
           "beam, where the travelling-wave ratio falls away from mid-span; those forces will "
           "be clamped to the nearest reachable (summary.json: clamps.unreachable)")
    found = []
    if reach.stroke_share:
        found.append(f"{escape_path(path)}: forces: {_share(reach.stroke_share)} of typical "
                     f"strokes ({STROKE_S:g} s over the display, and over each directional or "
                     f"guidance layer's region) asks for a tangential force out of the wave's "
                     f"reach, {why}")
    found += [f'{escape_path(path)}: forces: key-click "{name}": {_share(share)} of a press '
              f"at its centre (to {PRESS_PEAK:g} times click_n) asks for a push out of the "
              f"wave's reach, {why}" for name, share in reach.presses if share]
    return found


def renderer_problems(path, scene) -> list[Problem]:
    """A problem for each layer of ``scene`` (read from ``path``) whose ``render`` names a
    renderer that cannot be loaded (``textures.model.RENDERERS``: a plugin's entry point
    whose module or object is missing, or whose import fails)."""
    problems = []
    for index, layer in enumerate(scene.layers):
        if layer.render == SHO:
            continue
        try:
            RENDERERS.get(layer.render)
        except PluginError as exc:
            line = Locator(Path(path).read_text(encoding="utf-8")).line(("layer", index, "render"))
            problems.append(Problem(str(path), line, f"layer[{index + 1}].render",
                                    f'"{layer.name}": {exc}'))
    return problems


def _is_protocol(name: str) -> bool:
    """True for a readable TOML file with a top-level ``method`` (an experiment protocol).
    A file the safe reader refuses (too large, deep, not a regular file) is not one: the
    texture loader then reports it."""
    from frictex.textures.schema import Reader
    from frictex.textures.toml_safe import parse_toml, read_text

    r = Reader(name, None)
    text = read_text(Path(name), r)
    doc = parse_toml(text, r) if text is not None else None
    return doc is not None and "method" in doc


def _about(finding) -> str:
    """"rendering" for a note on how a layer renders (``RENDERING_KINDS``), else
    "perception" (what a finger will not feel)."""
    from frictex.rendering.perception import RENDERING_KINDS
    return "rendering" if finding.kind in RENDERING_KINDS else "perception"


def _perception(label, findings) -> None:
    """Print ``findings`` (``rendering.perception``), each as "perception:" or
    "rendering:" (:func:`_about`)."""
    for finding in findings:
        print(f"frictex: warning: {escape_path(label)}: {_about(finding)}: "
              f"{printable(finding.message)}", file=sys.stderr)


def _counted(count: int, what: str) -> str:
    """``1 perception warning``, ``2 rendering notes``."""
    return f"{count} {what}{'s' * (count != 1)}"


def _protocol(path) -> bool:
    """Check the protocol file ``path`` with --perception; True if it is good. Its ok line
    counts the perception warnings, and apart from them any rendering notes."""
    from frictex.app.experiment.perception_check import protocol_findings
    from frictex.app.experiment.protocol import check_protocol

    protocol, problems = check_protocol(path)
    for problem in problems:
        print(f"frictex: error: {printable(str(problem))}", file=sys.stderr)
    if protocol is None:
        return False
    findings = protocol_findings(protocol)
    _perception(path, findings)
    rendering = sum(_about(finding) == "rendering" for finding in findings)
    notes = f", {_counted(rendering, 'rendering note')}" if rendering else ""
    print(f"ok {escape_path(path)} (protocol, "
          f"{_counted(len(findings) - rendering, 'perception warning')}{notes})")
    return True


def _find(name: str, perception: bool) -> tuple[str, Path]:
    """What ``name`` is and its file: ``("protocol", path)`` with --perception for a file
    with a top-level ``method`` or, when no file ``name`` exists and no bundled scene has
    that name, a bundled protocol's name; else ``("scene", path)``. TextureError saying
    which kinds of bundled name were searched when it is none of them."""
    from frictex.app.experiment.protocol import (bundled_protocol, names_a_path,
                                                 protocol_names, unknown_name)
    from frictex.textures.library import list_scenes

    if perception and _is_protocol(name):
        return "protocol", Path(name)
    try:
        return "scene", resolve_scene(name)
    except TextureError:
        protocol = bundled_protocol(name)
        if protocol is not None and perception:
            return "protocol", protocol
        if protocol is not None:
            raise TextureError(f"{escape_path(name)}: no bundled scene of that name, but a "
                               f"bundled protocol: frictex validate --perception checks "
                               f"protocols") from None
        if not perception or names_a_path(name):  # a missing path: no name was looked up
            raise
        raise TextureError(unknown_name(name, {"scene": [entry.name for entry in list_scenes()],
                                               "protocol": protocol_names()})) from None


def run(args: argparse.Namespace) -> int:
    bad = 0
    for name in args.files:
        try:
            kind, path = _find(name, args.perception)
        except TextureError as exc:
            print(f"frictex: error: {printable(str(exc))}", file=sys.stderr)
            bad += 1
            continue
        if kind == "protocol":
            bad += not _protocol(path)
            continue
        scene, problems, warnings = check_scene(path)
        if scene is not None:
            problems += renderer_problems(path, scene)
            scene = None if problems else scene  # as check_scene gives none with a problem
        for problem in problems:
            print(f"frictex: error: {printable(str(problem))}", file=sys.stderr)
        notes = [str(w) for w in warnings]
        if scene is not None:
            reach = reach_warning(path, scene)
            notes += ([reach] if reach is not None else []) + force_reach_warnings(path, scene)
        for note in notes:
            print(f"frictex: warning: {printable(note)}", file=sys.stderr)
        if args.perception and scene is not None:
            from frictex.rendering.perception import scene_findings
            _perception(path, scene_findings(scene))
        if scene is None:
            bad += 1
        elif args.strict and notes:
            print(f"frictex: error: {escape_path(path)}: {len(notes)} warning{'s' * (len(notes) != 1)} "
                  f"(--strict)", file=sys.stderr)
            bad += 1
        else:
            n = len(scene.layers)
            print(f"ok {escape_path(path)} ({n} layer{'s' * (n != 1)})")
    if bad and len(args.files) > 1:
        print(f"frictex: error: {bad} of {len(args.files)} files have problems", file=sys.stderr)
    return 2 if bad else 0

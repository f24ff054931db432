"""``frictex replay SCENE TRACE --out DIR``: the pipeline on a recorded trace, headless."""

from __future__ import annotations

import argparse
import sys

from frictex.app.commands.argtypes import (add_link_arguments, add_max_unplayed, block_size, bounded,
                                   output_rate, positive_float, sim_device_args)
from frictex.app.engine.clocks import CLOCKS
from frictex.app.engine.device_changes import device_clamped, unplayed_problem
from frictex.app.engine.replay import MAX_UNPLAYED, ReplayOptions, replay_with
from frictex.app.engine.sinks import SINKS
from frictex.app.engine.sources import MAX_GAP_S
from frictex.app.engine.summary import control_line
from frictex.app.engine.tables import FORMATS
from frictex.rendering.renderers import loadable_render_modes
from frictex.textures.outside import add_allow_outside


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("scene", help="texture file (.toml) or bundled scene name (see frictex library)")
    parser.add_argument("trace", help="trace CSV or bundled trace name (see frictex library)")
    parser.add_argument("--out", required=True, metavar="DIR", help="output folder")
    parser.add_argument("--rate", type=output_rate, default=10_000.0, metavar="HZ",
                        help="output sample rate (default 10000 Hz, the seed 003 link)")
    parser.add_argument("--block", type=block_size, default=None,
                        metavar="N",
                        help="block size in output samples: touch samples take effect at "
                             "block boundaries, as live (default: 5 ms of samples, 50 at "
                             "10 kHz, 1 at 100 Hz)")
    parser.add_argument("--format", choices=FORMATS, default="csv",
                        help="csv (default), npz (one array per column) or parquet (columnar, "
                             "compressed; pandas and polars open it): the two faster for "
                             "long replays")
    parser.add_argument("--renderer", choices=loadable_render_modes(), default=None,
                        help="render every periodic layer this way instead of as its file says "
                             "(sho: the run's SHO variant, sho-predicted unless sho-held is "
                             "chosen; rendering/RENDERERS.md)")
    add_link_arguments(parser)
    add_max_unplayed(parser, MAX_UNPLAYED)
    parser.add_argument("--max-gap", type=positive_float, default=MAX_GAP_S, metavar="S",
                        help=f"a gap between touch samples longer than this is a lift; its "
                             f"silence is not written (default {MAX_GAP_S:g} s)")
    parser.add_argument("--strict", action="store_true",
                        help="refuse a trace whose time goes back (default: samples up to "
                             "5 ms back are sorted into order, further back dropped, counted)")
    parser.add_argument("--frames", type=bounded(float, 0.01, 1000.0, "frames/s"), default=None,
                        metavar="FPS",
                        help="also write PNG frames of the visual layer at FPS into DIR/frames")
    parser.add_argument("--sink", action="append", default=[], metavar="NAME[:ARG]",
                        help="also feed every block to this sink (repeatable; registered: "
                             f"{_listed(SINKS.loadable_names())}; a package adds one under entry "
                             "points 'frictex.sinks'); the run's own tables, link, frames and "
                             "progress bar are built already")
    parser.add_argument("--clock", default="virtual", metavar="NAME[:ARG]",
                        help="what paces the replay: virtual (default: as fast as it computes), "
                             "wall (real time), device (the --device's room), or a package's "
                             f"(entry points 'frictex.clocks'; registered: "
                             f"{_listed(CLOCKS.loadable_names())})")
    parser.add_argument("--quiet", action="store_true",
                        help="no progress bar, no summary line (warnings still print)")
    add_allow_outside(parser)


def _written(tables: list[str], frames) -> list[str]:
    """What a replay wrote in its folder, for its closing line: its ``tables``, the
    summary and, with ``frames`` (a FrameWriter), the frames' folder and its PNG count."""
    folders = [] if frames is None else [f"frames/ ({frames.count} PNGs)"]
    return [*tables, "summary.json", *folders]


def _listed(names: tuple[str, ...]) -> str:
    """Registered names for a help text (argparse formats it with %)."""
    return ", ".join(names).replace("%", "%%")


def inversion_clamps(clamps: dict[str, int]) -> str:
    """What the friction inversion's guards changed (``summary.json``'s ``clamps``), for
    the replay's line: the total, then each guard's count where one changed anything (a
    sample a bad force and an unreachable target both changed is in both counts)."""
    total = sum(clamps.values())
    each = ", ".join(f"{name.replace('_', ' ')} {n}" for name, n in clamps.items() if n)
    return f"{total} clamped by the friction inversion" + (f" ({each})" if each else "")


def run(args: argparse.Namespace) -> int:
    sim_args = sim_device_args(args)  # options needing a device refused before any output
    frames = None
    if args.frames is not None:
        from frictex.app.engine.frames import FrameWriter
        frames = FrameWriter(args.out, args.scene, fps=args.frames, rate_hz=args.rate)
    options = ReplayOptions(rate_hz=args.rate, fmt=args.format, device=args.device,
                            block_size=args.block, render_override=args.renderer,
                            progress=not args.quiet, strict=args.strict, faults=args.faults,
                            max_gap_s=args.max_gap, control=args.control,
                            sim_args=sim_args, sinks=tuple(args.sink),
                            clock=args.clock)
    summary = replay_with(args.scene, args.trace, args.out, options, frames=frames).summary
    if not args.quiet:
        out = summary["output"]
        timing = summary["timings"]
        clamps = inversion_clamps(summary["clamps"])
        on_device, counted = device_clamped(summary.get("device") or {})
        if on_device:  # the device's own clamp (its warning says to what)
            clamps += f", {on_device} {counted} by the device's limit"
        clipped = sum((summary.get("layer_clipped") or {}).values())
        if clipped:  # a layer's own limits (its warning says which and where)
            clamps += f", {clipped} clipped by the layers' own limits"
        limited = summary["counts"].get("actuator_limited")
        if limited:  # a modal structure's actuators short of what a finger wanted
            clamps += f", {limited} samples at an actuator limit"
        print(f"replayed {summary['trace']['samples']} touch samples -> {out['samples']} output "
              f"samples ({out['duration_s']:.3f} s at {out['rate_hz']:g} Hz) in {args.out}: "
              f"{', '.join(_written(out['files'], frames))}; {clamps}; "
              f"{timing['x_realtime_end_to_end']:.3g}x real time end to end (read, compute, "
              f"write; {timing['x_realtime_with_setup']:.3g}x with the {timing['setup_s']:.2f} s "
              f"of loading the scene and its kernels, {timing['x_realtime_compute']:.3g}x "
              "compute only; the interpreter's start and imports in none)")
        if summary.get("control") is not None:
            print(control_line(summary["control"]))
    for warning in summary["warnings"]:  # --quiet or not: clamps, unplayed samples, ...
        print(f"frictex: warning: {warning}", file=sys.stderr)
    limit = MAX_UNPLAYED if args.max_unplayed is None else args.max_unplayed
    problem = unplayed_problem(summary.get("device"), limit, "--max-unplayed")
    if problem is not None:
        print(f"frictex: error: {problem}; outputs in {args.out}", file=sys.stderr)
        return 1
    return 0

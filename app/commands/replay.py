"""``frictex replay SCENE TRACE --out DIR``: the pipeline on a recorded trace, headless."""

from __future__ import annotations

import argparse
import sys

from app.commands.argtypes import positive_float, positive_int
from app.engine.replay import run_replay
from app.engine.tables import FORMATS
from rendering.pipeline import RENDERERS


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("scene", help="texture file (.toml) or bundled scene name (see frictex library)")
    parser.add_argument("trace", help="trace CSV or bundled trace name (see frictex library)")
    parser.add_argument("--out", required=True, metavar="DIR", help="output folder")
    parser.add_argument("--rate", type=positive_float, default=10_000.0, metavar="HZ",
                        help="output sample rate (default 10000 Hz, the seed 003 link)")
    parser.add_argument("--block", type=positive_int, default=50, metavar="N",
                        help="block size in output samples: touch samples take effect at "
                             "block boundaries, as live (default 50 = 5 ms at 10 kHz)")
    parser.add_argument("--format", choices=FORMATS, default="csv",
                        help="csv (default), npz (one array per column) or parquet (columnar, "
                             "compressed; pandas and polars open it): the two faster for "
                             "long replays")
    parser.add_argument("--renderer", choices=("sho", *RENDERERS), default=None,
                        help="render every periodic layer this way instead of as its file says")
    parser.add_argument("--device", metavar="sim|PORT", default=None,
                        help="also stream the commands to a device: 'sim' starts a simulated "
                             "one, otherwise a serial port or pyserial URL")
    parser.add_argument("--frames", type=positive_float, default=None, metavar="FPS",
                        help="also write PNG frames of the visual layer at FPS into DIR/frames")
    parser.add_argument("--quiet", action="store_true", help="no progress bar, no summary line")


def run(args: argparse.Namespace) -> int:
    frames = None
    if args.frames is not None:
        from app.engine.frames import FrameWriter
        frames = FrameWriter(args.out, args.scene, fps=args.frames, rate_hz=args.rate)
    summary = run_replay(args.scene, args.trace, args.out, rate_hz=args.rate,
                         fmt=args.format, device=args.device, block_size=args.block,
                         render_override=args.renderer, progress=not args.quiet,
                         frames=frames)
    if not args.quiet:
        out = summary["output"]
        timing = summary["timings"]
        clamps = sum(summary["clamps"].values())
        print(f"replayed {summary['trace']['samples']} touch samples -> {out['samples']} output "
              f"samples ({out['duration_s']:.3f} s at {out['rate_hz']:g} Hz) in {args.out}: "
              f"{', '.join(out['files'])}, summary.json; {clamps} clamped; "
              f"{timing['x_realtime_end_to_end']:.0f}x real time end to end "
              f"({timing['x_realtime_compute']:.0f}x compute only)")
        for warning in summary["warnings"]:
            print(f"frictex: warning: {warning}", file=sys.stderr)
    return 0

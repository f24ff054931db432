"""``frictex trace synth|import``: make touch traces.

``synth`` writes a synthetic motion sampled like a touch screen (and, with
``--truth``, the true path at a high rate beside it, for accuracy checks); ``import``
converts recordings of real touch screens to the trace CSV.
"""

from __future__ import annotations

import argparse

from app.cmd_replay import positive_float
from app.trace_synth import MOTIONS, make_motion, sample, truth
from rendering.trace_file import write_trace


def add_arguments(parser: argparse.ArgumentParser) -> None:
    sub = parser.add_subparsers(dest="trace_command", metavar="ACTION", required=True)
    synth = sub.add_parser("synth", help="write a synthetic trace",
                           description="Write a synthetic touch trace (CSV).")
    synth.add_argument("motion", choices=MOTIONS)
    synth.add_argument("-o", "--out", required=True, metavar="FILE", help="trace CSV to write")
    synth.add_argument("--rate", type=positive_float, default=50.0, metavar="HZ",
                       help="touch sampling rate (default 50 Hz, seed 003's screen)")
    synth.add_argument("--speed", type=positive_float, default=40.0, metavar="MM_S",
                       help="finger speed (human: typical peak speed), default 40 mm/s")
    synth.add_argument("--duration", type=positive_float, default=2.0, metavar="S")
    synth.add_argument("--x0", type=float, default=14.0, metavar="MM", help="start x")
    synth.add_argument("--y0", type=float, default=32.4, metavar="MM", help="start y")
    synth.add_argument("--angle", type=float, default=0.0, metavar="DEG",
                       help="direction of travel, from +x towards +y")
    synth.add_argument("--length", type=positive_float, default=80.0, metavar="MM",
                       help="stroke length for back-and-forth")
    synth.add_argument("--radius", type=positive_float, default=20.0, metavar="MM",
                       help="circle radius")
    synth.add_argument("--noise", type=float, default=0.0, metavar="MM",
                       help="position noise (standard deviation)")
    synth.add_argument("--jitter", type=float, default=0.0, metavar="S",
                       help="timestamp jitter (standard deviation)")
    synth.add_argument("--force", type=float, default=0.5, metavar="N", help="normal force")
    synth.add_argument("--seed", type=int, default=0, help="random seed (human motion, noise)")
    synth.add_argument("--truth", metavar="FILE", help="also write the true path here")
    synth.add_argument("--truth-rate", type=positive_float, default=10_000.0, metavar="HZ")
    imp = sub.add_parser("import", help="convert a touch recording to a trace CSV",
                         description="Convert a recording (Android getevent -lt, evemu, "
                                     "trace CSV) to a frictex trace CSV.")
    from app.trace_import import add_import_arguments
    add_import_arguments(imp)


def _provenance(args: argparse.Namespace) -> str:
    """The comment line a synthetic trace starts with: how to make it again."""
    return (f"{args.motion} at {args.speed:g} mm/s, sampled at {args.rate:g} Hz "
            f"(frictex trace synth {args.motion} --rate {args.rate:g} --speed {args.speed:g} "
            f"--duration {args.duration:g} --x0 {args.x0:g} --y0 {args.y0:g} --angle {args.angle:g} "
            f"--length {args.length:g} --radius {args.radius:g} --noise {args.noise:g} "
            f"--jitter {args.jitter:g} --force {args.force:g} --seed {args.seed})")


def run(args: argparse.Namespace) -> int:
    if args.trace_command == "import":
        from app.trace_import import run_import
        return run_import(args)
    for name in ("noise", "jitter", "force"):
        if getattr(args, name) < 0:
            raise ValueError(f"--{name} {getattr(args, name)} must be >= 0")
    motion = make_motion(args.motion, speed_mm_s=args.speed, duration_s=args.duration,
                         x0_mm=args.x0, y0_mm=args.y0, angle_deg=args.angle,
                         length_mm=args.length, radius_mm=args.radius, seed=args.seed)
    trace = sample(motion, args.rate, noise_mm=args.noise, jitter_s=args.jitter,
                   force_n=args.force, seed=args.seed)
    write_trace(args.out, trace, comment=_provenance(args))
    print(f"wrote {len(trace)} samples ({trace.duration_s:.3f} s at {args.rate:g} Hz) to {args.out}")
    if args.truth:
        true = truth(motion, args.truth_rate, force_n=args.force)
        write_trace(args.truth, true)
        print(f"wrote the true path ({len(true)} samples at {args.truth_rate:g} Hz) to {args.truth}")
    return 0

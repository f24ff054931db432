"""``frictex trace synth|import``: make touch traces.

``synth`` writes a synthetic motion sampled like a touch screen (and, with
``--truth``, the true path at a high rate beside it, for accuracy checks); ``import``
converts recordings of real touch screens to the trace CSV.
"""

from __future__ import annotations

import argparse
import os

from frictex.app.commands.argtypes import positive_float
from frictex.rendering.input.press_synth import PRESS_MM, PRESS_RATE_HZ, TOUCH_N, press_trace
from frictex.rendering.input.trace_synth import (HUMAN_AREA_MM, MOTIONS, START_MM, make_motion,
                                                sample, sample_count, truth)
from frictex.app.engine.outfile import check_writable, write_file
from frictex.device.errors import InputError, OutputSpaceError
from frictex.rendering.input.trace_file import format_trace


#: a path motion's touch rate (Hz) and normal force (N) unless told
PATH_RATE_HZ = 50.0
PATH_FORCE_N = 0.5
#: the defaults of the options some motions do not use (:data:`UNUSED`)
UNUSED_DEFAULTS = {"speed": 40.0, "duration": 2.0, "angle": 0.0, "length": 80.0, "radius": 20.0,
                   "noise": 0.0, "jitter": 0.0, "peaks": [1.0, 0.95, 1.1], "force_noise": 0.03,
                   "truth_rate": 10_000.0}
_HUMAN_UNUSED = ("angle", "length", "radius", "peaks", "force_noise")
#: the options each motion does not use: refused at any value but their default (which a
#: trace's first line may repeat); --area and --truth have their own messages
UNUSED = {"swipe": ("length", "radius", "peaks", "force_noise"),
          "back-and-forth": ("radius", "peaks", "force_noise"),
          "circle": ("angle", "length", "peaks", "force_noise"),
          "human": _HUMAN_UNUSED, "human-varied": _HUMAN_UNUSED,
          "press": ("speed", "duration", "angle", "length", "radius", "noise", "jitter",
                    "truth_rate")}


def add_arguments(parser: argparse.ArgumentParser) -> None:
    sub = parser.add_subparsers(dest="trace_command", metavar="ACTION", required=True)
    synth = sub.add_parser("synth", help="write a synthetic trace",
                           description="Write a synthetic touch trace (CSV).")
    synth.add_argument("motion", choices=(*MOTIONS, "press"),
                       help="a finger path, or 'press': a still finger pressing (normal force "
                            "rising to --peaks and back, for key-click scenes)")
    synth.add_argument("-o", "--out", required=True, metavar="FILE", help="trace CSV to write")
    synth.add_argument("--rate", type=positive_float, default=None, metavar="HZ",
                       help=f"touch sampling rate (default {PATH_RATE_HZ:g} Hz, seed 003's "
                            f"screen; press: {PRESS_RATE_HZ:g} Hz)")
    synth.add_argument("--speed", type=positive_float, default=UNUSED_DEFAULTS["speed"],
                       metavar="MM_S",
                       help="finger speed (human: typical peak speed), default 40 mm/s")
    synth.add_argument("--duration", type=positive_float, default=UNUSED_DEFAULTS["duration"],
                       metavar="S", help="length of the motion (default 2 s)")
    synth.add_argument("--x0", type=float, default=None, metavar="MM",
                       help=f"start x (default {START_MM[0]:g}; human motions: 30 %% across "
                            f"--area; press: {PRESS_MM[0]:g})")
    synth.add_argument("--y0", type=float, default=None, metavar="MM",
                       help=f"start y (default {START_MM[1]:g}; human motions: half way up "
                            f"--area; press: {PRESS_MM[1]:g})")
    synth.add_argument("--area", type=positive_float, nargs=2, default=None,
                       metavar=("W_MM", "H_MM"),
                       help="human, human-varied: the area (from 0, 0) the finger wanders in "
                            "(default 108 x 64.8, the demo's display)")
    synth.add_argument("--angle", type=float, default=UNUSED_DEFAULTS["angle"], metavar="DEG",
                       help="direction of travel, from +x towards +y (default 0 deg)")
    synth.add_argument("--length", type=positive_float, default=UNUSED_DEFAULTS["length"],
                       metavar="MM",
                       help="stroke length for back-and-forth (default 80 mm)")
    synth.add_argument("--radius", type=positive_float, default=UNUSED_DEFAULTS["radius"],
                       metavar="MM",
                       help="circle radius (default 20 mm)")
    synth.add_argument("--noise", type=float, default=UNUSED_DEFAULTS["noise"], metavar="MM",
                       help="position noise, standard deviation (default 0 mm: none)")
    synth.add_argument("--jitter", type=float, default=UNUSED_DEFAULTS["jitter"], metavar="S",
                       help="timestamp jitter, standard deviation, under half the sample "
                            "interval (default 0 s: none)")
    synth.add_argument("--force", type=float, default=None, metavar="N",
                       help=f"normal force (press: the force at touch-down, default "
                            f"{TOUCH_N:g} N; otherwise default {PATH_FORCE_N:g} N)")
    synth.add_argument("--peaks", type=float, nargs="+", default=UNUSED_DEFAULTS["peaks"],
                       metavar="N",
                       help="press: peak normal force of each press (default 1.0 0.95 1.1)")
    synth.add_argument("--force-noise", type=float, default=UNUSED_DEFAULTS["force_noise"],
                       metavar="N",
                       help="press: force sensor noise, standard deviation (default 0.03 N)")
    synth.add_argument("--seed", type=int, default=0,
                       help="random seed (human motion, noise; default 0)")
    synth.add_argument("--truth", metavar="FILE", help="also write the true path here")
    synth.add_argument("--truth-rate", type=positive_float, default=UNUSED_DEFAULTS["truth_rate"],
                       metavar="HZ",
                       help="sampling rate of the true path (default 10000 Hz)")
    imp = sub.add_parser("import", help="convert a touch recording to a trace CSV",
                         description="Convert a recording (Android getevent -lt, evemu, "
                                     "trace CSV) to a frictex trace CSV.")
    from frictex.rendering.input.trace_import import add_import_arguments
    add_import_arguments(imp)


#: Accepted ranges of the synth options (lowest, highest, unit): a value beyond them is a
#: typo, and would overflow or exhaust memory further on (or, for a duration and rate
#: whose product is under a billionth of a sample interval, a trace of one lift only).
LIMITS = {"rate": (1e-3, 1e5, "Hz"), "truth_rate": (1e-3, 1e6, "Hz"), "duration": (1e-6, 1e5, "s"),
          "speed": (0.0, 1e4, "mm/s"), "x0": (-1e5, 1e5, "mm"), "y0": (-1e5, 1e5, "mm"),
          "angle": (-360.0, 360.0, "deg"), "length": (0.0, 1e5, "mm"), "radius": (0.0, 1e5, "mm"),
          "noise": (0.0, 1e3, "mm"), "jitter": (0.0, 1.0, "s"), "force": (0.0, 1e3, "N"),
          "force_noise": (0.0, 100.0, "N"), "peaks": (0.0, 1e3, "N"), "area": (0.0, 1e5, "mm"),
          "seed": (0, 1e18, "(a whole number)")}
#: the options whose lowest value is excluded (argparse takes them as positive numbers)
ABOVE_LOWEST = {"speed", "length", "radius", "area"}
#: Most samples a synthetic trace (or its true path) may hold.
MAX_SAMPLES = 10_000_000
#: Most presses (--peaks) a press trace may hold: its first line, which repeats them twice,
#: stays within the trace reader's line limit (``trace_file.MAX_LINE_BYTES``).
MAX_PRESSES = 100
#: Length of one press of ``press_trace`` (s): rise, hold and fall (2 x 0.6 + 0.1 s).
PRESS_S = 2 * 0.6 + 0.1

PATH_OPTIONS = ("rate", "speed", "duration", "x0", "y0", "area", "angle", "length", "radius",
                "noise", "jitter", "force", "seed")
PRESS_OPTIONS = ("rate", "x0", "y0", "force", "peaks", "force_noise", "seed")


def _synth_command(args: argparse.Namespace, options) -> str:
    """The ``frictex trace synth`` command that makes this trace again."""
    def value(v):
        return " ".join(f"{p:g}" for p in v) if isinstance(v, list) else f"{v:g}"
    flags = " ".join(f"--{name.replace('_', '-')} {value(getattr(args, name))}" for name in options
                     if getattr(args, name) is not None)
    return f"frictex trace synth {args.motion} {flags}"


def _provenance(args: argparse.Namespace) -> str:
    """The comment line a synthetic trace starts with: what it is, how to make it again."""
    if args.motion == "press":
        peaks = " ".join(f"{p:g}" for p in args.peaks)
        what = (f"{len(args.peaks)} presses of a still finger at ({args.x0:g}, {args.y0:g}) mm, "
                f"force {args.force:g} N to peaks {peaks} N and back, noise "
                f"{args.force_noise:g} N, sampled at {args.rate:g} Hz")
        return f"{what} ({_synth_command(args, PRESS_OPTIONS)})"
    what = f"{args.motion} at {args.speed:g} mm/s, sampled at {args.rate:g} Hz"
    return f"{what} ({_synth_command(args, PATH_OPTIONS)})"


def _check_limits(args: argparse.Namespace) -> None:
    """InputError for a synth option outside LIMITS, or a trace of more than MAX_SAMPLES."""
    for name, (lo, hi, unit) in LIMITS.items():
        values = getattr(args, name)
        for value in values if isinstance(values, list) else [] if values is None else [values]:
            if not lo <= value <= hi:
                low = f"over {lo:g}, up" if name in ABOVE_LOWEST else f"{lo:g}"
                raise InputError(f"--{name.replace('_', '-')} {value:g}: expected {low} to "
                                 f"{hi:g} {unit}")
    if args.motion == "press":
        _check_presses(args.peaks, args.rate)
        return
    rates = [("--rate", args.rate)] + ([("--truth-rate", args.truth_rate)] if args.truth else [])
    for option, rate in rates:
        if rate * args.duration > MAX_SAMPLES:
            raise InputError(f"{option} {rate:g} Hz over --duration {args.duration:g} s is "
                             f"{rate * args.duration:,.0f} samples; at most {MAX_SAMPLES:,}")


def _check_presses(peaks: list[float], rate_hz: float) -> None:
    """InputError for more than MAX_PRESSES ``peaks`` (N), or presses that would take more
    than MAX_SAMPLES samples at ``rate_hz`` (a press ignores --duration)."""
    if len(peaks) > MAX_PRESSES:
        raise InputError(f"--peaks: {len(peaks)} presses; at most {MAX_PRESSES}")
    samples = len(peaks) * sample_count(PRESS_S, rate_hz)
    if samples > MAX_SAMPLES:
        raise InputError(f"--peaks: {len(peaks)} presses of {PRESS_S:g} s at --rate {rate_hz:g} Hz "
                         f"are {samples:,} samples; at most {MAX_SAMPLES:,}")


def motion_defaults(motion: str) -> tuple[float, float, tuple[float, float] | None]:
    """What a motion takes unless told: its touch rate (Hz), normal force (N) and where
    it starts (mm; None: the motion's own start). A press's are ``press_synth``'s (the
    bundled keyclick-press-100hz, on keyclick-ring's button); a path's 50 Hz and 0.5 N."""
    if motion == "press":
        return PRESS_RATE_HZ, TOUCH_N, PRESS_MM
    return PATH_RATE_HZ, PATH_FORCE_N, None


def _set_motion_defaults(args: argparse.Namespace) -> None:
    """Fill in the options whose default depends on the motion (:func:`motion_defaults`)."""
    rate_hz, force_n, start_mm = motion_defaults(args.motion)
    args.rate = rate_hz if args.rate is None else args.rate
    args.force = force_n if args.force is None else args.force
    if start_mm is not None:
        args.x0 = start_mm[0] if args.x0 is None else args.x0
        args.y0 = start_mm[1] if args.y0 is None else args.y0


def _check_used(args: argparse.Namespace) -> None:
    """InputError for an option the motion does not use, given a value other than its
    default: it would be ignored (so is --truth-rate without --truth)."""
    if not args.truth and args.truth_rate != UNUSED_DEFAULTS["truth_rate"]:
        raise InputError(f"--truth-rate {args.truth_rate:g}: the rate of --truth's true path, "
                         "and no --truth was given")
    for name in UNUSED[args.motion]:
        value = getattr(args, name)
        if value != UNUSED_DEFAULTS[name]:
            shown = " ".join(f"{v:g}" for v in value) if isinstance(value, list) else f"{value:g}"
            raise InputError(f"--{name.replace('_', '-')} {shown}: a {args.motion} does not use "
                             "it; leave it out")
    random = ("force_noise",) if args.motion == "press" else ("noise", "jitter")
    if (args.seed != 0 and args.motion not in ("human", "human-varied")
            and not any(getattr(args, name) for name in random)):
        shown = " or ".join(f"--{name.replace('_', '-')}" for name in random)
        raise InputError(f"--seed {args.seed}: a {args.motion} without {shown} has nothing "
                         "random to seed; leave it out")


def _check_outputs(args: argparse.Namespace) -> None:
    """Refuse, before making the trace, an -o or --truth that cannot be written (naming
    the option), and a --truth that is -o's own file (it would overwrite the trace)."""
    check_writable("-o", args.out, 0)  # the room is checked with the text's size
    if not args.truth:
        return
    check_writable("--truth", args.truth, 0)
    if os.path.realpath(args.out) == os.path.realpath(args.truth):  # links followed
        raise InputError(f"--truth {args.truth}: the same file as -o {args.out}; the true path "
                         "would overwrite the trace: give it a file of its own")


def _write(path: str, trace, comment: str | None = None) -> None:
    """The trace CSV at ``path``, room-checked and written whole or not at all
    (``app.engine.outfile``)."""
    _write_text(path, format_trace(trace, comment))


def _write_text(path: str, text: str, option: str = "-o") -> None:
    """Write ``text`` (UTF-8) to ``path``; an OS error (a full /dev/full, a stream that
    refuses) becomes one line naming ``option`` and ``path``."""
    data = text.encode("utf-8")
    try:
        write_file(path, lambda to: to.write_bytes(data), len(data))
    except OutputSpaceError:  # already names the path and says what to do
        raise
    except OSError as exc:
        raise InputError(f"{option} {path}: cannot be written ({exc.strerror or exc})") from None


def _check_import_output(args: argparse.Namespace) -> None:
    """Refuse, before reading the recording, an -o that cannot be written or that is the
    input itself (the CSV would overwrite the raw recording)."""
    if os.path.realpath(args.out) == os.path.realpath(args.input):  # links followed
        raise InputError(f"-o {args.out}: the same file as the input {args.input}; the trace "
                         "would overwrite the recording: give it a file of its own")
    check_writable("-o", args.out, 0)  # the room is checked with the text's size


def run(args: argparse.Namespace) -> int:
    if args.trace_command == "import":
        from frictex.rendering.input.trace_import import run_import
        _check_import_output(args)
        return run_import(args, _write_text)
    _set_motion_defaults(args)
    _check_limits(args)
    _check_used(args)
    _check_outputs(args)
    if args.area is not None and args.motion not in ("human", "human-varied"):
        raise InputError(f"--area: only the human motions wander in an area; a {args.motion} "
                         "starts at --x0, --y0")
    if args.motion == "press":
        if args.truth:
            raise InputError("--truth: a press does not move; its trace is its true path")
        trace = press_trace(peaks_n=args.peaks, x_mm=args.x0, y_mm=args.y0, rate_hz=args.rate,
                            touch_n=args.force, noise_n=args.force_noise, seed=args.seed)
        _write(args.out, trace, comment=_provenance(args))
        print(f"wrote {len(trace)} samples ({trace.duration_s:.3f} s at {args.rate:g} Hz) "
              f"to {args.out}")
        return 0
    motion = make_motion(args.motion, speed_mm_s=args.speed, duration_s=args.duration,
                         x0_mm=args.x0, y0_mm=args.y0, angle_deg=args.angle,
                         length_mm=args.length, radius_mm=args.radius,
                         area_mm=tuple(args.area or HUMAN_AREA_MM), seed=args.seed)
    trace = sample(motion, args.rate, noise_mm=args.noise, jitter_s=args.jitter,
                   force_n=args.force, seed=args.seed)
    _write(args.out, trace, comment=_provenance(args))
    print(f"wrote {len(trace)} samples ({trace.duration_s:.3f} s at {args.rate:g} Hz) to {args.out}")
    if args.truth:
        true = truth(motion, args.truth_rate, force_n=args.force)
        _write_text(args.truth, format_trace(true), "--truth")
        print(f"wrote the true path ({len(true)} samples at {args.truth_rate:g} Hz) to {args.truth}")
    return 0

"""``frictex trace import``: recordings of real touch screens to the trace CSV.

Inputs: Android ``getevent -lt`` logs, evemu recordings (both Linux evdev multi-touch,
protocol A or B, decoded by ``rendering.input.evdev_decode``) and trace CSVs (validated and
rewritten). Device counts become mm through the axis ranges (options, else the evemu
``A:`` header or the getevent ``-p`` section, else the observed min..max with a warning)
and the screen size (options, else the recording's resolution). The output adds
``pressure`` and ``touch_major`` columns (device units) when the recording has them; the
trace reader ignores them (``trace_file.RECORDED_COLUMNS``: and says nothing of them).
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np

from frictex.rendering.input.evdev_decode import (ABS_MT_POSITION_X, ABS_MT_POSITION_Y, EV_ABS,
                                                  LIFT_LOST_S, AbsInfo, Event, RawSample,
                                                  ScreenMap, ScreenSpec, decode_all,
                                                  observed_ranges, read_text, screen_map)
from frictex.rendering.input.import_evemu import parse_evemu
from frictex.rendering.input.import_getevent import read_log
from frictex.rendering.input.trace_file import (DEFAULT_FORCE_N, MAX_COORD_MM, TraceError, ascii_float,
                                                concat_traces, UP, format_trace, iter_trace,
                                                most_touching)
from frictex.device.safe_text import quoted

FORMATS = ("auto", "getevent", "evemu", "csv")

EPILOG = """\
ranges and sizes: --x-range and --y-range are in the device's counts along its own X and Y
(before --swap-xy); --width-mm and --height-mm are the screen's size along its x (right) and
y (down). A getevent log records the ranges when made with 'getevent -lpt' (its -p section
is read; an option given wins); 'getevent -lt' logs need the options.
Example, the Samsung Galaxy S phone of the Android refdata (0..1023 digitizer, 4.0-inch
480x800 screen, about 52 x 87 mm):
  frictex trace import phone-two-finger-drag.txt -o drag.csv \\
      --x-range 0 1023 --y-range 0 1023 --width-mm 52 --height-mm 87
"""


def _finite(text: str) -> float:
    try:
        value = ascii_float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{quoted(text)} is not a number (ASCII decimal, as "
                                         "in trace files)") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"{text!r} is not a finite number")
    return value


def _positive(text: str) -> float:
    value = _finite(text)
    if value <= 0:
        raise argparse.ArgumentTypeError(f"{text!r} must be > 0")
    return value


def _non_negative(text: str) -> float:
    value = _finite(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f"{text!r} must be >= 0")
    return value


def add_import_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``frictex trace import``."""
    parser.epilog = EPILOG
    parser.formatter_class = argparse.RawDescriptionHelpFormatter
    parser.add_argument("input", metavar="INPUT", help="recording to convert")
    parser.add_argument("-o", "--out", required=True, metavar="OUT.csv", help="trace CSV to write")
    parser.add_argument("--format", choices=FORMATS, default="auto",
                        help="input format (default: recognised from the content)")
    parser.add_argument("--x-range", nargs=2, type=_finite, metavar=("MIN", "MAX"),
                        help="device X counts that span the screen (default: the evemu "
                             "header or getevent -p section, else the observed range, with a "
                             "warning)")
    parser.add_argument("--y-range", nargs=2, type=_finite, metavar=("MIN", "MAX"),
                        help="device Y counts that span the screen")
    parser.add_argument("--width-mm", type=_positive, metavar="W",
                        help="screen width (mm; default: from the evemu resolution)")
    parser.add_argument("--height-mm", type=_positive, metavar="H",
                        help="screen height (mm; default: from the evemu resolution)")
    parser.add_argument("--swap-xy", action="store_true",
                        help="device X runs along the screen's y (rotated screen)")
    parser.add_argument("--flip-x", action="store_true", help="screen x runs against the device axis")
    parser.add_argument("--flip-y", action="store_true", help="screen y runs against the device axis")
    parser.add_argument("--pressure-scale", type=_positive, metavar="N_PER_UNIT",
                        help="normal force = ABS_MT_PRESSURE x this (N); default: every "
                             "sample gets --force")
    parser.add_argument("--force", type=_non_negative, metavar="N",
                        help=f"normal force when pressure is not mapped (default {DEFAULT_FORCE_N} N)")
    parser.add_argument("--device", metavar="PATH",
                        help="getevent log with several devices: keep this one (/dev/input/eventN)")
    parser.add_argument("--keep-time", action="store_true",
                        help="keep the recording's clock (default: the first sample is at t = 0 s)")


def detect_format(path: Path, text: str) -> str:
    """``getevent``, ``evemu`` or ``csv``, from the first meaningful line of ``text``."""
    for line in text.splitlines():
        s = line.strip()
        if not s:
            continue
        if s.startswith("# EVEMU") or s[:2] in ("N:", "I:", "E:", "A:"):
            return "evemu"
        if s.startswith("[") or s.startswith("add device"):
            return "getevent"
        if s.startswith("#"):
            continue
        if "t_s" in s.split(","):
            return "csv"
        break
    raise TraceError(f"{path}: format not recognised (expected a getevent -lt log, an evemu "
                     "recording or a trace CSV); give --format")


def _extra_columns(trace_csv: str, samples: list[RawSample]) -> str:
    """Add the pressure and touch_major columns the recording has to the trace CSV text."""
    cols = [(name, i) for name, i in (("pressure", 4), ("touch_major", 5))
            if any(not math.isnan(s[i]) for s in samples)]
    if not cols:
        return trace_csv
    lines = trace_csv.splitlines()
    header = next(i for i, ln in enumerate(lines) if not ln.startswith("#"))
    lines[header] += "".join(f",{name}" for name, _ in cols)
    for k, s in enumerate(samples, start=header + 1):
        lines[k] += "".join("," if math.isnan(s[i]) else f",{s[i]:g}" for _, i in cols)
    return "\n".join(lines) + "\n"


def _pair(values: list[float] | None) -> tuple[float, float] | None:
    return None if values is None else (values[0], values[1])


def _copy_csv(path: Path, args: argparse.Namespace, write: Callable[[str, str], None]) -> int:
    """A trace CSV in: validate it and write it back out."""
    mapping = [o for o in ("x_range", "y_range", "width_mm", "height_mm", "swap_xy", "flip_x",
                           "flip_y", "pressure_scale", "force", "device", "keep_time")
               if getattr(args, o) is not None and getattr(args, o) is not False]  # 0 is given
    if mapping:
        raise TraceError(f"--{mapping[0].replace('_', '-')} does not apply to a trace CSV "
                         "(it is already in mm, s and N)")
    reader = iter_trace(path)
    trace = concat_traces(reader)
    write(args.out, format_trace(trace, comment=f"imported from {path}"))
    for w in reader.order.warnings():
        print(f"frictex: warning: {w}", file=sys.stderr)
    print(f"wrote {len(trace)} samples, {len(trace.fingers)} finger(s), "
          f"{trace.duration_s:.3f} s, to {args.out}")
    return 0


def _events(path: Path, text: str, fmt: str,
            device: str | None) -> tuple[list[Event], dict[int, AbsInfo], list[str]]:
    """The evdev events of a getevent or evemu recording, the axis ranges it states, and
    the warnings its reading gave."""
    if fmt == "getevent":
        log = read_log(text, str(path), device)
        return log.events, log.absinfo, log.warnings
    if device is not None:
        raise TraceError("--device applies to getevent logs; an evemu recording holds one device")
    recording = parse_evemu(text, str(path))
    return recording.events, recording.absinfo, recording.warnings


def _check_positions(samples: list[RawSample], events: list[Event], screen: ScreenMap,
                     where: str) -> None:
    """TraceError naming the line of the event behind the first sample's position that
    ``screen`` puts more than MAX_COORD_MM from the screen's origin (a glitch count such as
    0x7fffffff, or a range that is not the device's), with its count, its mm and the
    axis's map: the trace's own check comes later and can only name a sample. Only the
    samples count: a glitch in events the decoder threw away (after a SYN_DROPPED) is no
    error; the line is that of the first position event of that axis with that count."""
    for code, axis in ((ABS_MT_POSITION_X, "x"), (ABS_MT_POSITION_Y, "y")):
        m = (screen.y if screen.swap_xy else screen.x) if axis == "x" else (
            screen.x if screen.swap_xy else screen.y)
        counts = np.array([getattr(sample, axis) for sample in samples], dtype=np.float64)
        with np.errstate(invalid="ignore"):  # nan: a position the device did not say
            far = np.flatnonzero(np.abs(m.mm(counts)) > MAX_COORD_MM)
        if far.size:
            count = counts[far[0]]
            line = next((e.line for e in events
                         if e.type == EV_ABS and e.code == code and e.value == count), None)
            at = f"{where}:{line}" if line else where
            raise TraceError(f"{at}: device {axis} count {count:.0f} is {m.mm(count):.6g} mm "
                             f"on the screen (device {axis} range {m.lo:g}..{m.hi:g} over "
                             f"{m.size_mm:g} mm); expected -{MAX_COORD_MM:g} to {MAX_COORD_MM:g} "
                             f"mm (a glitch value? else check --{axis}-range)")


def still_down(trace) -> list[int]:
    """The finger ids (ascending) whose last sample in ``trace`` is not a lift."""
    fingers, last = np.unique(trace.finger[::-1], return_index=True)  # each one's last row
    return fingers[trace.event[::-1][last] != UP].tolist()


def run_import(args: argparse.Namespace, write: Callable[[str, str], None]) -> int:
    """Convert ``args.input`` to the trace CSV ``args.out``, written by ``write(path,
    text)`` (the command's room-checked, all-or-nothing writer); print a summary; return 0."""
    path = Path(args.input)
    text = read_text(path, "recording")
    fmt = detect_format(path, text) if args.format == "auto" else args.format
    if fmt == "csv":
        return _copy_csv(path, args, write)
    events, absinfo, read_warnings = _events(path, text, fmt, args.device)
    samples, decoder = decode_all(events, str(path))
    if not samples:
        raise TraceError(f"{path}: no touches found ({len(events)} events, {decoder.frames} frames; "
                         "expected ABS_MT_* contacts)")
    spec = ScreenSpec(args.width_mm, args.height_mm, _pair(args.x_range), _pair(args.y_range),
                      args.swap_xy, args.flip_x, args.flip_y, args.pressure_scale,
                      DEFAULT_FORCE_N if args.force is None else args.force)
    screen, warnings = screen_map(spec, absinfo, observed_ranges(samples), str(path))
    warnings = read_warnings + warnings
    t0 = samples[0].t_s
    if not args.keep_time:
        # both formats stamp whole microseconds: rounding gives back the exact decimal difference
        samples = [s._replace(t_s=round(s.t_s - t0, 6)) for s in samples]
    _check_positions(samples, events, screen, str(path))
    trace = screen.trace(samples, str(path))
    outside = int(np.count_nonzero((trace.x_mm < 0) | (trace.x_mm > screen.x.size_mm)
                                   | (trace.y_mm < 0) | (trace.y_mm > screen.y.size_mm)))
    if outside:
        warnings.append(f"{outside} of {len(trace)} samples fall outside the "
                        f"{screen.x.size_mm:g} x {screen.y.size_mm:g} mm screen (check the ranges)")
    if decoder.dropped:
        lifted = (f"; {decoder.lifts_lost} touch{'es' * (decoder.lifts_lost > 1)} silent for "
                  f"over {LIFT_LOST_S:g} s after one taken as lifted where last seen (the "
                  f"lift lost with the events)" if decoder.lifts_lost else "")
        warnings.append(f"{decoder.dropped} SYN_DROPPED: the kernel lost events there{lifted}")
    if decoder.unplaced:
        warnings.append(f"{decoder.unplaced} contact reports without a position were left out")
    if decoder.untracked:
        warnings.append(f"positions in {decoder.untracked} frame"
                        f"{'s' if decoder.untracked != 1 else ''} came with no "
                        "ABS_MT_TRACKING_ID (protocol B contacts start with one) and were left out")
    if decoder.pending:
        warnings.append(f"{decoder.pending} events after the last SYN_REPORT (an unfinished "
                        "frame) were left out")
    still = still_down(trace)
    if still:
        warnings.append(f"finger{'s' if len(still) > 1 else ''} {', '.join(map(str, still))} "
                        f"still down at the end of the recording (cut mid-touch?"
                        f"{' or a lift lost to SYN_DROPPED?' if decoder.dropped else ''}): no "
                        f"lift follows {'their' if len(still) > 1 else 'its'} last sample")
    comment = (f"imported from {path} ({fmt}, multitouch protocol {decoder.protocol}); "
               f"recording clock at the first sample: {t0!r} s"
               f"{'' if args.keep_time else ' (shifted to t = 0)'}; x {screen.x.lo:g}..{screen.x.hi:g} "
               f"-> 0..{screen.x.size_mm:g} mm, y {screen.y.lo:g}..{screen.y.hi:g} -> "
               f"0..{screen.y.size_mm:g} mm{', axes swapped' if args.swap_xy else ''}")
    write(args.out, _extra_columns(format_trace(trace, comment), samples))
    for w in warnings:
        print(f"frictex: warning: {w}", file=sys.stderr)
    most = most_touching(trace)
    print(f"wrote {len(trace)} samples, {len(trace.fingers)} finger id(s) (at most {most} down "
          f"at once), {trace.duration_s:.3f} s, protocol {decoder.protocol}, to {args.out}")
    return 0


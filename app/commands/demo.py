"""``frictex demo [SCENE]``: the live demo window; the mouse, or a touch screen, gives the fingers.

With no SCENE the window cycles through the bundled scenes (N / B). The haptic
pipeline runs at block cadence in its own process (``app.live.haptic_process``; ``--haptic
thread``: on a thread of the window's process, ``app.live.haptic_thread``), the window on
the main thread (``app.live.demo_loop``). ``--input`` picks the fingers: the mouse, the
mouse and a follower finger, a TUIO tracker over UDP, or a Linux evdev touch screen
(read by the haptic side as its samples arrive, not by the window).
``--record DIR`` writes what was sent
(``commands.csv``, ``friction.csv`` as in a replay), the touches taken (``touches.csv``, a
trace file: ``frictex replay SCENE DIR/touches.csv --block N`` replays them, N the demo's
block), ``events.csv`` and ``summary.json``,
into a staging folder beside DIR that replaces DIR as a whole when the demo ends
(``app.engine.staging``, as a replay's ``--out``): a demo that crashes or is killed leaves
the previous recording as it was; one that replaces a recording says so.
SIGINT (Ctrl-C), SIGTERM and SIGHUP end the demo as Q does (held as a flag the window's
loop looks at, never raised inside a window callback: ``app.engine.driver.
deferred_interrupts``): the plate stopped, the recording committed, the usual last lines,
then ``frictex: interrupted`` (exit 130) or ``frictex: terminated by SIGTERM`` (128 + the
signal); with ``--record`` it says on stderr that it is writing the recording, and a
second signal then ends it at once, saying the recording was not written.
N / B skip the playlist's scenes that drive other channels than the link and the
recording were opened for (``app.live.demo_loop``).
``--faults SPEC`` injects link faults on ``--device`` (as ``frictex replay --faults``).
A demo on ``--device`` exits 1, with one line saying why, when the link was lost and
not back by the end, or when more than ``--max-unplayed`` of the commanded samples never
played on the device (``app.engine.device_changes.unplayed_problem``, as a replay's).

Without a display: ``frictex demo`` says so and exits 1 (a run that could not do what
was asked); ``--headless`` (or ``--headless-fallback`` when no display is found) runs
the same demo loop on a window without a display (``rendering.visual.headless``), a
synthesized human-like stroke driving its mouse (``app.live.synthetic``) for ``--duration``
(3 s by default), which then lifts the finger and quits, and writes its
frames as PNG files (``frames/``, at most 30 a second) to ``--out``, and what a ``--record`` would
(``commands.csv``, ``friction.csv``, ``touches.csv``, ``events.csv``, ``summary.json``)
to ``--record``, or without it to ``--out`` too.
"""

from __future__ import annotations

import argparse
import json
import signal
import sys
import threading
from dataclasses import dataclass, replace
from pathlib import Path

from frictex.app.engine.device_changes import faults_not_reached, unplayed_problem
from frictex.app.engine.driver import deferred_interrupts
from frictex.app.engine.staging import FRAMES, Staging
from frictex.app.engine.summary import counted, finite_json, were
from frictex.app.live.link_watch import device_clamps, run_underruns
from frictex.app.live.synthetic import STROKE_S
from frictex.app.live.touch_log import TOUCHES
from frictex.app.commands.preview import MAX_PANEL_PX, frame_size
from frictex.app.commands.argtypes import (add_link_arguments, add_max_unplayed, output_rate,
                                   positive_float, positive_int, sim_device_args)
from frictex.device.errors import InputError
from frictex.rendering.renderers import loadable_render_modes
from frictex.rendering.visual.context import NoDisplayError
from frictex.rendering.visual.windows import open_backend
from frictex.rendering.visual.device_panels import default_frame_size
from frictex.rendering.visual.viewport import MIN_FRAME
from frictex.textures.outside import add_allow_outside

#: what a demo writes into ``--record`` (or ``--out``) besides a replay's tables, summary
#: and frames: the folder is replaced as a whole when the demo ends (``app.engine.staging``;
#: a ``frames`` folder holding anything but frames is refused, as for a replay)
DEMO_OUTPUTS = ("events.csv", TOUCHES)

#: share of the commanded samples a device may leave unplayed before the demo exits 1
#: (``--max-unplayed``), the blocks a live link skipped to catch up after the machine
#: stalled it not counted (20 % of a 2 s run with the haptic thread on a loaded 2-core
#: machine): looser than a replay's 0.01, as the demo's own thread shares the machine
MAX_UNPLAYED = 0.1
#: unplayed samples the demo's limit leaves out: a live link's deliberate catch-up skips
CATCH_UP = ("skipped",)
#: share of the commanded samples the link may skip to catch up before the demo exits 1:
#: a machine that skips more than half never kept up with the device
MAX_CATCH_UP = 0.5

def input_option(text: str) -> tuple[str, object]:
    """argparse type for ``--input``: (name, argument) as ``app.live.inputs.parse_input``
    gives them (the kinds are ``app.live.inputs.INPUTS``)."""
    from frictex.app.live.inputs import parse_input
    try:
        return parse_input(text)
    except InputError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def sender_option(text: str) -> tuple[str, int | None]:
    """argparse type for ``--tuio-from``: ``rendering.input.tuio.parse_sender``."""
    from frictex.rendering.input.tuio import parse_sender
    try:
        return parse_sender(text)
    except InputError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("scene", nargs="?", default=None,
                        help="texture file (.toml) or bundled scene name; default: the bundled playlist")
    parser.add_argument("--fullscreen", action="store_true", help="fullscreen on --monitor")
    parser.add_argument("--monitor", type=int, default=0, metavar="N", help="monitor for --fullscreen (default 0)")
    parser.add_argument("--size", type=frame_size, default=None, metavar="WxH",
                        help=f"window size in px, each side 1 to {MAX_PANEL_PX} (default: the "
                             "scene's display size with the scope's strip, at least "
                             f"{MIN_FRAME[0]}x{MIN_FRAME[1]}); a window is then cut to the "
                             "screen's work area")
    parser.add_argument("--renderer", choices=loadable_render_modes(), default=None,
                        help="start with every periodic layer rendered this way (R cycles it live)")
    add_link_arguments(parser)
    add_max_unplayed(parser, MAX_UNPLAYED, "; the blocks a live link skips to catch up not "
                                           "counted, up to half the samples; a link lost "
                                           "and not back by the end exits 1 as well")
    parser.add_argument("--rate", type=output_rate, default=10_000.0, metavar="HZ",
                        help="output sample rate (default 10000 Hz)")
    parser.add_argument("--block", type=positive_int, default=None, metavar="N",
                        help="block size in output samples (default: 2.5 ms of samples, 25 "
                             "at 10 kHz: a touch waits at most one block, and the device "
                             "plays two blocks (at least 5 ms) behind; replay's default is "
                             "5 ms, so replay a demo's recorded touches.csv with --block 25 "
                             "to apply its touches at the same boundaries)")
    from frictex.app.live.inputs import INPUTS
    kinds = list(INPUTS.loaded().items())  # a plugin's that cannot load: left out, warned
    parser.add_argument("--input", type=input_option, default=("mouse", None),
                        metavar="|".join(kind.usage for _, kind in kinds),
                        help="where the fingers come from (default mouse): "
                             + "; ".join(f"'{name}': {kind.help}" for name, kind in kinds)
                             + ". With a touch screen the mouse only hovers and every finger "
                             "gets the force set with the wheel")
    parser.add_argument("--tuio-from", type=sender_option, default=None, metavar="ADDR[:PORT]",
                        help="with --input tuio: accept datagrams from this IPv4 address only, "
                             "and with a port from that port only; with no port, one port of "
                             "the address is served at a time (the first heard; another takes "
                             "over after 1.5 s of silence). Default: the first sender of a "
                             "TUIO frame (listening beyond loopback, the demo then warns at "
                             "start). Datagrams from others are dropped and counted in the "
                             "summary. Not 0.0.0.0, broadcast or multicast; an address on the "
                             "network needs the listener there, --input tuio:0.0.0.0:PORT")
    parser.add_argument("--haptic", choices=("process", "thread"), default="process",
                        help="where the haptic pipeline runs: its own process (default: the "
                             "window's GL calls cannot delay it) or a thread of the window's "
                             "process (for debugging; misses deadlines on a software renderer)")
    parser.add_argument("--record", metavar="DIR", default=None,
                        help="write commands.csv, friction.csv, touches.csv (the touches, a "
                             "trace file to replay), events.csv and summary.json to DIR "
                             "(replaced as a whole when the demo ends, as a replay's --out)")
    parser.add_argument("--screenshots", metavar="DIR", default=".",
                        help="folder for screenshots taken with P (default: current folder)")
    parser.add_argument("--duration", type=positive_float, default=None, metavar="S",
                        help="close the window after S seconds (default: run until closed); "
                             "--headless: the synthesized stroke lasts S seconds (default "
                             f"{STROKE_S:g}), then lifts and quits")
    mode = parser.add_mutually_exclusive_group()
    mode.add_argument("--headless", action="store_true",
                      help="no display: run the demo on a synthesized stroke of the mouse "
                           "(--duration long), writing its PNG frames to --out's frames/ "
                           "(and without --record its outputs to --out)")
    mode.add_argument("--headless-fallback", action="store_true",
                      help="open the window if a display exists, else behave as --headless")
    parser.add_argument("--out", metavar="DIR", default="frictex-demo-out",
                        help="output folder for --headless (default: frictex-demo-out; --record "
                             "takes the tables elsewhere)")
    add_allow_outside(parser)


def _start_haptic(args, scene, scene_path: Path, record: Path | None):
    """The haptic side of ``--haptic``, started with its link and touch screen, and its
    ``finish()`` (as open_haptic's). A touch screen that cannot be opened raises here."""
    from frictex.app.live.inputs import INPUTS
    kind, arg = args.input
    touch = (kind, arg) if INPUTS.get(kind).touch_screen else None
    if args.haptic == "thread":
        from frictex.app.live.haptic_setup import open_haptic
        from frictex.app.live.haptic_thread import shorten_switch_interval
        from frictex.app.live.inputs import open_source
        shorten_switch_interval(args.block / args.rate)
        sim_args = sim_device_args(args)  # refused before the touch screen is opened
        haptic, finish = open_haptic(scene, args.rate, args.block, args.renderer, args.device,
                                     record, faults=args.faults,
                                     source=None if touch is None else open_source(*touch),
                                     control=args.control, sim_args=sim_args)
        haptic.start()
        return haptic, finish
    from frictex.app.live.haptic_process import HapticConfig, HapticProcess
    haptic = HapticProcess(scene, HapticConfig(scene_path, args.rate, args.block, args.renderer,
                                               args.device, record, touch, args.faults,
                                               args.control, sim_device_args(args)))

    def finish():
        haptic.stop()
        return haptic.link, haptic.dropped_records

    return haptic, finish


def _playlist(scene_arg):
    from frictex.textures.library import list_scenes, resolve_scene
    if scene_arg is not None:
        return [resolve_scene(scene_arg)], 0
    paths = [entry.path for entry in list_scenes()]
    if not paths:
        raise InputError("no bundled scenes found; give a texture file")
    return paths, 0


def _load(path):
    from frictex.textures.loader import load_scene
    return load_scene(path)


def input_name(kind: str, arg) -> str:
    """``--input`` as the status line and the summary show it."""
    from frictex.app.live.inputs import INPUTS
    return INPUTS.get(kind).label(arg)


#: what a TUIO input did not play, as its closing line says it: ``counters()`` key, the
#: thing counted (singular, plural) and why it was not played
_TUIO_DROPS = (("refused", "datagram", "datagrams",
                "refused (other senders, or before one was served)"),
               ("kernel_dropped", "datagram", "datagrams",
                "dropped by the kernel (socket receive buffer full)"),
               ("dropped", "datagram", "datagrams", "dropped (queue full)"),
               ("stale", "datagram", "datagrams", "dropped unread (stale, a newer one queued)"),
               ("bad_packets", "malformed datagram", "malformed datagrams", "dropped"),
               ("bad_sets", "cursor set", "cursor sets", "skipped (cannot be played)"),
               ("late", "late frame", "late frames", "dropped (out of order)"),
               ("stray", "stray set", "stray sets", "ignored (cursor not alive)"),
               ("over_limit", "cursor or source command", "cursor or source commands",
                "ignored (over the limit)"),
               ("unread", "argument", "arguments", "unread (over the limit of one message)"))


def tuio_line(counts: dict) -> str:
    """The demo's last line about a TUIO input: from its ``counters()``, what came from
    whom, every nonzero count of what was not played and why, the kinds of malformed
    datagrams and cursor sets with their counts, and the takeovers."""
    if counts["sender"] is not None:
        sender = counts["sender"]
    elif counts["refused"]:
        sender = "no sender (none was served)"
    else:
        sender = "no sender (nothing came)"
    drops = [f"{counted(counts[key], noun, nouns)} {why}"
             for key, noun, nouns, why in _TUIO_DROPS if counts[key]]
    if counts["sender"] is None and counts["refused"]:
        drops[0] = f"{counted(counts['refused'], 'datagram')} refused (none claimed the input)"
    if counts["malformed"]:
        kinds = ", ".join(f"{n} {kind}" for kind, n in counts["malformed"].items())
        drops.append(f"by kind (datagrams and cursor sets together): {kinds}")
    if counts["takeovers"]:
        drops.append(f"{counted(counts['takeovers'], 'takeover')} after a silence")
    return (f"demo: TUIO on {counts['listen']} from {sender}: "
            f"{counted(counts['datagrams'], 'datagram')}; {', '.join(drops) or 'nothing dropped'}")


def run(args: argparse.Namespace) -> int:
    if args.block is None:
        from frictex.app.live.haptic_thread import BLOCK_S
        from frictex.rendering.pipeline import default_block_size
        args.block = default_block_size(args.rate, BLOCK_S)
    kind, arg = args.input
    if args.tuio_from is not None:
        if kind != "tuio":
            raise InputError(f"--tuio-from needs --input tuio (the input is {input_name(kind, arg)})")
        args.input = (kind, replace(arg, accept_from=args.tuio_from))
    if kind == "tuio" and not args.headless:  # headless refuses a live input anyway
        from frictex.rendering.input.tuio import exposure_warning
        warning = exposure_warning(arg.host, args.tuio_from)
        if warning is not None:
            print(f"frictex demo: {warning}", file=sys.stderr, flush=True)
    sim_device_args(args)  # options needing a device refused before the window opens
    try:
        return _run(args, headless=args.headless)
    except NoDisplayError as exc:
        if args.headless or not args.headless_fallback:
            raise NoDisplayError(f"{exc}: the demo needs a window. Without a display run "
                                 "'frictex demo --headless' (the demo on a synthesized stroke, "
                                 "writing frames) or 'frictex replay SCENE TRACE --out DIR'"
                                 ) from None
        print(f"frictex demo: {exc}; running the demo headless on a synthesized stroke instead",
              flush=True)
        return _run(args, headless=True)


def _open_window(args, size, scene, frames_dir: Path | None):
    """The demo's window (glfw), or with ``frames_dir`` (headless: --out's staging
    folder) an injected-input one whose frames go to ``frames_dir``/frames; and the
    frame files (None with a window)."""
    if frames_dir is None:
        return open_backend("glfw", size, title=f"frictex demo: {scene.name}",
                            fullscreen=args.fullscreen, monitor=args.monitor, vsync=False), None
    from frictex.app.live.frame_files import FrameFiles
    frames = FrameFiles(frames_dir / FRAMES)
    return open_backend("headless", size, on_frame=frames.write), frames


def _run(args: argparse.Namespace, headless: bool) -> int:
    """The demo on a window, or ``headless`` on a synthesized stroke (outputs to --out)."""
    from frictex.app.live.inputs import INPUTS
    kind, arg = args.input
    if headless and INPUTS.get(kind).touch_screen:
        raise InputError(f"--input {input_name(kind, arg)}: the headless demo drives the mouse "
                         "with a synthesized stroke and takes no touch screen")
    paths, index = _playlist(args.scene)
    scene = _load(paths[index])
    staging, frames_staging = _stagings(args, headless)
    for folder in (staging, frames_staging):
        if folder is not None:
            folder.check()
    with deferred_interrupts() as check:  # a signal held is raised as it ends (exit 128 + n)
        return _run_demo(args, headless, paths, index, scene, (staging, frames_staging), check)


def _stagings(args, headless: bool) -> tuple[Staging | None, Staging | None]:
    """Where the demo writes: (the recording's tables, events and summary: ``--record``,
    or headless without it ``--out``; the headless frames' ``--out`` when that is another
    folder, else None). Each is replaced as a whole when the demo ends."""
    record = Path(args.record) if args.record else None
    out = Path(args.out) if headless else None
    if record is None or out is None or record.resolve() == out.resolve():
        tables = record or out
        return (None if tables is None else Staging(tables, owned=DEMO_OUTPUTS)), None
    # the frames' own folder has no summary.json of its own (the recording's has it)
    return (Staging(record, owned=DEMO_OUTPUTS),
            Staging(out, owned=DEMO_OUTPUTS, claimed_by_summary=False))


def _run_demo(args, headless: bool, paths, index: int, scene, stagings, check) -> int:
    """:func:`_run` with its outputs staged in ``stagings`` (:func:`_stagings`; the first
    None: no recording) and SIGINT, SIGTERM and SIGHUP held by ``check``
    (``deferred_interrupts``): the first ends the demo as Q does (the recording
    committed), and is raised after its lines."""
    staging, frames_staging = stagings
    from frictex.app.live.inputs import INPUTS
    kind, arg = args.input
    touch_screen = INPUTS.get(kind).touch_screen
    size = args.size or default_frame_size(scene)
    previous = staging is not None and any(
        (staging.out / name).exists() for name in ("summary.json", "commands.csv", "events.csv"))
    record = None if staging is None else staging.begin()
    try:
        frames_dir = None if not headless else (
            record if frames_staging is None else frames_staging.begin())
        result = _live(args, paths, index, scene, size, record, frames_dir, touch_screen, check)
        summary = result.summary
        if record is not None:
            if staging.removed:
                summary["warnings"] = [f"removed the leftovers of killed runs beside "
                                       f"{staging.out.name}: " + ", ".join(staging.removed)]
            (record / "summary.json").write_text(json.dumps(finite_json(summary), indent=2,
                                                            allow_nan=False) + "\n",
                                                 encoding="utf-8")
            staging.commit()
        if frames_staging is not None:
            frames_staging.commit()
    except BaseException:
        check.end()
        for folder in (staging, frames_staging):
            if folder is not None:
                folder.abort()
        if staging is not None and len(check.held) > 1:
            kept = "the previous recording is kept" if previous else "nothing was written"
            print(f"frictex demo: a second signal: the recording in {staging.out} was not "
                  f"written ({kept})", file=sys.stderr, flush=True)
        raise
    _print_lines(args, summary, result, None if staging is None else staging.out,
                 (frames_staging or staging).out / FRAMES if headless else None)
    if previous:
        print(f"demo: replaced the previous recording in {staging.out}")
    problem = device_problem(result.link, unplayed_limit(args))
    if problem is not None:
        where = "" if staging is None else f"; outputs in {staging.out}"
        print(f"frictex demo: error: {problem}{where}", file=sys.stderr)
        return 1
    return 0


def unplayed_limit(args) -> float:
    """The share of the commanded samples a device may leave unplayed (``--max-unplayed``,
    catch-up skips not counted)."""
    given = getattr(args, "max_unplayed", None)
    return MAX_UNPLAYED if given is None else given


def held_to_limits(link: dict, max_unplayed: float) -> str:
    """The closing line's words on which unplayed share each limit holds: those not
    skipped to catch up to ``max_unplayed``, the skipped to :data:`MAX_CATCH_UP`."""
    commanded = link.get("commanded_samples") or 0
    if not commanded:
        return ""
    causes = link.get("unplayed_by_cause", {})
    skipped = sum(causes.get(cause, 0) for cause in CATCH_UP)
    held = link["unplayed_samples"] - skipped
    return (f"; {held / commanded:.2%} held to --max-unplayed {max_unplayed:.2%}, "
            f"the skipped {skipped / commanded:.2%} to {MAX_CATCH_UP:.0%}")


def device_problem(link: dict, max_unplayed: float) -> str | None:
    """Why a demo on a device failed (exit 1): its link lost and not back by the end
    (``link``: the link's last status), or more than ``max_unplayed`` of the commanded
    samples never played (catch-up skips not counted), or more than :data:`MAX_CATCH_UP`
    of them were skipped; None for a run without a device or one that played enough."""
    lost = link.get("disconnects", 0) - link.get("reconnects", 0)
    if lost > 0 or link.get("state") in ("disconnected", "failed"):
        why = link.get("last_error") or "port failed"
        return f"the device link was lost ({why}) and not back by the end"
    commanded = link.get("commanded_samples") or 0
    skipped = sum(link.get("unplayed_by_cause", {}).get(cause, 0) for cause in CATCH_UP)
    if commanded and skipped / commanded > MAX_CATCH_UP:
        return (f"the link skipped {skipped / commanded:.2%} of the commanded samples to catch "
                f"up (limit {MAX_CATCH_UP:.0%}): this machine did not keep up with the device")
    return unplayed_problem(link, max_unplayed, "--max-unplayed", excused=CATCH_UP)


@dataclass
class _Ended:
    """What a demo's run left for its summary and last lines."""

    summary: dict
    link: dict
    frames: object  # FrameFiles (headless) or None
    hand: object  # SyntheticStroke (headless) or None


def _live(args, paths, index, scene, size, record, frames_dir, touch_screen, check) -> _Ended:
    """Start the haptic side, open the window (headless: ``frames_dir`` given, the
    folder its frames go into), run the loop until it ends (Q, the window closed,
    ``--duration``, a signal held by ``check``), stop both."""
    from frictex.app.live.cpu_steal import StealMeter
    from frictex.app.live.demo_loop import DemoLoop
    kind, arg = args.input
    # first the haptic side: a bad --input or --device fails before a window opens
    haptic, finish = _start_haptic(args, scene, paths[index], record)
    loop = backend = frames = hand = None
    link = {"state": "none"}
    dropped_records = 0
    steal = StealMeter()
    try:
        backend, frames = _open_window(args, size, scene, frames_dir)
        if args.haptic == "process":  # llvmpipe's threads, started with the window,
            # yield to the child; this thread (input) does not, nor the render thread
            # it starts, which mostly waits on llvmpipe and holds the GIL the input
            # thread needs: niced, it could be descheduled holding it)
            from frictex.app.live.haptic_process import yield_to_haptic
            yield_to_haptic(keep=(threading.get_native_id(),))
        loop = DemoLoop(backend, haptic, paths, index, scene, _load, Path(args.screenshots),
                        events_path=record / "events.csv" if record else None,
                        link_name="none" if args.device is None else "starting",
                        follow_mm=arg if kind == "follow" else None,
                        touch_screen=touch_screen, input_name=input_name(kind, arg))
        if frames is not None:
            from frictex.app.live.synthetic import SyntheticStroke
            hand = SyntheticStroke(backend, loop.compositor.viewport.to_px,
                                   (scene.display.width_mm, scene.display.height_mm),
                                   duration_s=args.duration or STROKE_S,
                                   lifted=lambda: not loop.fingers_down)
            hand.start()
        try:  # headless: the stroke (--duration long) ends the run, lifted, with Q
            loop.run(args.duration if hand is None else None, stop=lambda: bool(check.held))
        except Exception:
            if not check.held:  # the output stopped as a signal came (timeout signals
                raise  # the process group): the signal ends the demo, as it asked
    finally:
        if hand is not None:
            hand.stop()
        if check.held and record is not None:  # the link's drain can take seconds
            print("frictex demo: stopping the plate and writing the recording (another "
                  "signal ends the demo at once, without it)", file=sys.stderr, flush=True)
        try:
            link, dropped_records = finish()
        finally:
            if loop is not None:
                loop.close()
            if backend is not None:
                backend.close()
    summary = _summary(haptic.stats, haptic.block_s, loop, dropped_records, link)
    summary["haptic"] = args.haptic
    summary["clock_origin_s"] = haptic.t0  # output time 0 on CLOCK_MONOTONIC (time.monotonic)
    summary["cpu_steal_pct"] = steal.percent()
    summary["ended_by"] = signal.Signals(check.held[0]).name if check.held else "window"
    return _Ended(summary, link, frames, hand)


def _print_lines(args, summary: dict, ended: _Ended, out: Path | None,
                 frames_out: Path | None) -> None:
    """The demo's last lines on stdout: blocks, link, input, frames (headless: kept in
    ``frames_out``), control."""
    link, frames, hand = ended.link, ended.frames, ended.hand
    misses = summary["deadline_misses"]
    notes = [f"worst {summary['worst_lateness_ms']:.1f} ms late"] if misses else []
    if misses and summary["cpu_steal_pct"] is not None:
        notes.append(f"CPU steal by a VM host meanwhile: {summary['cpu_steal_pct']:.0f} %")
    late = f" ({'; '.join(notes)})" if notes else ""
    print(f"demo: {counted(summary['blocks'], 'block')} ({summary['output_s']:.1f} s of "
          f"output), {counted(misses, 'deadline miss', 'deadline misses')}"
          f"{late}, "
          f"{counted(summary['clamps_total'], 'clamped sample')}{device_clamps(link)}, "
          f"{counted(summary['frames'], 'frame')} drawn ({summary['frame_ms_mean']:.1f} ms mean), "
          f"link: {link['state']}")
    if "skipped_blocks" in link:  # a device link: what its lead cost
        skipped = link["skipped_blocks"]
        print(f"demo: link: the device ran dry {counted(run_underruns(link), 'time')} and "
              f"{counted(skipped, 'block')} {were(skipped)} skipped to catch up; "
              f"{link['unplayed_samples']} of {link['commanded_samples']} samples unplayed"
              + "".join(f", {k} {v}" for k, v in link["unplayed_by_cause"].items() if v)
              + held_to_limits(link, unplayed_limit(args)))
    for warning in faults_not_reached(link):
        print(f"frictex demo: warning: {warning}", file=sys.stderr)
    if summary["dropped_record_blocks"]:  # the recorder fell behind: the tables miss them
        print(f"frictex demo: warning: {counted(summary['dropped_record_blocks'], 'block')} "
              f"{were(summary['dropped_record_blocks'])} left out of the recording (its "
              "writer's queue was full): its tables miss them", file=sys.stderr)
    if "datagrams" in summary["input_counts"]:  # TUIO: what came from whom
        print(tuio_line(summary["input_counts"]))
    if frames is not None:
        from frictex.app.live.frame_files import FPS
        print(f"demo: headless, {stroke_said(hand, summary['ended_by'])} drove "
              f"the mouse: {counted(frames.count, 'frame')} kept (at most {FPS:g} a second; "
              f"{frames.save_s / max(frames.count, 1) * 1e3:.1f} ms each to save as PNG, within "
              f"the frames' mean) in {frames_out}; outputs in {out}")
    if summary["control"] is not None:
        from frictex.app.engine.summary import control_line
        print(f"demo: {control_line(summary['control'])}")


def stroke_said(hand, ended_by: str) -> str:
    """The synthesized stroke as the headless demo's last line says it: "a synthesized
    stroke of 3 s", or where the demo ended first, how far it went and what cut it
    ("... cut at 1.6 s of its 3 s by SIGTERM"; ``ended_by``: the summary's)."""
    if hand.stroked_s >= hand.duration_s:
        return f"a synthesized stroke of {hand.duration_s:g} s"
    by = ended_by if ended_by != "window" else "the window closing"
    return (f"a synthesized stroke cut at {hand.stroked_s:.1f} s of its {hand.duration_s:g} s "
            f"by {by}")


def _summary(st, block_s: float, loop, dropped_records: int, link) -> dict:
    return {"blocks": st.blocks, "output_s": st.blocks * block_s,
            "deadline_misses": st.deadline_misses, "worst_lateness_ms": st.worst_lateness_s * 1e3,
            "dropped_touches": st.dropped_touches, "dropped_snapshots": st.dropped_snapshots,
            "dropped_record_blocks": dropped_records, "ramps": st.ramps,
            "clamps": st.clamps.as_dict(), "clamps_total": st.clamps.total,
            "output_changes": [{"t_s": t, "event": e, "detail": d} for t, e, d in st.applied],
            "input": loop.input_name, "input_counts": st.input,
            "frames": loop.frames, "frame_ms_mean": loop.frame_seconds / max(loop.frames, 1) * 1e3,
            "screenshots": [str(p) for p in loop.screenshots], "link": link,
            "control": st.control}

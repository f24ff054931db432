"""``frictex demo [SCENE]``: the live demo window; the mouse is a finger.

With no SCENE the window cycles through the bundled scenes (N / B). The haptic
pipeline runs on its own thread at block cadence (``app.haptic_thread``), the window
on the main thread (``app.demo_loop``). ``--record DIR`` writes what was sent
(``commands.csv``, ``friction.csv`` as in a replay), ``events.csv`` and ``summary.json``.

Without a display: ``frictex demo`` says so and exits 2; ``--headless`` (or
``--headless-fallback`` when no display is found) replays the bundled swipe trace on
the scene instead and writes its outputs and PNG frames to ``--out``.
"""

from __future__ import annotations

import argparse
import json
import queue
import sys
import threading
from pathlib import Path

from app.cmd_preview import frame_size
from app.cmd_replay import positive_float, positive_int
from app.outputs import TableWriter
from app.replay import FRICTION_COLUMNS, friction_rows
from rendering.visual.context import NoDisplayError, open_backend

HEADLESS_TRACE = "swipe-40mms-50hz"
RECORD_QUEUE = 4000  # blocks (20 s at 5 ms) the writer may fall behind before dropping


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("scene", nargs="?", default=None,
                        help="texture file (.toml) or bundled scene name; default: the bundled playlist")
    parser.add_argument("--fullscreen", action="store_true", help="fullscreen on --monitor")
    parser.add_argument("--monitor", type=int, default=0, metavar="N", help="monitor for --fullscreen (default 0)")
    parser.add_argument("--size", type=frame_size, default=None, metavar="WxH",
                        help="window size in px (default: the scene's display size)")
    parser.add_argument("--renderer", choices=("sho", "sht", "hybrid"), default=None,
                        help="start with every periodic layer rendered this way (R cycles it live)")
    parser.add_argument("--device", metavar="sim|PORT", default=None,
                        help="stream the commands: 'sim' starts a simulated device, otherwise a "
                             "serial port or pyserial URL (default: no link)")
    parser.add_argument("--rate", type=positive_float, default=10_000.0, metavar="HZ",
                        help="output sample rate (default 10000 Hz)")
    parser.add_argument("--block", type=positive_int, default=50, metavar="N",
                        help="block size in output samples (default 50 = 5 ms at 10 kHz)")
    parser.add_argument("--record", metavar="DIR", default=None,
                        help="write commands.csv, friction.csv, events.csv and summary.json to DIR")
    parser.add_argument("--screenshots", metavar="DIR", default=".",
                        help="folder for screenshots taken with P (default: current folder)")
    parser.add_argument("--duration", type=positive_float, default=None, metavar="S",
                        help="close the window after S seconds (default: run until closed)")
    mode = parser.add_mutually_exclusive_group()
    mode.add_argument("--headless", action="store_true",
                      help="no window: replay the bundled trace on the scene into --out, with frames")
    mode.add_argument("--headless-fallback", action="store_true",
                      help="open the window if a display exists, else behave as --headless")
    parser.add_argument("--out", metavar="DIR", default="frictex-demo-out",
                        help="output folder for --headless (default: frictex-demo-out)")


class Recorder:
    """Writes each block's commands and friction rows on its own thread; the haptic
    thread only enqueues (a full queue drops the block, counted in ``dropped``)."""

    def __init__(self, out_dir: Path, channels: tuple[str, ...]):
        out_dir.mkdir(parents=True, exist_ok=True)
        self.channels = channels
        cols = [("t_s", float, "%.7f")] + [(f"{ch}_um", float, "%.6f") for ch in channels]
        self.commands = TableWriter(out_dir, "commands", cols, "csv")
        self.friction = TableWriter(out_dir, "friction", FRICTION_COLUMNS, "csv")
        self.queue: queue.Queue = queue.Queue(RECORD_QUEUE)
        self.dropped = 0
        self.thread = threading.Thread(target=self._run, name="frictex-recorder", daemon=True)
        self.thread.start()

    def __call__(self, out, commands_um) -> None:
        try:
            self.queue.put_nowait((out, commands_um))
        except queue.Full:
            self.dropped += 1

    def _run(self) -> None:
        while (item := self.queue.get()) is not None:
            out, commands = item
            cols = {"t_s": out.t_s}
            cols.update({f"{ch}_um": commands[:, k] for k, ch in enumerate(self.channels)})
            self.commands.write(cols)
            self.friction.write(friction_rows(out))

    def close(self) -> None:
        self.queue.put(None)
        self.thread.join()
        self.commands.commit()
        self.friction.commit()


def _playlist(scene_arg):
    from textures.library import list_scenes, resolve_scene
    if scene_arg is not None:
        return [resolve_scene(scene_arg)], 0
    paths = [entry.path for entry in list_scenes()]
    if not paths:
        raise ValueError("no bundled scenes found; give a texture file")
    return paths, 0


def _load(path):
    from textures.loader import load_scene
    return load_scene(path)


def run_headless(args, reason: str | None = None) -> int:
    from app.frames import FrameWriter
    from app.replay import run_replay
    paths, index = _playlist(args.scene)
    scene = _load(paths[index])
    if reason:
        print(f"frictex demo: {reason}; running headless instead")
    frames = FrameWriter(args.out, scene, fps=30.0, rate_hz=args.rate)
    summary = run_replay(scene, HEADLESS_TRACE, args.out, rate_hz=args.rate, block_size=args.block,
                         render_override=args.renderer, progress=False, frames=frames)
    print(f"replayed {HEADLESS_TRACE} on {scene.name}: {summary['output']['samples']} output samples, "
          f"{frames.count} frames in {Path(args.out) / 'frames'}; outputs in {args.out}")
    return 0


def run(args: argparse.Namespace) -> int:
    if args.headless:
        return run_headless(args)
    paths, index = _playlist(args.scene)
    scene = _load(paths[index])
    size = args.size or (scene.display.width_px, scene.display.height_px)
    try:
        backend = open_backend("glfw", size, title=f"frictex demo: {scene.name}",
                               fullscreen=args.fullscreen, monitor=args.monitor)
    except NoDisplayError as exc:
        if args.headless_fallback:
            return run_headless(args, reason=str(exc))
        raise NoDisplayError(f"{exc}: the demo needs a window. Without a display run "
                             "'frictex demo --headless' (replays a bundled trace, writes frames) "
                             "or 'frictex replay SCENE TRACE --out DIR'") from None
    from app.demo_loop import DemoLoop
    from app.haptic_thread import HapticThread
    # the haptic thread must get the GIL back within a fraction of a block, not after
    # the default 5 ms switch interval (a whole block at 10 kHz / 50 samples)
    sys.setswitchinterval(min(sys.getswitchinterval(), 0.25 * args.block / args.rate))
    sink = recorder = haptic = loop = None
    record = Path(args.record) if args.record else None
    try:
        if args.device is not None:
            from device.link import open_sink
            sink = open_sink(args.device, channels=1, rate_hz=args.rate, paced=False)
        haptic = HapticThread(scene, args.rate, args.block, args.renderer, sink=sink)
        if record is not None:
            recorder = Recorder(record, haptic.pipeline.channels)
            haptic.recorder = recorder
        loop = DemoLoop(backend, haptic, paths, index, scene, _load, Path(args.screenshots),
                        events_path=record / "events.csv" if record else None,
                        link_name="none" if sink is None else "starting")
        haptic.start()
        loop.run(args.duration)
    finally:
        if haptic is not None:
            haptic.stop()
            if haptic.is_alive():
                haptic.join(timeout=2.0)
        if recorder is not None:
            recorder.close()
        link = sink.status() if sink is not None else {"state": "none"}
        if sink is not None:
            sink.close()
        if loop is not None:
            loop.close()
        backend.close()
    summary = _summary(haptic, loop, recorder, link)
    if record is not None:
        (record / "summary.json").write_text(json.dumps(summary, indent=2) + "\n", encoding="utf-8")
    print(f"demo: {summary['blocks']} blocks ({summary['output_s']:.1f} s of output), "
          f"{summary['deadline_misses']} deadline misses, {summary['clamps_total']} clamped samples, "
          f"{summary['frames']} frames ({summary['frame_ms_mean']:.1f} ms mean), link: {link['state']}")
    return 0


def _summary(haptic, loop, recorder, link) -> dict:
    st = haptic.stats
    return {"blocks": st.blocks, "output_s": st.blocks * haptic.block_s,
            "deadline_misses": st.deadline_misses, "worst_lateness_ms": st.worst_lateness_s * 1e3,
            "dropped_touches": st.dropped_touches, "dropped_snapshots": st.dropped_snapshots,
            "dropped_record_blocks": recorder.dropped if recorder else 0, "ramps": st.ramps,
            "clamps": st.clamps.as_dict(), "clamps_total": st.clamps.total,
            "frames": loop.frames, "frame_ms_mean": loop.frame_seconds / max(loop.frames, 1) * 1e3,
            "screenshots": [str(p) for p in loop.screenshots], "link": link}

"""The live haptic pipeline on its own thread, block by block, on the run engine.

The thread runs ``app.engine.driver.drive`` with the live touch queue as its source
(``app.engine.sources.QueueSource``), :class:`LiveStage` (the pipeline, scene switches
and the emergency stop) and as sinks the device link, the recording and the window's
snapshots. Its clock (``app.engine.clocks``) is the wall clock: block k starts at
t0 + k * block / rate (a block of 25 samples, 2.5 ms at 10 kHz, by default: a touch waits
at most one block for the next boundary). The link asks its device to start playing once
its jitter buffer holds ``LEAD_BLOCKS`` blocks (:func:`link_options`: the prefill), so
block k is due that long after its start; one sent later is a deadline miss (counted,
with the worst lateness past the block's own end), and the thread catches up without
sleeping. A device that fell behind (it ran dry and waited for its prefill again, or its
clock is slow) is brought back to that lead by the link, which skips blocks
(``device.link.catch_up``): a touch is felt the same lead after it, however long the
run. With ``pacing="device"`` the device's own sample clock paces the blocks
instead (each wait bounded). The thread never waits on the window: a full snapshot
queue drops the oldest snapshot (counted).

Changes between blocks ramp across one block (STYLE.md 5): a scene or renderer switch
crossfades the old pipeline's commands into the new one's (the new pipeline takes over
the old one's finger tracks), resuming after an emergency stop ramps from 0. The
emergency stop itself is immediate: while it is set every sample sent is 0 um, and the
amplitude under each finger the output reports (friction.csv, the scope) is the 0 um sent
(a ramp scales it as it scales the commands); the friction inversion's clamps count only
the samples played, none while stopped. Each
stop, resume and switch as it took effect on the output is kept in ``stats.applied``
(output time of its first block, kind, detail) and the latest reach the window with
every snapshot, so the demo logs when the output changed, not when a key was pressed.

Touch samples carry times on this thread's clock (``now()``, s since start). A sample
is used from the first block boundary at or after its time (``rendering.tracking.tracks``).
Samples from several fingers and sources (the mouse, a TUIO or evdev touch screen) may
be queued one after another; their stamps never go back (``touch_at``). A touch screen
(``pump``: ``app.live.touch_pump.TouchPump``) feeds the queue from a thread of its own
as its samples arrive, whatever the window is doing.
"""

from __future__ import annotations

import queue
import sys
import threading
import time
from dataclasses import dataclass, field, replace
from types import SimpleNamespace

import numpy as np

from frictex.app.engine.clocks import DevicePacedClock, WallClock
from frictex.app.engine.driver import drive, force_reports_of
from frictex.app.engine.sinks import LinkSink
from frictex.app.engine.sources import QueueSource
from frictex.app.live.touch_log import LoggedTouches
from frictex.device.friction import ClampCounts
from frictex.rendering.input.trace_file import DOWN, MOVE, UP
from frictex.rendering.pipeline import PipelineState, build_pipeline, default_block_size
from frictex.rendering.visual.overlay import BlockRecord, record_from_output

TOUCH_QUEUE = 4096
COMMAND_QUEUE = 64
SNAPSHOT_QUEUE = 256
#: the live block (s): a touch waits at most this long to take effect
BLOCK_S = 0.0025
#: the live block at 10 kHz (samples)
BLOCK_SIZE = default_block_size(10_000.0, BLOCK_S)
#: blocks a live link's device holds before it plays: one playing, one on its way
LEAD_BLOCKS = 2
#: the least prefill a live link asks for, whatever the block (s): a thread handing over
#: a block every half millisecond is late more often than not (``--block 5``: three
#: blocks in four skipped with a prefill of two blocks)
MIN_PREFILL_S = 0.005
LINK_STATUS_EVERY = 20  # blocks between two sink.status() calls
APPLIED_IN_STATUS = 8  # the latest stops, resumes and switches each snapshot carries
EVENTS = {"down": DOWN, "move": MOVE, "up": UP}


def live_prefill_s(block_s: float) -> float:
    """A live link's prefill for blocks of ``block_s`` (s): :data:`LEAD_BLOCKS` blocks, at
    least :data:`MIN_PREFILL_S`; a block is due that long after its start."""
    return max(LEAD_BLOCKS * block_s, MIN_PREFILL_S)


def link_options(block_s: float) -> dict:
    """``open_sink``'s keywords for a live link whose blocks last ``block_s`` (s): its
    prefill (:func:`live_prefill_s`) and the catch-up."""
    return {"prefill_s": live_prefill_s(block_s), "catch_up": True}


def shorten_switch_interval(block_s: float) -> None:
    """Let the haptic thread get the GIL back within a quarter of a block (``block_s``,
    s), not after Python's default 5 ms switch interval (two blocks at 10 kHz / 25)."""
    sys.setswitchinterval(min(sys.getswitchinterval(), 0.25 * block_s))


@dataclass(frozen=True)
class Snapshot:
    """What the window needs from one block: the decimated record and the counters."""

    record: BlockRecord
    status: dict


@dataclass
class HapticStats:
    blocks: int = 0
    deadline_misses: int = 0
    worst_lateness_s: float = 0.0
    dropped_touches: int = 0
    dropped_snapshots: int = 0
    dropped_records: int = 0
    ramps: int = 0
    clamps: ClampCounts = field(default_factory=ClampCounts)
    #: the friction loop's figures when the thread stopped (``ClosedLoop.report``), or None
    control: dict | None = None
    #: (output time s of the first block it shaped, "output-stop" | "output-resume" |
    #: "output-switch" | "loop" (what the friction loop said), detail) in the order they
    #: took effect
    applied: list = field(default_factory=list)
    #: a touch screen's counts when it stopped (``TouchPump.counters``: samples forwarded;
    #: TUIO's counters, ``TuioListener.counters``), else empty
    input: dict = field(default_factory=dict)


class ChannelMismatch(ValueError):
    """A scene that drives other channels than the outputs open (``held``: "the link",
    "the recording" or both, as :func:`held_outputs` says them) were opened for
    (``wants``, ``opened``: the channels with the device profile, as text): the demo
    cannot switch to it without reopening them."""

    def __init__(self, scene: str, wants: str, opened: str, held: str):
        verb = "were" if " and " in held else "was"
        super().__init__(f"{scene} drives channels {wants}; {held} {verb} opened "
                         f"for {opened}: start the demo on that scene instead")
        self.scene, self.wants, self.opened, self.held = scene, wants, opened, held

    def __reduce__(self):  # sent from the haptic process to the window's
        return type(self), (self.scene, self.wants, self.opened, self.held)


def say_at_end(messages) -> None:
    """What the friction loop says only once it has run (``ClosedLoop.report``: reports
    missed or late, a loop that never closed) on stderr, as the window says its messages
    while it runs (those were said then)."""
    for message in messages:
        print(f"frictex: {message}", file=sys.stderr, flush=True)


def held_outputs(link: bool, recording: bool) -> str:
    """The outputs open for one set of channels, as a message names them: "the link",
    "the recording", "the link and the recording" ("" for none)."""
    return " and ".join(name for name, is_open in (("the link", link), ("the recording", recording))
                        if is_open)


class TouchInput:
    """The window's side of the touch queue: ``now()``, ``touch``, ``touch_at``.

    Needs ``clock``, ``t0`` (the output clock's start on ``clock``), ``touches`` (a
    queue), ``stats`` (a :class:`HapticStats`) and ``_last_stamp`` (s, initially 0).
    """

    def now(self) -> float:
        """Seconds on the haptic output clock."""
        return self.clock() - self.t0

    def touch(self, finger: int, x_mm: float, y_mm: float, force_n: float, event: str) -> None:
        """Queue a touch sample stamped now (``event``: "down", "move" or "up")."""
        self.touch_at(self.now(), finger, x_mm, y_mm, force_n, EVENTS[event])

    def touch_at(self, t_s: float, finger: int, x_mm: float, y_mm: float, force_n: float,
                 event: int) -> None:
        """Queue a touch sample stamped ``t_s`` (s, the output clock; ``event`` a
        ``rendering.input.trace_file`` code), moved into [the last stamp, now]: a live batch must
        not go back in time, and a sample from the future would wait. Never blocks (a full
        queue drops the sample, counted). Call it from one thread (the window's)."""
        self.touches_at(t_s, [(finger, x_mm, y_mm, force_n, event)])

    def touches_at(self, t_s: float, fingers) -> None:
        """:meth:`touch_at` for several fingers at one instant, ``fingers`` a list of
        ``(finger, x_mm, y_mm, force_n, event)``: one stamp and one queue item, so the
        haptic side takes them in the same block however the window's thread is scheduled
        (follow mode's second finger came a block late under a CPU hog)."""
        t = max(min(float(t_s), self.now()), self._last_stamp)
        self._last_stamp = t
        try:
            self.touches.put_nowait([(t, *finger) for finger in fingers])
        except queue.Full:
            self.stats.dropped_touches += len(fingers)


class LiveStage:
    """The live pipeline: scene and renderer switches crossfaded across one block, the
    emergency stop (immediate: 0 um while set; resuming ramps from 0 over a block), the
    normal force and the force reports the device measures (the friction loop's: it is
    told what the plate played where a stop, ramp or crossfade changed the commands, and
    what it says goes to ``stats.applied`` as a "loop" event for the window), and the
    clamp counts (STYLE.md 5)."""

    def __init__(self, pipeline, estop, stats: "HapticStats"):
        self.pipeline = pipeline
        self.state = pipeline.initial_state()
        self.estop = estop
        self.stats = stats
        self.changes: queue.Queue = queue.Queue(COMMAND_QUEUE)
        self.render_override = None
        self.device_force = None  # callable -> N or None, when a link measures it
        self.force_reports = None  # callable (index0, n) -> ForceReport or None, from a link
        self._said = 0  # the loop's messages written so far
        self.stopped = estop.is_set()
        self._gain = 0.0 if self.stopped else 1.0

    def process(self, k: int, samples, n: int):
        change = self._latest_change()
        out, commands, played = self._run(k, samples, change)
        t = float(out.t_s[0])
        if change is not None:
            self.stats.applied.append((t, "output-switch",
                                       f"{change[0].scene.name}, {change[1] or 'file'}"))
        was_stopped, self.stopped = self.stopped, self.estop.is_set()
        if self.stopped != was_stopped:
            self.stats.applied.append((t, "output-stop" if self.stopped else "output-resume", ""))
        if self.stopped:  # the output (the recording, the scope) shows the 0 um sent,
            # and the clamps of the commands not sent are not counted
            commands = np.zeros_like(commands)
            out = replace(out, amplitude_um=np.zeros_like(out.amplitude_um), clamps=ClampCounts())
            played = 0.0
        elif self._gain < 1.0:
            ramp = np.linspace(self._gain, 1.0, commands.shape[0] + 1)[1:]
            commands = commands * ramp[:, None]
            out = replace(out, amplitude_um=out.amplitude_um * ramp)
            played = ramp if played is None else played * ramp
            self.stats.ramps += 1
        self._gain = 0.0 if self.stopped else 1.0
        self.stats.clamps.add(out.clamps)
        self.stats.blocks += 1
        loop, control = self.pipeline.control, self.state.control
        if loop is not None:
            if played is not None:  # the plate played other than the loop asked
                self.state = replace(self.state, control=loop.played(control, played))
            for message in control.messages[self._said:]:  # the window logs them
                self.stats.applied.append((t, "loop", message))
            self._said = len(control.messages)
        return out, commands

    def _latest_change(self):
        latest = None
        while True:
            try:
                latest = self.changes.get_nowait()
            except queue.Empty:
                return latest

    def _run(self, k, samples, change):
        """(output, commands, the gain per sample the new pipeline's commands were
        crossfaded in with, or None when they go out as computed)."""
        force = None if self.device_force is None else self.device_force()
        measured = {"normal_force_n": force, "force_reports": self.force_reports}
        if change is None:
            out, self.state = self.pipeline.process(k, samples, self.state, **measured)
            return out, out.commands_um, None
        # crossfade: both pipelines run this block from the same finger tracks (another
        # device, with other channels, ramps up from 0 instead)
        new, self.render_override = change
        fresh = new.initial_state()  # its own layers, wave forces and loop, from rest
        new_state = PipelineState(tracker=self.state.tracker, layers=fresh.layers,
                                  forces=fresh.forces, control=fresh.control)
        old_out, _ = self.pipeline.process(k, samples, self.state, **measured)
        out, self.state = new.process(k, samples, new_state, **measured)
        self._said = 0
        same_device = new.channels == self.pipeline.channels
        self.pipeline = new
        fade = np.linspace(0.0, 1.0, out.commands_um.shape[0] + 1)[1:, None]
        self.stats.ramps += 1
        before = old_out.commands_um * (1.0 - fade) if same_device else 0.0
        return out, before + out.commands_um * fade, fade[:, 0]


def _layout(pipeline) -> str:
    """A pipeline's channels and device profile, as :class:`ChannelMismatch` says them."""
    phases = ", with phases" if pipeline.actuation.has_phases else ""
    return f"{', '.join(pipeline.channels)} ({pipeline.scene.device.profile}{phases})"


class SnapshotSink:
    """Hands the window a decimated record of every block with the counters, through a
    bounded queue that drops the oldest snapshot when full (counted)."""

    def __init__(self, haptic: "HapticThread"):
        self.haptic = haptic
        self._link = {"state": "none"}

    def write(self, out, commands_um) -> None:
        h = self.haptic
        if h.sink is not None and h.stats.blocks % LINK_STATUS_EVERY == 1:
            self._link = h.sink.status()
        applied = h.stats.applied
        status = {"blocks": h.stats.blocks, "deadline_misses": h.wall.stats.misses,
                  "clamps": h.stats.clamps.total, "estop": h.stage.stopped,
                  "renderer": h.stage.render_override or "file", "link": self._link,
                  "applied": (len(applied), tuple(applied[-APPLIED_IN_STATUS:]))}
        snap = Snapshot(record_from_output(out, h.stride, commands_um=commands_um), status)
        try:
            h.snapshots.put_nowait(snap)
        except queue.Full:
            h.stats.dropped_snapshots += 1
            try:
                h.snapshots.get_nowait()
                h.snapshots.put_nowait(snap)
            except (queue.Empty, queue.Full):
                pass

    def commit(self) -> None:
        """Nothing to finish."""

    abort = commit


class HapticThread(TouchInput, threading.Thread):
    """Runs ``build_pipeline(scene, ...)`` live; see the module docstring.

    ``sink``: optional device link (``device.link.host.open_sink(..., paced=False)``),
    closed by the thread when it stops. ``recorder``: optional sink
    (``app.engine.sinks``) receiving each block's output and the commands actually sent,
    committed when the thread stops (``app.live.haptic_setup``: a table sink on a thread
    of its own). ``touch_log``: optional sink (set after construction, as
    ``app.live.haptic_setup`` does) receiving the touch samples each block took
    (``app.live.touch_log``), committed with the recording. ``estop``, ``touches``,
    ``snapshots``: the emergency stop event and the touch and snapshot queues, when
    another process holds their other ends
    (``app.live.haptic_process``); by default the thread makes its own. ``clock`` and
    ``sleep``: the wall clock (s) and how to wait on it, injectable for tests.
    ``pacing``: "wall", or "device" (the link's room paces the blocks; needs ``sink``).
    ``control``: the friction loop's mode instead of each scene file's (None: the file's);
    the loop reads the link's force reports.
    ``touch_force``: what a touch screen's samples press with (``.value``, N; TUIO and
    many touch screens report none), set by the window's wheel; by default the
    scene's normal force. ``pump``: a touch screen's :class:`app.live.touch_pump.
    TouchPump` feeding this thread, started with it (``app.live.haptic_setup``).
    """

    def __init__(self, scene, rate_hz: float = 10_000.0, block_size: int = BLOCK_SIZE,
                 render_override: str | None = None, sink=None, recorder=None,
                 clock=time.perf_counter, snapshot_stride: int = 10, estop=None,
                 touches=None, snapshots=None, sleep=time.sleep, pacing: str = "wall",
                 touch_force=None, control: str | None = None):
        super().__init__(name="frictex-haptic", daemon=True)
        self.rate_hz = float(rate_hz)
        self.block_size = int(block_size)
        self.block_s = self.block_size / self.rate_hz
        self.clock = clock
        self.sink = sink
        self.recorder = recorder
        self.touch_log = None
        self.stride = snapshot_stride
        self.pacing = pacing
        self.touches = queue.Queue(TOUCH_QUEUE) if touches is None else touches
        self.snapshots = queue.Queue(SNAPSHOT_QUEUE) if snapshots is None else snapshots
        self.estop = threading.Event() if estop is None else estop
        self.stats = HapticStats()
        self._quit = threading.Event()
        self._last_stamp = 0.0
        self.render_override = render_override
        self.control = control
        self.stage = LiveStage(build_pipeline(scene, rate_hz, block_size, render_override,
                                              control=control), self.estop, self.stats)
        self.stage.render_override = render_override
        self.wall = WallClock(self.block_s, live_prefill_s(self.block_s), now=clock, sleep=sleep)
        self.t0 = self.wall.t0
        self.error: BaseException | None = None
        self.touch_force = (SimpleNamespace(value=scene.device.normal_force_n)
                            if touch_force is None else touch_force)
        self.pump = None

    @property
    def pipeline(self):
        """The pipeline running now (the last switch's once it has taken over)."""
        return self.stage.pipeline

    # -- called from other threads ------------------------------------------------------

    def switch(self, scene=None, render_override: str | None | bool = False,
               text: str | None = None):
        """Change scene and/or renderer (False: keep the current one). The pipeline is
        built here, on the caller's thread (errors raise here: nothing changes), returned,
        and taken over, crossfaded, at the next block. ``text``: the scene file's text
        (``HapticProcess.switch`` sends it; here the scene itself is at hand)."""
        override = self.render_override if render_override is False else render_override
        pipeline = build_pipeline(scene or self.pipeline.scene, self.rate_hz, self.block_size,
                                  override, control=self.control)
        old = self.pipeline
        held = held_outputs(self.sink is not None, self.recorder is not None)
        if held and ((pipeline.channels, pipeline.actuation.has_phases)
                     != (old.channels, old.actuation.has_phases)):
            raise ChannelMismatch(pipeline.scene.name, _layout(pipeline), _layout(old), held)
        self.stage.changes.put_nowait((pipeline, override))
        self.render_override = override
        return pipeline

    def stop(self) -> None:
        self._quit.set()

    def input_error(self) -> str | None:
        """Why the touch screen stopped (once; None while it works or without one)."""
        return None if self.pump is None else self.pump.take_error()

    def start(self) -> None:
        self.wall.restart()  # the output clock starts with the thread
        self.t0 = self.wall.t0
        super().start()
        if self.pump is not None:
            self.pump.start()

    # -- the thread ---------------------------------------------------------------------

    def run(self) -> None:
        sinks = [SnapshotSink(self)]
        clock = self.wall
        if self.sink is not None:
            self.stage.device_force = self.sink.device_force_n
            self.stage.force_reports = force_reports_of(self.sink)
            sinks.insert(0, LinkSink(self.sink, self.block_size))
            if self.pacing == "device":
                clock = DevicePacedClock(self.sink)
        if self.recorder is not None:
            sinks.append(self.recorder)
        source = QueueSource(self.touches, self.block_s)
        if self.touch_log is not None:
            source = LoggedTouches(source, self.touch_log)
            sinks.append(source)  # commits the touch log with the recording
        try:
            drive(self.stage, source, sinks, clock, stop=self._quit.is_set)
        except BaseException as exc:  # reported by the window; output stops
            self.error = exc
        finally:
            loop, state = self.stage.pipeline.control, self.stage.state.control
            self.stats.control = None if loop is None else loop.report(state)
            if loop is not None:
                say_at_end(self.stats.control["messages"][len(state.messages):])
            self.stats.deadline_misses = self.wall.stats.misses
            self.stats.worst_lateness_s = self.wall.stats.worst_lateness_s

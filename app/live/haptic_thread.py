"""The live haptic pipeline on its own thread, paced by the wall clock, block by block.

At the start of block k (wall time t0 + k * block / rate) the thread drains its
bounded input queues (touch samples, commands), runs the pipeline for that block,
sends the commands to the sink and hands a decimated snapshot to the window through
another bounded queue. It never waits on the window: a full snapshot queue drops the
oldest snapshot (counted). The device starts playing a stream once its jitter buffer
holds ``DEADLINE_S`` (the link's 10 ms prefill, ``device.link.host.PREFILL_S``), so block k
is due ``DEADLINE_S`` after its start; one sent later is a deadline miss (counted, with
the worst lateness past the block's own end), and the thread catches up without sleeping.

Changes between blocks ramp across one block (STYLE.md 5): a scene or renderer switch
crossfades the old pipeline's commands into the new one's (the new pipeline takes over
the old one's finger tracks), resuming after an emergency stop ramps from 0. The
emergency stop itself is immediate: while it is set every sample sent is 0 um.

Touch samples carry times on this thread's clock (``now()``, s since start). A sample
is used from the first block boundary at or after its time (``rendering.tracking.tracks``).
Samples from several fingers and sources (the mouse, a TUIO or evdev touch screen) may
be queued one after another; their stamps never go back (``touch_at``).
"""

from __future__ import annotations

import queue
import sys
import threading
import time
from dataclasses import dataclass, field

import numpy as np

from device.friction import ClampCounts
from rendering.pipeline import PipelineState, build_pipeline
from rendering.input.trace_file import DOWN, MOVE, UP, make_trace
from rendering.visual.overlay import BlockRecord, record_from_output

TOUCH_QUEUE = 4096
COMMAND_QUEUE = 64
SNAPSHOT_QUEUE = 256
DEADLINE_S = 0.010  # = device.link.host.PREFILL_S, not imported: the link is optional
LINK_STATUS_EVERY = 20  # blocks between two sink.status() calls
EVENTS = {"down": DOWN, "move": MOVE, "up": UP}


def shorten_switch_interval(block_s: float) -> None:
    """Let the haptic thread get the GIL back within a quarter of a block (``block_s``,
    s), not after Python's default 5 ms switch interval (a whole block at 10 kHz / 50)."""
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
        t = max(min(float(t_s), self.now()), self._last_stamp)
        self._last_stamp = t
        try:
            self.touches.put_nowait((t, finger, x_mm, y_mm, force_n, event))
        except queue.Full:
            self.stats.dropped_touches += 1


class HapticThread(TouchInput, threading.Thread):
    """Runs ``build_pipeline(scene, ...)`` live; see the module docstring.

    ``sink``: optional command sink (``device.link.host.open_sink(..., paced=False)``).
    ``recorder``: optional callable ``recorder(out, commands_um)`` called with each
    block's output and the commands actually sent (must not block).
    ``estop``, ``touches``, ``snapshots``: the emergency stop event and the touch and
    snapshot queues, when another process holds their other ends (``app.live.haptic_process``);
    by default the thread makes its own.
    """

    def __init__(self, scene, rate_hz: float = 10_000.0, block_size: int = 50,
                 render_override: str | None = None, sink=None, recorder=None,
                 clock=time.perf_counter, snapshot_stride: int = 10, estop=None,
                 touches=None, snapshots=None):
        super().__init__(name="frictex-haptic", daemon=True)
        self.rate_hz = float(rate_hz)
        self.block_size = int(block_size)
        self.block_s = self.block_size / self.rate_hz
        self.clock = clock
        self.sink = sink
        self.recorder = recorder
        self.stride = snapshot_stride
        self.touches = queue.Queue(TOUCH_QUEUE) if touches is None else touches
        self.commands: queue.Queue = queue.Queue(COMMAND_QUEUE)
        self.snapshots = queue.Queue(SNAPSHOT_QUEUE) if snapshots is None else snapshots
        self.estop = threading.Event() if estop is None else estop
        self.stats = HapticStats()
        self._quit = threading.Event()
        self._pending: list[tuple] = []
        self._last_stamp = 0.0
        self.render_override = render_override
        self.pipeline = build_pipeline(scene, rate_hz, block_size, render_override)
        self.state = self.pipeline.initial_state()
        self.t0 = clock()
        self.error: BaseException | None = None
        self._link = {"state": "none"}

    # -- called from other threads ------------------------------------------------------

    def switch(self, scene=None, render_override: str | None | bool = False):
        """Change scene and/or renderer (False: keep the current one). The pipeline is
        built here, on the caller's thread (errors raise here: nothing changes), returned,
        and taken over, crossfaded, at the next block."""
        override = self.render_override if render_override is False else render_override
        pipeline = build_pipeline(scene or self.pipeline.scene, self.rate_hz, self.block_size,
                                  override)
        old = self.pipeline
        if ((self.sink is not None or self.recorder is not None)
                and (pipeline.channels, pipeline.actuation.has_phases)
                != (old.channels, old.actuation.has_phases)):
            raise ValueError(f"{pipeline.scene.name} drives channels {', '.join(pipeline.channels)} "
                             f"({pipeline.scene.device.profile}); the link and recording were opened "
                             f"for {', '.join(old.channels)} ({old.scene.device.profile}): start "
                             "the demo on that scene instead")
        self.commands.put_nowait((pipeline, override))
        return pipeline

    def stop(self) -> None:
        self._quit.set()

    def start(self) -> None:
        self.t0 = self.clock()  # the output clock starts with the thread
        super().start()

    # -- the thread ---------------------------------------------------------------------

    def run(self) -> None:
        try:
            self._loop()
        except BaseException as exc:  # reported by the window; output stops
            self.error = exc

    def _loop(self) -> None:
        k = 0
        gain = 0.0 if self.estop.is_set() else 1.0
        while not self._quit.is_set():
            start = self.t0 + k * self.block_s
            wait = start - self.clock()
            if wait > 0:
                time.sleep(wait)
            samples = self._drain_touches(k * self.block_s)
            out, commands = self._process(k, samples, self._drain_commands())
            stopped = self.estop.is_set()
            target = 0.0 if stopped else 1.0
            if stopped:
                commands = np.zeros_like(commands)
            elif gain < 1.0:
                ramp = np.linspace(gain, 1.0, self.block_size + 1)[1:, None]
                commands = commands * ramp
                self.stats.ramps += 1
            gain = target
            if self.sink is not None:
                self.sink.send(k * self.block_size, commands, out.phases_rad)
            if self.recorder is not None:
                self.recorder(out, commands)
            self.stats.clamps.add(out.clamps)
            self.stats.blocks += 1
            self._publish(k, out, commands, stopped)
            late = self.clock() - (start + self.block_s)
            self.stats.worst_lateness_s = max(self.stats.worst_lateness_s, late)
            if self.clock() > start + max(self.block_s, DEADLINE_S):
                self.stats.deadline_misses += 1
            k += 1

    def _drain_touches(self, block_start_s: float):
        """Touch samples stamped at or before the block start (later ones wait)."""
        while True:
            try:
                self._pending.append(self.touches.get_nowait())
            except queue.Empty:
                break
        due = [s for s in self._pending if s[0] <= block_start_s]
        if not due:
            return None
        self._pending = self._pending[len(due):]
        t, finger, x, y, force, event = (np.array(c) for c in zip(*due))
        return make_trace(t, finger, x, y, force, event, where="live touch", normalise=False)

    def _drain_commands(self):
        """The latest pipeline asked for since the last block, or None."""
        latest = None
        while True:
            try:
                latest = self.commands.get_nowait()
            except queue.Empty:
                return latest

    def _process(self, k, samples, change):
        # a device with force sensors measures the normal force itself (key-click scenes)
        force = self.sink.device_force_n() if self.sink is not None else None
        if change is None:
            out, self.state = self.pipeline.process(k, samples, self.state, normal_force_n=force)
            return out, out.commands_um
        # crossfade: both pipelines run this block from the same finger tracks (another
        # device, with other channels, ramps up from 0 instead)
        new, self.render_override = change
        new_state = PipelineState(tracker=self.state.tracker, layers=new.initial_state().layers)
        old_out, _ = self.pipeline.process(k, samples, self.state, normal_force_n=force)
        out, self.state = new.process(k, samples, new_state, normal_force_n=force)
        same_device = new.channels == self.pipeline.channels
        self.pipeline = new
        fade = np.linspace(0.0, 1.0, self.block_size + 1)[1:, None]
        self.stats.ramps += 1
        before = old_out.commands_um * (1.0 - fade) if same_device else 0.0
        return out, before + out.commands_um * fade

    def _publish(self, k: int, out, commands, stopped: bool) -> None:
        if self.sink is not None and k % LINK_STATUS_EVERY == 0:
            self._link = self.sink.status()
        status = {"blocks": self.stats.blocks, "deadline_misses": self.stats.deadline_misses,
                  "clamps": self.stats.clamps.total, "estop": stopped,
                  "renderer": self.render_override or "file", "link": self._link}
        snap = Snapshot(record_from_output(out, self.stride, commands_um=commands), status)
        try:
            self.snapshots.put_nowait(snap)
        except queue.Full:
            self.stats.dropped_snapshots += 1
            try:
                self.snapshots.get_nowait()
                self.snapshots.put_nowait(snap)
            except (queue.Empty, queue.Full):
                pass

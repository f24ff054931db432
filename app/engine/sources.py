"""Where touch samples come from: a trace (recorded or synthetic) or live touch input.

A source hands the driver, for blocks ``k .. k + n - 1``, the touch samples that take
effect in them (a sample takes effect at the first block boundary at or after its time:
``rendering.tracking.tracks.apply_index``) and says how many of those blocks to run:

    samples, n_run = source.take(k, n)      # Trace or None; 1 <= n_run <= n
    source.done                              # nothing more to run

A trace source ends with the block after its last sample (so every sample, and the
last touch's end, is in the output); a live source runs until the driver is stopped.

Finger ids. A trace source hands the pipeline slots, not the recording's finger ids: a
touch takes the row of a finger that lifted (``app.engine.finger_slots``), so a call's
rows follow the fingers touching at once, however many ids a log has used;
``source.label(out)`` puts the recording's ids back on the output.

Gaps. A recorded trace may stop reporting for a long time (a log paused, a clock that
jumped). A gap longer than ``max_gap_s`` between two samples is taken as a lift: every
finger touching is lifted one block after the gap starts (so that the sample there takes
effect; at the gap's end where that comes first), and the output skips from
:data:`GAP_KEEP_S` after the gap's start to :data:`GAP_KEEP_S` before its end
(``source.resume_at(k)`` tells the driver; ``t_s`` jumps there). Counted in
``source.gaps``.
"""

from __future__ import annotations

import queue
from operator import itemgetter

import numpy as np

from frictex.app.engine.finger_slots import FingerSlots
from frictex.app.engine.finger_table import MAX_LISTED
from frictex.app.engine.summary import counted, were
from frictex.device.friction import MIN_NORMAL_N
from frictex.rendering.input.trace_file import UP, Trace, concat_traces, make_trace
from frictex.rendering.tracking.tracks import apply_index

#: default longest gap between touch samples that is output as it is (s)
MAX_GAP_S = 5.0
#: output kept on each side of a longer gap (s): the lift, and the touch after it
GAP_KEEP_S = 0.1


class Gaps:
    """Gaps between touch samples longer than ``limit_s``, taken as lifts and skipped, of
    a trace whose ``stats`` (:class:`TraceStats`) say how often it samples."""

    def __init__(self, limit_s: float, stats: TraceStats):
        self.limit_s = limit_s
        self.stats = stats
        self.count = 0
        self.skipped_s = 0.0

    def as_dict(self) -> dict:
        return {"limit_s": self.limit_s, "count": self.count, "skipped_s": self.skipped_s}

    def warnings(self) -> list[str]:
        return self._below_sampling() + self._taken()

    def _below_sampling(self) -> list[str]:
        """A limit under the trace's median sample interval: most steps are lifts."""
        step_s = self.stats.median_step_s()
        if self.limit_s is None or step_s is None or self.limit_s >= step_s:
            return []
        return [f"the longest gap kept ({self.limit_s:g} s, --max-gap) is shorter than the "
                f"trace's median sample interval ({step_s:.6g} s): most of its steps are taken "
                "as lifts; give a --max-gap above it"]

    def _taken(self) -> list[str]:
        if not self.count:
            return []
        return [f"{self.count} gaps of more than {self.limit_s:g} s between touch samples were "
                "taken as lifts (of the fingers still touching then, if any); of their "
                f"silence, {self.skipped_s:.6g} s of output was not written (t_s jumps there; "
                f"{GAP_KEEP_S:g} s is kept on each side of a gap)"]


class TraceSource:
    """Samples of a trace given as an iterator of chunks (``rendering.input.trace_file.
    iter_trace``, or ``iter([trace])``), read ahead only as far as the blocks asked for.

    ``until_s``: run the output to this time (s, on the trace's clock) instead of to the
    block after the last sample (a synthetic motion scored over a fixed span).
    """

    def __init__(self, chunks, until_s: float | None = None, max_gap_s: float | None = MAX_GAP_S):
        self.chunks = chunks
        self.until_s = until_s
        self.stats = TraceStats()
        self.gaps = Gaps(max_gap_s, self.stats)
        self._down: set[int] = set()  # fingers touching after the last sample read
        self._last_t: float | None = None
        self._last_xy: dict[int, tuple] = {}  # finger -> (x_mm, y_mm, force_n) last read
        self._gap_times: list[tuple[float, float]] = []  # long gaps (start s, end s) ahead
        self.pending: Trace | None = None
        self.applied = np.zeros(0, dtype=np.int64)
        self.config = None
        self.ended = False
        self.slots = FingerSlots()
        self.end_index: int | None = None
        self.next_index = 0

    def first_time(self) -> float:
        """Time (s) of the first sample: where the output clock starts."""
        if self.pending is None:
            self._read_more()
        if self.pending is None:
            raise ValueError("the trace has no samples")
        return float(self.pending.t_s[0])

    def start(self, tracker_config) -> None:
        """Begin handing out samples for a pipeline with this tracker configuration
        (after reading one chunk more: ``ended`` then says whether the whole trace is in)."""
        self.config = tracker_config
        self.stats.set_area(tracker_config.area_mm)
        if self.pending is not None:  # read by first_time, before a block's length was known
            self.pending = self._lift_at_gaps(self.pending)
        self.first_time()
        if not self.ended:
            self._read_more()
        self.applied = apply_index(self.pending.t_s, tracker_config)
        if self.until_s is not None:
            quantum = tracker_config.quantum
            span = (self.until_s - tracker_config.t0_s) * tracker_config.rate_hz / quantum
            self.end_index = int(np.ceil(span - 1e-9)) * quantum

    def _read_more(self) -> None:
        chunk = next(self.chunks, None)
        if chunk is None:
            self.ended = True
            return
        self.stats.add(chunk)
        if self.config is not None:  # else start() does, knowing a block's length
            chunk = self._lift_at_gaps(chunk)
        self.pending = chunk if self.pending is None else concat_traces([self.pending, chunk])
        if self.config is not None:
            self.applied = apply_index(self.pending.t_s, self.config)

    def _lift_at_gaps(self, chunk: Trace) -> Trace:
        """``chunk`` with an up for every finger touching one block after a long gap starts
        (or at its end, if sooner)."""
        block_s = self.config.quantum / self.config.rate_hz
        limit = self.gaps.limit_s
        times = chunk.t_s if self._last_t is None else np.concatenate(([self._last_t], chunk.t_s))
        starts = np.flatnonzero(np.diff(times) > limit) if limit is not None else []
        offset = 0 if self._last_t is None else 1
        pieces, lo = [], 0
        for g in starts:
            at = g - offset  # the chunk's sample before the gap (-1: the previous chunk's)
            down = _down_after(self._down, chunk.slice(0, at + 1))
            t_gap = float(times[g])
            if down:
                ids = np.array(sorted(down))
                prev = chunk.slice(0, at + 1) if at >= 0 else None
                pieces.append(chunk.slice(lo, at + 1))
                t_up = min(t_gap + block_s, float(times[g + 1]))
                pieces.append(_ups(ids, t_up, prev, self._last_xy))
                lo = at + 1
            self.gaps.count += 1
            self.gaps.skipped_s += max(0.0, float(times[g + 1]) - t_gap - 2 * GAP_KEEP_S)
            self._gap_times.append((t_gap, float(times[g + 1])))
        if pieces:
            pieces.append(chunk.slice(lo, len(chunk)))
            chunk = concat_traces(pieces)
        self._down = self.stats.still_down = _down_after(self._down, chunk)
        self._last_t = float(chunk.t_s[-1])
        ids, from_end = np.unique(chunk.finger[::-1], return_index=True)
        last = len(chunk) - 1 - from_end  # each finger's last sample
        self._last_xy = {f: (x, y, fn) for f, x, y, fn in zip(
            ids.tolist(), chunk.x_mm[last].tolist(), chunk.y_mm[last].tolist(),
            chunk.force_n[last].tolist())}
        return chunk

    def resume_at(self, k: int) -> int:
        """The block to run next, ``k`` unless an idle stretch of a long gap starts there."""
        if self.config is None or not self._gap_times:
            return k
        quantum = self.config.quantum
        keep = int(np.ceil(GAP_KEEP_S * self.config.rate_hz / quantum))
        while self._gap_times:
            start, end = apply_index(np.array(self._gap_times[0]), self.config) // quantum
            if k < start + keep:
                return k
            self._gap_times.pop(0)
            if k < end - keep:
                self.next_index = (end - keep) * quantum
                return int(end - keep)
        return k

    def take(self, k: int, n: int) -> tuple[Trace | None, int]:
        block = self.config.quantum
        if self._gap_times:  # never run past the start of a skipped stretch
            keep = int(np.ceil(GAP_KEEP_S * self.config.rate_hz / block))
            start = int(apply_index(np.array([self._gap_times[0][0]]), self.config)[0]) // block
            if k < start + keep:
                n = min(n, start + keep - k)
        end = (k + n) * block
        while not self.ended and (self.applied.size == 0 or self.applied[-1] < end):
            self._read_more()
        hi = int(np.searchsorted(self.applied, end))
        taken = None
        if hi:
            samples, applied = self.pending.slice(0, hi), np.maximum(self.applied[:hi], k * block)
            taken = self.slots.assign(samples, applied)
            self.pending = self.pending.slice(hi, len(self.pending))
            self.applied = self.applied[hi:]
        if self.end_index is not None:
            n_run = min(n, -(-(self.end_index - k * block) // block))
        elif self.ended and self.applied.size == 0:
            last = int(apply_index(taken.t_s[-1:], self.config)[0]) if taken is not None else -1
            n_run = max(1, min(n, last // block + 1 - k))
        else:
            n_run = n
        self.next_index = (k + n_run) * block
        return taken, n_run

    def label(self, out):
        """``out`` with the recording's finger ids (module docstring)."""
        return self.slots.label(out)

    def report(self, path) -> dict:
        """The summary's ``trace`` section: the trace's figures (:class:`TraceStats`), the
        touches that began and lifted within one output block (no output sample in
        contact: ``FingerSlots.brief_touches``) and the touch samples off the display."""
        return {**self.stats.report(path), "touches_within_a_block": self.slots.brief_touches,
                "touch_samples_off_display": self.stats.off_display}

    @property
    def done(self) -> bool:
        if self.end_index is not None:
            return self.next_index >= self.end_index
        return self.ended and self.applied.size == 0


def _down_after(down: set[int], samples: Trace) -> set[int]:
    """The fingers touching after ``samples``, given those touching before."""
    down = set(down)
    if len(samples) == 0:
        return down
    for f in samples.fingers:
        last = samples.event[samples.finger == f][-1]
        (down.discard if last == UP else down.add)(f)
    return down


def _ups(ids: np.ndarray, t_s: float, before: Trace | None, last_xy: dict) -> Trace:
    """An up at ``t_s`` for each finger of ``ids``, where it was last seen."""
    where = dict(last_xy)
    if before is not None:
        for f, x, y, fn in zip(before.finger.tolist(), before.x_mm, before.y_mm, before.force_n):
            where[f] = (float(x), float(y), float(fn))
    x, y, force = (np.array([where[int(f)][k] for f in ids]) for k in range(3))
    return Trace(np.full(ids.size, t_s), ids.astype(np.int64), x, y, force,
                 np.full(ids.size, UP, dtype=np.int8))


def _lone_ups(finger: np.ndarray, up: np.ndarray, down: set[int]) -> int:
    """How many of the samples (in time order; ``up``: their up events) lift a finger
    that is not touching. ``down``: the fingers touching before them, updated in place."""
    order = np.argsort(finger, kind="stable")  # each finger's samples in time order
    f, u = finger[order], up[order]
    first = np.ones(f.size, dtype=bool)
    first[1:] = f[1:] != f[:-1]
    touching_before = np.empty(f.size, dtype=bool)
    touching_before[1:] = ~u[:-1]
    touching_before[first] = np.isin(f[first], np.fromiter(down, dtype=np.int64, count=len(down)))
    last = np.append(first[1:], True)
    for fid, lifts in zip(f[last].tolist(), u[last].tolist()):
        (down.discard if lifts else down.add)(fid)
    return int(np.count_nonzero(u & ~touching_before))


class TraceStats:
    """What a summary says about a trace, gathered chunk by chunk.

    Touch samples off the display. The tracker holds every finger within the display's
    area (``TrackerConfig.area_mm``, from (0, 0) mm), so a touch sample outside it plays
    as if at the edge. Such samples are counted in ``off_display`` (one on the edge is
    inside). A touch screen reports slightly past its edge, and a mouse drag may run past
    the window's, so only samples more than :data:`EDGE_SLACK_MM` outside (``far_off``)
    are warned about, and only when they are more than :data:`OFF_SHARE` of the touch
    samples: a trace recorded on another display, or in metres. A trace in metres may lie
    on the display and still be wrong: every touch sample within :data:`METRES_BOX_MM` of
    (0, 0) over more than :data:`METRES_SPAN_S` of touching is warned about too (a still
    finger pressing stays within a tiny box, but not at the display's corner).
    """

    MAX_STEPS = 100_000  # the touch rate is the median over the first steps
    #: how far (mm) past the display's edge a touch sample is counted but not warned about
    EDGE_SLACK_MM = 0.5
    #: the share of touch samples beyond that slack that is warned about
    OFF_SHARE = 0.1
    #: a trace whose touch samples all lie within this (mm) of (0, 0) ...
    METRES_BOX_MM = 1.0
    #: ... over more than this span of touching (s) reads as metres taken for mm
    METRES_SPAN_S = 0.5

    def __init__(self):
        self.samples = 0
        self.fingers: set[int] = set()
        self.first_t = self.last_t = None
        self.steps: list[np.ndarray] = []
        self.n_steps = 0
        #: touch samples (down or move), those pressing under ``MIN_NORMAL_N``, the least force
        self.touching = 0
        self.unpressed = 0
        self.least_force_n = np.inf
        #: the display's (width, height) (mm), once known (:meth:`set_area`)
        self.area_mm: tuple[float, float] | None = None
        #: touch samples outside it, and those more than ``EDGE_SLACK_MM`` outside
        self.off_display = 0
        self.far_off = 0
        #: the touch samples' extent: (x_lo, y_lo, x_hi, y_hi) (mm), times of the first
        #: and last (s)
        self.touch_box = np.array([np.inf, np.inf, -np.inf, -np.inf])
        self.touch_first_t = self.touch_last_t = None
        self._unchecked: list[tuple[np.ndarray, np.ndarray]] = []  # read before the area
        #: up events of a finger not touching (nothing to lift); the fingers touching
        #: after the samples read so far
        self.lone_ups = 0
        self._down: set[int] = set()
        #: up events read (a trace with none lifts nothing anywhere: no event column), and
        #: the fingers touching after the samples handed on, long gaps' lifts included
        #: (kept by :class:`TraceSource`)
        self.ups = 0
        self.still_down: set[int] = set()

    def add(self, chunk: Trace) -> None:
        times = chunk.t_s if self.last_t is None else np.concatenate(([self.last_t], chunk.t_s))
        if self.n_steps < self.MAX_STEPS:
            steps = np.diff(times)
            steps = steps[steps > 0][: self.MAX_STEPS - self.n_steps]
            self.steps.append(steps)
            self.n_steps += steps.size
        self.samples += len(chunk)
        touch = chunk.event != UP
        touching = chunk.force_n[touch]
        self.touching += touching.size
        self.unpressed += int(np.count_nonzero(touching < MIN_NORMAL_N))
        self.least_force_n = float(np.min(touching, initial=self.least_force_n))
        self._add_positions(chunk.t_s[touch], chunk.x_mm[touch], chunk.y_mm[touch])
        self.lone_ups += _lone_ups(chunk.finger, chunk.event == UP, self._down)
        self.ups += int(np.count_nonzero(chunk.event == UP))
        self.fingers.update(chunk.fingers)
        self.first_t = float(chunk.t_s[0]) if self.first_t is None else self.first_t
        self.last_t = float(chunk.t_s[-1])

    def set_area(self, area_mm: tuple[float, float] | None) -> None:
        """The display's (width, height) (mm; None: unbounded) that touch samples are
        held within; those read before it are counted now."""
        self.area_mm = area_mm
        for x, y in self._unchecked:
            self._count_off(x, y)
        self._unchecked = []

    def _add_positions(self, t_s: np.ndarray, x: np.ndarray, y: np.ndarray) -> None:
        if not t_s.size:
            return
        lo, hi = self.touch_box[:2], self.touch_box[2:]
        self.touch_box = np.concatenate((np.minimum(lo, [x.min(), y.min()]),
                                         np.maximum(hi, [x.max(), y.max()])))
        if self.touch_first_t is None:
            self.touch_first_t = float(t_s[0])
        self.touch_last_t = float(t_s[-1])
        if self.area_mm is None:
            self._unchecked.append((x, y))
        else:
            self._count_off(x, y)

    def _count_off(self, x: np.ndarray, y: np.ndarray) -> None:
        """Count the touch samples at ``x``, ``y`` (mm) outside the display's area."""
        if self.area_mm is None:
            return
        width, height = self.area_mm
        past = np.maximum.reduce([-x, x - width, -y, y - height])  # mm outside; <= 0 inside
        self.off_display += int(np.count_nonzero(past > 0))
        self.far_off += int(np.count_nonzero(past > self.EDGE_SLACK_MM))

    #: the share of touch samples pressing under ``MIN_NORMAL_N`` that is warned about: a
    #: finger landing or lifting passes through a low force for a few samples (the bundled
    #: key-press traces: 1 of their touch samples at 0.04 N), not for a tenth of its touch
    UNPRESSED_SHARE = 0.1

    def warnings(self, pressing: bool = True) -> list[str]:
        """What is wrong with the trace's touch samples, a line each: off the display, in
        metres (class docstring), or (``pressing``) not pressing."""
        return (self._off_display() + self._in_metres() + self._lifting_nothing()
                + self._left_down() + (self._unpressed() if pressing else []))

    def _left_down(self) -> list[str]:
        """The fingers a trace that lifts fingers (it has up events) leaves touching at
        its end: held down to the end of the output, as a recording cut short or whose
        last lift was lost leaves them. A trace without up events (no event column: every
        sample touches) is not said to."""
        if not (self.ups and self.still_down):
            return []
        fingers = sorted(self.still_down)
        named = ", ".join(map(str, fingers[:MAX_LISTED]))
        return [f"trace: finger{'s' * (len(fingers) > 1)} {named} still touching at its "
                f"end ({self.last_t:.6g} s), with no up event: held down to the end of the "
                "output (a recording cut short, or its last lift lost?)"]

    def _lifting_nothing(self) -> list[str]:
        if not self.lone_ups:
            return []
        n = self.lone_ups
        return [f"trace: {counted(n, 'up event')} with no touch to lift (a finger with no "
                f"down or move since its last up) {were(n)} ignored"]

    def _unpressed(self) -> list[str]:
        """A touch input that does not press, said in one line (none where at most
        ``UNPRESSED_SHARE`` of its touch samples press under ``MIN_NORMAL_N``): the friction
        model's inversion takes the normal force from it."""
        if self.unpressed <= self.UNPRESSED_SHARE * self.touching:
            return []
        return [f"trace: {self.unpressed} of {self.touching} touch samples press under {MIN_NORMAL_N:g} N (the "
                f"least {self.least_force_n:.2g} N), implausible under a finger: seed 003's "
                "inversion takes the normal force from the trace (its asymptote k F_n), so it "
                "inverts for a finger that barely presses; give the trace its finger's force_n, "
                "or leave the column out for 0.5 N"]

    def _off_display(self) -> list[str]:
        if self.far_off <= self.OFF_SHARE * self.touching:
            return []
        (x_lo, y_lo, x_hi, y_hi), (width, height) = self.touch_box, self.area_mm
        hint = "recorded on another display"
        hint += ", or in metres?" if self._within_metres_box() else "?"
        return [f"trace: {self.off_display} of {self.touching} touch samples lie off the "
                f"{width:g} x {height:g} mm display (x {x_lo:.4g} to {x_hi:.4g} mm, y "
                f"{y_lo:.4g} to {y_hi:.4g} mm) and are held at its edge: {hint}"]

    def _in_metres(self) -> list[str]:
        if self._off_display() or not self._within_metres_box():
            return []
        span_s = self.touch_last_t - self.touch_first_t
        if span_s <= self.METRES_SPAN_S:
            return []
        x_lo, y_lo, x_hi, y_hi = self.touch_box
        return [f"trace: all {self.touching} touch samples over {span_s:.3g} s lie within "
                f"{self.METRES_BOX_MM:g} mm of (0, 0) (x {x_lo:.4g} to {x_hi:.4g} mm, y "
                f"{y_lo:.4g} to {y_hi:.4g} mm): in metres? positions are in mm"]

    def _within_metres_box(self) -> bool:
        """Whether every touch sample lies within ``METRES_BOX_MM`` of (0, 0) (mm)."""
        return self.touching > 0 and bool(np.all(np.abs(self.touch_box) < self.METRES_BOX_MM))

    def median_step_s(self) -> float | None:
        """The median interval (s) between the trace's distinct sample times (over its
        first ``MAX_STEPS``); None for a single time."""
        steps = np.concatenate(self.steps) if self.steps else np.zeros(0)
        return float(np.median(steps)) if steps.size else None

    def report(self, path) -> dict:
        step_s = self.median_step_s()
        # a list bounded like the summary's fingers section (a new id per touch: 100,000)
        return {"path": str(path) if path else None, "samples": self.samples,
                "fingers": sorted(self.fingers)[:MAX_LISTED], "finger_count": len(self.fingers),
                "duration_s": self.last_t - self.first_t,
                "touch_rate_hz": 1.0 / step_s if step_s is not None else None}


class QueueSource:
    """Live touch samples from a queue whose items are lists of ``(t_s, finger, x_mm,
    y_mm, force_n, event)`` tuples stamped on the output clock (s since the run's start;
    the samples of one item arrive together); a sample is handed out with the first block
    starting at or after its stamp, taken after it arrived. Never ends by itself.

    Several producers (the window's mouse, a touch screen's pump) put items in whatever
    order their threads or processes are scheduled, so the items need not arrive in the
    order of their stamps: each call hands out every sample due, once, sorted by stamp
    (samples with equal stamps in the order they arrived, so a finger's down and up at
    one instant stay in order), and keeps the rest, whatever their order, for later.
    """

    done = False

    def __init__(self, touches: queue.Queue, block_s: float):
        self.touches = touches
        self.block_s = block_s
        self._pending: list[tuple] = []

    def take(self, k: int, n: int) -> tuple[Trace | None, int]:
        while True:
            try:
                self._pending.extend(self.touches.get_nowait())
            except queue.Empty:
                break
        start_s = k * self.block_s
        due = [s for s in self._pending if s[0] <= start_s]
        if not due:
            return None, n
        self._pending = [s for s in self._pending if s[0] > start_s]
        due.sort(key=itemgetter(0))  # stable: equal stamps keep their arrival order
        t, finger, x, y, force, event = (np.array(c) for c in zip(*due))
        return make_trace(t, finger, x, y, force, event, where="live touch", normalise=False), n

    def resume_at(self, k: int) -> int:
        """Live time never skips."""
        return k

    def label(self, out):
        """Live fingers keep their own ids: ``out`` as it is."""
        return out

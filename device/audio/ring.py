"""The frames between the producer (the pipeline's thread) and the audio callback.

:class:`FrameRing` is a single-producer/single-consumer ring of audio frames: a
preallocated float32 array and two monotonic frame counters, ``tail`` written only by the
producer (after the frames), ``head`` only by the consumer. No lock: each side reads the
other's counter once per step, and an int attribute is replaced whole. With the frames the
producer publishes the ramp to zero that would follow them (``fade``), computed by the
synthesis, so that a starving callback has nothing to compute.

:class:`Player` is the callback's body (``fill(out)``), free of PortAudio so that tests
drive it directly. It never blocks, logs or allocates arrays: it copies from the ring and
from its own preallocated buffers, in place. Output slot s is the time of frame s: the
first frame plays at the first slot after the stream has frames, and from then on frame n
plays at slot n or never.

- Starved (no frame n at slot n): the published fade plays (to 0 within ``ramp_frames``),
  then zeros; the slots are counted as ``underrun_frames``. Frames that arrive after
  their slot has passed are dropped and counted as unplayed (``late``); the stream
  resumes at the next frame on time, ramped up from the level the fade had reached.
- Emergency stop: the stream ramps from its current level to 0 over ``ramp_frames``
  and plays zeros from then on; what the ring still holds is unplayed (``stopped``).
- Ended (the producer's last frames, themselves a ramp to 0, have played): zeros, no
  underrun.
"""

from __future__ import annotations

import numpy as np

#: marks of where underruns began in a tap (``Player.tap``), at most this many
MAX_MARKS = 256
#: callbacks the play log keeps (the latest; 87 s of 256-frame callbacks at 192 kHz)
LOG_CALLBACKS = 65_536


class FrameRing:
    """``capacity`` frames of ``channels`` float32, with the fade that follows them.

    Producer: :meth:`room`, :meth:`write` (frames then fade, then ``tail`` published).
    Consumer: :meth:`read_into` and ``head``.
    """

    def __init__(self, capacity: int, channels: int, fade_frames: int):
        self.capacity = int(capacity)
        self.frames = np.zeros((self.capacity, channels), dtype=np.float32)
        # three fade buffers, one published at a time: the producer writes the next one
        self.fades = np.zeros((3, fade_frames, channels), dtype=np.float32)
        self.head = 0  # consumer: frames taken (played or dropped)
        self.tail = 0  # producer: frames written
        self.published = (0, -1)  # (tail, fade buffer) of the last write; -1: no fade

    def room(self) -> int:
        """Frames the producer may write now."""
        return self.capacity - (self.tail - self.head)

    def write(self, frames: np.ndarray, fade: np.ndarray | None) -> None:
        """Producer: append ``frames`` (m, channels), which must fit (:meth:`room`), and
        publish ``fade`` (the ramp to 0 after them; None: silence follows)."""
        m, tail = frames.shape[0], self.tail
        at = tail % self.capacity
        first = min(m, self.capacity - at)
        self.frames[at:at + first] = frames[:first]
        self.frames[:m - first] = frames[first:]
        which = -1
        if fade is not None:
            which = (self.published[1] + 1) % 3
            self.fades[which] = fade
        self.tail = tail + m
        self.published = (tail + m, which)

    def read_into(self, start: int, out: np.ndarray) -> None:
        """Consumer: frames ``start .. start + len(out) - 1`` into ``out`` (in place)."""
        m = out.shape[0]
        at = start % self.capacity
        first = min(m, self.capacity - at)
        out[:first] = self.frames[at:at + first]
        out[first:] = self.frames[:m - first]


class Player:
    """The audio callback's body over a :class:`FrameRing` (module docstring).

    Counters (ints, written by the callback only): ``slot`` (output slots since the
    first frame), ``played``, ``late`` (frames dropped after their slot), ``underrun_frames``
    (slots without a frame before the end), ``underruns`` (times it starved),
    ``stopped`` (frames left at an emergency stop). ``tap``: an optional (frames,
    channels) float32 array the callback copies its output into, up to its length, with
    ``marks`` the tap positions where underruns began and ``resumes`` those where frames
    played again after one (tests; ``tap_len`` filled).

    Play log, one entry per callback (the latest :data:`LOG_CALLBACKS`): the ring position
    of the first frame it played (``log_pos``; -1: none), that frame's offset in the
    callback's buffer (``log_off``), and the time (s, the caller's clock) the
    buffer's first frame reaches the DAC (``log_dac``), the frames it played (``log_n``,
    contiguous in the ring); ``log_count`` callbacks so far. :meth:`dac_time` reads it.
    """

    def __init__(self, ring: FrameRing, ramp_frames: int, tap_frames: int = 0):
        self.ring = ring
        self.ramp = int(ramp_frames)
        channels = ring.frames.shape[1]
        self._up = (np.arange(1, self.ramp + 1, dtype=np.float32) / self.ramp)[:, None]
        self._down = self._up[::-1] - np.float32(1.0 / self.ramp)  # (R-1)/R .. 0
        self._fade = np.zeros((self.ramp, channels), dtype=np.float32)
        self.tap = np.zeros((tap_frames, channels), dtype=np.float32) if tap_frames else None
        self.tap_len = 0
        self.marks = np.zeros(MAX_MARKS, dtype=np.int64)
        self.mark_count = 0
        self.resumes = np.zeros(MAX_MARKS, dtype=np.int64)
        self.resume_count = 0
        self.log_pos = np.full(LOG_CALLBACKS, -1, dtype=np.int64)
        self.log_off = np.zeros(LOG_CALLBACKS, dtype=np.int64)
        self.log_n = np.zeros(LOG_CALLBACKS, dtype=np.int64)
        self.log_dac = np.zeros(LOG_CALLBACKS, dtype=np.float64)
        self.log_count = 0
        self.slot = self.played = self.late = self.underrun_frames = self.underruns = 0
        self.stopped = 0
        self.started = False
        self.ended = False  # producer: no frame will follow the ring's
        self.estop = False  # producer: ramp to 0 now and stay there
        self._gain = self.ramp  # ramp-in position: ramp = full level
        self._fading = -1  # frames of the fade played; -1: not starving
        self._stopping = False  # the emergency stop's ramp has begun

    @property
    def silent(self) -> bool:
        """After an emergency stop (``estop``): whether its ramp to 0 has played (or nothing
        had played), so that the callback plays zeros from now on. For the producer."""
        return self.estop and (not self.started
                               or (self._stopping and self._fading >= self.ramp))

    def fill(self, out: np.ndarray, dac_time: float = 0.0) -> None:
        """Fill ``out`` (frames, channels) float32 in place: the PortAudio callback.
        ``dac_time``: when its first frame reaches the DAC (s, any clock; logged)."""
        pos, frames, ring = 0, out.shape[0], self.ring
        entry = self.log_count % LOG_CALLBACKS
        self.log_pos[entry] = -1
        self.log_n[entry] = 0
        self.log_dac[entry] = dac_time
        self.log_count += 1
        while pos < frames:
            # published before tail: the writer sets tail first, so a fade read here is
            # the one that follows `tail` whenever the ring turns out empty
            published = ring.published
            tail, head = ring.tail, ring.head
            if not self.started:
                if tail == head or self.estop:
                    out[pos:] = 0.0
                    break
                self.started = True
            if self._stopping or self.estop:
                pos = self._stop(out, pos, tail, head)
                break
            if head < self.slot:  # frames whose slot has passed never play
                drop = min(tail, self.slot) - head
                if drop > 0:
                    head += drop
                    ring.head = head
                    self.late += drop
            if tail > head:
                pos = self._play(out, pos, min(tail - head, frames - pos), head)
            else:
                self._starve(out, pos, tail, published)
                break
        self._record(out)

    def _play(self, out, pos: int, m: int, head: int) -> int:
        seg = out[pos:pos + m]
        self.ring.read_into(head, seg)
        entry = (self.log_count - 1) % LOG_CALLBACKS
        if self.log_pos[entry] < 0:
            self.log_pos[entry] = head
            self.log_off[entry] = pos
        self.log_n[entry] += m
        if self._fading >= 0:  # resume from the level the fade reached
            self._gain = self.ramp - min(self._fading, self.ramp)
            self._fading = -1
            if self.resume_count < MAX_MARKS:
                self.resumes[self.resume_count] = self.tap_len + pos
                self.resume_count += 1
        if self._gain < self.ramp:
            g = min(m, self.ramp - self._gain)
            seg[:g] *= self._up[self._gain:self._gain + g]
            self._gain += g
        self.ring.head = head + m
        self.slot += m
        self.played += m
        return pos + m

    def _starve(self, out, pos: int, tail: int, published: tuple[int, int]) -> None:
        rest = out.shape[0] - pos
        if self.ended:
            out[pos:] = 0.0
            return
        if self._fading < 0:  # starving from this slot on
            self._fading = 0
            self.underruns += 1
            if self.mark_count < MAX_MARKS:
                self.marks[self.mark_count] = self.tap_len + pos
                self.mark_count += 1
            at, which = published
            if at == tail and which >= 0 and tail == self.slot:
                self._fade[:] = self.ring.fades[which]
                if self._gain < self.ramp:  # still ramping in: fade from where it is
                    self._fade *= self._gain / self.ramp
            else:
                self._fade[:] = 0.0
        n = max(0, min(self.ramp - self._fading, rest))
        out[pos:pos + n] = self._fade[self._fading:self._fading + n]
        out[pos + n:] = 0.0
        self._fading += n
        self.slot += rest
        self.underrun_frames += rest

    def _stop(self, out, pos: int, tail: int, head: int) -> int:
        """Emergency stop: the next ``ramp`` frames (from the ring, then the published
        fade) ramped down from the current level, then zeros; the ring's other frames
        are dropped (``stopped``). A starving stream's fade is already that ramp."""
        if not self._stopping:
            self._stopping = True
            if self._fading < 0:
                m = min(tail - head, self.ramp)
                self.ring.read_into(head, self._fade[:m])
                head += m
                self.ring.head = head
                self.played += m
                at, which = self.ring.published
                if m < self.ramp and at == head and which >= 0:
                    self._fade[m:] = self.ring.fades[which][:self.ramp - m]
                else:
                    self._fade[m:] = 0.0
                self._fade *= self._down
                if self._gain < self.ramp:
                    self._fade *= self._gain / self.ramp
                self._fading = 0
        n = max(0, min(self.ramp - self._fading, out.shape[0] - pos))
        out[pos:pos + n] = self._fade[self._fading:self._fading + n]
        out[pos + n:] = 0.0
        self._fading += n
        tail = self.ring.tail
        if tail > head:
            self.stopped += tail - head
            self.ring.head = tail
        return out.shape[0]

    def dac_time(self, position: int, rate: int) -> float | None:
        """When the frame at ring ``position`` reached the DAC (s, ``fill``'s clock),
        from the play log; None if it never played or its callback left the log. Not
        for the callback's thread (it reads the log while the callback writes it)."""
        n = min(self.log_count, LOG_CALLBACKS)
        idx = np.arange(self.log_count - n, self.log_count) % LOG_CALLBACKS
        pos, count = self.log_pos[idx], self.log_n[idx]
        hit = np.flatnonzero((pos >= 0) & (pos <= position) & (position < pos + count))
        if hit.size == 0:
            return None
        i = idx[hit[-1]]
        return float(self.log_dac[i] + (self.log_off[i] + position - self.log_pos[i]) / rate)

    def _record(self, out) -> None:
        if self.tap is None or self.tap_len >= self.tap.shape[0]:
            return
        m = min(out.shape[0], self.tap.shape[0] - self.tap_len)
        self.tap[self.tap_len:self.tap_len + m] = out[:m]
        self.tap_len += m

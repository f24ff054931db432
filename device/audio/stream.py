"""``audio[:NAME]``: the stream played through PortAudio (python-sounddevice, the ``audio``
extra; Debian: ``libportaudio2``).

The producer (the pipeline's thread) renders frames and writes them into a
:class:`~device.audio.ring.FrameRing`; PortAudio's callback runs
:meth:`~device.audio.ring.Player.fill` and nothing else (it never blocks, logs or
allocates arrays). A paced stream starts once half the ring is queued (or at close), so the
first callback finds frames; a live one with its first frames, and its ring holds
:data:`LIVE_BLOCKS` of the first block at least, whatever ``buffer_frames`` (less would
drop every block). The ring always keeps ``ramp_frames`` of room in reserve:
a live producer (``paced=False``) that finds no room for a block drops it (counted,
``ring_full``) and writes the ramp to 0 instead, and the next block ramps in. A paced
producer (replay) waits for room, at most ``stall_s * max_stalls`` seconds (less once
PortAudio says the stream is no longer active: a JACK server that went away), then lets
the device go and fails with one DeviceError: the audio device stopped taking frames.

Opening it: PortAudio's initialisation (``import sounddevice``) and ``Pa_OpenStream``
wait for a JACK server's answer without a bound (a stopped jackd: forever, signals
unanswered); each is bounded by :data:`PA_CALL_LIMIT_S` too, and one that does not return
is abandoned, a DeviceError: the audio server is not answering.

Letting the device go: ``Pa_StopStream`` then ``Pa_CloseStream``. They and
``Pa_StartStream`` are each bounded by :data:`PA_CALL_LIMIT_S` (``device.audio.bounded``:
with its server gone, PortAudio's JACK host API blocks in them for 10 minutes, signals
unanswered). One that does not return is abandoned with the stream (the callback, should
it ever run again, ramps to 0), and that is a DeviceError too. A started stream that
PortAudio reports no longer active (its JACK server gone) is abandoned without either
call: a close there unregisters the stream's ports from the server that has gone, and
Debian's PortAudio asserts that this succeeds (``CleanUpStream``), aborting the process
(a CI run: exit -6 instead of the one line).

:meth:`StreamOutput.close` writes the stream's own ramp to 0, waits (bounded) for the
ring to play out, then stops the stream after PortAudio's reported output latency (the
bounded stop and close above).
:meth:`StreamOutput.emergency_stop` ramps to 0 within ``ramp_ms`` from whatever plays;
:meth:`StreamOutput.abort` (a run ended by a signal or an error) is that, then the close.
Every wait here asks whether a held signal ends it (``device.link.waits``).
"""

from __future__ import annotations

import os
import sys
import time

import numpy as np

from frictex.device.audio.bounded import abandon_portaudio, call_bounded
from frictex.device.audio.options import AudioPlan
from frictex.device.audio.output import CAUSES, AudioOutput
from frictex.device.audio.ring import FrameRing, Player
from frictex.device.errors import DeviceError, InputError, MissingExtra
from frictex.device.link.waits import check_interrupt

#: how often a waiting producer looks at the ring again (s)
POLL_S = 0.001
#: bound on waiting for the end of the stream beyond what is queued (s)
DRAIN_MARGIN_S = 2.0
#: bound on one PortAudio start, stop or close (s); a healthy device returns within a few
#: periods
PA_CALL_LIMIT_S = 3.0
#: live blocks the ring holds at least (the first block's size): one playing, the next
#: handed over
LIVE_BLOCKS = 2


def import_sounddevice(label: str = "audio"):
    """python-sounddevice, PortAudio initialised (its import does that), or MissingExtra /
    DeviceError saying what to install. PortAudio's initialisation asks each host API for
    its devices, a JACK server too, and waits for an answer without a bound: one that has not
    returned within :data:`PA_CALL_LIMIT_S` is abandoned (``device.audio.bounded``), a
    DeviceError starting with ``label``."""
    loaded = []

    def load() -> None:
        import sounddevice
        loaded.append(sounddevice)

    stderr = os.dup(2)  # sounddevice points fd 2 at /dev/null while PortAudio initialises
    try:
        returned = call_bounded(load, PA_CALL_LIMIT_S)
    except ModuleNotFoundError:
        raise MissingExtra("audio", "--device audio", "sounddevice") from None
    except OSError as exc:  # the module is there, the PortAudio library is not
        raise DeviceError(f"audio device: {exc} (Debian: apt-get install libportaudio2)") from None
    except BaseException:  # a signal during the wait (the import perhaps left running)
        abandon_portaudio(sys.modules.get("sounddevice"))
        raise
    finally:  # the line that says why must not go to /dev/null
        os.dup2(stderr, 2)
        os.close(stderr)
    if not returned:  # half imported: its exit handler (PortAudio's end) is registered
        abandon_portaudio(sys.modules.get("sounddevice"))
        raise _not_answering(label, "initialisation")
    return loaded[0]


def _not_answering(label: str, call: str) -> DeviceError:
    """The error for a PortAudio ``call`` (initialisation, open) left running after
    :data:`PA_CALL_LIMIT_S`."""
    return DeviceError(f"{label}: the audio server is not answering: PortAudio's {call} "
                       f"(which connects to the JACK server) did not return within "
                       f"{PA_CALL_LIMIT_S:g} s; is jackd stopped or frozen?")


def _outputs(sd) -> str:
    """The output devices PortAudio lists, for a message: ``audio:NAME`` takes a name (or
    part of one) or a number."""
    try:
        devices = [d for d in sd.query_devices() if d["max_output_channels"] > 0]
    except sd.PortAudioError as exc:
        return f"PortAudio cannot list its devices ({exc})"
    if not devices:
        return "PortAudio lists no output device on this machine (a sound card, or JACK)"
    return "output devices: " + ", ".join(
        f"{d['index']}: {d['name']} ({d['max_output_channels']} ch)" for d in devices)


def _target(sd, device: str | None):
    """PortAudio's output device for ``audio:NAME``: None (the default), a name (or part
    of one; sounddevice raises ValueError for no match) or a number, which must be one of
    the output devices PortAudio lists (InputError)."""
    # a number in ASCII digits: '²' is a digit to str.isdigit but not to int()
    if not device or not (device.isascii() and device.isdecimal()):
        return device or None
    index = int(device)
    try:
        listed = any(d["index"] == index and d["max_output_channels"] > 0
                     for d in sd.query_devices())
    except sd.PortAudioError:  # opening it says what is wrong
        return index
    if not listed:
        raise InputError(f"audio device {device!r}: No output device number {index}; "
                         f"{_outputs(sd)}")
    return index


class StreamOutput(AudioOutput):
    """Plays the stream on a PortAudio output device (module docstring).

    Parameters
    ----------
    plan : synthesis figures. device : PortAudio output device (name or index; "" or
    None: the default). blocksize : frames per callback. buffer_frames : ring capacity
    (frames; at least 4 blocksize, and live :data:`LIVE_BLOCKS` of the first block).
    phases, paced, stderr : as ``AudioOutput``. wait_s : how long a paced ``send`` may
    wait for room (s). tap_frames : record the callback's first ``tap_frames`` output
    frames (``player.tap``; tests).
    """

    def __init__(self, plan: AudioPlan, device: str | None, *, blocksize: int,
                 buffer_frames: int, phases: bool, paced: bool, wait_s: float,
                 stderr=sys.stderr, tap_frames: int = 0):
        super().__init__(plan, f"audio:{device}" if device else "audio", phases=phases,
                         paced=paced, stderr=stderr)
        sd = self._sd = import_sounddevice(self.label)
        self._tap_frames = tap_frames
        self._make_ring(max(int(buffer_frames), 4 * blocksize))
        self.wait_s = float(wait_s)
        self.ring_full = 0
        self.not_drained = 0
        self.xruns = 0  # callbacks PortAudio flagged with an output underflow
        self._ramp_in = plan.ramp_frames  # producer's ramp-in after a dropped block
        # ring position - synth frame, from a synth frame on (it moves at a dropped block)
        self._offsets = [(0, 0)]
        self._started = False
        self._running = False  # PortAudio's start returned: the stream ran
        self._released = False  # stop and close done (or abandoned): the stream is gone
        target, opened = _target(sd, device), []

        def open_stream() -> None:
            opened.append(sd.OutputStream(
                samplerate=plan.audio_rate, blocksize=blocksize, device=target,
                channels=plan.channels, dtype="float32", latency="low",
                callback=self._callback))

        try:
            returned = call_bounded(open_stream, PA_CALL_LIMIT_S)
        except ValueError as exc:  # no such device
            raise InputError(f"audio device {device!r}: {exc}; {_outputs(sd)}") from None
        except sd.PortAudioError as exc:
            raise DeviceError(f"{self.label}: cannot open a {plan.channels}-channel output "
                              f"at {plan.audio_rate} Hz: {exc}; {_outputs(sd)}") from None
        except BaseException:  # a signal during the wait (the open perhaps left running)
            abandon_portaudio(sd)
            raise
        if not returned:
            abandon_portaudio(sd)
            raise _not_answering(self.label, "open of the stream")
        self.stream = opened[0]
        #: PortAudio's reported output latency (s): from a callback's buffer to the DAC
        self.output_latency_s = float(self.stream.latency)

    def _make_ring(self, frames: int) -> None:
        """The ring, ``frames`` ahead of the callback and the ramp's reserve besides, and
        its player."""
        ramp = self.plan.ramp_frames
        self.ring = FrameRing(frames + ramp, self.plan.channels, ramp)
        self.player = Player(self.ring, ramp, self._tap_frames)

    def _callback(self, outdata, frames, time_info, status) -> None:
        if status.output_underflow:
            self.xruns += 1
        # on the producer's clock: when the callback runs, plus PortAudio's time from then
        # to the buffer's first frame at the DAC (its stream clock can jump under load)
        self.player.fill(outdata, time.monotonic() + (time_info.outputBufferDacTime
                                                      - time_info.currentTime))

    # ----------------------------------------------------------------- producer
    def _emit(self, frames: np.ndarray) -> None:
        ramp, need = self.plan.ramp_frames, LIVE_BLOCKS * frames.shape[0]
        if not (self.paced or self._started) and self.ring.capacity - ramp < need:
            self._make_ring(need)  # the first live block: no callback has the ring yet
        ring = self.ring
        ramped = self._ramp_in  # frames of the ramp in after a dropped block before these
        if self._ramp_in < ramp:  # after a dropped block: ramp in from 0
            g = min(frames.shape[0], ramp - self._ramp_in)
            frames[:g] *= (np.arange(self._ramp_in + 1, self._ramp_in + g + 1) / ramp)[:, None]
            self._ramp_in += g
        if not self.paced and ring.room() - ramp < frames.shape[0]:
            self.ring_full += frames.shape[0]
            self.commanded_frames += frames.shape[0]
            offset = self._offsets[-1][1] - frames.shape[0]
            # the stream so far ends in a ramp, not a step: the one published with the last
            # frames written, which follows them (carrier and level; the synthesis has
            # moved on by the dropped block)
            fade = ring.published[1]
            if self._ramp_in >= ramp and fade >= 0:
                self._write(ring.fades[fade])
                offset += ramp
            self._offsets.append((self.synth.frames, offset))
            self._ramp_in = 0
            return
        step = ring.capacity - ramp
        first = self.synth.frames - frames.shape[0]  # the synthesis's frame of frames[0]
        for lo in range(0, frames.shape[0], step):
            chunk = frames[lo:lo + step]
            self._wait_room(chunk.shape[0] + ramp)
            # the fade after this part: the callback may run dry before the next; from
            # the level the ramp in would give the next frame, where one is under way
            end = lo + chunk.shape[0]
            self._write(chunk, self.synth.fade_tail(first + end)
                        * min(1.0, (ramped + end + 1) / ramp))

    def _write(self, frames: np.ndarray, fade: np.ndarray | None = None) -> None:
        self.ring.write(frames.astype(np.float32), None if fade is None else fade.astype(np.float32))
        self.commanded_frames += frames.shape[0]
        if not self._started and (not self.paced or self.closed
                                  or self.ring.tail >= self.ring.capacity // 2):
            self._start()

    def _wait_room(self, frames: int) -> None:
        deadline = time.monotonic() + self.wait_s
        while self.ring.room() < frames:
            if not self._started:
                self._start()
            gone = not self._active()
            if gone or time.monotonic() > deadline:
                problem = self.label + (
                    ": the audio device went away" if gone else f": the audio device took no frames for "
                    f"{self.wait_s:g} s (it stopped or went away)")
                self.player.estop = True
                self._release(problem)  # raises for a stream gone or abandoned
                raise DeviceError(problem + "; the stream was stopped and closed")
            check_interrupt()
            time.sleep(POLL_S)

    def _active(self) -> bool:
        """Whether PortAudio still runs the stream (False once a JACK server has gone)."""
        try:
            return bool(self.stream.active)
        except self._sd.PortAudioError:
            return False

    def now(self) -> float:
        """The clock of :meth:`dac_time_of_command` (s): ``time.monotonic``."""
        return time.monotonic()

    def dac_time_of_command(self, index: int) -> float | None:
        """When the first frame carrying command sample ``index`` (``send``'s
        ``start_index`` counting) reached the DAC (s, :meth:`now`'s clock: when its
        callback ran, plus PortAudio's time from then to the DAC, plus the frame's offset
        in the buffer); None if that frame never played."""
        frame = self.synth.frames_until(int(index) - self.first_index)
        offset = 0
        for since, value in self._offsets:
            if since <= frame:
                offset = value
        return self.player.dac_time(frame + offset, self.plan.audio_rate)

    def _start(self) -> None:
        """Start the stream, bounded like stop and close: JACK's start also waits for the
        callback thread."""
        self._started = True
        try:
            started = call_bounded(self.stream.start, PA_CALL_LIMIT_S)
        except self._sd.PortAudioError as exc:  # closing still stops and closes it
            raise DeviceError(f"{self.label}: cannot start the stream: {exc}") from None
        except BaseException:
            self._abandon()
            raise
        if not started:
            self._abandon()
            raise DeviceError(f"{self.label}: PortAudio's start did not return within "
                              f"{PA_CALL_LIMIT_S:g} s (the audio device stopped responding), "
                              "so the stream was abandoned")
        self._running = True

    # ----------------------------------------------------------------- ending
    def emergency_stop(self) -> None:
        """Ramp to 0 within ``ramp_ms`` from what plays now; drop the rest (``stopped``).
        Never waits; :meth:`close` releases the device."""
        self.player.estop = True

    def abort(self) -> None:
        """End at once (a run stopped by a signal or an error): :meth:`emergency_stop`,
        then :meth:`close`, which plays the ramp out and releases the device."""
        self.emergency_stop()
        self.close()

    def _end(self, tail: np.ndarray) -> None:
        if self._released:  # a failed wait has let the device go
            return
        try:
            if not self.player.estop:
                self._ramp_in = self.plan.ramp_frames
                self._wait_room(tail.shape[0])
                self._write(tail)
            self.player.ended = True
            if self.player.estop and not self._started:  # stopped before it played
                self.player.stopped += self.ring.tail - self.ring.head
                self.ring.head = self.ring.tail
                return
            if not self._started:
                self._start()
            try:
                self._drain()
            finally:  # the last callback's frames (or the ramp) still on their way to the DAC
                time.sleep(self.output_latency_s + (self.stream.blocksize + self.plan.ramp_frames)
                           / self.plan.audio_rate)
                self.not_drained = self.ring.tail - self.ring.head
        finally:
            self._release(f"{self.label}: the audio device stopped responding while the "
                          "stream closed")

    def _drain(self) -> None:
        """Wait (bounded) until the ring has played out, or after an emergency stop until
        its ramp to 0 has. A held signal (Ctrl-C, SIGTERM: ``device.link.waits``) makes
        it an emergency stop, raised once the ramp has played."""
        queued = self.ring.tail - self.ring.head
        deadline = time.monotonic() + queued / self.plan.audio_rate + DRAIN_MARGIN_S
        interrupted = None
        while ((self.ring.head < self.ring.tail or self.player.estop and not self.player.silent)
               and time.monotonic() < deadline and self._active()):
            if interrupted is None:
                try:
                    check_interrupt()
                except BaseException as exc:  # noqa: BLE001 - raised below
                    interrupted = exc
                    self.emergency_stop()
            time.sleep(POLL_S)
        if interrupted is not None:
            raise interrupted

    def _release(self, context: str) -> None:
        """Stop and close the stream, each PortAudio call bounded by
        :data:`PA_CALL_LIMIT_S`; one that does not return (or a signal during the wait)
        abandons the stream (module docstring). Raises DeviceError, starting with
        ``context``, for an abandoned stream."""
        if self._released:
            return
        if self._running and not self._active():  # its server went away (module docstring)
            self._abandon()
            raise DeviceError(f"{context}; PortAudio reports the stream no longer active, so "
                              "it was abandoned without a stop or close")
        self._released = True
        calls = (("stop", self.stream.stop), ("close", self.stream.close))
        for what, call in calls if self._started else calls[1:]:
            try:
                returned = call_bounded(call, PA_CALL_LIMIT_S)
            except BaseException:
                self._abandon()
                raise
            if not returned:
                self._abandon()
                raise DeviceError(f"{context}; PortAudio's {what} did not return within "
                                  f"{PA_CALL_LIMIT_S:g} s, so the stream was abandoned")

    def _abandon(self) -> None:
        """Leave the stream to PortAudio for good: should its callback run again, it
        ramps to 0 and plays silence."""
        self._released = True
        self.player.estop = True
        abandon_portaudio(self._sd)

    # ----------------------------------------------------------------- accounting
    def played_frames(self) -> int:
        return self.player.played

    def unplayed_by_cause(self) -> dict[str, int]:
        counts = {"late": self.player.late, "ring_full": self.ring_full,
                  "stopped": self.player.stopped, "not_drained": self.not_drained}
        return {k: counts[k] for k in CAUSES}

    def status(self) -> dict:
        out = super().status()
        out["underruns"] = self.player.underruns
        out["audio"].update({"underrun_frames": self.player.underrun_frames,
                             "xruns": self.xruns, "output_latency_s": self.output_latency_s,
                             "blocksize": self.stream.blocksize})
        return out

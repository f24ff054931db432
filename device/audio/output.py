"""The producer's side of the audio outputs: the ``OutputDevice`` contract of
``device.link.devices`` over :class:`~device.audio.synth.AudioSynth`.

:class:`AudioOutput` validates and renders each block; a subclass says where the frames
go (``_emit``) and how the stream ends (``_end``): :class:`device.audio.stream.StreamOutput`
into PortAudio, :class:`device.audio.wav.WavOutput` into a file.

Accounting, in audio frames: ``commanded_frames`` is every frame handed to the output
(rendered frames and the ramps that end the stream); each is played or unplayed, by
cause (``late``: its slot passed while the producer starved the callback; ``ring_full``:
a live producer ahead of the ring; ``stopped``: dropped by an emergency stop;
``not_drained``: still queued when closing gave up). In command samples (the units of the
link's ``commanded_samples``/``unplayed_samples``): frames x rate_hz / audio_rate, rounded up.
"""

from __future__ import annotations

import math
import sys
from dataclasses import asdict

import numpy as np

from frictex.device.audio.options import AudioPlan
from frictex.device.audio.synth import AudioSynth
from frictex.device.errors import DeviceError, InputError
from frictex.device.link.protocol import Info

#: longest run of zero commands rendered at once for a gap in ``start_index`` (samples)
GAP_CHUNK = 10_000
CAUSES = ("late", "ring_full", "stopped", "not_drained")


class AudioOutput:
    """An output device that synthesises the carrier on the host (module docstring).

    Parameters
    ----------
    plan : the synthesis figures. label : the device's name in messages.
    phases : commands come with phases (rad). paced : ``send`` may wait (replay).
    stderr : where warnings go.
    """

    def __init__(self, plan: AudioPlan, label: str, *, phases: bool, paced: bool,
                 stderr=sys.stderr):
        self.plan = plan
        self.label = label
        self.channels = plan.channels
        self.rate_hz = plan.rate_hz
        self.paced = paced
        self.phases = phases
        self._stderr = stderr
        self.synth = AudioSynth(plan)
        limit_um = plan.limit_v * plan.um_per_volt
        self.info = Info(channels=plan.channels, sample_rate_hz=plan.rate_hz,
                         limits_um=(limit_um,) * plan.channels, buffer_samples=0,
                         watchdog_ms=0, ramp_ms=round(plan.ramp_frames * 1e3 / plan.audio_rate),
                         has_phases=phases, name=label)
        self.commanded_frames = 0
        self.gap_samples = 0
        self.closed = False
        self._next: int | None = None  # the start index the next block should have
        self.first_index = 0  # the first block's start index (command sample 0 of the stream)

    # ----------------------------------------------------------------- OutputDevice
    def send(self, start_index: int, amplitudes_um: np.ndarray,
             phases_rad: np.ndarray | None = None) -> None:
        """Play (n, channels) amplitudes (um) from command sample ``start_index`` on.

        A forward jump in ``start_index`` is silence (zero commands, counted as
        ``gap_samples``); paced, waits for room (bounded); live, never waits.
        """
        if self.closed:
            raise DeviceError(f"{self.label}: send after close")
        if self.phases != (phases_rad is not None):
            raise InputError(f"phases {'missing' if self.phases else 'given'}: this output "
                             f"was opened with phases={self.phases}")
        start_index = int(start_index)
        if self._next is not None and start_index < self._next:
            raise InputError(f"start_index = {start_index}: expected {self._next} or later "
                             "(blocks in order, without overlap)")
        if self._next is None:
            self.first_index = self._next = start_index
        gap = start_index - self._next
        while gap > 0:
            n = min(gap, GAP_CHUNK)
            zeros = np.zeros((n, self.channels))
            self._emit(self.synth.render(zeros, zeros if self.phases else None))
            self.gap_samples += n
            gap -= n
        commands0 = self.synth.commands
        frames = self.synth.render(amplitudes_um, phases_rad)
        self._next = start_index + self.synth.commands - commands0
        self._emit(frames)

    def wait_for_room(self, timeout_s: float) -> bool:
        """True at once: ``send`` waits itself where it must (paced)."""
        return True

    def device_force_n(self) -> float | None:
        """None: an audio interface measures no force."""
        return None

    def force_report(self, index0: int | None = None, n: int | None = None):
        """None: no lateral force sensor."""
        return None

    def forces_covered(self, index0: int, n: int) -> tuple[np.ndarray, np.ndarray]:
        """Empty: no force reports."""
        return np.zeros(0), np.zeros(0)

    def close(self) -> None:
        """End the stream with its ramp to 0 and release the output; idempotent."""
        if self.closed:
            return
        self.closed = True
        self._end(self.synth.finish())

    def __enter__(self) -> AudioOutput:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # ----------------------------------------------------------------- accounting
    def unplayed_by_cause(self) -> dict[str, int]:
        """Frames never played, by cause (module docstring)."""
        raise NotImplementedError

    def played_frames(self) -> int:
        """Frames played so far."""
        raise NotImplementedError

    def unplayed_share(self) -> float:
        """Frames never played over all commanded (0 when none were)."""
        if not self.commanded_frames:
            return 0.0
        return sum(self.unplayed_by_cause().values()) / self.commanded_frames

    def status(self) -> dict:
        """JSON-able counters for ``summary.json``'s ``device`` section."""
        causes = self.unplayed_by_cause()
        to_samples = self.plan.rate_hz / self.plan.audio_rate
        by_cause = {k: min(self.synth.commands, math.ceil(v * to_samples))
                    for k, v in causes.items()}
        plan = self.plan
        return {
            "state": "closed" if self.closed else "open",
            "port": self.label,
            "paced": self.paced,
            "commanded_samples": self.synth.commands,
            "played_samples": self.synth.commands - min(self.synth.commands,
                                                         sum(by_cause.values())),
            "unplayed_samples": sum(by_cause.values()),
            "unplayed_by_cause": by_cause,
            "clamped_samples": self.synth.clamped,
            "gap_samples": self.gap_samples,
            "device": asdict(self.info),
            "audio": {
                "rate_hz": plan.audio_rate, "carrier_hz": None if plan.envelope else plan.carrier_hz,
                "envelope": plan.envelope, "profile": plan.profile,
                "um_per_volt": plan.um_per_volt, "limit_v": plan.limit_v,
                "full_scale_v": plan.full_scale_v,
                "ramp_ms": plan.ramp_frames * 1e3 / plan.audio_rate,
                "commanded_frames": self.commanded_frames,
                "played_frames": self.played_frames(),
                "unplayed_frames": causes,
            },
        }

    # ----------------------------------------------------------------- subclasses
    def _emit(self, frames: np.ndarray) -> None:
        """Queue rendered frames (m, channels) float64 for playing."""
        raise NotImplementedError

    def _end(self, tail: np.ndarray) -> None:
        """Queue the last frames (the ramp to 0), play out, release."""
        raise NotImplementedError


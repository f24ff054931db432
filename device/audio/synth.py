"""Sans-IO synthesis of the audio stream: commands (um, rad) in, audio frames out.

Timeline. Audio frame n plays at ``n / audio_rate`` s; command sample k belongs to
``k / rate_hz`` s. Frame n carries the command stream at position q = n * rate_hz /
audio_rate (in command samples), linearly interpolated between commands floor(q) - 1 and
floor(q): the stream runs exactly one command sample (100 us at 10 kHz) behind the
commands, so that every frame of a block is known when the block arrives and no block
boundary is a step. Command -1 is zero. The index arithmetic is exact (integers).

Carrier. Phase of frame n: 2 pi * ((n * f / audio_rate) mod 1), the fraction taken in
exact integer arithmetic every 1024 frames (the carrier f is a float64, an exact binary
fraction) and advanced in float64 only in between: the phase never drifts,
after hours as after a second (``tests/test_audio_synth.py``: 10 h within 1e-9 rad).

Amplitude. um / ``um_per_volt`` gives volts zero-to-peak; a channel's phase (rad) makes
it complex; its magnitude is clamped to ``limit_v`` and scaled by ``1 / full_scale_v``.
A negative amplitude plays 0, as the serial link's device plays it
(``device.link.protocol``): a zero-to-peak amplitude is never below 0, and its magnitude
would otherwise drive the plate, its carrier inverted. Both are counted per command
sample and channel. A frame is ``Re(A(t) exp(i theta_n))``, one audio
channel per actuator, all on one carrier (phase-locked); envelope mode plays ``|A(t)|``.
The first ``ramp_frames`` frames ramp up from 0; :meth:`AudioSynth.finish` ramps down.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np

from frictex.device.audio.options import AudioPlan
from frictex.device.errors import InputError

TWO_PI = 2.0 * np.pi
#: frames between exact phase anchors (``carrier_cycles``)
ANCHOR = 1024


def carrier_cycles(n0: int, count: int, carrier_hz: float, audio_rate: int) -> np.ndarray:
    """Carrier phase in cycles, ``(n * carrier_hz / audio_rate) mod 1``, of frames
    ``n0 .. n0 + count - 1``: (count,) float64 in [0, 1).

    The fraction is exact (integers: ``carrier_hz`` is a binary fraction) every
    :data:`ANCHOR` frames; between anchors it advances by the float64 step, an error
    below 1e-13 cycles.
    """
    num, den = float(carrier_hz).as_integer_ratio()
    period = den * int(audio_rate)
    anchors = np.array([(int(n) * num % period) / period
                        for n in range(int(n0), int(n0) + count, ANCHOR)], dtype=np.float64)
    j = np.arange(count)
    cycles = anchors[j // ANCHOR] + (j % ANCHOR) * (carrier_hz / audio_rate)
    return cycles - np.floor(cycles)


class AudioSynth:
    """The synthesis state of one stream (module docstring): :meth:`render` one block of
    commands after another, :meth:`finish` at the end.

    Attributes: ``frames`` (the next frame's index n), ``commands`` (command samples
    taken), ``clamped`` (command samples x channels clamped to ``plan.limit_v``, or
    negative and played 0).
    """

    def __init__(self, plan: AudioPlan):
        self.plan = plan
        rate = Fraction(plan.rate_hz).limit_denominator(1_000_000)
        self._rn, self._rd = rate.numerator, rate.denominator
        self._period = plan.audio_rate * self._rd  # frame n is at command n * rn / period
        self.frames = 0
        self.commands = 0
        self.clamped = 0
        self.finished = False
        self._last = np.zeros(plan.channels, dtype=np.complex128)  # command k - 1, full scale
        # the last block's commands (its command k0 - 1 first) and k0: a fade may start at
        # any of its frames (``fade_tail``)
        self._block = (np.zeros((1, plan.channels), dtype=np.complex128), 0)

    def frames_until(self, commands: int) -> int:
        """Frames the stream has once ``commands`` command samples are in (exact)."""
        return -(-int(commands) * self._period // self._rn)

    def render(self, amplitudes_um: np.ndarray, phases_rad: np.ndarray | None = None
               ) -> np.ndarray:
        """The frames one block of commands completes: (m, channels) float64, full scale 1.

        ``amplitudes_um``: (n, channels) float64, um zero-to-peak, finite; ``phases_rad``:
        the same shape or None (phase 0). m is ``frames_until(commands + n) - frames``
        (19 or 20 frames per command at 10 kHz into 192 kHz).
        """
        plan = self.plan
        if self.finished:
            raise InputError("audio stream: commands after its end")
        a = np.asarray(amplitudes_um, dtype=np.float64)
        if a.ndim != 2 or a.shape[1] != plan.channels:
            raise InputError(f"amplitudes shape {a.shape}: expected (n, {plan.channels})")
        negative = a < 0.0
        volts = np.where(negative, 0.0, a) / plan.um_per_volt
        if phases_rad is not None:
            p = np.asarray(phases_rad, dtype=np.float64)
            if p.shape != a.shape:
                raise InputError(f"phases shape {p.shape}: expected {a.shape}")
            volts = volts * np.exp(1j * p)
        if not np.all(np.isfinite(volts)):
            raise InputError("audio stream: amplitudes and phases must be finite")
        magnitude = np.abs(volts)
        over = magnitude > plan.limit_v
        self.clamped += int(np.count_nonzero(over) + np.count_nonzero(negative))
        scale = np.where(over, plan.limit_v / np.where(over, magnitude, 1.0), 1.0)
        commands = np.empty((a.shape[0] + 1, plan.channels), dtype=np.complex128)
        commands[0] = self._last
        commands[1:] = volts * (scale / plan.full_scale_v)

        n0, k0 = self.frames, self.commands
        n1 = self.frames_until(k0 + a.shape[0])
        out = self._carry(self._levels(commands, k0, n0, n1), n0)
        self.frames, self.commands = n1, k0 + a.shape[0]
        self._last = commands[-1].copy()
        self._block = (commands, k0)
        return out

    def fade_tail(self, end: int | None = None) -> np.ndarray:
        """The ``ramp_frames`` frames that would follow frame ``end - 1`` if no command
        came after it: the level of frame ``end`` ramped linearly to 0, the carrier going
        on. ``end``: a frame of the last block rendered (where the ring's part of it
        ends), or None: the stream's end (``frames``), whose level is the last command's.
        (ramp_frames, channels) float64; the state is unchanged (the ring keeps it for a
        starving callback)."""
        end = self.frames if end is None else int(end)
        if end < self.frames:
            level = self._levels(*self._block, end, end + 1)[0]
        else:  # the next command is not known: the last one held
            level = self._last * self._start_ramp(end, end + 1)[0]
        r = self.plan.ramp_frames
        gain = 1.0 - np.arange(1, r + 1, dtype=np.float64)[:, None] / r
        return self._carry(level[None, :] * gain, end)

    def finish(self) -> np.ndarray:
        """The stream's last frames (:meth:`fade_tail`), taken: the stream ends at 0."""
        tail = self.fade_tail()
        self.frames += tail.shape[0]
        self._last[:] = 0.0
        self.finished = True
        return tail

    def _levels(self, commands: np.ndarray, k0: int, n0: int, n1: int) -> np.ndarray:
        """Complex amplitudes (n1 - n0, channels), full scale, of frames ``n0 .. n1 - 1``:
        ``commands`` (command ``k0 - 1`` first) interpolated (module docstring), on the
        stream's ramp up from 0."""
        q0, r0 = divmod(n0 * self._rn, self._period)
        t = r0 + np.arange(n1 - n0, dtype=np.int64) * self._rn
        i = (q0 - k0) + t // self._period  # command index - k0, frame by frame
        frac = ((t % self._period) / self._period)[:, None]
        amp = commands[i] * (1.0 - frac) + commands[i + 1] * frac
        if n0 < self.plan.ramp_frames:
            amp *= self._start_ramp(n0, n1)
        return amp

    def _start_ramp(self, n0: int, n1: int) -> np.ndarray:
        """The gains (n1 - n0, 1) of frames ``n0 .. n1 - 1`` on the stream's first
        ``ramp_frames`` frames' ramp up from 0 (1 after it)."""
        return np.minimum(1.0, (np.arange(n0, n1) + 1.0) / self.plan.ramp_frames)[:, None]

    def _carry(self, amp: np.ndarray, n0: int) -> np.ndarray:
        """Complex amplitudes (m, channels) on the carrier from frame ``n0``, or their
        magnitude in envelope mode: (m, channels) float64."""
        if self.plan.envelope:
            return np.abs(amp)
        theta = TWO_PI * carrier_cycles(n0, amp.shape[0], self.plan.carrier_hz,
                                        self.plan.audio_rate)
        return amp.real * np.cos(theta)[:, None] - amp.imag * np.sin(theta)[:, None]

"""A simulated plate microcontroller: the device side of ``device/PROTOCOL.md``.

:class:`DeviceCore` is the firmware's logic on a virtual clock (pure apart from the
optional log writers): it decodes the host's frames, keeps received samples in a jitter
buffer indexed by sample number, plays one sample per tick at its sample rate, models
the plate's closed amplitude loop as a first-order low pass (seed 003, Fig. 3b: 400 Hz
bandwidth; the exact discretisation of the loop held over each tick, PROTOCOL.md 5.4; run
where it is seen: a ``sensor`` reporting it, or a ``plate_log``), enforces the watchdog
(no valid frame for ``watchdog_ms`` and the output ramps to zero within ``ramp_ms`` and
the buffer is flushed) and the bounded hold (a BUFFERING device holds its setpoint at most
``watchdog_ms`` after the last sample it played, a Hello not at all, then ramps it to zero
keeping its buffer: PROTOCOL.md 5.1), asks for host frames it found missing (version 4:
Missing, answered by Resend) and, with a force sensor (``device.link.simsensor``), reports
the lateral and normal force in ForceReport messages to a version 3 or later host.

:func:`serve` binds a core to the wall clock and to a pseudo-terminal or a TCP listener
(one host at a time); ``frictex sim-device`` runs it for external tools. The host's
``--device sim`` runs a core in its own process instead (``device.link.simport``). The core answers each frame in the
protocol version the frame was sent in (up to ``DeviceConfig.protocol_version``).

Played-sample log (CSV, ``--log``): ``index,ch0_um,...[,ch0_phase_rad,...]``, one row per
sample actually played from a valid frame (exactly the commanded fixed-point values,
before the plate model). Plate log (``--plate-log``): ``t_s,state,ch0_setpoint_um,...,
ch0_plate_um,...``, one row per tick.
"""

from __future__ import annotations

import errno
import math
import os
import select
import socket
import stat
import sys
import threading
import time
import tty
from dataclasses import dataclass, field

import numpy as np

from frictex.device.errors import DeviceError, InputError
from frictex.device.link import protocol as p
from frictex.device.link.protocol import DeviceState as S
from frictex.device.link.simsensor import FINGER_FORCE_N, ConstantSensor, FingerSensor, ForceWindows
from frictex.device.safe_text import escape_path


#: how long the device keeps asking for a missing frame (ms, PROTOCOL.md 4.10)
MISSING_TTL_MS = 100
#: most actuator channels, as the firmware's ``FW_MAX_CHANNELS``
#: (device/firmware/core/fw_limits.h; Info's channels field is a u8)
MAX_CHANNELS = 8
#: jitter-buffer storage (samples x channels), as the firmware's ``FW_STORE_WORDS``
STORE_WORDS = 32768 * 8
#: longest device name (UTF-8 bytes), as the firmware's ``FW_NAME_MAX``
NAME_MAX = 32


@dataclass(frozen=True)
class DeviceConfig:
    """What the simulated device is (all of it is declared in its Info answer).

    limits_um : per-channel amplitude limit (um zero-to-peak); one value means all channels.
        The device declares and clamps to it floored to a whole wire count (:attr:`limit_counts`).
    buffer_samples : jitter-buffer capacity (samples per channel).
    bandwidth_hz : corner frequency f_c (Hz) of the modelled amplitude loop, a continuous
        first-order low pass discretised exactly at ``rate_hz`` (PROTOCOL.md 5.4): any
        positive finite value at any rate. The discrete response is -3 dB at f_c only
        where f_c is well under the rate (400 Hz: -2.99 dB at 10 kHz, -1.29 dB at 1 kHz).
    force_n : normal force reported by a simulated force sensor (N), None for no sensor.
    lateral_n : a constant lateral force (N) in force reports (normal: ``force_n`` or 0).
    finger : force reports from a simulated finger, person ``finger`` of
        ``device.finger.draw_finger``, sliding at ``finger_speed_mm_s`` (negative: towards
        -x, its lateral force negative) and pressing with
        ``force_n`` (default 0.5 N) (``device.link.simsensor.FingerSensor``).
    force_decimation, force_pairs : ticks averaged per reported value, values per report.
    """

    channels: int = 1
    rate_hz: float = 10_000.0
    limits_um: tuple[float, ...] = (4.0,)
    buffer_samples: int = 4096
    bandwidth_hz: float = 400.0
    watchdog_ms: int = 25
    ramp_ms: int = 20
    phases: bool = False
    sensor: bool = False
    force_n: float | None = None
    name: str = "frictex sim-device"
    protocol_version: int = p.PROTOCOL_VERSION
    lateral_n: float | None = None
    finger: int | None = None
    finger_speed_mm_s: float = 100.0
    force_decimation: int = 4
    force_pairs: int = 10

    def __post_init__(self):
        channels_ok = 1 <= self.channels <= MAX_CHANNELS
        rate_ok = 0.001 <= self.rate_hz < 4e6  # else (NaN, inf) there are no ticks to count
        checks = [(channels_ok, "channels", f"1 to {MAX_CHANNELS} (the firmware's "
                   "FW_MAX_CHANNELS)"),
                  (rate_ok, "rate_hz",
                   "in [0.001, 4e6) Hz (the wire carries a u32 of mHz)"),
                  (len(self.limits_um) in (1, self.channels), "limits_um",
                   f"one value for all channels or one per channel ({self.channels})"),
                  (all(p.AMPLITUDE_STEP_UM <= x <= p.AMPLITUDE_MAX_UM for x in self.limits_um),
                   "limits_um", f"in [1/4096, {p.AMPLITUDE_MAX_UM:.4f}] um (one wire count "
                   "to the wire's top)"),
                  (not channels_ok or 2 <= self.buffer_samples <= STORE_WORDS // self.channels,
                   "buffer_samples", f"2 to {STORE_WORDS // max(self.channels, 1)} samples for "
                   f"{self.channels} channel(s) (the firmware's store, FW_STORE_WORDS = "
                   f"{STORE_WORDS} values)"),
                  (len(self.name.encode("utf-8")) <= NAME_MAX, "name",
                   f"at most {NAME_MAX} UTF-8 bytes (the firmware's FW_NAME_MAX)"),
                  (self.bandwidth_hz > 0 and math.isfinite(self.bandwidth_hz),
                   "bandwidth_hz", "positive and finite"),
                  (1 <= self.watchdog_ms <= p.MAX_STOP_MS - 1, "watchdog_ms",
                   f"in [1, {p.MAX_STOP_MS - 1}] ms"),
                  (0 <= self.ramp_ms <= p.MAX_STOP_MS - self.watchdog_ms, "ramp_ms",
                   f"in [0, {p.MAX_STOP_MS - self.watchdog_ms}] ms: watchdog_ms + ramp_ms must "
                   f"not exceed {p.MAX_STOP_MS} ms (PROTOCOL.md 5.3)"),
                  (not rate_ok or self.ramp_ms == 0 or self.ticks(self.ramp_ms) >= 2, "ramp_ms",
                   f"0 or at least 2 ticks at {self.rate_hz:g} Hz: a shorter ramp is a step "
                   "to zero (PROTOCOL.md 5.3)"),
                  (not rate_ok or self.stop_fits_in_ticks(), "watchdog_ms",
                   f"ticks(watchdog_ms) + ticks(ramp_ms = {self.ramp_ms}) within "
                   f"{p.MAX_STOP_MS} ms at {self.rate_hz:g} Hz (PROTOCOL.md 5.3): raise the "
                   "rate or shorten them"),
                  (self.force_n is None or 0 <= self.force_n <= 65.0, "force_n", "in [0, 65] N"),
                  (1 <= self.protocol_version <= p.PROTOCOL_VERSION, "protocol_version",
                   f"in [1, {p.PROTOCOL_VERSION}]"),
                  (self.lateral_n is None or abs(self.lateral_n) <= 8.0, "lateral_n",
                   "in [-8, 8] N"),
                  (self.finger is None or self.finger >= 0, "finger", "a seed >= 0"),
                  (self.lateral_n is None or self.finger is None, "lateral_n",
                   "None with a simulated finger (it makes the lateral force)"),
                  (abs(self.finger_speed_mm_s) <= 1e4, "finger_speed_mm_s",
                   "in [-1e4, 1e4] mm/s (negative: sliding towards -x)"),
                  (1 <= self.force_decimation <= 65535, "force_decimation", "in [1, 65535]"),
                  (1 <= self.force_pairs <= p.FORCE_PAIRS_MAX, "force_pairs",
                   f"in [1, {p.FORCE_PAIRS_MAX}]"),
                  (not self.force_reports or self.protocol_version >= 3, "protocol_version",
                   "3 for force reports (lateral_n or finger)")]
        for ok, name, expected in checks:
            if not ok:
                raise InputError(f"sim-device {name} = {getattr(self, name)!r}: expected {expected}")

    @property
    def limit_counts(self) -> np.ndarray:
        """Per-channel limit in wire counts, floored (never above ``limits_um``): what the
        device declares in Info and clamps to."""
        um = np.broadcast_to(np.asarray(self.limits_um, dtype=np.float64), (self.channels,))
        return np.floor(um / p.AMPLITUDE_STEP_UM + 1e-9).astype(np.uint16)

    @property
    def limits(self) -> np.ndarray:
        """The declared per-channel limits (um), whole wire counts."""
        return p.amplitude_from_wire(self.limit_counts)

    @property
    def force_reports(self) -> bool:
        """Whether the device has a lateral force sensor (sends ForceReports)."""
        return self.lateral_n is not None or self.finger is not None

    def ticks(self, ms: int) -> int:
        """``ms`` in ticks of the sample clock: ceil(ms * rate_mHz / 10^6), at least 1, in
        integers on the declared rate (PROTOCOL.md 5.3), as the firmware counts."""
        rate_mhz = int(round(self.rate_hz * 1000.0))
        return max(1, -(-ms * rate_mhz // 1_000_000))

    def stop_fits_in_ticks(self) -> bool:
        """Whether the hold and the ramp, in the whole ticks the device counts, end within
        :data:`MAX_STOP_MS`: (ticks(watchdog_ms) + ticks(ramp_ms)) / rate <= 50 ms
        (PROTOCOL.md 5.3); the ms sum alone is too weak at low rates."""
        rate_mhz = int(round(self.rate_hz * 1000.0))
        ticks = self.ticks(self.watchdog_ms) + self.ticks(self.ramp_ms)
        return ticks * 1_000_000 <= p.MAX_STOP_MS * rate_mhz

    def force_sensor(self):
        """The simulated sensor behind the force reports, or None (``simsensor``)."""
        if self.finger is not None:
            normal = FINGER_FORCE_N if self.force_n is None else self.force_n
            return FingerSensor(self.finger, self.rate_hz, float(self.limits[0]),
                                self.finger_speed_mm_s, normal)
        if self.lateral_n is not None:
            return ConstantSensor(self.lateral_n, self.force_n or 0.0)
        return None

    def info(self) -> p.Info:
        return p.Info(self.channels, self.rate_hz, tuple(float(x) for x in self.limits),
                      self.buffer_samples, self.watchdog_ms, self.ramp_ms, self.phases,
                      self.sensor, self.force_n is not None, self.name, self.protocol_version,
                      self.force_reports)


@dataclass
class Counters:
    """Cumulative since power-up (Status version 1 counters, plus ``played_samples``)."""

    underruns: int = 0
    gap_samples: int = 0
    late_samples: int = 0
    overflow_samples: int = 0
    watchdog_trips: int = 0
    clamped: int = 0
    played_samples: int = 0


@dataclass
class SessionCounters:
    """Since the last Hello (Status version 2 accounting)."""

    played: int = 0
    flushed: int = 0
    flushes: int = 0


def _signed_offset(index: int, origin: int) -> int:
    """``index - origin`` modulo 2**64, as a signed 64-bit number (PROTOCOL.md 4.3)."""
    return (index - origin + 2 ** 63) % p.INDEX_MODULUS - 2 ** 63


@dataclass
class DeviceCore:
    """The device's logic on a virtual clock (see the module docstring).

    Drive it with :meth:`receive` (bytes from the host at time ``t_s``; returns bytes to
    send back) and :meth:`advance_to` (play every tick up to time ``t_s``; returns bytes
    the device sends on its own: a Flushed after a watchdog trip, ForceReports). ``log``
    and ``plate_log`` are optional callables receiving the played samples and the per-tick
    output (see :class:`CsvLog`). ``sensor``: the force sensor (``simsensor``; default:
    the one ``config`` describes); used only when ``config.force_reports`` (the device's
    Info announces ForceReports), else ignored, as the C core does.
    """

    config: DeviceConfig = field(default_factory=DeviceConfig)
    log: object = None
    plate_log: object = None
    sensor: object = None

    def __post_init__(self):
        c = self.config
        self.decoder = p.Decoder(max_version=c.protocol_version, on_device=True)
        self.counters = Counters()
        self.session = SessionCounters()
        self.state = S.IDLE
        self._cap = c.buffer_samples
        # a ring: the sample at play_index sits in slot _head, the one after in _head + 1...
        self._amp = np.zeros((self._cap, c.channels), dtype=np.uint16)
        self._phase = np.zeros((self._cap, c.channels), dtype=np.uint16)
        self._filled = np.zeros(self._cap, dtype=bool)
        self._head = 0
        self._end = 0              # one past the furthest sample held, relative to play_index
        self.level = 0
        self.play_index = 0        # modulo 2**64
        self.host_version = 1      # version of the last valid frame from the host
        self.hello_seen = False
        self.hellos = 0            # Hellos handled (a connection that adds none is silent)
        self._origin_set = False
        self.prefill = 1
        self.tick = 0
        self._last_rx_tick: int | None = None
        self._wd_ticks = c.ticks(c.watchdog_ms)
        self.missing: dict[int, int] = {}  # host seq -> tick it was found missing (4.10)
        self._missing_ttl = c.ticks(MISSING_TTL_MS)
        self._ramp_ticks = c.ticks(c.ramp_ms)
        self._top = c.limit_counts
        self.setpoint = np.zeros(c.channels)  # um, what the loop is told to produce now
        self._ramp_from = np.zeros(c.channels)
        self._ramp_pos = self._ramp_ticks      # ticks into the current ramp (done)
        # BUFFERING ticks held since the last sample played; _wd_ticks + 1: a ramp to zero
        # has begun since (PROTOCOL.md 5.1)
        self._held = 0
        # PROTOCOL.md 5.4: the first-order loop held over each tick, discretised exactly:
        # y[k] = a y[k-1] + (1 - a) u[k], a = exp(-2 pi f_c / f_s) in [0, 1), no overshoot
        pole = math.exp(-2.0 * math.pi * c.bandwidth_hz / c.rate_hz)
        self._b = np.array([1.0 - pole])
        self._a = np.array([1.0, -pole])
        self._zi = np.zeros((c.channels, 1))
        self.plate_um = np.zeros(c.channels)
        self.stopped = False                   # a Stop finished: output is zero
        self._tx_seq = 0
        if not c.force_reports:
            self.sensor = None  # Info announces no ForceReports: none is sent
        elif self.sensor is None:
            self.sensor = c.force_sensor()
        self._windows = ForceWindows(c.force_decimation, c.force_pairs)

    # ------------------------------------------------------------------ host -> device
    def new_connection(self) -> None:
        """Start the receiver afresh for a host that has just connected: bytes the one
        before left half-sent are dropped, not taken as the start of the new host's first
        frame (which PROTOCOL.md 2 lets begin without a 0x00). The counts go on."""
        self.decoder = p.Decoder(max_version=self.config.protocol_version, on_device=True,
                                 counts=self.decoder.counts)

    def receive(self, data: bytes, t_s: float) -> bytes:
        """Handle bytes from the host arriving at ``t_s``; returns the reply bytes."""
        out = bytearray()
        for frame in self.decoder.feed(data):
            if frame.message.TYPE >= p.DEVICE_TYPES:
                continue  # 5.3: our own frames echoed back neither arm nor feed the watchdog
            tick = max(self.tick, int(t_s * self.config.rate_hz))
            self._last_rx_tick = tick
            self.host_version = frame.version
            gap = frame.lost and frame.version >= 4
            if isinstance(frame.message, p.Hello):
                self.missing.clear()
            elif gap:
                self._note_missing(frame.seq, frame.lost, tick)
            reply = self._handle(frame)
            if reply is not None:
                out += self._encode(reply)
            if frame.version >= 4 and (gap or isinstance(frame.message, p.Heartbeat)):
                missing = self._missing_report(tick)
                if missing is not None:
                    out += self._encode(missing)
        return bytes(out)

    def _note_missing(self, seq: int, lost: int, tick: int) -> None:
        """The ``lost`` frames just before ``seq`` are missing since ``tick`` (the newest
        :data:`~device.link.protocol.MISSING_MAX` kept, PROTOCOL.md 4.10)."""
        for k in range(min(lost, p.MISSING_MAX), 0, -1):
            self.missing[(seq - k) & 0xFFFF] = tick
        while len(self.missing) > p.MISSING_MAX:
            self.missing.pop(next(iter(self.missing)))

    def _missing_report(self, tick: int) -> p.Missing | None:
        """A Missing message of what is still wanted (older than ``MISSING_TTL_MS``
        forgotten), or None."""
        for seq in [q for q, t in self.missing.items() if tick - t > self._missing_ttl]:
            del self.missing[seq]
        return p.Missing(tuple(self.missing)) if self.missing else None

    def _encode(self, msg) -> bytes:
        """A frame in the version the host last spoke."""
        data = p.encode(msg, self._tx_seq, self.host_version)
        self._tx_seq += 1
        return data

    def _handle(self, frame: p.Frame):
        msg = frame.message
        if isinstance(msg, p.Hello):
            self._flush()
            self.session = SessionCounters()
            self._origin_set = False
            self.prefill = int(min(max(msg.prefill, 1), self._cap // 4))
            self.state = S.BUFFERING
            if self._held <= self._wd_ticks:  # 5.1: the flushed stream's setpoint ramps out now
                self._begin_ramp()
            self.stopped = False
            self.hello_seen = True
            self.hellos += 1
            return self.config.info()
        if isinstance(msg, p.Heartbeat):
            if self.state == S.SILENT and not self.stopped:
                self.state = S.BUFFERING  # the host is back after a watchdog trip
            return self.status(msg.token)
        if isinstance(msg, p.Stop):
            if msg.drain and self.level:
                self.state = S.DRAINING
            else:
                if not msg.drain:  # 4.6: a drained Stop discards nothing, even when empty
                    self._count_flush()
                self._silence()
                self.stopped = True
            return self.status(0)
        if isinstance(msg, p.Resend):
            if self.missing.pop(msg.orig_seq, None) is None:
                return None  # not missing (any more): a duplicate, no effect
            return self._block(frame.seq, msg)
        if isinstance(msg, p.Block):
            return self._block(frame.seq, msg)
        return None

    def _block(self, seq: int, msg: p.Block):
        c = self.config
        if not self.hello_seen or self.stopped:
            return p.ErrorReport(p.ErrorCode.NOT_READY, seq, 0, "block before Hello")
        n, ch = msg.amplitudes.shape
        if ch != c.channels or (msg.phases is not None) != c.phases:
            return p.ErrorReport(p.ErrorCode.BAD_BLOCK, seq, ch,
                                 f"block has {ch} channels, phases={msg.phases is not None}; "
                                 f"device has {c.channels}, phases={c.phases}")
        if self.state == S.SILENT:
            self.state = S.BUFFERING
        if not self._origin_set:  # the first block of a session sets the clock's origin
            self.play_index = msg.start_index
        ahead = _signed_offset(msg.start_index, self.play_index)
        if self.level == 0 and self.state == S.BUFFERING and ahead > 0:
            self.counters.gap_samples += ahead
            self.play_index = msg.start_index
            ahead = 0
        self._origin_set = True
        amps = msg.amplitudes
        over = amps > self._top
        if over.any():  # the host must clamp; the device checks anyway
            self.counters.clamped += int(over.sum())
            amps = np.minimum(amps, self._top)
        # offsets from the play position; anything this far out is late or beyond anyway
        rel = min(max(ahead, -2 ** 40), 2 ** 40) + np.arange(n, dtype=np.int64)
        late = rel < 0
        beyond = rel >= self._cap
        keep = ~(late | beyond)
        self.counters.late_samples += int(late.sum())
        self.counters.overflow_samples += int(beyond.sum())
        slots = (self._head + rel[keep]) % self._cap
        self.level += int((~self._filled[slots]).sum())
        self._filled[slots] = True
        self._amp[slots] = amps[keep]
        if msg.phases is not None:
            self._phase[slots] = msg.phases[keep]
        if keep.any():
            self._end = max(self._end, int(rel[keep][-1]) + 1)
        if self.state == S.BUFFERING and self.level >= self.prefill:
            self.state = S.PLAYING
        if beyond.any():
            return p.ErrorReport(p.ErrorCode.OVERFLOW, seq, int(beyond.sum()),
                                 f"{int(beyond.sum())} samples beyond the buffer")
        if late.any():
            return p.ErrorReport(p.ErrorCode.LATE, seq, int(late.sum()),
                                 f"{int(late.sum())} samples arrived after their time")
        return None

    def status(self, echo: int) -> p.Status:
        """The device's current :class:`Status` (``echo``: the heartbeat token)."""
        d, k, s = self.decoder.counts, self.counters, self.session
        force = self.config.force_n
        return p.Status(echo & 0xFFFFFFFF, self.state, self.play_index, self.level,
                        k.underruns, d.discarded, d.frames_ok, d.lost_frames, k.gap_samples,
                        k.late_samples, k.overflow_samples, k.watchdog_trips, k.clamped,
                        tuple(self.plate_um) if self.config.sensor else None,
                        force, self.buffer_end, s.played, s.flushed, s.flushes)

    @property
    def buffer_end(self) -> int:
        """One past the furthest sample held (``play_index`` when empty), modulo 2**64."""
        return (self.play_index + self._end) % p.INDEX_MODULUS

    @property
    def finished(self) -> bool:
        """A Stop has completed and the output has ramped to zero."""
        return self.stopped and self.state == S.SILENT and self._ramp_pos >= self._ramp_ticks

    # ------------------------------------------------------------------ the clock
    def _flush(self):
        self._filled[:] = False
        self.level = 0
        self._end = 0

    def _count_flush(self) -> int:
        """Count a flush that discards what the host sent (trip, Stop without drain)."""
        flushed = self.level
        self.session.flushed += flushed
        self.session.flushes += 1
        return flushed

    def _silence(self):
        """Start ramping the output to zero (a ramp under way goes on); drop everything
        buffered."""
        self._flush()
        self.state = S.SILENT
        if self._held <= self._wd_ticks:
            self._begin_ramp()

    def _begin_ramp(self):
        """Start a linear ramp from the current setpoint to zero (PROTOCOL.md 5.1-5.3)."""
        self._held = self._wd_ticks + 1
        self._ramp_from = self.setpoint.copy()
        self._ramp_pos = 0

    def advance_to(self, t_s: float) -> bytes:
        """Play every tick up to (not including) tick ``floor(t_s * rate)``; returns the
        frames the device sends on its own meanwhile (version 2 and later: Flushed after a
        trip; 3 and later: ForceReports)."""
        out = bytearray()
        end = int(t_s * self.config.rate_hz)
        while self.tick < end:
            n = end - self.tick
            if self.state != S.SILENT and self._last_rx_tick is not None:
                deadline = self._last_rx_tick + self._wd_ticks
                if self.tick >= deadline:
                    self.counters.watchdog_trips += 1
                    flushed = self._count_flush()
                    self._silence()
                    if self.host_version >= 2:
                        out += self._encode(p.Flushed(p.FlushCause.WATCHDOG, self.play_index,
                                                      flushed, self.session.flushes))
                    continue
                n = min(n, deadline - self.tick)
            for report in self._run(min(n, self._cap)):
                if self.host_version >= 3:
                    out += self._encode(report)
        return bytes(out)

    def _run(self, n: int) -> list:
        """Run ``n`` ticks; returns the ForceReports they complete."""
        c = self.config
        sp = np.empty((n, c.channels))
        first, advanced, start_state = self.play_index, 0, self.state
        if self.state in (S.PLAYING, S.DRAINING):
            advanced = self._play(sp)
        if self.state == S.SILENT:
            self._ramp(sp[advanced:])
        elif self.state == S.BUFFERING:  # the tick that ran dry holds too
            self._hold(sp[advanced:])
        elif self.state == S.IDLE:
            sp[:] = self.setpoint
        self.setpoint = sp[-1].copy()
        if c.sensor or self.plate_log is not None:  # the plate model, where it is seen
            from scipy.signal import lfilter  # here: scipy.signal takes a second to import
            plate, self._zi = lfilter(self._b, self._a, sp, axis=0, zi=self._zi.T)
            self._zi = self._zi.T
            self.plate_um = plate[-1].copy()
            if self.plate_log is not None:
                ticks = np.arange(n)  # the state of each tick: a run can only end playing
                state = np.where(ticks < advanced, int(start_state), int(self.state))
                self.plate_log((self.tick + ticks) / c.rate_hz, state, sp, plate)
        reports = []
        if self.sensor is not None:
            lateral, normal = self.sensor.read(self.tick, sp)
            reports = self._windows.add(first, lateral[:advanced], normal[:advanced])
            if advanced < n:  # the play position stopped: the report being built is dropped
                self._windows.reset()
        self.tick += n
        return reports

    def _ramp(self, sp: np.ndarray) -> None:
        """Go on with the ramp to zero for ``len(sp)`` ticks into ``sp``."""
        k = self._ramp_pos + np.arange(1, len(sp) + 1)
        frac = np.clip(1.0 - k / self._ramp_ticks, 0.0, 1.0)
        sp[:] = frac[:, None] * self._ramp_from
        self._ramp_pos = min(self._ramp_pos + len(sp), self._ramp_ticks)

    def _hold(self, sp: np.ndarray) -> None:
        """``len(sp)`` BUFFERING or gap ticks into ``sp``: the setpoint held for at most
        ``watchdog_ms`` since the last sample played, then ramped to zero (5.1)."""
        n = min(max(self._wd_ticks - self._held, 0), len(sp))
        sp[:n] = self.setpoint
        self._held += n
        if n == len(sp):
            return
        if self._held == self._wd_ticks:
            self._begin_ramp()
        self._ramp(sp[n:])

    def _play_or_hold(self, sp: np.ndarray, has: np.ndarray, values: np.ndarray) -> None:
        """Setpoints into ``sp`` for ticks that advance the play index: a tick that
        ``has`` its sample plays ``values`` (um); a gap tick holds under the bound of
        5.1, so a gap as long as the watchdog begins the ramp to zero."""
        if not len(has):
            return
        edges = np.flatnonzero(has[1:] != has[:-1]) + 1
        for a, b in zip(np.r_[0, edges], np.r_[edges, len(has)]):
            if has[a]:
                sp[a:b] = values[a:b]
                self._held = 0
            else:
                self._hold(sp[a:b])
            self.setpoint = sp[b - 1].copy()

    def _play(self, sp: np.ndarray) -> int:
        """Play ticks into ``sp`` until it is full or the buffer runs dry (BUFFERING; a
        drain ends in SILENT); returns how many ticks advanced the play index (the ticks
        after them are left to the new state)."""
        n = len(sp)
        idx = np.uint64(self.play_index) + np.arange(n, dtype=np.uint64)  # wraps at 2**64
        slots = (self._head + np.arange(n)) % self._cap
        has = self._filled[slots]
        count = np.cumsum(has)
        if count[-1] >= self.level:  # the buffer runs dry inside this run
            used = int(np.argmax(count >= self.level)) + 1 if self.level else 0
        else:
            used = n
        has[used:] = False
        played = np.flatnonzero(has)
        values = p.amplitude_from_wire(self._amp[slots])
        self._play_or_hold(sp[:used], has[:used], values[:used])
        self.counters.gap_samples += used - len(played)
        self.counters.played_samples += len(played)
        self.session.played += len(played)
        if self.log is not None and len(played):
            phases = p.phase_from_wire(self._phase[slots[played]]) if self.config.phases else None
            self.log(idx[played], values[played], phases)
        self._filled[slots[:used]] = False
        self.level -= len(played)
        self.play_index = (self.play_index + used) % p.INDEX_MODULUS
        self._head = (self._head + used) % self._cap
        self._end = max(self._end - used, 0) if self.level else 0
        if used < n:
            if self.state == S.DRAINING:
                self._silence()
                self.stopped = True
            else:
                self.counters.underruns += 1
                self.state = S.BUFFERING
        return used


#: longest a played or plate log's rows wait in memory before they are written (s)
LOG_FLUSH_S = 0.25


class CsvLog:
    """Append-only CSV writer for the played-sample or plate log (see module docstring).

    Rows reach the file at most :data:`LOG_FLUSH_S` after they are written, whether or not
    more rows follow, so that a reader sees what was played while the device runs (an
    idle device included), not only once it exits: a daemon thread flushes every
    :data:`LOG_FLUSH_S` when there are rows it has not flushed. Writes, flushes and
    :meth:`close` hold one lock (the device writes from its thread, the flusher from its own).

    A write the file system refuses (a full disk, ``/dev/full``) is said once on stderr,
    naming the file, and ends the log: later rows are dropped and the device goes on (its
    watchdog and clamps do not depend on the log).
    """

    def __init__(self, path, header: list[str]):
        self._path = path
        self._fh = _open_log(path)
        self._fh.write(",".join(header) + "\n")
        self.lost = False  #: a write was refused: the log ended there
        self._lock = threading.Lock()
        self._dirty = True  # the header
        self._closing = threading.Event()
        self._flusher = threading.Thread(target=self._flush_every, name="frictex-log-flush",
                                         daemon=True)
        self._flusher.start()

    def rows(self, columns: list[np.ndarray], formats: list[str]) -> None:
        """Append one row per element of the columns (each (n,) or (n, k)), ``formats``
        one printf format per column of the table."""
        table = np.column_stack(columns)
        with self._lock:
            if self._fh.closed:
                return
            try:
                np.savetxt(self._fh, table, fmt=formats, delimiter=",")
                self._dirty = True
            except OSError as exc:
                self._lose(exc)

    def flush(self) -> None:
        """Write out the rows not yet on disk (none after :meth:`close`)."""
        with self._lock:
            if self._dirty and not self._fh.closed:
                try:
                    self._fh.flush()
                except OSError as exc:
                    self._lose(exc)
                self._dirty = False

    def _flush_every(self) -> None:
        while not self._closing.wait(LOG_FLUSH_S):
            self.flush()

    def close(self) -> None:
        """Stop the flusher, write out the last rows and close the file; idempotent."""
        self._closing.set()
        self._flusher.join(timeout=LOG_FLUSH_S + 1.0)
        with self._lock:
            try:
                self._fh.close()
            except OSError as exc:  # the last rows refused
                self._lose(exc)

    def _lose(self, exc: OSError) -> None:
        """End the log after a write the file system refused: say so, close the file (its
        buffered rows are dropped; a closed log takes no more). Called holding the lock."""
        print(f"frictex: warning: cannot write the log file {escape_path(self._path)}: "
              f"{exc.strerror or exc}; logging stopped, the simulated device goes on",
              file=sys.stderr, flush=True)
        self.lost = True
        try:
            self._fh.close()
        except OSError:  # the same refusal, for the rows still buffered
            pass


def _open_log(path):
    """``path`` made or emptied and opened for writing text; InputError naming it if it
    cannot be. A FIFO or a terminal (``/dev/stdout``) is written as a stream, a FIFO only
    once it has a reader: it is opened non-blocking, as a plain open would wait for a
    reader forever (SIGTERM or not), then made blocking so that writes wait for a slow
    reader as a file's would."""
    try:
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC | os.O_NONBLOCK, 0o666)
    except OSError as exc:
        reason = exc.strerror or exc
        if exc.errno == errno.ENXIO and _is_fifo(path):
            reason = "a FIFO with no reader; start its reader first"
        raise InputError(f"cannot write the log file {escape_path(path)}: {reason}") from None
    os.set_blocking(fd, True)
    return os.fdopen(fd, "w", encoding="ascii", newline="\n")


def _is_fifo(path) -> bool:
    try:
        return stat.S_ISFIFO(os.stat(path).st_mode)
    except OSError:
        return False


def played_log(path, channels: int, phases: bool):
    """A ``log`` callable for :class:`DeviceCore` writing ``path``; returns (callable, CsvLog)."""
    names = [f"ch{k}_um" for k in range(channels)]
    if phases:
        names += [f"ch{k}_phase_rad" for k in range(channels)]
    csv = CsvLog(path, ["index", *names])
    fmts = ["%d"] + ["%.9f"] * len(names)

    def write(index, values, phase_values):
        cols = [index, values] + ([phase_values] if phase_values is not None else [])
        csv.rows(cols, fmts)
    return write, csv


def plate_log_growth(channels: int, rate_hz: float) -> tuple[float, float]:
    """How fast a plate log grows: (rows a second, MB an hour). It writes one row per
    tick, host or no host. A row is ``t_s`` (12 bytes with its comma from 1000 s on), the
    state (2) and 24 bytes per channel: 38 bytes for one channel (measured: 126 MB in
    the first 6 minutes at 10 kHz, 35 bytes a row while ``t_s`` is shorter)."""
    return rate_hz, rate_hz * 3600.0 * (14 + 24 * channels) / 1e6


def plate_log(path, channels: int):
    """A ``plate_log`` callable for :class:`DeviceCore`; returns (callable, CsvLog)."""
    csv = CsvLog(path, ["t_s", "state", *[f"ch{k}_setpoint_um" for k in range(channels)],
                        *[f"ch{k}_plate_um" for k in range(channels)]])
    fmts = ["%.6f", "%d"] + ["%.9f"] * (2 * channels)

    def write(t, state, setpoint, plate):
        csv.rows([t, np.full(len(t), state), setpoint, plate], fmts)
    return write, csv


def open_pty() -> tuple[int, int, str]:
    """A raw pseudo-terminal: (master fd, slave fd, slave path)."""
    master, slave = os.openpty()
    tty.setraw(slave)
    os.set_blocking(master, False)
    return master, slave, os.ttyname(slave)


def open_listener(host: str = "127.0.0.1", port: int = 0) -> socket.socket:
    """A listening TCP socket (``port`` 0: any free port) on ``host``, a name or an IPv4
    or IPv6 address (``::1``, without brackets); its URL is :func:`socket_url`. Raises
    InputError for a host that is no address of this machine, DeviceError when the
    address cannot be taken (in use, not allowed)."""
    where = host_port(host, port)
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    try:
        listener = socket.create_server((host, port), family=family)
    except OSError as exc:  # create_server re-raises getaddrinfo's errors (errno < 0) too
        why = str(exc.strerror or exc).split(" (while attempting")[0]
        if exc.errno is not None and (exc.errno < 0 or exc.errno == errno.EADDRNOTAVAIL):
            raise InputError(f"cannot listen on {where!r}: {why} (expected an address of "
                             "this machine, such as 127.0.0.1)") from None
        raise DeviceError(f"cannot listen on {where!r}: {why}") from None
    listener.setblocking(False)
    return listener


def host_port(host: str, port: int) -> str:
    """``HOST:PORT``, an IPv6 address in brackets (``[::1]:5000``) as URLs write it."""
    return f"[{host}]:{port}" if ":" in host else f"{host}:{port}"


def socket_url(listener: socket.socket) -> str:
    """The pyserial URL a host opens to reach ``listener``."""
    return "socket://" + host_port(*listener.getsockname()[:2])


def _read(conn) -> bytes | None:
    """What a host sent; b"" if nothing, None if it hung up (a TCP peer closed)."""
    try:
        if isinstance(conn, socket.socket):
            return conn.recv(65536) or None
        return os.read(conn, 65536)
    except (BlockingIOError, InterruptedError):
        return b""
    except ConnectionError:
        return None
    except OSError:
        return b""  # a pty with no host on its slave side: EIO until one opens it


def _write(conn, data: bytes) -> None:
    """Send, dropping what does not fit (a UART does not wait either)."""
    try:
        if isinstance(conn, socket.socket):
            conn.send(data)
        else:
            os.write(conn, data)
    except OSError:
        pass


#: what a second TCP host is told before its connection is closed
BUSY_TEXT = "busy: serving another host; one host at a time"
#: a TCP host must say Hello within this long of connecting (s), else it is dropped: an
#: idle connection would otherwise hold the device and every other host be refused busy
HELLO_TIMEOUT_S = 2.0
#: a TCP host that has said Hello is dropped after this long without a valid frame (s),
#: so that a host gone quiet cannot hold the device either: a connected host heartbeats
#: every watchdog_ms / 5 (10 ms at most) even with nothing to send, and a host that hears
#: nothing says Hello again after 0.5 s and reconnects within 1 s (PROTOCOL.md 6.2); the
#: watchdog has stopped the plate 25-50 ms into the silence
SILENT_HOST_S = 5.0
#: refusals are reported at most once per this long (s), with their count
REFUSAL_REPORT_S = 1.0


def _refuse(sock: socket.socket) -> None:
    """Tell a second host the device is busy (an ErrorReport it can decode), close it."""
    try:
        sock.settimeout(0.1)
        sock.sendall(b"\x00" + p.encode(p.ErrorReport(p.ErrorCode.NOT_READY, 0, 0, BUSY_TEXT),
                                         0, 1))
    except OSError:
        pass
    finally:
        sock.close()


def _say_silent(address, silent_s: float) -> None:
    """The line on stderr for a host dropped ``silent_s`` seconds after its last valid frame."""
    print(f"frictex sim-device: dropped host {address[0]}:{address[1]}: no valid frame for "
          f"{silent_s:.1f} s after its Hello; the next host can connect", file=sys.stderr)


def serve(core: DeviceCore, master: int | None = None, listener: socket.socket | None = None,
          *, poll_s: float = 0.001, exit_on_stop: bool = False, parent_pid: int | None = None,
          quit_event=None, clock=time.monotonic, on_refused=None, on_dropped=None,
          hello_timeout_s: float = HELLO_TIMEOUT_S, on_silent=_say_silent,
          silent_host_s: float = SILENT_HOST_S) -> int:
    """Run ``core`` in real time on the pty ``master`` or on TCP connections to
    ``listener``, one host at a time, until ``quit_event`` is set, ``parent_pid`` is gone,
    or (``exit_on_stop``) a host's Stop has played out. Returns the number of TCP hosts
    served.

    One host at a time: a TCP connection made while a host is connected is refused, never
    allowed to take over: it gets one ErrorReport (``NOT_READY``, :data:`BUSY_TEXT`, in a
    version 1 frame that every host decodes) and is closed; ``on_refused(address, count)``
    is told at most once per :data:`REFUSAL_REPORT_S` (the latest address, and how many
    were refused since the last call; the rest when serving ends), so a flood of
    connections makes a line a second, not one each. A TCP host that has not said Hello
    within ``hello_timeout_s`` of connecting is dropped (closed; ``on_dropped(address)``
    told): a connection that never speaks cannot hold the device. A TCP host that said
    Hello and then sent no valid frame for ``silent_host_s`` (:data:`SILENT_HOST_S`, 5 s)
    is dropped too (``on_silent(address, seconds silent)`` told; by default one line on
    stderr): a host that goes quiet cannot hold it either, while a connected host, idle or
    not, heartbeats every ``watchdog_ms / 5``. The next host is
    served once the current one has hung up or been dropped (its socket closed: a host
    process that ends, however it ends, closes it). Received bytes are handled before
    the clock advances,
    so a sim process that was descheduled does not mistake its own sleep for host silence.
    """
    t0 = clock()
    hosts = _Hosts(core, master, listener, on_refused, on_dropped, hello_timeout_s, on_silent,
                   silent_host_s)
    try:
        while True:
            ready = hosts.wait(poll_s)
            now = clock() - t0
            if listener is not None and listener in ready:
                hosts.accept(now)
            hosts.report_refusals(now)
            out = hosts.receive(ready, now)
            hosts.drop_silent(now)
            hosts.send(out + core.advance_to(now))
            if _should_stop(core, exit_on_stop, quit_event, parent_pid):
                return hosts.served
    finally:
        hosts.close()


def _should_stop(core: DeviceCore, exit_on_stop: bool, quit_event, parent_pid: int | None) -> bool:
    """Whether :func:`serve` ends now: (``exit_on_stop``) a Stop has played out,
    ``quit_event`` is set, or the process ``parent_pid`` is gone (said on stderr)."""
    if (exit_on_stop and core.finished) or (quit_event is not None and quit_event.is_set()):
        return True
    if parent_pid is not None and os.getppid() != parent_pid:
        print("frictex sim-device: parent process gone; stopping", file=sys.stderr)
        return True
    return False


class _Hosts:
    """:func:`serve`'s hosts: the one connected (the pty master, or a TCP socket from
    ``listener``), when it connected and how many Hellos the core had then, when its last
    valid frame came, how many TCP hosts were served, and the refusals of second hosts not
    yet reported."""

    def __init__(self, core: DeviceCore, master: int | None, listener: socket.socket | None,
                 on_refused, on_dropped, hello_timeout_s: float, on_silent,
                 silent_host_s: float) -> None:
        self.core = core
        self.conn = master
        self.listener = listener
        self.on_refused = on_refused
        self.on_dropped = on_dropped
        self.hello_timeout_s = hello_timeout_s
        self.on_silent = on_silent
        self.silent_host_s = silent_host_s
        self.served = 0
        self.address = None  # the TCP host's, with the time it connected and core.hellos then
        self.connected_at = self.hellos_then = 0
        self.heard_at = self.frames_then = 0  # time of its last valid frame, frames_ok then
        self.refused, self.refused_from, self.reported_at = 0, None, -math.inf

    def wait(self, poll_s: float) -> list:
        """The connection and listener ready to read within ``poll_s`` (s)."""
        watch = [x for x in (self.conn, self.listener) if x is not None]
        ready, _, _ = select.select(watch, [], [], poll_s)
        return ready

    def accept(self, now: float) -> None:
        """Take a TCP connection waiting on the listener at ``now`` (s): served if no TCP
        host is connected, else refused busy."""
        try:
            accepted, peer = self.listener.accept()
        except (BlockingIOError, InterruptedError):
            return
        if isinstance(self.conn, socket.socket):
            _refuse(accepted)
            self.refused, self.refused_from = self.refused + 1, peer
            return
        accepted.setblocking(False)
        accepted.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.core.new_connection()
        self.conn, self.served, self.address = accepted, self.served + 1, peer
        self.connected_at, self.hellos_then = now, self.core.hellos
        self.heard_at, self.frames_then = now, self.core.decoder.counts.frames_ok

    def report_refusals(self, now: float) -> None:
        """Tell ``on_refused`` of the refusals since its last call, at most once per
        :data:`REFUSAL_REPORT_S`."""
        if self.refused and self.on_refused is not None and now - self.reported_at >= REFUSAL_REPORT_S:
            self.on_refused(self.refused_from, self.refused)
            self.refused, self.reported_at = 0, now

    def receive(self, ready: list, now: float) -> bytes:
        """The core's answer to what the host sent, if it is ``ready``; a host that hung up
        is closed."""
        if self.conn is None or self.conn not in ready:
            return b""
        data = _read(self.conn)
        if data is None:
            self.conn.close()
            self.conn = None
            return b""
        return self.core.receive(data, now) if data else b""

    def drop_silent(self, now: float) -> None:
        """Close a TCP host that has not said Hello within ``hello_timeout_s`` of
        connecting (telling ``on_dropped``), or that said it and then sent no valid frame
        for ``silent_host_s`` (telling ``on_silent``); ``now`` in s."""
        if not isinstance(self.conn, socket.socket):
            return
        frames = self.core.decoder.counts.frames_ok
        if frames != self.frames_then:
            self.heard_at, self.frames_then = now, frames
        if self.core.hellos == self.hellos_then:
            if now - self.connected_at > self.hello_timeout_s:
                self._hang_up(self.on_dropped, self.address)
        elif now - self.heard_at > self.silent_host_s:
            self._hang_up(self.on_silent, self.address, now - self.heard_at)

    def _hang_up(self, tell, *what) -> None:
        """Close the TCP host's connection and tell ``tell(*what)``, if given."""
        self.conn.close()
        self.conn = None
        if tell is not None:
            tell(*what)

    def send(self, out: bytes) -> None:
        """Write ``out`` to the connected host, if any."""
        if out and self.conn is not None:
            _write(self.conn, out)

    def close(self) -> None:
        """Close a TCP host still connected; report the refusals not yet reported."""
        if isinstance(self.conn, socket.socket):
            self.conn.close()
        if self.refused and self.on_refused is not None:
            self.on_refused(self.refused_from, self.refused)

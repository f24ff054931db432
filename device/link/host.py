"""The host side of the link to the plate's microcontroller (protocol: ``device/PROTOCOL.md``).

    sink = open_sink("sim", channels=1, rate_hz=10_000.0, paced=True, log_path="played.csv")
    sink.wait_for_room(0.5)                        # device-paced clock: True when send won't wait
    sink.send(start_index, amplitudes_um, None)   # (n, channels) um, per block
    sink.status()                                  # JSON-able counters
    sink.unplayed_share()                          # commanded samples that never played
    sink.force_report()                            # latest lateral/normal force, or None
    sink.close()                                   # drains, sends Stop; the sim exits

One thread owns the port (pyserial: a device path, ``COM3``, ``socket://``, ``loop://``...);
callers hand blocks over through a bounded queue. ``paced=True`` (replay): the thread
sends a block only when the device's buffer has room, so the device's clock paces the
run, and ``send`` waits for a free queue slot. ``paced=False`` (live): ``send`` never
waits; a full queue drops the block (counted). Every amplitude is clamped to the limit the
device declared (counted). The thread heartbeats every ``watchdog_ms / 5`` and reads each
Status against how far it had sent when the heartbeat left (``device.link.ledger``), so
its estimate of the device's buffer is re-based on every answer: after a watchdog trip,
a lost block or a reconnect the host never waits for samples the device no longer has.
A version 3 device with a lateral force sensor streams ForceReports; the host keeps the
last second of them by sample number (:meth:`CommandSink.force_report`).

Every wait is bounded. The thread re-handshakes when the device says nothing valid for
``SILENCE_S`` or takes no block for that long; if the port fails (USB unplugged) it says
so once on stderr and reopens the port until it returns (live: queued blocks are dropped
and counted; paced: they wait, within the stall bound, and go out after). A caller's
wait (``send`` paced, ``wait_for_room``, ``close``) longer than ``stall_s`` is a *stall*:
a warning on stderr, the block dropped (counted), the stream going on; ``max_stalls``
stalls in a row with nothing sent between them raise :class:`LinkStalled`, and so does
every later call.
"""

from __future__ import annotations

import collections
import os
import select
import socket
import struct
import subprocess
import sys
import threading
import time
from dataclasses import asdict

import numpy as np
import serial
from serial.urlhandler import protocol_socket

try:
    import fcntl
    import termios
except ImportError:  # Windows: in_waiting stays pyserial's (0 or 1)
    fcntl = termios = None

from frictex.device.link import protocol as p
from frictex.device.link.forces import ForceHistory, ForceReport, per_sample
from frictex.device.link.ledger import Ledger, Pacing, Snapshot
from frictex.device.link.protocol import DeviceState, LinkError

#: jitter-buffer prefill asked of the device, and the level paced sending keeps (s)
PREFILL_S = 0.010
TARGET_S = 0.020
HANDSHAKE_TIMEOUT_S = 1.0
HANDSHAKE_RETRY_S = 0.1
RECONNECT_PERIOD_S = 0.25
#: longest the thread waits for a byte before doing its other work (s)
READ_WAIT_S = 0.002
#: a connected device that sends nothing valid, or takes no block while blocks wait, for
#: this long is handshaken again (s)
SILENCE_S = 0.5
#: a gap this long between two turns of the link thread means the host was starved (s)
STARVED_S = 0.1
#: default bound of one caller's wait on the device (s), and stalls in a row before
#: LinkStalled
STALL_S = 1.0
MAX_STALLS = 5
#: beyond the drain itself, how long close() waits for a Stop to play out (s)
STOP_MARGIN_S = 0.5


_COUNTS = ("frames_sent", "blocks_sent", "heartbeats", "retries", "reconnects", "disconnects",
           "recoveries", "stalls", "device_flushes", "clamped_samples", "dropped_blocks",
           "force_reports")


class LinkStalled(LinkError):
    """The device took nothing through ``max_stalls`` bounded waits in a row."""


class _TcpPort(protocol_socket.Serial):
    """pyserial's ``socket://`` port with TCP_NODELAY (without it small frames wait for
    the peer's delayed ACK, tens of ms, longer than the device's watchdog), and an
    ``in_waiting`` that counts the bytes waiting (pyserial's says 0 or 1, so draining
    ``in_waiting`` bytes would read one byte per call and fall behind the device)."""

    def open(self):
        super().open()
        self._socket.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)

    @property
    def in_waiting(self) -> int:
        if fcntl is None or not self.is_open:
            return super().in_waiting
        return struct.unpack("i", fcntl.ioctl(self._socket, termios.FIONREAD, b"\0" * 4))[0]


def open_port(spec: str):
    """Open a pyserial port or URL, reads waiting at most ``READ_WAIT_S``; raises
    :class:`LinkError`. ``socket://`` URLs get a :class:`_TcpPort`."""
    options = {"baudrate": 921_600, "timeout": READ_WAIT_S, "write_timeout": 0.5}
    try:
        if spec.startswith("socket://"):
            port = _TcpPort(None, **options)
            port.port = spec
            port.open()
        else:
            port = serial.serial_for_url(spec, **options)
    except (serial.SerialException, ValueError, OSError) as exc:
        raise LinkError(f"cannot open device port {spec!r}: {exc}") from None
    return port


class CommandSink:
    """A connected device link; see the module docstring. Use :func:`open_sink`.

    ``stall_s``: bound of one caller's wait (s); ``max_stalls``: stalls in a row before
    :class:`LinkStalled`.
    """

    def __init__(self, opener, channels: int, rate_hz: float, *, phases: bool = False,
                 paced: bool = False, queue_blocks: int = 64, label: str = "device",
                 process: subprocess.Popen | None = None, stderr=sys.stderr,
                 stall_s: float = STALL_S, max_stalls: int = MAX_STALLS):
        if channels < 1:
            raise ValueError(f"channels = {channels!r}: expected at least 1")
        if not (rate_hz > 0 and np.isfinite(rate_hz)):
            raise ValueError(f"rate_hz = {rate_hz!r}: expected a positive number")
        if not (stall_s > 0 and np.isfinite(stall_s)) or max_stalls < 1:
            raise ValueError(f"stall_s = {stall_s!r}, max_stalls = {max_stalls!r}: expected a "
                             "positive time and at least 1")
        self._opener = opener
        self.channels = int(channels)
        self.rate_hz = float(rate_hz)
        self.phases = bool(phases)
        self.paced = bool(paced)
        self.label = label
        self.stall_s = float(stall_s)
        self.max_stalls = int(max_stalls)
        self._process = process
        self._stderr = stderr
        self._capacity = int(queue_blocks)
        self._queue: collections.deque = collections.deque()
        self._cond = threading.Condition()
        self._closing = threading.Event()
        self._closed = False
        self._connected = False
        self._failure: LinkStalled | None = None
        self._stalls_in_row = 0
        # every key up front: status() copies these while the thread counts
        self._counts = collections.Counter(dict.fromkeys(_COUNTS, 0))
        self._errors = collections.Counter(dict.fromkeys([*p.ErrorCode.NAMES.values(), "other"], 0))
        self._ledger = Ledger()
        self._rtt_ms: collections.deque = collections.deque(maxlen=4096)
        self._marks: dict[int, tuple[float, int, int]] = {}   # token -> (t, sent_end, mark)
        self._token = 0
        self._seq = 0
        self._decoder = p.Decoder()
        self._status: p.Status | None = None
        self._forces = ForceHistory()
        self._forces_lock = threading.Lock()
        self._snapshot: Snapshot | None = None
        self._sent_end = 0            # host index after the last sample sent
        self._last_rx = self._last_progress = time.monotonic()
        self.version = 1
        self.last_error: str | None = None
        self.info: p.Info | None = None
        self._port = None
        self._connect()               # first connection: failures are the caller's error
        self._thread = threading.Thread(target=self._run, name=f"frictex-link-{label}",
                                        daemon=True)
        self._thread.start()

    # ------------------------------------------------------------------ connection
    def _connect(self) -> None:
        port = self._opener()
        try:
            self._start_session(self._handshake(port))
        except BaseException:
            port.close()
            raise
        self._port = port

    def _start_session(self, info: p.Info) -> None:
        self._check(info)
        self.info = info
        self.version = min(info.protocol_version, p.PROTOCOL_VERSION)
        self._limits = np.asarray(info.limits_um[:self.channels], dtype=np.float64)
        prefill = max(1, min(int(PREFILL_S * info.sample_rate_hz), info.buffer_samples // 4))
        self._target = max(prefill + 1,
                           min(int(TARGET_S * info.sample_rate_hz), info.buffer_samples // 2))
        self._pacing = Pacing(info.sample_rate_hz, self._target, prefill,
                              info.buffer_samples // 2)
        self._heartbeat_s = max(info.watchdog_ms / 5.0, 1.0) * 1e-3
        self._marks.clear()
        self._last_rx = self._last_progress = time.monotonic()
        if not info.has_force_reports:
            with self._forces_lock:
                self._forces = ForceHistory()
        with self._cond:
            self._snapshot = None
            self._ledger.start_session()
            self._connected = True
            self._cond.notify_all()

    def _handshake(self, port) -> p.Info:
        """Send Hello (in a version 1 frame: every device answers it) until Info comes
        back; the device flushes its buffer and restarts its counters on Hello.

        If a session is open (a recovery or a reconnect), a Heartbeat goes out just before
        the Hello, in the same write (again with each resent Hello until it is answered):
        the Status answering it (read here, before the Info) settles the session with the
        device's counters as of the Hello (PROTOCOL.md 6.1).
        """
        decoder = p.Decoder()
        deadline = time.monotonic() + HANDSHAKE_TIMEOUT_S
        settling = None  # token of that Heartbeat; _handle pops it from _marks when answered
        tries = 0
        while time.monotonic() < deadline:
            if tries:
                self._counts["retries"] += 1
            tries += 1
            settle = b""
            if self._ledger.reporting and (settling is None or settling in self._marks):
                settle = self._heartbeat()
                settling = self._token
            # a leading delimiter ends whatever partial frame the device was holding
            port.write(b"\x00" + settle
                       + self._frame(p.Hello(int(PREFILL_S * self.rate_hz)), 1))
            until = min(deadline, time.monotonic() + HANDSHAKE_RETRY_S)
            while time.monotonic() < until:
                for frame in decoder.feed(self._read(port)):
                    if isinstance(frame.message, p.Info):
                        self._decoder = decoder
                        return frame.message
                    if isinstance(frame.message, (p.ErrorReport, p.Status)):
                        self._handle(frame.message)
        bad = decoder.counts.last_bad_version
        if bad is not None:
            raise LinkError(f"{self.label}: device speaks protocol version {bad}; this host "
                            f"speaks 1 to {p.PROTOCOL_VERSION}")
        raise LinkError(f"{self.label}: no answer to the handshake within "
                        f"{HANDSHAKE_TIMEOUT_S:g} s ({tries} tries); is it a frictex device?")

    def _check(self, info: p.Info) -> None:
        problems = []
        if info.channels < self.channels:
            problems.append(f"{info.channels} channel(s), the pipeline needs {self.channels}")
        if self.phases and not info.has_phases:
            problems.append("no phase control, the actuation has phases")
        if abs(info.sample_rate_hz - self.rate_hz) > 1e-3:
            problems.append(f"sample rate {info.sample_rate_hz:g} Hz, the pipeline runs at "
                            f"{self.rate_hz:g} Hz")
        if problems:
            raise LinkError(f"{self.label} ({info.name or 'unnamed'}) has "
                            + "; ".join(problems))

    @staticmethod
    def _read(port) -> bytes:
        """What has arrived, waiting at most the port's timeout for the first byte."""
        data = port.read(1)
        waiting = port.in_waiting if data else 0
        return data + port.read(waiting) if waiting else data

    def _frame(self, msg, version: int | None = None) -> bytes:
        data = p.encode(msg, self._seq, self.version if version is None else version)
        self._seq = (self._seq + 1) & 0xFFFF
        self._counts["frames_sent"] += 1
        return data

    def _heartbeat(self) -> bytes:
        """A Heartbeat frame, its token remembered with how far the host had sent."""
        self._token = self._token % 0xFFFFFFFF + 1   # never 0: a Stop's Status echoes 0
        self._counts["heartbeats"] += 1
        self._marks[self._token] = (time.monotonic(), self._sent_end, self._ledger.mark())
        if len(self._marks) > 64:
            self._marks.pop(next(iter(self._marks)))
        return self._frame(p.Heartbeat(self._token))

    def _warn(self, text: str) -> None:
        print(f"frictex: warning: {self.label}: {text}", file=self._stderr)

    def _lost(self, exc: BaseException) -> None:
        self.last_error = f"{type(exc).__name__}: {exc}"
        try:
            self._port.close()
        except Exception:  # noqa: BLE001 -- the port is already gone; nothing to save
            pass
        self._port = None
        self._counts["disconnects"] += 1
        with self._cond:  # the session is settled by the next handshake, or by close
            self._connected = False
            if not self.paced:  # live blocks go stale; paced ones go out on reconnecting
                self._drop_queued("disconnected")
        self._warn(f"link lost ({self.last_error}); output continues without it, reconnecting")

    def _drop_queued(self, cause: str) -> None:
        """Drop every queued block (counted); the caller holds ``_cond``."""
        while self._queue:
            _, counts, _ = self._queue.popleft()
            self._counts["dropped_blocks"] += 1
            self._ledger.drop(cause, len(counts))
        self._cond.notify_all()

    def _resync(self, reason: str) -> None:
        """Handshake again on the same port (the device restarts its buffer)."""
        self._counts["recoveries"] += 1
        self._warn(f"{reason}; handshaking again")
        try:
            self._start_session(self._handshake(self._port))
        except (LinkError, OSError, serial.SerialException) as exc:
            self._lost(exc)

    # ------------------------------------------------------------------ the thread
    def _run(self) -> None:
        try:
            self._loop()
            self._finish()
        except Exception as exc:  # noqa: BLE001 -- a dead thread must not hang the caller
            self._fail(LinkStalled(f"{self.label}: link thread failed: "
                                   f"{type(exc).__name__}: {exc}"))
        finally:
            port, self._port = self._port, None
            if port is not None:
                port.close()
            with self._cond:
                self._connected = False
                self._cond.notify_all()

    def _loop(self) -> None:
        next_hb = next_try = 0.0
        last = time.monotonic()
        while not self._closing.is_set():
            now = time.monotonic()
            if now - last > STARVED_S:  # this thread did not run: not the device's silence
                self._last_rx = self._last_progress = now
            last = now
            if self._port is None:
                if now >= next_try:
                    next_try = now + RECONNECT_PERIOD_S
                    try:
                        self._connect()
                        self._counts["reconnects"] += 1
                        print(f"frictex: {self.label} link back", file=self._stderr)
                    except (LinkError, OSError, serial.SerialException):
                        pass
                self._closing.wait(0.005)
                continue
            try:
                self._service(now >= next_hb)
                if now >= next_hb:
                    next_hb = now + self._heartbeat_s
                self._watch(time.monotonic())
            except (OSError, serial.SerialException) as exc:
                self._lost(exc)

    def _watch(self, now: float) -> None:
        """Re-handshake a device that went quiet or stopped taking blocks."""
        if now - self._last_rx > SILENCE_S:
            self._resync(f"no valid frame from the device for {now - self._last_rx:.2f} s")
        elif self._queue and now - self._last_progress > SILENCE_S:
            snap, start = self._snapshot, self._queue[0][0]
            where = ("no Status yet" if snap is None else
                     f"device at {snap.play_index}, holding {snap.held} up to {snap.end}, "
                     f"{'playing' if snap.playing else 'waiting'}; next block {start}")
            self._resync(f"device took no block for {now - self._last_progress:.2f} s "
                         f"({where})")

    def _service(self, heartbeat: bool) -> None:
        port = self._port
        data = self._read(port)
        for frame in self._decoder.feed(data):
            self._handle(frame.message)
        out = bytearray(self._heartbeat() if heartbeat else b"")
        sent = 0
        with self._cond:
            # blocks wait for the session's first Status: it is the counters' baseline
            while self._queue and len(out) < 4096 and self._ledger.reporting:
                start, counts, phases = self._queue[0]
                if self.paced and not self._snapshot.room(
                        self._pacing, time.monotonic(), self._sent_end, self._ledger.mark(),
                        start, len(counts)):
                    break
                self._queue.popleft()
                out += self._frame(p.Block(start % p.INDEX_MODULUS, counts, phases))
                self._counts["blocks_sent"] += 1
                self._ledger.sent(len(counts))
                self._sent_end = max(self._sent_end, start + len(counts))
                sent += 1
            if sent:
                self._stalls_in_row = 0
                self._cond.notify_all()
        if not self._queue or sent:
            self._last_progress = time.monotonic()
        if out:
            port.write(bytes(out))

    def _handle(self, msg) -> None:
        now = time.monotonic()
        self._last_rx = now
        if isinstance(msg, p.Status):
            self._status = msg
            mark = self._marks.pop(msg.echo, None)
            if mark is not None:
                sent_t, sent_end, ledger_mark = mark
                self._rtt_ms.append((now - sent_t) * 1e3)
                with self._cond:
                    self._snapshot = Snapshot.from_status(msg, 0.5 * (now + sent_t), sent_end,
                                                          ledger_mark)
                    self._ledger.status(msg, ledger_mark)
        elif isinstance(msg, p.Flushed):
            self._counts["device_flushes"] += 1
            with self._cond:
                self._snapshot = Snapshot.flushed(msg.play_index, now, self._sent_end,
                                                  self._ledger.mark())
        elif isinstance(msg, p.ForceReport):
            if self.info is not None and self.info.has_force_reports:
                self._counts["force_reports"] += 1
                report = per_sample(msg, self._sent_end)
                with self._forces_lock:
                    self._forces.add(report)
        elif isinstance(msg, p.ErrorReport):
            self._errors[p.ErrorCode.NAMES.get(msg.code, "other")] += 1

    def _finish(self) -> None:
        """Closing: send what a live queue still holds (a paced one was drained or given
        up by ``close``), Stop with drain, heartbeat until the device reports silence
        (bounded), so the last Status settles the ledger."""
        port = self._port
        if port is None:
            with self._cond:
                self._drop_queued("disconnected")
                self._ledger.end_session()
            return
        try:
            with self._cond:
                out = bytearray()
                while self._queue and self._ledger.reporting and not self.paced:
                    start, counts, phases = self._queue.popleft()
                    out += self._frame(p.Block(start % p.INDEX_MODULUS, counts, phases))
                    self._counts["blocks_sent"] += 1
                    self._ledger.sent(len(counts))
                    self._sent_end = max(self._sent_end, start + len(counts))
                self._drop_queued("stalled")
            port.write(bytes(out) + self._frame(p.Stop(drain=True)))
            first_after_stop = self._token + 1
            deadline = time.monotonic() + self._drain_s()
            while time.monotonic() < deadline:
                port.write(self._heartbeat())
                until = time.monotonic() + self._heartbeat_s
                while time.monotonic() < until:
                    for frame in self._decoder.feed(self._read(port)):
                        self._handle(frame.message)
                st = self._status
                if (st is not None and st.state == DeviceState.SILENT
                        and st.echo >= first_after_stop):
                    break
        except (OSError, serial.SerialException) as exc:
            self.last_error = f"{type(exc).__name__}: {exc}"
        with self._cond:
            self._ledger.end_session()

    def _drain_s(self) -> float:
        """Time for a drained Stop to play out: what may be buffered, the ramp, a margin."""
        buffered = (self._sent_end - (self._snapshot.play_index if self._snapshot else 0))
        buffered = min(max(buffered, 0), self.info.buffer_samples)
        return buffered / self.rate_hz + self.info.ramp_ms * 1e-3 + STOP_MARGIN_S

    # ------------------------------------------------------------------ the caller's side
    def send(self, start_index: int, amplitudes_um: np.ndarray,
             phases_rad: np.ndarray | None = None) -> None:
        """Queue one block: (n, channels) amplitudes (um) from sample ``start_index`` on.

        Clamps to the device's limits (counted). Paced: waits for a queue slot, at most
        ``stall_s`` (then drops the block: a stall). Live: never waits; a full queue
        drops the block (counted). Disconnected: live drops at once, paced waits for the
        link to come back (at most ``stall_s``). Raises :class:`LinkStalled` after
        ``max_stalls`` stalls in a row.
        """
        a = np.asarray(amplitudes_um, dtype=np.float64)
        if a.ndim != 2 or a.shape[1] != self.channels:
            raise ValueError(f"amplitudes shape {a.shape}: expected (n, {self.channels})")
        if self.phases != (phases_rad is not None):
            raise ValueError(f"phases {'missing' if self.phases else 'given'}: this link was "
                             f"opened with phases={self.phases}")
        start_index = int(start_index)
        if start_index < 0:
            raise ValueError(f"start_index = {start_index}: expected a sample number >= 0")
        counts, clamped = p.amplitude_to_wire(a, self._limits)
        wire_phases = None if phases_rad is None else p.phase_to_wire(phases_rad)
        if wire_phases is not None and wire_phases.shape != counts.shape:
            raise ValueError(f"phases shape {wire_phases.shape}: expected {counts.shape}")
        with self._cond:
            if self._failure is not None:
                raise self._failure
            if self._closing.is_set():
                raise LinkError(f"{self.label}: send after close")
            self._counts["clamped_samples"] += clamped
            self._ledger.command(len(counts))
        step = p.max_block_samples(self.channels, self.phases)
        for lo in range(0, len(counts), step):
            self._put((start_index + lo, counts[lo:lo + step],
                       None if wire_phases is None else wire_phases[lo:lo + step]))

    def _has_room(self) -> bool:
        return self._connected and len(self._queue) < self._capacity

    def _put(self, item) -> None:
        n = len(item[1])
        with self._cond:
            if not self.paced:
                if self._has_room():
                    self._queue.append(item)
                else:
                    self._counts["dropped_blocks"] += 1
                    self._ledger.drop("queue_full" if self._connected else "disconnected", n)
                return
            if self._wait_room(self.stall_s):
                self._queue.append(item)
                return
            self._counts["dropped_blocks"] += 1
            self._ledger.drop("stalled" if self._connected else "disconnected", n)
            self._stall(self.stall_s, f"dropped a block of {n} samples")

    def _wait_room(self, timeout_s: float) -> bool:
        """Wait (holding ``_cond``) until a block can be queued; False after ``timeout_s``."""
        deadline = time.monotonic() + timeout_s
        while not self._has_room():
            if self._failure is not None:
                raise self._failure
            left = deadline - time.monotonic()
            if left <= 0 or not self._thread.is_alive():
                return False
            self._cond.wait(left)
        return True

    def _stall(self, waited_s: float, what: str) -> None:
        """Count a stall of ``waited_s`` (the caller holds ``_cond``); raise after too
        many in a row."""
        self._counts["stalls"] += 1
        self._stalls_in_row += 1
        why = "no device" if not self._connected else "device took no blocks"
        if self._stalls_in_row >= self.max_stalls:
            self._failure = LinkStalled(
                f"{self.label}: {why} through {self._stalls_in_row} bounded waits in a row "
                f"(the last {waited_s:g} s); giving up ({self._ledger.unplayed} of "
                f"{self._ledger.commanded} samples unplayed)")
            raise self._failure
        self._warn(f"{why} for {waited_s:g} s; {what}, stream goes on (stall "
                   f"{self._stalls_in_row} of {self.max_stalls} in a row)")

    def _fail(self, failure: LinkStalled) -> None:
        with self._cond:
            self._failure = failure
            self._cond.notify_all()
        print(f"frictex: error: {failure}", file=self._stderr)

    def wait_for_room(self, timeout_s: float) -> bool:
        """Block at most ``timeout_s`` until ``send`` of one more block would not wait.

        True when it would; False on timeout, counted as a stall. Raises
        :class:`LinkStalled` after ``max_stalls`` stalls in a row (and ever after).
        In live mode ``send`` never waits, so this returns True at once.
        """
        with self._cond:
            if self._failure is not None:
                raise self._failure
            if not self.paced or self._wait_room(timeout_s):
                return True
            self._stall(timeout_s, "no room for a block")
            return False

    def device_force_n(self) -> float | None:
        """The normal force (N) the device's force sensors last reported, or None if it
        has none (or has not reported yet). Cheap: the haptic thread asks every block."""
        st = self._status
        if self.info is None or not self.info.has_force or st is None:
            return None
        return st.force_n

    def force_report(self, index0: int | None = None, n: int | None = None
                     ) -> ForceReport | None:
        """Lateral and normal force (N) per output sample, from the device's ForceReports
        (PROTOCOL.md 4.9), as the closed loop reads them (``index0``, ``lateral_n`` (m,),
        ``normal_n`` (m,)).

        Without arguments: the latest report the device sent (m = its decimation times
        its values; 40 samples from the reference device). With ``index0`` and ``n``: the
        forces over exactly samples ``index0 .. index0 + n - 1`` if the reports of the
        last second cover all of them, else None. None as well when the device announces
        no lateral force sensor (a version 1 or 2 device, or Info flags bit 3 clear) or
        has sent no report yet. Cheap and never blocks on the link: the haptic thread may
        ask every block.
        """
        with self._forces_lock:
            if index0 is None:
                return self._forces.latest()
            return self._forces.window(int(index0), int(n))

    def forces_covered(self, index0: int, n: int) -> tuple[np.ndarray, np.ndarray]:
        """(lateral, normal) forces (N) of those of samples ``index0 .. index0 + n - 1``
        the reports of the last second cover, in sample order (``ForceHistory.covered``:
        a device drops a report when it underruns); empty arrays if none. Never blocks."""
        with self._forces_lock:
            return self._forces.covered(int(index0), int(n))

    def unplayed_share(self) -> float:
        """Commanded samples known never to have played, as a share of all commanded (0
        when nothing was commanded). Final once :meth:`close` has returned."""
        with self._cond:
            ledger = self._ledger
            return ledger.unplayed / ledger.commanded if ledger.commanded else 0.0

    def status(self) -> dict:
        """JSON-able counters: see PROTOCOL.md section 6 for their meaning."""
        with self._cond:
            st = self._status
            c = collections.Counter(self._counts)
            breakdown = self._ledger.breakdown()
            commanded, played = self._ledger.commanded, self._ledger.played
            queued = len(self._queue)
            connected = self._connected
        rtt = np.array(self._rtt_ms)
        if self._closed:
            state = "closed"
        elif self._failure is not None:
            state = "failed"
        elif not connected:
            state = "disconnected"
        else:
            state = "simulated" if self._process is not None else "connected"
        out = {
            "state": state,
            "port": self.label,
            "paced": self.paced,
            "protocol_version": self.version,
            "frames_sent": c["frames_sent"], "blocks_sent": c["blocks_sent"],
            "queued_blocks": queued,
            "retries": c["retries"], "reconnects": c["reconnects"],
            "disconnects": c["disconnects"], "recoveries": c["recoveries"],
            "stalls": c["stalls"], "device_flushes": c["device_flushes"],
            "force_reports": c["force_reports"],
            "resyncs": self._decoder.counts.discarded,
            "crc_errors": self._decoder.counts.crc_errors,
            "lost_frames_from_device": self._decoder.counts.lost_frames,
            "clamped_samples": c["clamped_samples"], "dropped_blocks": c["dropped_blocks"],
            "commanded_samples": commanded,
            "played_samples": played,
            "unplayed_samples": sum(v for v in breakdown.values() if v is not None),
            "unplayed_by_cause": breakdown,
            "device_errors": {k: v for k, v in dict(self._errors).items() if v},
            "latency_ms_p50": float(np.percentile(rtt, 50)) if rtt.size else None,
            "latency_ms_p99": float(np.percentile(rtt, 99)) if rtt.size else None,
            "last_error": self.last_error,
            "failure": str(self._failure) if self._failure is not None else None,
            "device": asdict(self.info) if self.info else None,
        }
        if st is not None:
            out.update({
                "device_state": DeviceState.NAMES[st.state] if st.state < 5 else st.state,
                "device_level": st.level, "target_level": self._target,
                "underruns": st.underruns, "device_crc_errors": st.crc_errors,
                "device_lost_frames": st.lost_frames, "gap_samples": st.gap_samples,
                "late_samples": st.late_samples, "overflow_samples": st.overflow_samples,
                "watchdog_trips": st.watchdog_trips, "device_clamped": st.clamped,
                "measured_um": list(st.measured_um) if st.measured_um else None,
                "force_n": st.force_n})
        else:
            out["underruns"] = None
        return out

    def close(self) -> None:
        """Drain (paced: bounded by ``stall_s`` without progress), send Stop, let it play
        out, stop the thread, close the port; the sim exits. Never raises LinkStalled."""
        if self._closing.is_set():
            return
        if self.paced:
            self._wait_queue_sent()
        self._closing.set()
        drain_s = (self.info.buffer_samples / self.rate_hz + self.info.ramp_ms * 1e-3
                   + STOP_MARGIN_S)
        self._thread.join(timeout=drain_s + HANDSHAKE_TIMEOUT_S + 1.0)
        if self._thread.is_alive():
            self._warn("link thread did not finish; closing without it")
        with self._cond:
            self._connected = False
        self._closed = True
        if self._process is not None:
            for stop in (None, self._process.terminate, self._process.kill):
                if stop is not None:
                    stop()
                try:
                    self._process.wait(timeout=2.0)
                    break
                except subprocess.TimeoutExpired:
                    continue

    def _wait_queue_sent(self) -> None:
        """Paced close: wait while the queue drains; give up (dropping, counted) when no
        block went out for ``stall_s``."""
        with self._cond:
            while self._queue and self._connected and self._failure is None:
                before = len(self._queue)
                self._cond.wait(self.stall_s)
                if len(self._queue) == before and self._queue:
                    self._warn(f"device took no blocks for {self.stall_s:g} s while closing; "
                               f"dropping {len(self._queue)} queued")
                    self._drop_queued("stalled")

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def start_sim_device(channels: int, rate_hz: float, *, phases: bool = False, log_path=None,
                     tcp: bool = False, extra: tuple[str, ...] = ()
                     ) -> tuple[subprocess.Popen, str]:
    """Start ``frictex sim-device --once`` on a new pty (or, ``tcp``, a loopback TCP port);
    returns (process, pty path or ``socket://`` URL)."""
    cmd = [sys.executable, "-m", "frictex", "sim-device", "--once", "--channels",
           str(channels), "--rate", repr(float(rate_hz)), "--parent-pid", str(os.getpid()),
           *extra]
    if phases:
        cmd.append("--phases")
    if tcp:
        cmd += ["--tcp", "0"]
    if log_path is not None:
        cmd += ["--log", os.fspath(log_path)]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stdin=subprocess.DEVNULL, text=True)
    ready, _, _ = select.select([proc.stdout], [], [], 10.0)
    line = proc.stdout.readline().strip() if ready else ""
    if not line.startswith(("/", "socket://")):
        proc.kill()
        proc.wait(timeout=5.0)
        raise LinkError(f"the simulated device did not start (printed {line!r}; "
                        f"exit code {proc.poll()})")
    return proc, line


def open_sink(spec: str, channels: int, rate_hz: float, *, phases: bool = False,
              log_path=None, paced: bool = False, queue_blocks: int = 64, faults=None,
              stderr=sys.stderr, stall_s: float = STALL_S,
              max_stalls: int = MAX_STALLS, sim_args: tuple[str, ...] = ()) -> CommandSink:
    """Open the link to the device named by ``spec`` and handshake.

    Parameters
    ----------
    spec : ``"sim"`` (start a ``frictex sim-device`` subprocess on a pty, logging played
        samples to ``log_path`` if given), ``"sim:tcp"`` (the same on a loopback TCP
        port, reached through ``socket://``) or a pyserial port or URL.
    channels : number of actuator channels the pipeline produces.
    rate_hz : the pipeline's output sample rate (Hz); the device must run at it.
    phases : the actuation sends a phase (rad) per channel and sample.
    paced : True for replay (the device paces ``send``), False for live (never blocks).
    faults : a :class:`device.link.faults.FaultPlan` (``parse_faults("...")``) to inject
        on this link, or None.
    stall_s, max_stalls : bound of one wait on the device (s), stalls in a row before
        :class:`LinkStalled`.
    sim_args : more ``frictex sim-device`` flags for ``"sim"`` / ``"sim:tcp"``, e.g.
        ``("--finger", "3")`` for lateral force reports from a simulated finger.

    Raises :class:`LinkError` (an OSError) if the port cannot be opened or the device does
    not answer or does not fit the pipeline.
    """
    options = {"phases": phases, "paced": paced, "queue_blocks": queue_blocks,
               "stderr": stderr, "stall_s": stall_s, "max_stalls": max_stalls}
    proc = None
    if spec in ("sim", "sim:tcp"):
        proc, path = start_sim_device(channels, rate_hz, phases=phases, log_path=log_path,
                                      tcp=spec == "sim:tcp", extra=tuple(sim_args))
        label = f"sim {path}"
    elif log_path is not None or sim_args:
        raise ValueError("log_path and sim_args are for the simulated device only (spec "
                         "'sim' or 'sim:tcp')")
    else:
        path = label = spec

    def opener():
        return open_port(path)
    if faults is not None:
        opener = faults.opener(opener)
    try:
        return CommandSink(opener, channels, rate_hz, label=label, process=proc, **options)
    except BaseException:
        if proc is not None:
            proc.kill()
            proc.wait(timeout=5.0)
        raise

"""The host side of the link to the plate's microcontroller (protocol: ``device/PROTOCOL.md``).

    sink = open_sink("sim", channels=1, rate_hz=10_000.0, paced=True, log_path="played.csv")
    sink.send(start_index, amplitudes_um, None)   # (n, channels) um, per block
    sink.status()                                  # JSON-able counters
    sink.close()                                   # drains, sends Stop; the sim exits

One reader/writer thread owns the port (pyserial: a device path, ``COM3``, ``socket://``,
``loop://``...). Callers hand blocks over through a bounded queue. ``paced=True`` (replay,
virtual clock): ``send`` waits until the device has room, so the device's clock paces
the replay and nothing is dropped while connected. ``paced=False`` (live): ``send``
never blocks; a full queue drops the block and counts it. Every amplitude is clamped to
the limit the device declared (counted). The thread heartbeats every
``watchdog_ms / 5`` so the device's watchdog stays quiet while the caller computes, and
measures the round trip of each heartbeat. If the port fails (USB unplugged) the link
says so once on stderr, drops and counts what it cannot send, and reopens the port and
handshakes again when it returns.
"""

from __future__ import annotations

import collections
import os
import queue
import select
import subprocess
import sys
import threading
import time
from dataclasses import asdict

import numpy as np
import serial

from device.link import protocol as p
from device.link.protocol import DeviceState, LinkError

#: jitter-buffer prefill asked of the device, and the level paced sending keeps (s)
PREFILL_S = 0.010
TARGET_S = 0.020
HANDSHAKE_TIMEOUT_S = 1.0
HANDSHAKE_RETRY_S = 0.1
RECONNECT_PERIOD_S = 0.25
#: longest the thread waits for a byte before doing its other work (s)
READ_WAIT_S = 0.002
#: close() gives up draining a paced queue that made no progress for this long (s)
STALL_GIVE_UP_S = 2.0


def open_port(spec: str):
    """Open a pyserial port or URL, non-blocking reads; raises :class:`LinkError`."""
    try:
        port = serial.serial_for_url(spec, baudrate=921_600, timeout=READ_WAIT_S,
                                     write_timeout=0.5)
    except (serial.SerialException, ValueError, OSError) as exc:
        raise LinkError(f"cannot open device port {spec!r}: {exc}") from None
    return port


class CommandSink:
    """A connected device link; see the module docstring. Use :func:`open_sink`."""

    def __init__(self, opener, channels: int, rate_hz: float, *, phases: bool = False,
                 paced: bool = False, queue_blocks: int = 64, label: str = "device",
                 process: subprocess.Popen | None = None, stderr=sys.stderr):
        if channels < 1:
            raise ValueError(f"channels = {channels!r}: expected at least 1")
        if not (rate_hz > 0 and np.isfinite(rate_hz)):
            raise ValueError(f"rate_hz = {rate_hz!r}: expected a positive number")
        self._opener = opener
        self.channels = int(channels)
        self.rate_hz = float(rate_hz)
        self.phases = bool(phases)
        self.paced = bool(paced)
        self.label = label
        self._process = process
        self._stderr = stderr
        self._queue: queue.Queue = queue.Queue(maxsize=queue_blocks)
        self._lock = threading.Lock()
        self._closing = threading.Event()
        self._closed = False
        self._connected = threading.Event()
        self._counts = collections.Counter()
        self._errors = collections.Counter()
        self._rtt_ms: collections.deque = collections.deque(maxlen=4096)
        self._pending_hb: dict[int, float] = {}
        self._seq = 0
        self._decoder = p.Decoder()
        self._status: p.Status | None = None
        self._status_t = 0.0
        self._sent_end = 0            # index after the last sample sent
        self.last_error: str | None = None
        self.info: p.Info | None = None
        self._port = None
        self._connect()               # first connection: failures are the caller's error
        self._thread = threading.Thread(target=self._loop, name=f"frictex-link-{label}",
                                        daemon=True)
        self._thread.start()

    # ------------------------------------------------------------------ connection
    def _connect(self) -> None:
        port = self._opener()
        try:
            info = self._handshake(port)
        except BaseException:
            port.close()
            raise
        self._check(info)
        self.info = info
        self._limits = np.asarray(info.limits_um[:self.channels], dtype=np.float64)
        self._prefill = max(1, min(int(PREFILL_S * info.sample_rate_hz),
                                   info.buffer_samples // 4))
        self._target = max(self._prefill + 1,
                           min(int(TARGET_S * info.sample_rate_hz), info.buffer_samples // 2))
        self._heartbeat_s = max(info.watchdog_ms / 5.0, 1.0) * 1e-3
        self._sent_end = 0
        self._status = None
        self._port = port
        self._connected.set()

    def _handshake(self, port) -> p.Info:
        """Send Hello until Info comes back; the device flushes its buffer on Hello."""
        decoder = p.Decoder()
        deadline = time.monotonic() + HANDSHAKE_TIMEOUT_S
        tries = 0
        while time.monotonic() < deadline:
            if tries:
                self._counts["retries"] += 1
            tries += 1
            # a leading delimiter ends whatever partial frame the device was holding
            port.write(b"\x00" + self._frame(p.Hello(int(PREFILL_S * self.rate_hz))))
            until = min(deadline, time.monotonic() + HANDSHAKE_RETRY_S)
            while time.monotonic() < until:
                for frame in decoder.feed(self._read(port)):
                    if isinstance(frame.message, p.Info):
                        self._decoder = decoder
                        return frame.message
                    if isinstance(frame.message, p.ErrorReport):
                        self._errors[p.ErrorCode.NAMES.get(frame.message.code, "other")] += 1
        bad = decoder.counts.last_bad_version
        if bad is not None:
            raise LinkError(f"{self.label}: device speaks protocol version {bad}; this host "
                            f"speaks {p.PROTOCOL_VERSION}")
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

    def _count(self, key: str, n: int = 1) -> None:
        with self._lock:
            self._counts[key] += n

    def _frame(self, msg) -> bytes:
        data = p.encode(msg, self._seq)
        self._seq = (self._seq + 1) & 0xFFFF
        self._counts["frames_sent"] += 1
        return data

    def _lost(self, exc: BaseException) -> None:
        self.last_error = f"{type(exc).__name__}: {exc}"
        self._connected.clear()
        try:
            self._port.close()
        except Exception:  # noqa: BLE001 -- the port is already gone; nothing to save
            pass
        self._port = None
        self._counts["disconnects"] += 1
        self._drop_queued()
        print(f"frictex: warning: {self.label} link lost ({self.last_error}); "
              "output continues without it, reconnecting", file=self._stderr)

    def _drop_queued(self) -> None:
        while True:
            try:
                self._queue.get_nowait()
            except queue.Empty:
                return
            self._count("dropped_blocks")
            self._queue.task_done()

    # ------------------------------------------------------------------ the thread
    def _loop(self) -> None:
        next_hb = 0.0
        next_try = 0.0
        while not self._closing.is_set() or not self._queue.empty():
            now = time.monotonic()
            if self._port is None:
                if self._closing.is_set():
                    self._drop_queued()
                    return
                if now >= next_try:
                    next_try = now + RECONNECT_PERIOD_S
                    try:
                        self._connect()
                        self._counts["reconnects"] += 1
                        print(f"frictex: {self.label} link back", file=self._stderr)
                    except (LinkError, OSError, serial.SerialException):
                        pass
                time.sleep(0.005)
                continue
            try:
                self._service(now >= next_hb)
            except (OSError, serial.SerialException) as exc:
                self._lost(exc)
                continue
            if now >= next_hb:
                next_hb = now + self._heartbeat_s

    def _service(self, heartbeat: bool) -> None:
        port = self._port
        for frame in self._decoder.feed(self._read(port)):
            self._handle(frame.message)
        out = bytearray()
        if heartbeat:
            token = self._counts["heartbeats"] & 0xFFFFFFFF
            self._counts["heartbeats"] += 1
            self._pending_hb[token] = time.monotonic()
            if len(self._pending_hb) > 64:
                self._pending_hb.pop(next(iter(self._pending_hb)))
            out += self._frame(p.Heartbeat(token))
        while len(out) < 4096:
            try:
                start, counts, phases = self._queue.queue[0]
            except IndexError:
                break
            if self.paced and not self._room(start, len(counts)):
                break
            self._queue.get_nowait()
            self._queue.task_done()
            out += self._frame(p.Block(start, counts, phases))
            self._counts["blocks_sent"] += 1
            self._sent_end = max(self._sent_end, start + len(counts))
        if out:
            port.write(bytes(out))

    def _room(self, start: int, n: int) -> bool:
        """Paced mode: would the device's buffer stay at or below the target level?

        The device's play index is extrapolated from its last Status; when everything
        sent has (by that estimate) been played, the device is empty and takes any block
        (it jumps to a block that starts ahead of it).
        """
        st = self._status
        if st is None:
            return False
        played = st.play_index
        if st.state in (DeviceState.PLAYING, DeviceState.DRAINING):
            played += int((time.monotonic() - self._status_t) * self.info.sample_rate_hz)
        if self._sent_end <= played:
            return True
        return start + n - played <= self._target

    def _handle(self, msg) -> None:
        now = time.monotonic()
        if isinstance(msg, p.Status):
            sent = self._pending_hb.pop(msg.echo, None)
            if sent is not None:
                self._rtt_ms.append((now - sent) * 1e3)
            with self._lock:
                self._status, self._status_t = msg, now
        elif isinstance(msg, p.ErrorReport):
            self._errors[p.ErrorCode.NAMES.get(msg.code, "other")] += 1

    # ------------------------------------------------------------------ the caller's side
    def send(self, start_index: int, amplitudes_um: np.ndarray,
             phases_rad: np.ndarray | None = None) -> None:
        """Queue one block: (n, channels) amplitudes (um) from sample ``start_index`` on.

        Clamps to the device's limits (counted). Paced: waits for room while connected.
        Live: never waits; a full queue drops the block (counted). Disconnected: drops.
        """
        a = np.asarray(amplitudes_um, dtype=np.float64)
        if a.ndim != 2 or a.shape[1] != self.channels:
            raise ValueError(f"amplitudes shape {a.shape}: expected (n, {self.channels})")
        if self.phases != (phases_rad is not None):
            raise ValueError(f"phases {'missing' if self.phases else 'given'}: this link was "
                             f"opened with phases={self.phases}")
        counts, clamped = p.amplitude_to_wire(a, self._limits)
        wire_phases = None if phases_rad is None else p.phase_to_wire(phases_rad)
        if wire_phases is not None and wire_phases.shape != counts.shape:
            raise ValueError(f"phases shape {wire_phases.shape}: expected {counts.shape}")
        self._count("clamped_samples", clamped)
        step = p.max_block_samples(self.channels, self.phases)
        for lo in range(0, len(counts), step):
            item = (int(start_index) + lo, counts[lo:lo + step],
                    None if wire_phases is None else wire_phases[lo:lo + step])
            self._put(item)

    def _put(self, item) -> None:
        if self._closing.is_set():
            raise LinkError(f"{self.label}: send after close")
        while True:
            if not self._connected.is_set():
                self._count("dropped_blocks")
                return
            try:
                if self.paced:
                    self._queue.put(item, timeout=0.05)
                else:
                    self._queue.put_nowait(item)
                return
            except queue.Full:
                if not self.paced:
                    self._count("dropped_blocks")
                    return

    def device_force_n(self) -> float | None:
        """The normal force (N) the device's force sensors last reported, or None if it
        has none (or has not reported yet). Cheap: the haptic thread asks every block."""
        st = self._status
        if self.info is None or not self.info.has_force or st is None:
            return None
        return st.force_n

    def status(self) -> dict:
        """JSON-able counters: see PROTOCOL.md section 6 for their meaning."""
        with self._lock:
            st = self._status
        rtt = np.array(self._rtt_ms)
        with self._lock:
            c = collections.Counter(self._counts)
        if self._closed:
            state = "closed"
        elif not self._connected.is_set():
            state = "disconnected"
        else:
            state = "simulated" if self._process is not None else "connected"
        out = {
            "state": state,
            "port": self.label,
            "paced": self.paced,
            "frames_sent": c["frames_sent"], "blocks_sent": c["blocks_sent"],
            "queued_blocks": self._queue.qsize(),
            "retries": c["retries"], "reconnects": c["reconnects"],
            "disconnects": c["disconnects"],
            "resyncs": self._decoder.counts.discarded,
            "crc_errors": self._decoder.counts.crc_errors,
            "lost_frames_from_device": self._decoder.counts.lost_frames,
            "clamped_samples": c["clamped_samples"], "dropped_blocks": c["dropped_blocks"],
            "device_errors": dict(self._errors),
            "latency_ms_p50": float(np.percentile(rtt, 50)) if rtt.size else None,
            "latency_ms_p99": float(np.percentile(rtt, 99)) if rtt.size else None,
            "last_error": self.last_error,
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
        """Drain (paced), send Stop, stop the thread, close the port; the sim exits."""
        if self._closing.is_set():
            return
        if self.paced:
            self._wait_queue_sent()
        drain_s = self._target / self.rate_hz + 1.0
        self._closing.set()
        self._thread.join(timeout=drain_s + 2.0)
        port = self._port
        if port is not None:
            try:
                port.write(self._frame(p.Stop(drain=True)))
                self._wait_stopped(port, drain_s)
            except (OSError, serial.SerialException):
                pass
            port.close()
        self._connected.clear()
        self._closed = True
        if self._process is not None:
            try:
                self._process.wait(timeout=drain_s + 1.0)
            except subprocess.TimeoutExpired:
                self._process.terminate()
                self._process.wait(timeout=2.0)

    def _wait_queue_sent(self) -> None:
        """Paced close: wait while the queue drains; give up (dropping, counted) on a stall."""
        last, last_t = self._counts["blocks_sent"], time.monotonic()
        while self._queue.unfinished_tasks and self._connected.is_set():
            time.sleep(0.005)
            if self._counts["blocks_sent"] != last:
                last, last_t = self._counts["blocks_sent"], time.monotonic()
            elif time.monotonic() - last_t > STALL_GIVE_UP_S:
                print(f"frictex: warning: {self.label}: device stopped taking blocks; "
                      f"dropping {self._queue.qsize()} queued", file=self._stderr)
                self._drop_queued()
                return

    def _wait_stopped(self, port, timeout_s: float) -> None:
        """Keep heartbeating until the device reports silence (a drained Stop)."""
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            port.write(self._frame(p.Heartbeat(0)))
            until = time.monotonic() + self._heartbeat_s
            while time.monotonic() < until:
                for frame in self._decoder.feed(self._read(port)):
                    self._handle(frame.message)
            st = self._status
            if st is not None and st.state == DeviceState.SILENT:
                return

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def start_sim_device(channels: int, rate_hz: float, *, phases: bool = False, log_path=None,
                     extra: tuple[str, ...] = ()) -> tuple[subprocess.Popen, str]:
    """Start ``frictex sim-device`` on a new pty; returns (process, pty path)."""
    cmd = [sys.executable, "-m", "app.commands.cli", "sim-device", "--channels", str(channels),
           "--rate", repr(float(rate_hz)), "--parent-pid", str(os.getpid()), *extra]
    if phases:
        cmd.append("--phases")
    if log_path is not None:
        cmd += ["--log", os.fspath(log_path)]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stdin=subprocess.DEVNULL, text=True)
    ready, _, _ = select.select([proc.stdout], [], [], 10.0)
    line = proc.stdout.readline().strip() if ready else ""
    if not line.startswith("/"):
        proc.kill()
        proc.wait()
        raise LinkError(f"the simulated device did not start (printed {line!r}; "
                        f"exit code {proc.poll()})")
    return proc, line


def open_sink(spec: str, channels: int, rate_hz: float, *, phases: bool = False,
              log_path=None, paced: bool = False, queue_blocks: int = 64) -> CommandSink:
    """Open the link to the device named by ``spec`` and handshake.

    Parameters
    ----------
    spec : ``"sim"`` (start a ``frictex sim-device`` subprocess, logging played samples to
        ``log_path`` if given) or a pyserial port or URL.
    channels : number of actuator channels the pipeline produces.
    rate_hz : the pipeline's output sample rate (Hz); the device must run at it.
    phases : the actuation sends a phase (rad) per channel and sample.
    paced : True for replay (the device paces ``send``), False for live (never blocks).

    Raises :class:`LinkError` (an OSError) if the port cannot be opened or the device does
    not answer or does not fit the pipeline.
    """
    if spec == "sim":
        proc, path = start_sim_device(channels, rate_hz, phases=phases, log_path=log_path)
        try:
            return CommandSink(lambda: open_port(path), channels, rate_hz, phases=phases,
                               paced=paced, queue_blocks=queue_blocks, label=f"sim {path}",
                               process=proc)
        except BaseException:
            proc.kill()
            proc.wait()
            raise
    if log_path is not None:
        raise ValueError("log_path is for the simulated device only (spec 'sim')")
    return CommandSink(lambda: open_port(spec), channels, rate_hz, phases=phases, paced=paced,
                       queue_blocks=queue_blocks, label=spec)

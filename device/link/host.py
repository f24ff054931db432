"""The host's end of the link to the plate's microcontroller: what the engine calls.

    sink = open_sink("sim", channels=1, rate_hz=10_000.0, paced=True, log_path="played.csv")
    sink.wait_for_room(0.5)                        # device-paced clock: True when send won't wait
    sink.send(start_index, amplitudes_um, None)   # (n, channels) um, per block
    sink.status()                                  # JSON-able counters
    sink.unplayed_share()                          # commanded samples that never played
    sink.force_report()                            # latest lateral/normal force, or None
    sink.close()                                   # drains, sends Stop
    sink.abort()                                   # instead: stops now (Stop without drain)

Built in pyserial's shape, one job per piece: the port is opened by URL
(``device.link.port``; ``sim://`` is the simulated device in this process,
``device.link.simport``), a thread owns it and only moves bytes
(``device.link.portthread``), the protocol's state and bookkeeping are sans I/O
(``device.link.session``; framing in ``device.link.protocol``, the device's buffer and
where each sample went in ``device.link.ledger``, when to give up in
``device.link.stall``). :class:`CommandSink` is the caller's side: a bounded queue of
blocks, the waits on it, the counters. :func:`open_sink` finds the output device by name
in ``device.link.devices.DEVICES`` and opens it; the built-in devices (``sim``, ``port``)
are registered here.

``paced=True`` (replay): a block goes out only when the device's buffer has room, so the
device's clock paces the run, and ``send`` waits for a free queue slot. ``paced=False``
(live): ``send`` never waits; a full queue drops the block (counted). Every amplitude is
clamped to the limit the device declared (counted).

Every wait is bounded. Opening: the port opens at once or the link fails; the handshake
resends Hello with back-off (``session.HELLO_FIRST_S`` doubling to ``HELLO_MAX_S``) for
:data:`HANDSHAKE_TOTAL_S` in total before the link fails (a :class:`LinkError`, a
DeviceError: exit 1), or until the device has closed the link
``session.HANDSHAKE_CLOSES`` times in a row with no valid frame between. If the port fails later (USB unplugged) the link says so once on
stderr and reopens it until it returns (live: queued blocks are dropped and counted;
paced: they wait and go out after). A caller's wait (``send`` paced, ``wait_for_room``)
longer than ``stall_s`` is a *stall*: a warning on stderr, the block dropped (counted),
the stream going on, and a second warning when it ends. Time this process was stopped
(:data:`HOST_STOPPED_S`) is said as the host's and not counted in the wait. A paced link gives up (:class:`LinkStalled`, raised by that call
and every later one) when its time without progress passes the bound of
``device.link.stall``: ``stall_s x max_stalls`` plus a quarter of the time played.
"""

from __future__ import annotations

import collections
import subprocess
import sys
import time
from dataclasses import asdict

import numpy as np

from frictex.device.errors import InputError
from frictex.device.link import protocol as p
from frictex.device.link.devices import DEVICES, DeviceRequest, open_device, sim_pairs
from frictex.device.link.forces import ForceReport
from frictex.device.link.port import open_port
from frictex.device.link.portthread import PortThread
from frictex.device.link.protocol import LinkError
from frictex.device.link.session import (PREFILL_S, SILENCE_S, TARGET_S, HostSession,
                                         LinkProgress, LinkStalled, state_name)
from frictex.device.link.stall import StallPolicy
from frictex.device.link.waits import TURN_S, check_interrupt

__all__ = ["CommandSink", "LinkError", "LinkStalled", "open_port", "open_sink", "PREFILL_S",
           "TARGET_S", "HANDSHAKE_TOTAL_S", "STALL_S", "MAX_STALLS"]

#: the first handshake's total: Hellos with back-off for this long before the link fails (s)
HANDSHAKE_TOTAL_S = 10.0
#: default bound of one caller's wait on the device (s), and the multiple of it a paced
#: link may spend without progress before giving up (plus a share of the time played)
STALL_S = 1.0
MAX_STALLS = 5
#: a caller's wait that comes back this much later than it asked: this process was not
#: running (stopped, suspended, starved), and that time is not the device's (s)
HOST_STOPPED_S = 0.25


class CommandSink:
    """A connected device link; see the module docstring. Use :func:`open_sink`.

    Parameters
    ----------
    opener : callable returning an open pyserial-like port (``device.link.port``).
    channels, rate_hz : what the pipeline sends (Hz).
    phases, paced, queue_blocks, label : see :func:`open_sink`.
    process : a process that serves the device (a firmware build on a pty), ended by
        :meth:`close`. on_close : called by :meth:`close` once the link is down.
        simulated : the device is a simulation (its state reads "simulated").
    stall_s : bound of one caller's wait (s). max_stalls : the link gives up past
        ``stall_s * max_stalls`` s without progress (plus a share of the time played).
    handshake_s : total of the first handshake's tries (s).
    prefill_s, catch_up : the jitter-buffer prefill asked of the device (s), and for a
        live link whether it catches up after the device fell behind (both: see
        :func:`open_sink`).
    injected : the faults the opener injects (``--faults`` text), named where the first
        handshake fails, or None.
    """

    def __init__(self, opener, channels: int, rate_hz: float, *, phases: bool = False,
                 paced: bool = False, queue_blocks: int = 64, label: str = "device",
                 process: subprocess.Popen | None = None, stderr=sys.stderr,
                 stall_s: float = STALL_S, max_stalls: int = MAX_STALLS, on_close=None,
                 simulated: bool = False, handshake_s: float = HANDSHAKE_TOTAL_S,
                 prefill_s: float = PREFILL_S, catch_up: bool = False,
                 injected: str | None = None):
        if channels < 1:
            raise InputError(f"channels = {channels!r}: expected at least 1")
        if not (rate_hz > 0 and np.isfinite(rate_hz)):
            raise InputError(f"rate_hz = {rate_hz!r}: expected a positive number")
        if not (0 < prefill_s <= 1.0):
            raise InputError(f"prefill_s = {prefill_s!r}: expected a time in (0, 1] s")
        if not (stall_s > 0 and np.isfinite(stall_s)) or max_stalls < 1:
            raise InputError(f"stall_s = {stall_s!r}, max_stalls = {max_stalls!r}: expected a "
                             "positive time and at least 1")
        self.channels = int(channels)
        self.rate_hz = float(rate_hz)
        self.phases = bool(phases)
        self.paced = bool(paced)
        self.label = label
        self.stall_s = float(stall_s)
        self.max_stalls = int(max_stalls)
        self._process = process
        self._injected = injected
        self._on_close = on_close
        self._simulated = simulated or process is not None
        self._stderr = stderr
        self._capacity = int(queue_blocks)
        self._closed = False
        self._closed_at: float | None = None  # time.monotonic() when the link ended
        self._opener = opener
        self._session = s = HostSession(self.channels, self.rate_hz, phases=self.phases,
                                        paced=self.paced, label=label, stderr=stderr,
                                        prefill_s=prefill_s, catch_up=catch_up)
        self._policy = StallPolicy(self.rate_hz, self.stall_s * self.max_stalls)
        self._progress_seen = 0
        #: the stalls in a row said so far: [causes, host time the first began, stalls,
        #: samples dropped], or None (see :meth:`_stall`)
        self._stalls: list | None = None
        self._cond = s.cond
        port = opener()               # a port that cannot be opened is the caller's error
        self._thread = PortThread(port, opener, s, name=f"frictex-link-{label}",
                                  on_crash=self._crashed)
        self._thread.start()
        self._await_handshake(handshake_s)

    def _await_handshake(self, total_s: float) -> None:
        """Wait for the first session, at most ``total_s``; on failure the thread is
        stopped and the error raised (a :class:`LinkError`). The wait is interruptible
        (``device.link.waits``): the thread is stopped and the interrupt raised."""
        s, t0 = self._session, time.monotonic()
        try:
            with self._cond:
                while (not s.connected and s.refused is None and s.failure is None
                       and s.device_said is None and not s.closes_every_time):
                    left = t0 + total_s - time.monotonic()
                    if left <= 0 or not self._thread.is_alive():
                        break
                    self._cond.wait(min(left, TURN_S))
                    check_interrupt()
                if s.connected:
                    return
        except BaseException:
            self._abandon()
            raise
        self._abandon()
        raise s.failure or s.handshake_failure(time.monotonic() - t0, self._injected)

    def _abandon(self) -> None:
        """No session to close (a handshake that failed or was interrupted): stop the
        thread, close the port, end what serves the device."""
        with self._cond:
            self._session.close_requested = True
        self._closed, self._closed_at = True, time.monotonic()
        self._thread.stop_event.set()
        self._thread.join(timeout=5.0)
        self._end_resources()

    def _crashed(self, exc: BaseException) -> None:
        failure = LinkStalled(f"{self.label}: link thread failed: {type(exc).__name__}: {exc}")
        with self._cond:
            self._session.failure = failure
            self._session.connected = False
            self._cond.notify_all()
        print(f"frictex: error: {failure}", file=self._stderr)

    # ------------------------------------------------------------------ what the device is
    @property
    def info(self) -> p.Info | None:
        """The device's answer to the handshake (its Info)."""
        return self._session.info

    @property
    def version(self) -> int:
        """The protocol version this link speaks."""
        return self._session.version

    @property
    def last_error(self) -> str | None:
        return self._session.last_error

    # ------------------------------------------------------------------ the caller's side
    def send(self, start_index: int, amplitudes_um: np.ndarray,
             phases_rad: np.ndarray | None = None) -> None:
        """Queue one block: (n, channels) amplitudes (um) from sample ``start_index`` on.

        Clamps to the device's limits (counted). Paced: waits for a queue slot, at most
        ``stall_s`` (then drops the block: a stall). Live: never waits; a full queue
        drops the block (counted). Disconnected: live drops at once, paced waits for the
        link to come back (at most ``stall_s``). Raises :class:`LinkStalled` once the link
        has given up (``device.link.stall``).
        """
        a = np.asarray(amplitudes_um, dtype=np.float64)
        if a.ndim != 2 or a.shape[1] != self.channels:
            raise InputError(f"amplitudes shape {a.shape}: expected (n, {self.channels})")
        if self.phases != (phases_rad is not None):
            raise InputError(f"phases {'missing' if self.phases else 'given'}: this link was "
                             f"opened with phases={self.phases}")
        start_index = int(start_index)
        if start_index < 0:
            raise InputError(f"start_index = {start_index}: expected a sample number >= 0")
        counts, clamped = p.amplitude_to_wire(a, self._session.limits_um)
        wire_phases = None if phases_rad is None else p.phase_to_wire(phases_rad)
        if wire_phases is not None and wire_phases.shape != counts.shape:
            raise InputError(f"phases shape {wire_phases.shape}: expected {counts.shape}")
        s = self._session
        with self._cond:
            if s.failure is not None:
                raise s.failure
            if self._closed or s.close_requested:
                raise LinkError(f"{self.label}: send after close")
            too_small = self._buffer_problem(len(counts))
            if too_small is not None:
                raise LinkError(too_small)
            s.counts["clamped_samples"] += clamped
            s.ledger.command(len(counts))
        step = p.max_block_samples(self.channels, self.phases)
        for lo in range(0, len(counts), step):
            self._put((start_index + lo, counts[lo:lo + step],
                       None if wire_phases is None else wire_phases[lo:lo + step]))

    def _buffer_problem(self, block: int) -> str | None:
        """Why the device's buffer cannot take a stream of ``block``-sample blocks (it
        must hold two: one playing while the next arrives), or None; the caller holds
        the lock."""
        info = self._session.info
        if info is None or info.buffer_samples >= 2 * block:
            return None
        return (f"{self.label} ({info.name or 'unnamed'}) buffers {info.buffer_samples} "
                f"samples, less than two of the pipeline's {block}-sample blocks: it would "
                "overflow or run dry between them")

    def _has_room(self) -> bool:
        return self._session.connected and len(self._session.queue) < self._capacity

    def _put(self, item) -> None:
        n, s = len(item[1]), self._session
        if self.paced:
            check_interrupt()
        with self._cond:
            if not self.paced:
                if self._has_room():
                    s.queue.append(item)
                else:
                    s.counts["dropped_blocks"] += 1
                    s.ledger.drop("queue_full" if s.connected else "disconnected", n)
                return
            try:
                if self._wait_room(self.stall_s):
                    s.queue.append(item)
                    self._end_stalls("it took blocks again")
                    return
            except LinkStalled:  # the link gave up: this block is one it never took
                s.counts["dropped_blocks"] += 1
                s.ledger.drop("stalled", n)
                raise
            s.counts["dropped_blocks"] += 1
            s.ledger.drop("stalled" if s.connected else "disconnected", n)
            self._stall(self.stall_s, n)

    def _wait_room(self, timeout_s: float) -> bool:
        """Wait (holding the lock) until a block can be queued; False after ``timeout_s``.
        The time waited goes to the stall policy; past its bound the link fails. Asks
        every :data:`~device.link.waits.TURN_S` whether the caller is interrupted. Time
        this process was stopped is added to the wait (:meth:`_host_stopped_s`) and left
        out of the stall policy's lag."""
        deadline = time.monotonic() + timeout_s
        self._account(waiting=False)
        while not self._has_room():
            if self._session.failure is not None:
                raise self._session.failure
            left = deadline - time.monotonic()
            if left <= 0 or not self._thread.is_alive():
                self._account(waiting=True)
                return False
            asked_s, began = min(left, TURN_S), time.monotonic()
            self._cond.wait(asked_s)
            stopped_s = self._host_stopped_s(time.monotonic() - began - asked_s)
            deadline += stopped_s
            self._policy.skip(stopped_s)
            self._account(waiting=True)
            check_interrupt()
        self._account(waiting=True)
        return True

    def _host_stopped_s(self, late_s: float) -> float:
        """How long this process was stopped during a wait that came back ``late_s`` (s)
        past what it asked: ``late_s`` from :data:`HOST_STOPPED_S` on (said), else 0. The
        device was not waited on meanwhile, however its watchdog took the silence."""
        if late_s < HOST_STOPPED_S:
            return 0.0
        self._warn(f"this host was stopped for {late_s:.1f} s (not the device); "
                   "the wait for the device goes on")
        return late_s

    def _account(self, waiting: bool) -> None:
        """Tell the stall policy what played since it last heard (the caller holds the
        lock); set the link's failure, and raise it, once it is past its bound."""
        s = self._session
        played = s.ledger.played
        progress = played if played is not None else s.ledger.sent_total  # version 1: sent
        gained, self._progress_seen = max(progress - self._progress_seen, 0), progress
        self._policy.account(time.monotonic(), gained, waiting)
        if self._policy.failed and s.failure is None:
            progress = self._progress()
            s.failure = LinkStalled(f"{self.label}: {self._policy.describe()}; giving up: "
                                    f"{progress.describe()}", progress)
            self._cond.notify_all()
        if waiting and s.failure is not None:
            raise s.failure

    def _progress(self) -> LinkProgress:
        """Where the commanded samples stand now (the caller holds the lock)."""
        s, ledger = self._session, self._session.ledger
        causes = ledger.breakdown()
        played = ledger.played
        refused = (None if played is None else
                   sum(causes[c] or 0 for c in ("flushed", "late", "overflow", "lost")))
        return LinkProgress(commanded=ledger.commanded, sent=ledger.sent_total, played=played,
                            refused=refused, dropped=sum(ledger.host.values()),
                            queued=sum(len(item[1]) for item in s.queue))

    def progress(self) -> LinkProgress:
        """Where the samples handed to :meth:`send` stand now: sent, played, dropped,
        queued (a :class:`~device.link.session.LinkProgress`)."""
        with self._cond:
            return self._progress()

    def _stall(self, waited_s: float, dropped: int) -> None:
        """Count a stall of ``waited_s`` that dropped ``dropped`` samples (0: a wait for
        room that timed out); the caller holds the lock. The first of stalls in a row is
        said at once, the run again once it ends (:meth:`_end_stalls`), with how long the
        device was away in all."""
        s = self._session
        s.counts["stalls"] += 1
        why = "no device" if not s.connected else "device took no blocks"
        if self._stalls is None:
            self._stalls = [[why], time.monotonic() - waited_s, 1, dropped]
            what = f"dropped a block of {dropped} samples" if dropped else "no room for a block"
            self._warn(f"{why} for {waited_s:g} s; {what}, stream goes on (said again "
                       "when it ends)")
            return
        causes, _, stalls, samples = self._stalls
        if why not in causes:
            causes.append(why)
        self._stalls[2:] = [stalls + 1, samples + dropped]

    def _end_stalls(self, how: str) -> None:
        """Stalls in a row ended (``how``: why): say how long they lasted and what they
        dropped, as the first one's warning promised; the caller holds the lock."""
        run, self._stalls = self._stalls, None
        if run is None:
            return
        causes, began, stalls, samples = run
        self._warn(f"{', then '.join(causes)} for {time.monotonic() - began:.1f} s in all, "
                   f"until {how}: {stalls} stall{'s' * (stalls != 1)}, {samples} samples "
                   "dropped")

    def _warn(self, text: str) -> None:
        print(f"frictex: warning: {self.label}: {text}", file=self._stderr)

    def wait_for_room(self, timeout_s: float) -> bool:
        """Block at most ``timeout_s`` until ``send`` of one more block would not wait.

        True when it would; False on timeout, counted as a stall. Raises
        :class:`LinkStalled` once the link has given up. In live mode ``send`` never
        waits, so this returns True at once.
        """
        with self._cond:
            if self._session.failure is not None:
                raise self._session.failure
            if not self.paced or self._wait_room(timeout_s):
                self._end_stalls("it took blocks again")
                return True
            self._stall(timeout_s, 0)
            return False

    def device_force_n(self) -> float | None:
        """The normal force (N) the device's force sensors last reported, or None if it
        has none (or has not reported yet). Cheap: the haptic thread asks every block."""
        st, info = self._session.status, self._session.info
        if info is None or not info.has_force or st is None:
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
        s = self._session
        with s.forces_lock:
            if index0 is None:
                return s.forces.latest()
            return s.forces.window(int(index0), int(n))

    def forces_covered(self, index0: int, n: int) -> tuple[np.ndarray, np.ndarray]:
        """(lateral, normal) forces (N) of those of samples ``index0 .. index0 + n - 1``
        the reports of the last second cover, in sample order (``ForceHistory.covered``:
        a device drops a report when it underruns); empty arrays if none. Never blocks."""
        s = self._session
        with s.forces_lock:
            return s.forces.covered(int(index0), int(n))

    def device_index(self, index: int) -> int:
        """The device's number of sample ``index`` (the caller's): the same unless a live
        link skipped blocks to catch up (PROTOCOL.md 6.1); a skipped sample's is that
        of the first sample sent after it."""
        with self._cond:
            return self._session.index_map.device_index(int(index))

    def unplayed_share(self) -> float | None:
        """Commanded samples known never to have played, as a share of all commanded (0
        when nothing was commanded; None when a version 1 device leaves causes unknown).
        Final once :meth:`close` has returned."""
        with self._cond:
            ledger = self._session.ledger
            if not ledger.commanded:
                return 0.0
            return None if ledger.unplayed is None else ledger.unplayed / ledger.commanded

    def _queue_still_s(self, now: float) -> float:
        """How long (s, up to ``now`` on the monotonic clock) the queued blocks have not
        moved: 0 with none queued. Read from the time the link thread last took a block
        (or found none), so that a thread that is itself stuck shows here (the caller
        holds the lock)."""
        return max(now - self._session._last_progress, 0.0) if self._session.queue else 0.0

    def _fault_events_not_reached(self) -> list[str]:
        """The ``--faults`` events (their text) that had not begun when the link ended (or
        by now, while it runs): none without injected faults."""
        not_reached = getattr(self._opener, "events_not_reached", None)
        if not_reached is None:
            return []
        return not_reached(self._closed_at if self._closed_at is not None else time.monotonic())

    def status(self) -> dict:
        """JSON-able counters: see PROTOCOL.md section 6 for their meaning."""
        s = self._session
        with self._cond:
            st = s.status
            runs = dict(s.run_counts.totals)
            c = collections.Counter(s.counts)
            breakdown = s.ledger.breakdown()
            commanded, played = s.ledger.commanded, s.ledger.played
            queued = len(s.queue)
            connected = s.connected
            still_s = self._queue_still_s(time.monotonic())
        rtt = np.array(s.rtt_ms)
        if self._closed:
            state = "closed"
        elif s.failure is not None:
            state = "failed"
        elif not connected:
            state = "disconnected"
        elif still_s > SILENCE_S:
            state = "stalled"
        else:
            state = "simulated" if self._simulated else "connected"
        d = s.decoder.counts
        out = {
            "state": state,
            "queue_still_s": still_s,
            "port": self.label,
            "paced": self.paced,
            "protocol_version": s.version,
            "frames_sent": c["frames_sent"], "blocks_sent": c["blocks_sent"],
            "queued_blocks": queued,
            "retries": c["retries"], "reconnects": c["reconnects"],
            "disconnects": c["disconnects"], "handshake_closes": c["handshake_closes"],
            "recoveries": c["recoveries"],
            "stalls": c["stalls"], "device_flushes": c["device_flushes"],
            "force_reports": c["force_reports"],
            "resent_frames": c["resent_frames"], "resends_too_late": c["resends_too_late"],
            "stop_resends": c["stop_resends"], "stop_confirmed": s.stop_confirmed,
            "stale_statuses": c["stale_statuses"],
            "resyncs": d.discarded, "crc_errors": d.crc_errors,
            "lost_frames_from_device": d.lost_frames,
            "clamped_samples": c["clamped_samples"], "dropped_blocks": c["dropped_blocks"],
            "skipped_blocks": c["skipped_blocks"],
            "commanded_samples": commanded,
            "played_samples": played,
            "unplayed_samples": sum(v for v in breakdown.values() if v is not None),
            "unplayed_known": all(v is not None for v in breakdown.values()),
            "unplayed_by_cause": breakdown,
            "device_errors": {k: v for k, v in dict(s.errors).items() if v},
            "latency_ms_p50": float(np.percentile(rtt, 50)) if rtt.size else None,
            "latency_ms_p99": float(np.percentile(rtt, 99)) if rtt.size else None,
            "latency_ms_max": float(rtt.max()) if rtt.size else None,
            "latency_samples": int(rtt.size),
            "stalled_s": self._policy.lag_s if self.paced else None,
            "longest_turn_gap_ms": s.longest_turn_gap_s * 1e3,
            "longest_status_gap_ms": s.longest_status_gap_s * 1e3,
            "last_error": s.last_error,
            "failure": str(s.failure) if s.failure is not None else None,
            "device": asdict(s.info) if s.info else None,
            "fault_events_not_reached": self._fault_events_not_reached(),
        }
        if st is not None:
            out.update({
                "device_state": state_name(st.state),
                "device_level": st.level, "target_level": s.target,
                "underruns": st.underruns, "device_crc_errors": st.crc_errors,
                "device_lost_frames": st.lost_frames, "gap_samples": st.gap_samples,
                "late_samples": st.late_samples, "overflow_samples": st.overflow_samples,
                "watchdog_trips": st.watchdog_trips, "device_clamped": st.clamped,
                "measured_um": list(st.measured_um) if st.measured_um else None,
                "force_n": st.force_n})
            out.update({f"{name}_in_run": n for name, n in runs.items()})
        else:
            out["underruns"] = None
        return out

    def close(self) -> None:
        """Drain (paced: bounded by ``stall_s`` without progress), send Stop, let it play
        out, stop the thread, close the port. Never raises LinkStalled. Its waits are
        interruptible (``device.link.waits``): an interrupt leaves the link open for
        :meth:`abort`."""
        s = self._session
        if s.close_requested:
            return
        if self.paced:
            self._wait_queue_sent()
        with self._cond:
            s.close_requested = True
            self._end_stalls("the close")
        self._finish(interruptible=True)

    def abort(self) -> None:
        """Stop the plate now (an interrupted or failed run): drop what is queued
        (counted, ``stalled``), send Stop without drain, so that the device flushes what
        it holds and ramps to zero over its ``ramp_ms`` (PROTOCOL.md 4.5), wait for the
        Status that shows it silent (bounded: the ramp and 0.5 s, again for each of at
        most 3 resent Stops), stop the thread, close the port. Also cuts short a
        :meth:`close` that an interrupt ended. Never raises for the stream's faults and
        never asks whether it is interrupted: it is what an interrupt does."""
        if self._closed:
            return
        s = self._session
        with self._cond:
            s.abort_requested = s.close_requested = True
            s._drop_queued("stalled")
            self._end_stalls("the run ended")
        self._finish(interruptible=False)

    def _finish(self, interruptible: bool) -> None:
        """Wait for the thread to play the closing Stop out (bounded), then end the link;
        ``interruptible``: ask between turns whether the caller is interrupted."""
        s = self._session
        limit = time.monotonic() + s.close_limit_s() + 2.0
        while self._thread.is_alive() and (left := limit - time.monotonic()) > 0:
            self._thread.join(timeout=min(left, TURN_S))
            if interruptible:
                check_interrupt()
        if self._thread.is_alive():
            self._warn("link thread did not finish; closing without it")
            self._thread.stop_event.set()
            self._thread.join(timeout=2.0)
        with self._cond:
            s.connected = False
        self._closed, self._closed_at = True, time.monotonic()
        self._end_resources()

    def _end_resources(self) -> None:
        if self._on_close is not None:
            self._on_close()
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
        block went out for ``stall_s``. Interruptible (``device.link.waits``)."""
        s = self._session
        with self._cond:
            queued, since = len(s.queue), time.monotonic()
            while s.queue and s.connected and s.failure is None:
                self._cond.wait(TURN_S)
                check_interrupt()
                now = time.monotonic()
                if len(s.queue) != queued:
                    queued, since = len(s.queue), now
                elif now - since >= self.stall_s:
                    self._warn(f"device took no blocks for {now - since:.1f} s while closing; "
                               f"dropping {len(s.queue)} queued")
                    s._drop_queued("stalled")

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, tb):
        """Close; abort if the block raised (an interrupt, a failure): the plate stops
        at once instead of playing out what was queued."""
        if exc_type is None:
            self.close()
        else:
            self.abort()


@DEVICES.register("port")
def open_port_device(arg: str, request: DeviceRequest):
    """A device on a serial port or pyserial URL ``arg`` (``device.link.port``)."""
    if not arg:
        raise InputError("device 'port': expected port:PATH or port:URL")
    if request.log_path is not None or request.sim_args:
        raise InputError("a played-sample log and sim-device options are for the simulated "
                         "device only (--device sim)")

    def opener():
        return open_port(arg)
    if request.faults is not None:
        opener = request.faults.opener(opener)
    return CommandSink(opener, request.channels, request.rate_hz, label=arg,
                       **request.link_options())


@DEVICES.register("sim")
def open_sim_device(arg: str, request: DeviceRequest):
    """The simulated device in this process (``device.link.simport``): no subprocess,
    nothing to wait for but its handshake."""
    from frictex.device.link.simport import SimDevice, sim_config
    config = sim_config(sim_pairs(arg, request.sim_args), request.channels, request.rate_hz,
                        request.phases)
    device = SimDevice(config, request.log_path)
    opener = device.open
    if request.faults is not None:
        opener = request.faults.opener(opener)
    try:
        return CommandSink(opener, request.channels, request.rate_hz, label="sim://",
                           on_close=device.close, simulated=True, **request.link_options())
    except BaseException:
        device.close()
        raise


def open_sink(spec: str, channels: int, rate_hz: float, *, phases: bool = False,
              log_path=None, paced: bool = False, queue_blocks: int = 64, faults=None,
              stderr=sys.stderr, stall_s: float = STALL_S,
              max_stalls: int = MAX_STALLS, sim_args: tuple[str, ...] = (),
              profile: str | None = None, prefill_s: float = PREFILL_S,
              catch_up: bool = False):
    """Open the output device named by ``spec`` and handshake.

    Parameters
    ----------
    spec : ``NAME[:ARG]`` of an output device in ``device.link.devices.DEVICES``
        (``sim``, ``sim:finger=3``, a plugin's), a URL (``sim://?finger=3``, pyserial's
        ``socket://HOST:PORT``, ``loop://``, ...) or a port path (``/dev/ttyACM0``,
        ``/dev/pts/N``, ``COM3``).
    channels : number of actuator channels the pipeline produces.
    rate_hz : the pipeline's output sample rate (Hz); the device must run at it.
    phases : the actuation sends a phase (rad) per channel and sample.
    log_path : the simulated device's played-sample CSV (``sim`` only).
    paced : True for replay (the device paces ``send``), False for live (never blocks).
    faults : a :class:`device.link.faults.FaultPlan` (``parse_faults("...")``) to inject
        on this link, or None.
    stall_s, max_stalls : bound of one wait on the device (s); the link gives up past
        ``stall_s * max_stalls`` s without progress (``device.link.stall``).
    sim_args : ``frictex sim-device`` flags for ``sim`` (``("--finger", "3")``): the
        same options as ``sim:ARG``.
    profile : the scene's device profile name, for devices whose drive depends on the
        plate (``audio``: its carrier and um per volt); None: the device's default.
    prefill_s : the jitter-buffer prefill asked of a link's device (s): it starts playing
        once it holds this much, so a live stream plays this much less one block after
        the pipeline made it (default :data:`PREFILL_S`).
    catch_up : live only: skip a block while the device holds its prefill or more
        after it fell behind (an underrun, a slow clock), or while fresher blocks wait
        behind it, so that the delay comes back to the prefill (``device.link.catch_up``;
        skipped samples count as unplayed).

    Returns a ``device.link.devices.OutputDevice`` (the built-ins a :class:`CommandSink`). Raises :class:`LinkError` (an OSError, exit 1) if the port
    cannot be opened or the device does not answer or does not fit the pipeline,
    ``UnknownName`` (an InputError) for a name no device is registered under.
    """
    request = DeviceRequest(channels=int(channels), rate_hz=float(rate_hz), phases=phases,
                            paced=paced, queue_blocks=queue_blocks, log_path=log_path,
                            faults=faults, stderr=stderr, stall_s=stall_s,
                            max_stalls=max_stalls, sim_args=tuple(sim_args), profile=profile,
                            prefill_s=prefill_s, catch_up=catch_up)
    return open_device(spec, request)

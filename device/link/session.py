"""The host side of the protocol for one link, sans I/O: handshake, heartbeats, paced
sending, the ledger, recoveries and the closing Stop (``device/PROTOCOL.md``).

:class:`HostSession` is driven by the port thread (``device.link.portthread``), which
only moves bytes: :meth:`~HostSession.connection_made` when a port opens,
:meth:`~HostSession.data_received` with what arrived, :meth:`~HostSession.poll` for what
to write now, :meth:`~HostSession.connection_lost` when the port fails. The caller's side
(``device.link.host.CommandSink``) queues blocks into it and reads its counters under
:attr:`HostSession.cond`. Every method takes the host's time ``now`` (s, monotonic).

Heartbeats go out every ``watchdog_ms / 5``; each Status is read against how far the host
had sent when its heartbeat left (``device.link.ledger``), so the estimate of the
device's buffer is re-based on every answer. A device that says nothing valid for
:data:`SILENCE_S`, or takes no block for that long while blocks wait, is handshaken
again (a *recovery*); a recovery or a reconnect that gets no answer within
:data:`RESYNC_TIMEOUT_S` is taken as the port lost (the thread reopens it). Hellos are
resent with back-off, :data:`HELLO_FIRST_S` doubling up to :data:`HELLO_MAX_S`.
"""

from __future__ import annotations

import collections
import sys
import threading
from dataclasses import dataclass

import numpy as np

from frictex.device.link import protocol as p
from frictex.device.link.catch_up import IndexMap, behind
from frictex.device.link.forces import ForceHistory, ForceReport, per_sample
from frictex.device.link.ledger import Ledger, Pacing, RunCounts, Snapshot
from frictex.device.link.protocol import DeviceState, LinkError

#: jitter-buffer prefill asked of the device, and the level paced sending keeps (s)
PREFILL_S = 0.010
TARGET_S = 0.040
#: the first Hello's wait for an answer, and the longest, doubling between (s)
HELLO_FIRST_S = 0.1
HELLO_MAX_S = 1.0
#: a recovery or reconnect handshake unanswered this long: the port is taken as lost (s)
RESYNC_TIMEOUT_S = 1.0
#: a connected device that sends nothing valid, or takes no block while blocks wait, for
#: this long is handshaken again (s)
SILENCE_S = 0.5
#: a device that closes the link this many times in a row during the first handshake,
#: with no valid frame between, fails it at once (not after the handshake's whole wait)
HANDSHAKE_CLOSES = 5
#: a gap this long between two turns of the port thread means the host was starved (s)
STARVED_S = 0.1
#: beyond the drain itself, how long the closing Stop may take to play out (s)
STOP_MARGIN_S = 0.5
#: times a Stop is sent again when a Status after it shows a device that is not stopping
STOP_RESENDS = 3
#: a close waits at most this many times the longest drain (the host's target level, the
#: ramp and the margin), however often its Stop is resent or however slowly the device
#: plays on
CLOSE_STRETCH = 2
#: most bytes of blocks written in one turn
_TURN_BYTES = 4096

_COUNTS = ("frames_sent", "blocks_sent", "heartbeats", "retries", "reconnects", "disconnects",
           "handshake_closes",
           "recoveries", "stalls", "device_flushes", "clamped_samples", "dropped_blocks",
           "force_reports", "resent_frames", "resends_too_late", "stop_resends",
           "skipped_blocks", "stale_statuses")
#: Blocks kept for resending, by sequence number (PROTOCOL.md 4.10)
RESEND_KEEP = 512
#: a Block is resent at most once in this long, however often it is asked for (s)
RESEND_HOLDOFF_S = 0.001
#: Heartbeat tokens run 1 .. this and start again (0 is a Stop's Status's echo)
_TOKENS = 0xFFFFFFFF


@dataclass(frozen=True)
class LinkProgress:
    """Where the samples handed to a link stood at one moment (samples).

    ``commanded``: handed to ``send``. ``sent``: written to the device; of those
    ``played`` (None: a version 1 device, which does not say) and ``refused`` (known
    never to play: flushed, late, overflow, lost). ``dropped``: never sent, dropped by
    the host (stalls, a lost link, a full live queue, catch-up). ``queued``: never sent,
    waiting at the host. The rest of the commanded samples were being handed over.
    """

    commanded: int
    sent: int
    played: int | None
    refused: int | None
    dropped: int
    queued: int

    def describe(self) -> str:
        """One clause: what was sent and played, and what never was sent."""
        unsent = self.commanded - self.sent
        if self.played is None:
            fate = "played unknown: a version 1 device"
        else:
            waiting = self.sent - self.played - (self.refused or 0)
            fate = (f"{self.played} played, {waiting} not reported played"
                    + (f", {self.refused} flushed, refused or lost" if self.refused else ""))
        handing = unsent - self.dropped - self.queued
        return (f"of {self.commanded} samples commanded, {self.sent} were sent ({fate}) and "
                f"{unsent} never sent ({self.dropped} dropped, {self.queued} queued"
                + (f", {handing} being queued" if handing else "") + ")")


class LinkStalled(LinkError):
    """The device made too little progress for too long (``device.link.stall``).

    ``progress``: a :class:`LinkProgress` of the link when it gave up, or None.
    """

    def __init__(self, message: str, progress: LinkProgress | None = None):
        super().__init__(message)
        self.progress = progress


def state_name(state: int) -> str | int:
    """A Status's ``state`` by its name in PROTOCOL.md 4.6, or the number it does not name."""
    return DeviceState.NAMES[state] if state < len(DeviceState.NAMES) else state


def _watchdog_problems(info: p.Info) -> list[str]:
    """How ``info``'s watchdog breaks PROTOCOL.md 5.3: it must trip (``watchdog_ms`` at
    least 1) and leave the plate still within ``protocol.MAX_STOP_MS`` of the host
    falling silent (``watchdog_ms + ramp_ms``); the host heartbeats every ``watchdog_ms / 5``."""
    if info.watchdog_ms < 1:
        return [f"watchdog_ms {info.watchdog_ms}: a watchdog that never trips"]
    if info.watchdog_ms + info.ramp_ms > p.MAX_STOP_MS:
        return [f"watchdog_ms {info.watchdog_ms} + ramp_ms {info.ramp_ms} over "
                f"{p.MAX_STOP_MS} ms (PROTOCOL.md 5.3: the plate must be still within "
                f"{p.MAX_STOP_MS} ms of the host falling silent)"]
    return []


class HostSession:
    """One link's protocol state and bookkeeping (see the module docstring).

    Parameters
    ----------
    channels, rate_hz, phases : what the pipeline sends (rate in Hz).
    paced : True for replay (blocks go out as the device's buffer has room).
    label : the link's name in messages. stderr : where warnings go.
    prefill_s : the jitter-buffer prefill asked of the device (s; at most a quarter of
        its buffer): a live stream's lead.
    catch_up : live only: skip blocks while the device is behind (``device.link.catch_up``).
    """

    def __init__(self, channels: int, rate_hz: float, *, phases: bool, paced: bool,
                 label: str, stderr=sys.stderr, prefill_s: float = PREFILL_S,
                 catch_up: bool = False):
        self.channels, self.rate_hz, self.phases, self.paced = channels, rate_hz, phases, paced
        self.prefill_s = float(prefill_s)
        self.catch_up = bool(catch_up) and not self.paced
        #: the host's sample numbers to the device's (they differ once a block was skipped)
        self.index_map = IndexMap()
        self.label = label
        self._stderr = stderr
        self.cond = threading.Condition()
        self.queue: collections.deque = collections.deque()
        # every key up front: status() copies these while the thread counts
        self.counts = collections.Counter(dict.fromkeys(_COUNTS, 0))
        self.errors = collections.Counter(dict.fromkeys([*p.ErrorCode.NAMES.values(), "other"], 0))
        self.ledger = Ledger()
        self.rtt_ms: collections.deque = collections.deque(maxlen=4096)
        self.decoder = p.Decoder(on_device=False)
        #: bytes received from the device (what a failed handshake heard, if anything)
        self.bytes_heard = 0
        self.forces = ForceHistory()
        self.forces_lock = threading.Lock()
        self.status: p.Status | None = None
        #: the device's counters, which count since it powered up, summed over this
        #: host's run from its first Status on (PROTOCOL.md 6.4)
        self.run_counts = RunCounts(("watchdog_trips", "underruns"))
        self.snapshot: Snapshot | None = None
        self.info: p.Info | None = None
        self.version = 1
        self.connected = False       # a session is open (blocks may be queued)
        self.failure: LinkError | None = None
        self.refused: LinkError | None = None   # a device that does not fit the pipeline
        self.device_said: str | None = None     # an ErrorReport's text during a handshake
        self.last_error: str | None = None
        self.phase = "closed"        # closed, handshake, session, closing, done
        self.close_requested = False
        #: close at once (an interrupted or failed run): Stop without drain, the device
        #: flushes what it holds and ramps to zero (PROTOCOL.md 4.5)
        self.abort_requested = False
        self._stopping_drained = False
        #: after a close: True if the device reported SILENT after its Stop, False if the
        #: close ended on its bound without (its watchdog stops the plate); None before
        self.stop_confirmed: bool | None = None
        self._marks: dict[int, tuple[float, int, int]] = {}  # token -> (t, sent_end, mark)
        self._token = 0
        self._answered = 0           # the token of the newest heartbeat answered
        self._seq = 0
        self.sent_end = 0            # the device's sample number after the last one sent
        # version 4 repair: seq -> [start, counts, phases, last sent at]; resend seq -> seq
        self._kept: collections.OrderedDict = collections.OrderedDict()
        self._alias: collections.OrderedDict = collections.OrderedDict()
        self._due: dict[int, None] = {}  # original seqs the device asked for, in order
        self._last_rx = self._last_progress = self._last_turn = 0.0
        # the longest the port thread went without a turn, and without a Status from the
        # device, while a session was open (s): a starved host or device, which no repair
        # outruns once it exceeds the device's lead
        self.longest_turn_gap_s = 0.0
        self.longest_status_gap_s = 0.0
        self._last_status = None
        self._next_hb = 0.0
        self._ever_connected = False
        self._reconnecting = False
        # the first handshake: Hellos sent, links closed in all and in a row with no frame
        self._first_hellos = 0
        self._first_closes = 0
        self._closes_in_a_row = 0

    # ------------------------------------------------------------------ port events
    def connection_made(self, now: float) -> None:
        """A port opened: handshake on it."""
        self._begin_handshake(now)

    def connection_lost(self, exc: BaseException) -> None:
        """The port failed (or a recovery went unanswered): the thread reopens it."""
        self.last_error = f"{type(exc).__name__}: {exc}"
        was = self.phase in ("session", "closing") or (self.phase == "handshake"
                                                       and self.connected)
        closing = self.phase == "closing" or self.close_requested
        self.phase = "closed"
        self._reconnecting = True
        if not was:
            self._count_handshake_close()
            return
        self.counts["disconnects"] += 1
        # said first: whoever sees the link disconnected can read why
        self._warn(f"link lost ({self.last_error}); output continues without it, reconnecting")
        with self.cond:  # the session is settled by the next handshake, or by close
            self.connected = False
            if not self.paced or closing:  # live blocks go stale; paced go out on reconnecting
                self._drop_queued("disconnected")
            self.cond.notify_all()

    def _count_handshake_close(self) -> None:
        """The link closed during the first handshake: counted, and the caller's wait
        woken once the device has closed it every time (:data:`HANDSHAKE_CLOSES`)."""
        if self._ever_connected:
            return
        self._first_closes += 1
        self.counts["handshake_closes"] += 1
        self._closes_in_a_row += 1
        if self.closes_every_time:
            with self.cond:
                self.cond.notify_all()

    @property
    def closes_every_time(self) -> bool:
        """The device closed the link :data:`HANDSHAKE_CLOSES` times in a row during the
        first handshake, with no valid frame between: waiting longer is pointless."""
        return not self._ever_connected and self._closes_in_a_row >= HANDSHAKE_CLOSES

    def finish_without_port(self) -> None:
        """Closing with no port: what is queued is dropped, the session settled."""
        with self.cond:
            self._drop_queued("disconnected")
            self.ledger.end_session()
            self.connected = False
            self.phase = "done"
            self.cond.notify_all()

    def data_received(self, data: bytes, now: float) -> None:
        self.bytes_heard += len(data)
        for frame in self.decoder.feed(data):
            self._closes_in_a_row = 0
            msg = frame.message
            if self.phase == "handshake" and isinstance(msg, p.Info):
                self._start_session(msg, now)
            elif self.phase == "handshake" and isinstance(msg, p.ErrorReport) and msg.text:
                self.device_said = msg.text
                self._handle(msg, now)
            elif isinstance(msg, (p.Info, p.Hello, p.Block, p.Heartbeat, p.Stop)):
                continue  # a late Info, or our own frames echoed back (loop://)
            else:
                self._handle(msg, now)

    def poll(self, now: float) -> bytes:
        """What to write now. Raises :class:`LinkError` when a recovery or reconnect
        handshake went unanswered (the port thread then reopens the port)."""
        if now - self._last_turn > STARVED_S:  # the thread did not run: not the device's silence
            self._last_rx = self._last_progress = now
        if self.phase == "session":
            self.longest_turn_gap_s = max(self.longest_turn_gap_s, now - self._last_turn)
        self._last_turn = now
        if self.phase == "handshake":
            return self._poll_handshake(now)
        if self.phase == "session":
            if self.close_requested:
                return self._begin_closing(now)
            out = self._poll_session(now)
            self._watch(now)
            return out
        if self.phase == "closing":
            return self._poll_closing(now)
        return b""

    @property
    def done(self) -> bool:
        """The closing Stop has played out (or was given up): the thread may end."""
        return self.phase == "done"

    # ------------------------------------------------------------------ handshake
    def _begin_handshake(self, now: float) -> None:
        self.phase = "handshake"
        self._hs_start = now
        self._hello_at = now
        self._hello_wait = HELLO_FIRST_S
        self._hellos = 0
        self._settling = None  # token of the settling heartbeat; popped when answered

    def _poll_handshake(self, now: float) -> bytes:
        """Send Hello (in a version 1 frame: every device answers it) until Info comes
        back; the device flushes its buffer and restarts its counters on Hello.

        If a session is open (a recovery or a reconnect), a Heartbeat goes out just before
        each Hello, in the same write, until one is answered: the Status answering it
        settles the session with the device's counters as of the Hello (PROTOCOL.md 6.1).
        """
        if self._ever_connected and now - self._hs_start > RESYNC_TIMEOUT_S:
            raise LinkError(f"{self.label}: no answer to the handshake within "
                            f"{RESYNC_TIMEOUT_S:g} s")
        if self.close_requested and self._ever_connected:
            self.finish_without_port()
            return b""
        if now < self._hello_at:
            return b""
        if self._hellos:
            self.counts["retries"] += 1
        self._hellos += 1
        self._first_hellos += not self._ever_connected
        self._hello_at = now + self._hello_wait
        self._hello_wait = min(2.0 * self._hello_wait, HELLO_MAX_S)
        settle = b""
        if self.ledger.reporting and (self._settling is None or self._settling in self._marks):
            settle = self._heartbeat(now)
            self._settling = self._token
        # a leading delimiter ends whatever partial frame the device was holding
        return b"\x00" + settle + self._frame(p.Hello(int(self.prefill_s * self.rate_hz)), 1)

    def handshake_failure(self, waited_s: float, injected: str | None = None) -> LinkError:
        """Why the first handshake failed after ``waited_s`` (s), for the caller;
        ``injected``: the faults injected on the link (``--faults`` text), named as what
        may have kept a device from answering, or None."""
        suspect = ("is it a frictex device?" if injected is None else
                   f"the faults injected (--faults {injected}) may have kept it from answering")
        if self.refused is not None:
            return self.refused
        bad = self.decoder.counts.last_bad_version
        if bad is not None:
            return LinkError(f"{self.label}: device speaks protocol version {bad}; this host "
                             f"speaks 1 to {p.PROTOCOL_VERSION}")
        if self.device_said is not None:
            return LinkError(f"{self.label}: the device refused the handshake: "
                             f"{self.device_said!r}")
        if self._first_closes:
            times = "once" if self._first_closes == 1 else f"{self._first_closes} times"
            return LinkError(f"{self.label}: the device closed the link {times} "
                             f"during the handshake, in {waited_s:.3g} s (last: "
                             f"{self.last_error}); {suspect}")
        if self.bytes_heard and not self.decoder.counts.frames_ok:
            thrown = self.decoder.counts.discarded
            return LinkError(f"{self.label}: no answer to the handshake within {waited_s:.3g} "
                             f"s ({self._first_hellos} Hellos): {self.bytes_heard} bytes came "
                             f"back, none of them a valid frame ({thrown} malformed "
                             f"frame{'s' * (thrown != 1)} thrown away); "
                             + (suspect if injected is not None else
                                "is the baud rate right, and is it a frictex device?"))
        return LinkError(f"{self.label}: no answer to the handshake within {waited_s:.3g} s "
                         f"({self._first_hellos} Hellos); {suspect}")

    def _check(self, info: p.Info) -> LinkError | None:
        """Why the device that sent ``info`` cannot be driven by this host, or None."""
        if info.protocol_version < 1:
            return LinkError(f"{self.label} ({info.name or 'unnamed'}) says protocol version "
                             f"{info.protocol_version}; this host speaks 1 to "
                             f"{p.PROTOCOL_VERSION}")
        problems = _watchdog_problems(info)
        if info.channels != self.channels:  # a Block carries exactly Info.channels (4.3)
            problems.append(f"{info.channels} channel(s), the pipeline sends {self.channels}")
        if self.phases and not info.has_phases:
            problems.append("no phase control, the actuation has phases")
        if abs(info.sample_rate_hz - self.rate_hz) > 1e-3:
            problems.append(f"sample rate {info.sample_rate_hz:g} Hz, the pipeline runs at "
                            f"{self.rate_hz:g} Hz")
        if problems:
            return LinkError(f"{self.label} ({info.name or 'unnamed'}) has " + "; ".join(problems))
        return None

    def _start_session(self, info: p.Info, now: float) -> None:
        refused = self._check(info)
        if refused is not None:
            self.refused = refused
            return
        self.info = info
        self.version = min(info.protocol_version, p.PROTOCOL_VERSION)
        self._limits = np.asarray(info.limits_um[:self.channels], dtype=np.float64)
        prefill = max(1, min(int(self.prefill_s * info.sample_rate_hz), info.buffer_samples // 4))
        self.target = max(prefill + 1,
                          min(int(TARGET_S * info.sample_rate_hz), info.buffer_samples // 2))
        self._pacing = Pacing(info.sample_rate_hz, self.target, prefill, info.buffer_samples // 2)
        self._heartbeat_s = max(info.watchdog_ms / 5.0, 1.0) * 1e-3
        self._marks.clear()
        self._kept.clear()  # the device forgot what it missed on Hello
        self._alias.clear()
        self._due.clear()
        self._last_rx = self._last_progress = now
        self._last_status = None
        self._next_hb = now
        if not info.has_force_reports:
            with self.forces_lock:
                self.forces = ForceHistory()
        if self._reconnecting and self._ever_connected:
            self.counts["reconnects"] += 1
            print(f"frictex: {self.label} link back", file=self._stderr)
        elif self._first_closes:
            self._warn(f"the link closed {self._first_closes} time(s) during the first "
                       f"handshake (last: {self.last_error}) before the device answered")
        self._reconnecting = False
        self._ever_connected = True
        self.phase = "session"
        with self.cond:
            self.snapshot = None
            self.ledger.start_session()
            self.connected = True
            self.cond.notify_all()

    @property
    def limits_um(self) -> np.ndarray:
        """The device's declared limits for the pipeline's channels (um)."""
        return self._limits

    # ------------------------------------------------------------------ frames
    def _frame(self, msg, version: int | None = None) -> bytes:
        data = p.encode(msg, self._seq, self.version if version is None else version)
        self._seq = (self._seq + 1) & 0xFFFF
        self.counts["frames_sent"] += 1
        return data

    def _heartbeat(self, now: float) -> bytes:
        """A Heartbeat frame, its token remembered with how far the host had sent."""
        self._token = self._token % _TOKENS + 1   # never 0: a Stop's Status echoes 0
        self.counts["heartbeats"] += 1
        self._marks[self._token] = (now, self.sent_end, self.ledger.mark())
        if len(self._marks) > 64:
            self._marks.pop(next(iter(self._marks)))
        return self._frame(p.Heartbeat(self._token))

    def _warn(self, text: str) -> None:
        print(f"frictex: warning: {self.label}: {text}", file=self._stderr)

    def _drop_queued(self, cause: str) -> None:
        """Drop every queued block (counted); the caller holds ``cond``."""
        while self.queue:
            _, counts, _ = self.queue.popleft()
            self.counts["dropped_blocks"] += 1
            self.ledger.drop(cause, len(counts))
        self.cond.notify_all()

    def _handle(self, msg, now: float) -> None:
        self._last_rx = now
        if isinstance(msg, p.Status):
            if self._stale(msg):
                return
            self.status = msg
            self.run_counts.status(msg)
            if self.phase == "session" and self._last_status is not None:
                self.longest_status_gap_s = max(self.longest_status_gap_s,
                                                now - self._last_status)
            self._last_status = now
            mark = self._marks.pop(msg.echo, None)
            if mark is not None:
                self._answered = msg.echo
                sent_t, sent_end, ledger_mark = mark
                self.rtt_ms.append((now - sent_t) * 1e3)
                with self.cond:
                    self.snapshot = Snapshot.from_status(msg, 0.5 * (now + sent_t), sent_end,
                                                         ledger_mark)
                    self.ledger.status(msg, ledger_mark)
        elif isinstance(msg, p.Flushed):
            self.counts["device_flushes"] += 1
            with self.cond:
                self.snapshot = Snapshot.flushed(msg.play_index, now, self.sent_end,
                                                 self.ledger.mark())
        elif isinstance(msg, p.ForceReport):
            if self.info is not None and self.info.has_force_reports:
                self.counts["force_reports"] += 1
                report = per_sample(msg, self.sent_end)
                runs = self.index_map.host_runs(report.index0, report.lateral_n.size)
                with self.forces_lock:
                    for host, lo, hi in runs:
                        self.forces.add(ForceReport(host, report.lateral_n[lo:hi],
                                                    report.normal_n[lo:hi]))
        elif isinstance(msg, p.ErrorReport):
            self.errors[p.ErrorCode.NAMES.get(msg.code, "other")] += 1
        elif isinstance(msg, p.Missing):
            for seq in msg.seqs:
                orig = self._alias.get(seq, seq)
                if orig in self._kept:
                    self._due[orig] = None

    def _stale(self, st: p.Status) -> bool:
        """Whether Status ``st`` answers a heartbeat sent before the newest one answered
        (counted, said once). The byte stream keeps order (PROTOCOL.md 6.1), so only a
        faulty device sends one; read, it would take the device's buffer and counters
        back, and their fall would read as a wrap of 2**32 (the whole count added again).
        Counters that go back under an echo in order are a device that reset them (6.3),
        as one that restarted without closing the port does."""
        if not (st.echo and 0 < (self._answered - st.echo) % _TOKENS < _TOKENS // 2):
            return False
        self.counts["stale_statuses"] += 1
        if self.counts["stale_statuses"] == 1:
            self._warn(f"a Status from the device arrived out of order (it answers heartbeat "
                       f"{st.echo} after {self._answered} was answered); Statuses older than "
                       "one already read are ignored (stale_statuses)")
        return True

    # ------------------------------------------------------------------ streaming
    def _poll_session(self, now: float) -> bytes:
        out = bytearray()
        if now >= self._next_hb:
            out += self._heartbeat(now)
            self._next_hb = now + self._heartbeat_s
        if self._due:
            resent = self._resends(now)
            if resent:  # and a Heartbeat after them: the answer says at once what is still missing
                out += resent + self._heartbeat(now)
                self._next_hb = now + self._heartbeat_s
        taken = 0  # blocks sent or skipped
        with self.cond:
            queued = sum(len(counts) for _, counts, _ in self.queue) if self.catch_up else 0
            # blocks wait for the session's first Status: it is the counters' baseline
            while self.queue and len(out) < _TURN_BYTES and self.ledger.reporting:
                start, counts, phases = self.queue[0]
                if self.paced and not self.snapshot.room(
                        self._pacing, now, self.sent_end, self.ledger.mark(), start, len(counts)):
                    break
                self.queue.popleft()
                queued -= len(counts)  # the samples queued behind this block
                taken += 1
                if self.catch_up and behind(self.snapshot, now, self.rate_hz, self.sent_end,
                                            self._pacing.prefill, queued):
                    self._skip(start, len(counts))
                    continue
                out += self._send_block(self.index_map.to_device(start), counts, phases)
            if taken:
                self.cond.notify_all()
        if not self.queue or taken:
            self._last_progress = now
        return bytes(out)

    def _skip(self, start: int, n: int) -> None:
        """Host samples ``start ..`` (``n``) not sent: the device is behind (catch-up,
        PROTOCOL.md 6.1); the caller holds ``cond``."""
        self.counts["skipped_blocks"] += 1
        self.ledger.drop("skipped", n)
        self.index_map.skip(start, n)

    def _send_block(self, start: int, counts, phases) -> bytes:
        """A Block frame for samples ``start ..`` (the device's numbers), kept for
        resending (version 4); the caller holds ``cond``."""
        self.counts["blocks_sent"] += 1
        self.ledger.sent(len(counts))
        self.sent_end = max(self.sent_end, start + len(counts))
        if self.version >= 4:
            self._kept[self._seq] = [start, counts, phases, -1.0]
            if len(self._kept) > RESEND_KEEP:
                self._kept.popitem(last=False)
        return self._frame(p.Block(start % p.INDEX_MODULUS, counts, phases))

    def _resends(self, now: float) -> bytes:
        """Resend frames for the Blocks the device asked for (PROTOCOL.md 4.10): each
        at most once per :data:`RESEND_HOLDOFF_S` (the device asks again with every Status
        while it still misses one, and a Heartbeat follows the resends), and only while its samples can still play (estimated from
        the last Status: a later one is dropped, counted)."""
        out = bytearray()
        played = None
        if self.snapshot is not None:
            played, _ = self.snapshot.level(now, self.rate_hz, self.sent_end)
        for orig in list(self._due):
            entry = self._kept.get(orig)
            if entry is not None and now - entry[3] < RESEND_HOLDOFF_S:
                continue  # asked again before the last resend could arrive: wait a little
            del self._due[orig]
            if entry is None:
                continue
            start, counts, phases, _ = entry
            if played is not None and start + len(counts) <= played:
                self.counts["resends_too_late"] += 1
                del self._kept[orig]
                continue
            entry[3] = now
            self._alias[self._seq] = orig
            if len(self._alias) > RESEND_KEEP:
                self._alias.popitem(last=False)
            self.counts["resent_frames"] += 1
            out += self._frame(p.Resend(start % p.INDEX_MODULUS, counts, phases, orig))
        return bytes(out)

    def _watch(self, now: float) -> None:
        """Handshake again with a device that went quiet or stopped taking blocks."""
        if now - self._last_rx > SILENCE_S:
            self._resync(f"no valid frame from the device for {now - self._last_rx:.2f} s", now)
        elif self.queue and now - self._last_progress > SILENCE_S:
            snap, start = self.snapshot, self.queue[0][0]
            where = ("no Status yet" if snap is None else
                     f"device at {snap.play_index}, holding {snap.held} up to {snap.end}, "
                     f"{'playing' if snap.playing else 'waiting'}; next block {start}")
            self._resync(f"device took no block for {now - self._last_progress:.2f} s "
                         f"({where})", now)

    def _resync(self, reason: str, now: float) -> None:
        self.counts["recoveries"] += 1
        self._warn(f"{reason}; handshaking again")
        self._begin_handshake(now)

    # ------------------------------------------------------------------ closing
    def _begin_closing(self, now: float) -> bytes:
        """Send what a live queue still holds (a paced one was drained or given up by the
        caller), then Stop with drain; heartbeats follow until the device reports silence
        (bounded), so that the last Status settles the ledger. Aborting: nothing more is
        sent, and the Stop flushes and ramps at once."""
        out = bytearray()
        with self.cond:
            while (self.queue and self.ledger.reporting and not self.paced
                   and not self.abort_requested):
                start, counts, phases = self.queue.popleft()
                out += self._send_block(self.index_map.to_device(start), counts, phases)
            self._drop_queued("stalled")
        self._close_limit = now + self.close_limit_s()
        self._close_seen = self.snapshot.play_index if self.snapshot else None
        out += self._stop(now)
        self._next_hb = now
        self.phase = "closing"
        return bytes(out)

    def close_limit_s(self) -> float:
        """The longest a close may take once begun (s): :data:`CLOSE_STRETCH` times the
        drain of the most the host keeps sent ahead of the device, its target level
        (aborting: times the ramp and the margin, nothing is drained). The buffer the
        device declares does not lengthen it: a device that declares a vast one and
        creeps on after the Stop would otherwise hold the close for days."""
        held = 0 if self.abort_requested else self.target
        return CLOSE_STRETCH * self._play_out_s(held)

    def _stop(self, now: float) -> bytes:
        """A Stop, drained unless aborting; a Status that echoes a later Heartbeat tells
        whether it arrived."""
        drain = not self.abort_requested
        self._stopping_drained = drain
        self._first_after_stop = self._token + 1
        self._close_by = now + (self._drain_s() if drain else self._play_out_s(0))
        return self._frame(p.Stop(drain=drain))

    def _poll_closing(self, now: float) -> bytes:
        if self.abort_requested and self._stopping_drained:
            # an abort during a drained close: flush and ramp now (PROTOCOL.md 4.5)
            self._close_limit = min(self._close_limit, now + self.close_limit_s())
            return self._stop(now) + self._heartbeat(now)
        st = self.status
        answered = st is not None and st.echo >= self._first_after_stop
        if st is not None and st.play_index != self._close_seen:
            # the device plays on, slower than its clock promised (a starved emulator):
            # its drain is waited for while it lasts, up to the close's limit
            self._close_seen = st.play_index
            self._close_by = max(self._close_by, now + STOP_MARGIN_S)
        silent = answered and st.state == DeviceState.SILENT
        if silent or now >= min(self._close_by, self._close_limit):
            self._end_close(silent)
            return b""
        out = self._resends(now) if self._due else b""
        if (answered and st.state != DeviceState.DRAINING
                and self.counts["stop_resends"] < STOP_RESENDS):
            # The Stop was lost on the wire, or a watchdog trip cut its drain short (the
            # next Heartbeat took the device back to BUFFERING): neither is stopping.
            self.counts["stop_resends"] += 1
            out += self._stop(now)
        if now < self._next_hb:
            return out
        self._next_hb = now + self._heartbeat_s
        return out + self._heartbeat(now)

    def _end_close(self, silent: bool) -> None:
        """The close is over: ``silent``, the device confirmed its Stop; otherwise its
        bound ran out, and the plate is left to the device's watchdog (said)."""
        if not silent:
            st = self.status
            last = "no Status" if st is None else f"last state {state_name(st.state)}"
            self._warn(f"the device did not confirm it stopped ({last}); relying on its "
                       f"watchdog ({self.info.watchdog_ms} ms)")
        with self.cond:
            self.stop_confirmed = silent
            self.ledger.end_session()
            self.phase = "done"
            self.cond.notify_all()

    def _drain_s(self) -> float:
        """Time for a drained Stop to play out: what the host has outstanding (sent, not
        reported played; at most its target level, whatever the device reports), the
        ramp, a margin."""
        buffered = self.sent_end - (self.snapshot.play_index if self.snapshot else 0)
        return self._play_out_s(min(max(buffered, 0), self.target))

    def _play_out_s(self, samples: int) -> float:
        """Time for ``samples`` buffered to play, the ramp to run and a margin (s)."""
        return samples / self.rate_hz + self.info.ramp_ms * 1e-3 + STOP_MARGIN_S

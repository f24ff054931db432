"""What the host knows of the device's buffer: pacing estimate and where each sample went.

Pure bookkeeping for :class:`~device.link.host.CommandSink`, on times and counts it is
given (no clock, no I/O), so tests drive it directly.

Both halves rest on one fact of the byte stream: frames arrive in the order they were
written. A Heartbeat written after block B reaches the device after B, so the Status
answering it describes a buffer that already holds B (or lost it). The host remembers,
per heartbeat, how far it had sent (its *mark*); a Status is read against its mark. A
Status that arrives out of order (a faulty device) never reaches it: the session ignores it.

Sample numbers are the host's (unbounded integers from the caller); the device's are
modulo 2**64 and are mapped back with :func:`unwrap`.
"""

from __future__ import annotations

import collections
from dataclasses import dataclass

from frictex.device.link.protocol import INDEX_MODULUS, DeviceState

#: why a commanded sample was never played (``CommandSink.status()["unplayed_by_cause"]``)
CAUSES = ("disconnected", "queue_full", "stalled", "skipped", "flushed", "late", "overflow",
          "lost")
_HOST_CAUSES = CAUSES[:4]
_COUNTER_WRAP = 2 ** 32


def unwrap(device_index: int, near: int) -> int:
    """The host sample number congruent to ``device_index`` modulo 2**64 nearest ``near``."""
    offset = (device_index - near + INDEX_MODULUS // 2) % INDEX_MODULUS - INDEX_MODULUS // 2
    return near + offset


@dataclass(frozen=True)
class Pacing:
    """A paced host's limits, in samples at ``rate_hz``: keep at most ``target`` buffered;
    a device that waits for ``prefill`` samples (BUFFERING) gets blocks up to ``window``
    ahead of its play position, so it reaches its prefill across holes left by lost
    blocks (a version 4 device has them resent, PROTOCOL.md 4.10; an older one never
    fills a hole)."""

    rate_hz: float
    target: int
    prefill: int
    window: int


@dataclass(frozen=True)
class Snapshot:
    """The device's buffer as of host time ``t_s`` (s): it plays ``play_index`` next,
    holds ``held`` samples up to ``end`` (exclusive); ``playing``: its clock advances
    ``play_index``. ``mark_end`` / ``mark_count``: how far the host had sent (sample
    number after the last, samples this session) when the device's report left it;
    anything sent beyond is still on its way."""

    t_s: float
    play_index: int
    end: int
    held: int
    playing: bool
    mark_end: int
    mark_count: int

    @classmethod
    def from_status(cls, st, t_s: float, mark_end: int, mark_count: int) -> Snapshot:
        """From a Status answering a heartbeat sent at mark (``mark_end``,
        ``mark_count``); version 1 Statuses lack ``buffer_end`` and give ``play + level``.

        A device that holds, played and flushed nothing since its Hello has no origin in
        this session yet (its first block sets it, PROTOCOL.md 5.1): its ``play_index``
        is where its last session ended, not where this one plays. It is taken as empty
        at ``mark_end``, so its first block goes out and the next Status places it."""
        if st.accounted and st.level == 0 and st.played_samples == 0 and st.flushed_samples == 0:
            return cls(t_s, mark_end, mark_end, 0, False, mark_end, mark_count)
        play = unwrap(st.play_index, mark_end)
        end = unwrap(st.buffer_end, mark_end) if st.accounted else play + st.level
        return cls(t_s, play, max(end, play), st.level,
                   st.state in (DeviceState.PLAYING, DeviceState.DRAINING), mark_end,
                   mark_count)

    @classmethod
    def flushed(cls, play_index: int, t_s: float, sent_end: int, sent_count: int) -> Snapshot:
        """After a Flushed message: empty at ``play_index``; what was sent before it
        arrived is taken as flushed (an underestimate of the level at worst, which
        the next Status corrects).

        A device plays nothing it was not sent: a ``play_index`` past ``sent_end`` is
        where its last session ended (a watchdog trip before this session's first
        block set its origin), and it is taken as empty at ``sent_end``, as
        :meth:`from_status` takes a device with no origin."""
        play = min(unwrap(play_index, sent_end), sent_end)
        return cls(t_s, play, play, 0, False, sent_end, sent_count)

    def level(self, now_s: float, rate_hz: float, sent_end: int,
              horizon: int | None = None) -> tuple[int, int]:
        """(estimated play index now, estimated buffer end) given the host has sent up to
        ``sent_end``; the play index is extrapolated at most ``horizon`` samples past the
        report (None: no limit)."""
        end = max(self.end, sent_end) if sent_end > self.mark_end else self.end
        played = self.play_index
        if self.playing:
            ahead = int(max(now_s - self.t_s, 0.0) * rate_hz)
            played += ahead if horizon is None else min(ahead, horizon)
        return min(played, end), end

    def room(self, pacing: Pacing, now_s: float, sent_end: int, sent_count: int, start: int,
             n: int) -> bool:
        """May block ``[start, start + n)`` go out? Yes if the estimated buffer is empty
        (the device jumps to a block ahead), if the buffer stays at or below the target,
        or if the device waits for its prefill (counting what is on its way) and the
        block lands within the window. Without fresh reports nothing goes out beyond the
        window past the last reported play index: a device that stopped (or whose
        reports are lost) is never overfilled."""
        played, end = self.level(now_s, pacing.rate_hz, sent_end,
                                 horizon=pacing.window - pacing.target)
        if end <= played or start + n - played <= pacing.target:
            return True
        starving = (not self.playing
                    and self.held + sent_count - self.mark_count < pacing.prefill)
        return starving and start + n - played <= pacing.window


def _delta(new: int, old: int) -> int:
    """Increase of a device counter that wraps at 2**32. A counter that went back (a
    "wrap" of 2**31 or more, which no device plays between two Statuses) restarted."""
    return new if _went_back(new, old) else (new - old) % _COUNTER_WRAP


def _went_back(new: int, old: int) -> bool:
    """Whether a device counter that wraps at 2**32 went from ``old`` back to ``new``."""
    return (new - old) % _COUNTER_WRAP >= _COUNTER_WRAP // 2


class RunCounts:
    """The device's since-power-up counters ``names`` (Status fields, PROTOCOL.md 6.4)
    summed over one host's run: their increases from this host's first Status on, over
    every power-up of the device the host met.

    A device that comes back on a reconnect (the same power-up) goes on counting, so its
    increase is read against the last Status. One that restarted (powered up again: a new
    ``frictex sim-device`` process, a reset board) counts from 0 again: every count it
    reports is new. The host tells it by ``frames_ok``, which counts since power-up and
    which every session raises (its Hello and Heartbeats): it went back. A single counter
    that went back on its own is read as restarted too (:func:`_delta`).
    """

    def __init__(self, names: tuple[str, ...]):
        self.totals = dict.fromkeys(names, 0)
        self._prev = None

    def status(self, st) -> None:
        """A Status ``st`` arrived (the first one is the baseline)."""
        prev, self._prev = self._prev, st
        if prev is None:
            return
        restarted = _went_back(st.frames_ok, prev.frames_ok)
        for name in self.totals:
            new = getattr(st, name)
            self.totals[name] += new if restarted else _delta(new, getattr(prev, name))


class _Session:
    """One handshake's worth of samples sent, read against the device's counters."""

    def __init__(self):
        self.sent = 0
        self.first = None           # the first Status: the counters' baseline
        self.totals = collections.Counter()
        self.prev = None
        self.level = 0
        self.sent_at_mark = 0
        self.accounted = True

    def status(self, st, sent_at_mark: int) -> None:
        if self.first is None:
            self.first = self.prev = st
        fields = {"late": "late_samples", "overflow": "overflow_samples"}
        if st.accounted:
            fields |= {"played": "played_samples", "flushed": "flushed_samples"}
        else:
            self.accounted = False
        for key, name in fields.items():
            self.totals[key] += _delta(getattr(st, name), getattr(self.prev, name) or 0)
        # the Status answers a heartbeat written after the samples of its mark, and no
        # others: a device that says it played more is not believed
        self.totals["played"] = min(self.totals["played"], sent_at_mark)
        self.prev = st
        self.level = st.level
        self.sent_at_mark = sent_at_mark

    def lost(self, final: bool) -> int:
        """Sent but not accounted for; ``final``: the session is over, so samples still
        held or in flight at the last Status count too (their fate is unknown)."""
        if not self.accounted:
            return 0
        t = self.totals
        settled = t["played"] + t["flushed"] + t["late"] + t["overflow"]
        if final:
            return max(self.sent - settled, 0)
        return max(self.sent_at_mark - settled - self.level, 0)


class Ledger:
    """Where every commanded sample went (PROTOCOL.md section 6, "unplayed samples").

    ``commanded = played + unplayed + pending``, pending being samples queued, in flight
    or buffered whose fate is not known yet (0 once the link has closed after a drained
    Stop). Host causes are exact; device causes come from the device's counters read
    against the host's marks; ``lost`` is the rest (corrupted or dropped on the wire,
    refused, or held or in flight when a session ended: the host sends a Heartbeat just
    before the Hello that ends one, so samples played up to that Hello count as played).
    With a version 1 device,
    ``played``, ``flushed`` and ``lost`` are unknown (None).
    """

    def __init__(self):
        self.commanded = 0
        self.sent_total = 0
        self.host = collections.Counter()
        self.done = collections.Counter()
        self.partial = False
        self._session: _Session | None = None

    def command(self, n: int) -> None:
        """``n`` samples handed to ``send``."""
        self.commanded += n

    def drop(self, cause: str, n: int) -> None:
        """``n`` samples the host dropped for ``cause`` (one of the host causes)."""
        if cause not in _HOST_CAUSES:
            raise ValueError(f"cause {cause!r}: the host drops for {', '.join(_HOST_CAUSES)}")
        self.host[cause] += n

    def start_session(self) -> None:
        """A handshake completed: the device's since-Hello counters start from zero."""
        self.end_session()
        self._session = _Session()

    def sent(self, n: int) -> None:
        """``n`` samples written to the device in the current session."""
        self._session.sent += n
        self.sent_total += n

    def mark(self) -> int:
        """Samples sent in this session so far (taken when a heartbeat goes out)."""
        return self._session.sent if self._session is not None else 0

    @property
    def reporting(self) -> bool:
        """A Status has arrived in the current session (its counters have a baseline)."""
        return self._session is not None and self._session.first is not None

    def status(self, st, mark: int) -> None:
        """A Status answering a heartbeat whose :meth:`mark` was ``mark``."""
        if self._session is not None:
            self._session.status(st, mark)

    def end_session(self) -> None:
        """The session ended (link lost, reset or closed): settle it."""
        s = self._session
        if s is None:
            return
        self.partial |= not s.accounted
        self.done.update(s.totals)
        self.done["lost"] += s.lost(final=True)
        self._session = None

    def _device(self) -> collections.Counter:
        out = collections.Counter(self.done)
        s = self._session
        if s is not None:
            out.update(s.totals)
            out["lost"] += s.lost(final=False)
        return out

    def breakdown(self) -> dict[str, int | None]:
        """Unplayed samples by cause (None: not reported by a version 1 device)."""
        device = self._device()
        partial = self.partial or (self._session is not None and not self._session.accounted)
        out = {cause: self.host[cause] for cause in _HOST_CAUSES}
        for cause in ("flushed", "late", "overflow", "lost"):
            out[cause] = None if partial and cause in ("flushed", "lost") else device[cause]
        return out

    @property
    def played(self) -> int | None:
        """Samples the device confirmed playing (None with a version 1 device)."""
        device = self._device()
        partial = self.partial or (self._session is not None and not self._session.accounted)
        return None if partial else device["played"]

    @property
    def unplayed(self) -> int | None:
        """Commanded samples that never played (every cause summed); None when a cause is
        unknown (a version 1 device: ``flushed`` and ``lost``)."""
        causes = self.breakdown().values()
        return None if None in causes else sum(causes)

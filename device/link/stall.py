"""When a paced link gives up: time without progress, not failures in a row.

A paced stream (replay) hands blocks to the link faster than the device plays them, so
blocks wait while the device plays at its sample rate. While blocks wait, every second
of wall time should bring a second of played samples; the shortfall is *time without
progress*. :class:`StallPolicy` adds it up (played time credited back as it comes) and
fails the link once it exceeds ``give_up_s`` plus ``share`` of the time played:

    lag = sum over the time blocks waited of (dt - samples played in dt / rate)
    fail when lag > give_up_s + share * played_s

Bound: blocks wait for at most ``played_s + lag`` of wall time, so a paced stream of
``T`` s of samples spends at most ``(1 + share) T + give_up_s`` waiting on its device
before it has played or the link has failed; with the defaults (``share`` 0.25,
``give_up_s`` 5 s from ``stall_s`` 1 s x 5), a 10 s trace at most 17.5 s. A link that
comes back and loses again does not reset it (the old rule, five failed waits in a row,
never fired then). A clean link keeps ``lag`` near the jitter buffer's prefill. Time the
caller spends computing (no block waiting) never counts: a slow pipeline is not a stall;
nor does time the caller's process was stopped (:meth:`StallPolicy.skip`).

Pure: it is given times and counts (no clock).
"""

from __future__ import annotations

from dataclasses import dataclass

#: share of the time played that a paced link may lose to waiting without progress
SHARE = 0.25


@dataclass
class StallPolicy:
    """Time without progress of one paced stream (see the module docstring).

    rate_hz : the device's sample rate (Hz). give_up_s : lag allowed beyond ``share``
    of the time played (s). share : see the module docstring.
    """

    rate_hz: float
    give_up_s: float
    share: float = SHARE
    lag_s: float = 0.0
    played_s: float = 0.0
    _t: float | None = None

    def account(self, now: float, played: int, waiting: bool) -> None:
        """At host time ``now`` (s): ``played`` samples played since the last call,
        ``waiting``: blocks waited to go out (or to be played) over that interval."""
        gained = played / self.rate_hz
        self.played_s += gained
        if waiting and self._t is not None:
            self.lag_s = max(self.lag_s + (now - self._t) - gained, 0.0)
        self._t = now

    def skip(self, seconds: float) -> None:
        """Leave ``seconds`` (s) of the interval since the last call out of the lag: time
        this process was stopped, when no one waited on the device."""
        if self._t is not None:
            self._t += seconds

    @property
    def allowed_s(self) -> float:
        """The lag at which the link gives up now (s)."""
        return self.give_up_s + self.share * self.played_s

    @property
    def failed(self) -> bool:
        return self.lag_s > self.allowed_s

    def describe(self) -> str:
        """One line for the error: the lag against the bound."""
        return (f"{self.lag_s:.2f} s without progress while blocks waited, over the bound "
                f"of {self.give_up_s:g} s + {self.share:g} x {self.played_s:.2f} s played")

"""What the demo says about its device link, read from the link's status
(``device.link.host.CommandSink.status``) as the haptic side hands it over with its
snapshots: the clamps it made to the device's limit, the times the device ran dry, a limit
below the scene's, and the link going down or stalling and coming back.

:class:`LinkWatch` turns successive statuses into events for ``events.csv``
(``link-lost``, ``link-back``, ``link-stalled``, ``link-moving``) and the alarm the
window shows while the link is down or stalled. A loss and a return are read from the
link's ``disconnects`` and ``reconnects`` counters, so that one shorter than the
status's period is not missed; a stall from its ``state`` (``stalled``: queued blocks
have not moved for over 0.5 s, PROTOCOL.md 6.4).
"""

from __future__ import annotations


def device_clamps(link: dict) -> str:
    """The amplitude values the link clamped to its device's limit (a link's status),
    said apart from the pipeline's clamps as a replay says them: " by the friction
    inversion and 1234 by the device's limit", or "" when it clamped none."""
    clamped = link.get("clamped_samples") or 0
    return f" by the friction inversion and {clamped} by the device's limit" if clamped else ""


def run_underruns(link: dict) -> int:
    """The times the output device ran dry during the run, from its status: a device
    link's ``underruns_in_run`` (summed over the device's power-ups: a device restarted
    mid-run counts from 0 again, PROTOCOL.md 6.4), another output's ``underruns``; 0
    when neither says."""
    return link.get("underruns_in_run", link.get("underruns")) or 0


def limit_warning(link: dict, scene) -> str | None:
    """A warning when the device's declared amplitude limit (um, the link's Info) is
    below ``scene``'s ``amplitude_limit_um``: the link then clamps what the scene
    commands above it. None when it is not (or no device has answered yet)."""
    limits = list((link.get("device") or {}).get("limits_um") or [])
    wanted = scene.device.amplitude_limit_um
    if not limits or min(limits) >= wanted:
        return None
    said = (f"{limits[0]:.4g} um limit" if len(set(limits)) == 1 else
            "limits (" + ", ".join(f"{um:.4g}" for um in limits) + " um by channel)")
    return (f"the device's {said} is below {scene.name}'s amplitude limit of {wanted:.4g} um: "
            "the plate gets at most that where the scene commands more (counted as clamped "
            "by the device's limit)")


class LinkWatch:
    """The link's losses, returns and stalls from its successive statuses."""

    def __init__(self):
        self._disconnects = 0
        self._reconnects = 0
        self._stalled = False
        #: what the window shows while the link is down or stalled, else None
        self.alarm: str | None = None

    def update(self, link: dict) -> list[tuple[str, str]]:
        """The events since the last status (``link``): (event, detail) in order."""
        events = []
        if "disconnects" not in link:  # no device, or none answered yet
            return events
        for _ in range(link["disconnects"] - self._disconnects):
            events.append(("link-lost", link.get("last_error") or "port failed"))
        for _ in range(link["reconnects"] - self._reconnects):
            events.append(("link-back", "the device answered again"))
        self._disconnects, self._reconnects = link["disconnects"], link["reconnects"]
        stalled = link.get("state") == "stalled"
        if stalled != self._stalled:
            events.append(("link-stalled", stall_said(link)) if stalled else
                          ("link-moving", "queued blocks go out again"))
            self._stalled = stalled
        self.alarm = self._alarm(link)
        return events

    @staticmethod
    def _alarm(link: dict) -> str | None:
        state = link.get("state")
        if state == "disconnected":
            return (f"link lost ({link.get('last_error') or 'port failed'}): the plate gets "
                    "nothing; reconnecting")
        if state == "stalled":
            return f"link stalled: {stall_said(link)}; the plate gets nothing"
        return None


def stall_said(link: dict) -> str:
    """Why a status says ``stalled``: "no queued block went out for 0.6 s (62 queued)"."""
    return (f"no queued block went out for {link.get('queue_still_s', 0.0):.1f} s "
            f"({link.get('queued_blocks', 0)} queued)")

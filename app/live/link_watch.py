"""What the demo says about its device link, read from the link's status
(``device.link.host.CommandSink.status``) as the haptic side hands it over with its
snapshots: the clamps it made to the device's limit, and a limit below the scene's.
"""

from __future__ import annotations


def device_clamps(link: dict) -> str:
    """The amplitude values the link clamped to its device's limit (a link's status),
    said apart from the pipeline's clamps as a replay says them: " by the friction
    inversion and 1234 by the device's limit", or "" when it clamped none."""
    clamped = link.get("clamped_samples") or 0
    return f" by the friction inversion and {clamped} by the device's limit" if clamped else ""


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

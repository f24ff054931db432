"""The actuation of a device profile: built only for the profile a scene names."""

from __future__ import annotations

from frictex.device.actuation.base import SingleModeActuation
from frictex.device.profile import FORCE_PROFILES


def make_actuation(device):
    """The actuation for a device profile (``device.profile.DeviceProfile``)."""
    if device.profile == "plate-seed003":
        return SingleModeActuation()
    if device.structure is not None:
        from frictex.device.actuation.modal_actuation import make_modal_actuation  # built only for modal scenes
        return make_modal_actuation(device)
    if device.profile in FORCE_PROFILES:
        from frictex.device.actuation.push_actuation import make_push_actuation  # travelling waves only
        return make_push_actuation(device.profile, device.amplitude_limit_um)
    raise ValueError(f"device profile {device.profile!r} has no actuation")

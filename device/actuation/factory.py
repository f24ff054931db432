"""The actuation extension point: from the amplitude wanted under each finger to channel
commands, built only for the profile a scene names.

A device profile (``device.profile.PROFILES``) names its actuation; :data:`ACTUATIONS`
holds them by name (group ``frictex.actuations`` for other packages): a factory taking
the scene's ``device.profile.DeviceProfile`` and returning an :class:`Actuation`.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from frictex.device.actuation.base import Actuated, SingleModeActuation
from frictex.device.profile import PROFILES, DeviceProfile
from frictex.device.registry import Registry


class Actuation(Protocol):
    """Channel commands for the amplitude each finger's friction target asks for."""

    #: the channels' names, one command column each
    channels: tuple[str, ...]
    #: whether the commands carry a phase per channel
    has_phases: bool

    def command(self, wanted_um: np.ndarray, fingers) -> Actuated:
        """Commands for ``wanted_um`` (F, n) um zero-to-peak, under the F fingers of the
        tracks ``fingers`` (``rendering.tracking.tracks.FingerBlock``)."""


class ActuationFactory(Protocol):
    def __call__(self, device: DeviceProfile) -> Actuation:
        """The actuation of ``device``, its tables built now (at scene load)."""


#: actuations by the name a device profile gives (``device.profile.ProfileSpec.actuation``)
ACTUATIONS: Registry[ActuationFactory] = Registry("actuation", "frictex.actuations")


@ACTUATIONS.register("single-mode")
def single_mode(device: DeviceProfile) -> SingleModeActuation:
    """One channel for the whole plate (``device.actuation.base``)."""
    return SingleModeActuation()


@ACTUATIONS.register("modal")
def modal(device: DeviceProfile):
    """Modal control of a beam or a 2D plate (``device.actuation.modal_actuation``)."""
    from frictex.device.actuation.modal_actuation import make_modal_actuation  # modal scenes only
    return make_modal_actuation(device)


@ACTUATIONS.register("travelling-beam")
def travelling_beam(device: DeviceProfile):
    """Seed 002's travelling wave on a beam (``device.actuation.push_actuation``)."""
    from frictex.device.actuation.push_actuation import travelling_beam as build  # waves only
    return build(device.amplitude_limit_um)


@ACTUATIONS.register("travelling-ring")
def travelling_ring(device: DeviceProfile):
    """Seed 004's travelling wave on a ring (``device.actuation.push_actuation``)."""
    from frictex.device.actuation.push_actuation import travelling_ring as build  # waves only
    return build(device.amplitude_limit_um)


def make_actuation(device: DeviceProfile) -> Actuation:
    """The actuation for a device profile (``device.profile.DeviceProfile``); an
    unknown profile or actuation is an error listing the known ones."""
    return ACTUATIONS.get(PROFILES.get(device.profile).actuation)(device)

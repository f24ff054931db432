"""Actuation: from the vibration amplitude wanted under the fingers to channel commands.

A single-mode plate (seed 003: one resonance, 20 piezo motors driven together, one
closed amplitude loop on the MCU) has one channel and gives every finger the same
amplitude. With several fingers down it can serve only one: frictex serves the finger
that has been touching longest (the first down), so a second finger landing does not
snatch the texture from the first. Other fingers get the same amplitude, and the
friction they actually feel is reported (``friction.csv`` per finger).
"""

from __future__ import annotations

import numpy as np


class SingleModeActuation:
    """One channel, one amplitude for the whole plate."""

    channels = ("ch0",)
    has_phases = False

    def primary_finger(self, contact: np.ndarray, touch_start: np.ndarray) -> np.ndarray:
        """Row index (F, n -> n) of the finger served at each sample, -1 where none touches.

        ``touch_start`` holds, per finger and sample, the time (s) its current touch began.
        """
        if contact.shape[0] == 0:
            return np.full(contact.shape[1], -1)
        key = np.where(contact, touch_start, np.inf)
        row = np.argmin(key, axis=0)
        return np.where(contact.any(axis=0), row, -1)

    def command(self, wanted_um: np.ndarray, primary: np.ndarray):
        """Channel commands (n, 1) in um and the amplitude under every finger (F, n).

        ``wanted_um`` (F, n) is the amplitude each finger's target asks for.
        """
        n = wanted_um.shape[1]
        served = np.zeros(n)
        has = primary >= 0
        served[has] = wanted_um[primary[has], np.flatnonzero(has)]
        under = np.broadcast_to(served, wanted_um.shape)
        return served[:, None], under, None

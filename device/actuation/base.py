"""Actuation: from the vibration amplitude wanted under each finger to channel commands.

Every actuation answers ``command(wanted_um, fingers) -> Actuated``: ``wanted_um`` (F, n)
is the amplitude each finger's friction target asks for, ``fingers`` the tracks
(positions, contact, when each touch began). Which actuation a scene gets is decided by
its device profile (``make_actuation``), so a one-finger plate never builds modal
matrices.

A single-mode plate (seed 003: one resonance, 20 piezo motors driven together, one
closed amplitude loop on the MCU) has one channel and gives every finger the same
amplitude. With several fingers down it can serve only one: frictex serves the finger
that has been touching longest (the first down), so a second finger landing does not
snatch the texture from the first. Other fingers get the same amplitude, and what they
get is reported as their achieved amplitude.

The modal profiles (a beam or a 2D plate with several modes) get
``device.actuation.modal_actuation.ModalActuation``: one amplitude and phase per channel, a
different amplitude under each finger.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from frictex.device.jit import njit


@dataclass(frozen=True, eq=False)
class Actuated:
    """commands_um : (n, channels) amplitude per channel (um, zero-to-peak).
    phases_rad : (n, channels) or None. achieved_um : (F, n) amplitude under each finger.
    limited : number of samples where a channel limit changed the solution.
    capped : samples where two or more fingers were served but could not be given
    independent amplitudes (a singular locus, seed 001 eq 8; modal actuation only).
    off_structure : finger samples whose position lay off the vibrating structure and
    were held at its edge (modal actuation only).
    unserved : finger samples touching but not served, beyond the p longest-touching
    fingers that p modes can serve; they feel the vibration the served ones get (modal
    actuation only).
    """

    commands_um: np.ndarray
    phases_rad: np.ndarray | None
    achieved_um: np.ndarray
    limited: int = 0
    capped: int = 0
    off_structure: int = 0
    unserved: int = 0


def touch_rank(contact: np.ndarray, touch_start: np.ndarray) -> np.ndarray:
    """Order of touch-down among the fingers touching, per sample.

    Parameters
    ----------
    contact : bool (F, n)
    touch_start : float64 (F, n), time (s) each finger's current touch began.

    Returns
    -------
    int64 (F, n)
        0 for the finger touching longest, 1 for the next, ...; -1 where not touching.
        Equal start times are ordered by row.
    """
    return _touch_rank(np.asarray(contact, dtype=np.bool_), np.asarray(touch_start, dtype=np.float64))


@njit(cache=True, nogil=True)
def _touch_rank(contact, touch_start):
    """:func:`touch_rank`: finger f's rank counts the fingers j touching with an earlier
    start, or the same start and j < f; one pair of fingers at a time, so that the loop
    over the samples has no branch (and vectorises)."""
    f_count, n = contact.shape
    rank = np.zeros((f_count, n), dtype=np.int64)
    for f in range(f_count):
        for j in range(f_count):
            if j != f:
                tie = j < f
                for i in range(n):
                    rank[f, i] += contact[j, i] & ((touch_start[j, i] < touch_start[f, i])
                                                   | (tie & (touch_start[j, i] == touch_start[f, i])))
        for i in range(n):
            if not contact[f, i]:
                rank[f, i] = -1
    return rank


def primary_finger(contact: np.ndarray, touch_start: np.ndarray) -> np.ndarray:
    """Row index of the finger touching longest at each sample (F, n -> n), -1 where none."""
    if contact.shape[0] == 0:
        return np.full(contact.shape[1], -1)
    key = np.where(contact, touch_start, np.inf)
    row = np.argmin(key, axis=0)
    return np.where(contact.any(axis=0), row, -1)


class SingleModeActuation:
    """One channel, one amplitude for the whole plate."""

    channels = ("ch0",)
    has_phases = False

    def command(self, wanted_um: np.ndarray, fingers) -> Actuated:
        if wanted_um.shape[0] == 1:  # one finger: served whenever it touches
            served = np.where(fingers.contact[0], wanted_um[0], 0.0)
        else:
            primary = primary_finger(fingers.contact, fingers.touch_start)
            served = np.zeros(wanted_um.shape[1])
            has = primary >= 0
            served[has] = wanted_um[primary[has], np.flatnonzero(has)]
        return Actuated(served[:, None], None, np.broadcast_to(served, wanted_um.shape))

"""Travelling-wave actuation for the profiles that push (``device.profile.FORCE_PROFILES``).

One travelling wave serves the whole surface: an amplitude W (um zero-to-peak, the
propagating amplitude of ``device.actuation.travelling``) and a direction d (+1 towards +x, -1
towards -x, 0 a standing wave) per output sample become two channel commands with
phases (``has_phases``):

- ``travelling-beam-seed002`` (:func:`travelling_beam`): seed 002's 600 x 6 x 6 mm aluminium beam, modes 28 and 29
  (wavelength near the paper's 41 mm), Langevin transducers 19 mm from each end (its
  Fig. 1). The references are the field at the actuators, W_A = +-j W_B (seed 002,
  eqs 4-5): neither equal amplitudes nor 90 degrees apart.
- ``ring-seed004`` (:func:`travelling_ring`): seed 004's Ultraloop (L 140, R 50, h 2.75, w 30 mm, aluminium 5052),
  its 24th-order degenerate pair; one channel per mode, W_A = e^{j phi} W_B with
  phi = +-90 degrees (seed 004, eq 1 and Fig. 4): the sign of the shift sets d.

The display's x axis runs along the wave: display x = 0 is the beam's end x = 0, or the
left end of the ring's touched straight (ring x = -L/2); display y is across and does not
enter the modes. The local travelling-wave ratio tau(x) and envelope gain g(x) (envelope
maximum per unit W) are tabulated once when the scene loads: a finger where tau is small
(near a beam end) is not promised a force the wave cannot give there.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from frictex.device.actuation.base import Actuated
from frictex.device.structures.beam import FreeFreeBeam
from frictex.device.structures.ring import RingResonator
from frictex.device.actuation.travelling import BeamActuation, TwoModeWave, beam_wave, ring_wave

_DIRECTIONS = (-1, 0, 1)


@dataclass(frozen=True, eq=False)
class PushActuation:
    """Two channels with phases driven by one travelling wave (see the module docstring).

    wave : the two modes on the surface. unit_refs : (3, 2) complex channel references
        for W = 1 and d = -1, 0, +1. x0_mm : structure x at display x = 0.
    limit_um : the largest channel command (um zero-to-peak). The references at the
        actuators are not W itself (on the beam, |W_A| reaches 1.16 W): where one would
        pass the limit both are scaled down together, so the wave keeps its shape and
        direction and only its amplitude drops (counted as ``limited``).
    """

    channels: tuple[str, ...]
    wave: TwoModeWave
    unit_refs: np.ndarray
    x0_mm: float
    ratio_table: np.ndarray
    gain_table: np.ndarray
    limit_um: float
    has_phases = True

    @classmethod
    def build(cls, channels, wave: TwoModeWave, unit_refs, x0_mm: float,
              limit_um: float) -> "PushActuation":
        travelling = wave.modal(1.0, 1)
        return cls(tuple(channels), wave, np.asarray(unit_refs, dtype=np.complex128), float(x0_mm),
                   wave.local_ratio(travelling), wave.local_max(travelling), float(limit_um))

    def ratio_at(self, x_mm) -> np.ndarray:
        """Local travelling-wave ratio tau in [0, 1] at display positions ``x_mm`` (any shape)."""
        return np.interp(np.asarray(x_mm, dtype=np.float64) + self.x0_mm, self.wave.x_mm,
                         self.ratio_table)

    def gain_at(self, x_mm) -> np.ndarray:
        """Local envelope maximum per unit W at display positions ``x_mm`` (any shape)."""
        return np.interp(np.asarray(x_mm, dtype=np.float64) + self.x0_mm, self.wave.x_mm,
                         self.gain_table)

    def envelope_limit_at(self, x_mm) -> np.ndarray:
        """Largest local envelope w (um zero-to-peak) a travelling wave (d = +-1) gives at
        display positions ``x_mm`` (any shape) with no channel command past ``limit_um``:
        W at most limit / max_d |reference per unit W|, times the gain g(x) there (on seed
        002's beam 3 um / 1.164 x g: 2.58 um at x = 300 mm, where g = 1)."""
        return self.limit_um / self._travelling_peak() * self.gain_at(x_mm)

    def _travelling_peak(self) -> float:
        """The largest channel reference per unit W over the directions d = -1 and +1."""
        return float(np.abs(self.unit_refs[[0, 2]]).max())

    def within_limit(self, amplitude_um: np.ndarray, direction: np.ndarray):
        """W scaled down where a channel command would pass ``limit_um``, and how many
        samples were: ``(amplitude_um (n,), limited)``. A W planned at
        :meth:`envelope_limit_at` and divided back by g(x) may pass it by a rounding error:
        not counted."""
        unit_peak = np.abs(self.unit_refs).max(axis=1)[np.asarray(direction, dtype=np.int64) + 1]
        allowed = self.limit_um / unit_peak
        passed = amplitude_um > allowed * (1.0 + 1e-12)
        return np.minimum(amplitude_um, allowed), int(np.count_nonzero(passed))

    def drive(self, amplitude_um: np.ndarray, direction: np.ndarray, fingers,
              limited: int = 0) -> Actuated:
        """Channel commands for a wave of amplitude W and direction d per sample.

        Parameters
        ----------
        amplitude_um : (n,) W (um zero-to-peak), >= 0, already :meth:`within_limit`.
        direction : (n,) int, -1 / 0 / +1.
        fingers : the block's tracks (``rendering.tracking.tracks.FingerBlock``).
        limited : how many samples :meth:`within_limit` scaled down (reported).

        Returns
        -------
        Actuated: commands_um (n, 2) and phases_rad (n, 2) of the references,
        achieved_um (F, n) the envelope W g(x) under each touching finger (0 elsewhere).
        """
        refs = amplitude_um[:, None] * self.unit_refs[np.asarray(direction, dtype=np.int64) + 1]
        achieved = np.where(fingers.contact, amplitude_um * self.gain_at(fingers.x_pred), 0.0)
        # within_limit already holds them there; this only removes last-bit rounding
        commands = np.minimum(np.abs(refs), self.limit_um)
        return Actuated(commands, np.angle(refs), achieved, limited=limited)


def travelling_beam(limit_um: float) -> PushActuation:
    """Seed 002's beam (``travelling-beam`` actuation), channel commands limited to
    ``limit_um`` (um zero-to-peak)."""
    wave = beam_wave(FreeFreeBeam(600.0, 6.0, 6.0, 69.0, 2700.0), 28)
    beam = BeamActuation(wave, (19.0, 581.0))
    refs = [beam.references(1.0, d) for d in _DIRECTIONS]
    return PushActuation.build(("actuator1", "actuator2"), wave, refs, 0.0, limit_um)


def travelling_ring(limit_um: float) -> PushActuation:
    """Seed 004's ring (``travelling-ring`` actuation), channel commands limited to
    ``limit_um`` (um zero-to-peak)."""
    ring = RingResonator(140.0, 50.0, 2.75, 30.0, 69.0, 2680.0)
    wave = ring_wave(ring, 24)
    refs = [wave.modal(1.0, d) for d in _DIRECTIONS]
    return PushActuation.build(("mode_sym", "mode_asym"), wave, refs, -ring.length_mm / 2,
                               limit_um)

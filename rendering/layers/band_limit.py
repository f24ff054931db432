"""A periodic texture faster than the output can play: its mean instead of an alias.

A renderer that synthesises a period from the finger's velocity (SHT, the hybrid) plays
a texture of frequency |v . axis| / P (Hz). Above the output's Nyquist frequency (half
the output rate) the samples of that texture are an alias: at 1 kHz output a 0.6 mm
grating under a finger at 420 mm/s is a 700 Hz texture, and sampling it played 300 Hz
(1000 - 700), a texture nobody touched. There the texture's mean mu' over one period is
played instead, which is what the texture is to a plate that cannot play it, and those
touching samples are counted (``summary.json``'s ``layer_clipped``, with a warning). At
the default 10 kHz output it takes a finger beyond 3 m/s on a 0.6 mm grating.

SHO reads a map at the finger's position and has no texture frequency of its own to
limit: at a low output rate it aliases a fine grating as any sampling does.
"""

from __future__ import annotations

import numpy as np

#: phases over one period the texture's mean mu' is taken at
MEAN_PHASES = 4096


class BandLimit:
    """The band limit of one periodic layer (grating or waveform) at ``rate_hz`` output."""

    def __init__(self, layer, rate_hz: float):
        self.nyquist_hz = rate_hz / 2.0
        self.axis = np.array(layer.axis, dtype=np.float64)
        self.period_mm = float(layer.period_mm)
        phases = np.arange(MEAN_PHASES)[None, :] / MEAN_PHASES
        #: mu' averaged over one period: what is played above the Nyquist frequency
        self.mean_mu = float(layer.profile_where(phases, np.ones(phases.shape, bool)).mean())

    def apply(self, mu: np.ndarray, covers: np.ndarray, block) -> int:
        """Set ``mu`` (F, n) to the mean where a touching finger on the layer (``covers``)
        moves the texture past the Nyquist frequency (the tracker's velocity,
        ``block.vx``, ``block.vy``); the number of such samples."""
        ax, ay = self.axis
        texture_hz = np.abs(block.vx * ax + block.vy * ay) / self.period_mm
        above = (texture_hz > self.nyquist_hz) & covers & block.contact
        mu[above] = self.mean_mu
        return int(np.count_nonzero(above))

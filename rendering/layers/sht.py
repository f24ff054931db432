"""SHT, the surface haptic texture (seed 003, section 4.4.2): one spatial period
replayed at the rate the finger's velocity sets.

The spatial phase (cycles) advances by (v . axis) / period per second: the velocity
projected on the texture's axis (across its lines) over the period. It is integrated
sample by sample (a cumulative sum of phase increments), wrapped to [0, 1) and carried
to the next call, so its error does not grow with time: float64 increments of at most
a few hundredths of a cycle keep a one-hour integral within ~1e-9 cycle (see
tests/test_sht.py). A new touch (down, or a jump) restarts the phase at 0: plain SHT
does not know where the finger landed (the seed's stated drawback; the hybrid renderer
fixes it). The layer's region gates the output at the predicted finger position.

Each sample plays the profile's mean over the phase interval from the previous sample's
phase to its own, and above the output's Nyquist frequency the texture's mean instead of
an alias, counted in ``clipped`` (``rendering.layers.band_limit``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from frictex.rendering.layers.band_limit import BandLimit
from frictex.rendering.layers.hybrid import integrate_phase
from frictex.rendering.tracking.tracks import FingerBlock


@dataclass(frozen=True)
class ShtState:
    """Per finger: the touch the phase belongs to and the wrapped phase (cycles) to go on
    from; and the touching samples played as the texture's mean so far
    (``rendering.layers.band_limit``)."""

    phase: dict[int, tuple[int, float]]
    clipped: int = 0


class ShtRenderer:
    """Period synthesis of one periodic layer (grating or waveform)."""

    #: what it makes of a period finer than the touch samples can place
    #: (``rendering.perception``)
    fine_period = ("SHO alone (the map read at the touch samples) would alias it; SHT plays "
                   "it from the finger's velocity, so it is felt, but its phase is not kept "
                   "with the drawing")
    #: plays its texture from the tracker's velocity between touch samples
    #: (``rendering.renderers.from_velocity``)
    from_velocity = True

    def __init__(self, layer, rate_hz: float):
        self.layer = layer
        self.dt_s = 1.0 / rate_hz
        self.axis = np.array(layer.axis)
        self.band_limit = BandLimit(layer)

    def initial_state(self) -> ShtState:
        return ShtState(phase={})

    def render(self, block: FingerBlock, state: ShtState):
        """mu' (F, n) and coverage (F, n) under each finger (mu' 1 where the layer does
        not cover), and the new state."""
        phase = np.empty((len(block.ids), block.n))
        steps = np.empty_like(phase)
        carried = {fid: state.phase[fid] for fid in block.ids if fid in state.phase}
        ax, ay = self.axis
        for row, fid in enumerate(block.ids):
            rate = (block.vx[row] * ax + block.vy[row] * ay) / self.layer.period_mm
            phase[row], carry = integrate_phase(rate, self.dt_s, block.touch_id[row],
                                                carried.get(fid), steps[row])
            carried[fid] = (int(block.touch_id[row, -1]), carry)
        covers = self.layer.covers(block.x_pred, block.y_pred)
        mu = self.band_limit.play_forward(phase, covers, steps)
        limited = self.band_limit.apply(mu, covers, block, steps)
        return mu, covers, ShtState(phase=carried, clipped=state.clipped + limited)

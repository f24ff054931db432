"""SHO, the surface haptic object (seed 003, section 4.4.1): mu' read from the map at
the finger's position, sampled only where fingers are.

Two variants: ``held`` uses the last measured position until the next touch sample
arrives (the seed's plain scheme: at 50 Hz it can only render up to 25 Hz, section
4.4.1); ``predicted`` extrapolates the position at the estimated velocity between
samples (see ``rendering.tracking.tracks``).

On a periodic layer each sample plays the profile's mean over the phase interval from
the previous sample's position to its own (``rendering.layers.band_limit``): ``held``
thus plays the point value between touch samples, as before, and at each touch sample
the mean over the jump to the new one. A texture past the output's Nyquist frequency (a
stretch over half a cycle, the finger's velocity moving the phase that far too) plays
its mean, counted in ``clipped``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from frictex.rendering.layers.band_limit import BandLimit
from frictex.rendering.tracking.tracks import FingerBlock


@dataclass(frozen=True)
class ShoState:
    """Per finger: the touch and the phase (cycles, unwrapped) of its last sample
    (``BandLimit.play_since``'s ``last``); and the touching samples played as the
    texture's mean so far (``rendering.layers.band_limit``)."""

    last: dict[int, tuple[int, float]]
    clipped: int = 0


class ShoRenderer:
    """Position-map rendering of one layer. Its state: None for a layer without a period;
    a :class:`ShoState` for a periodic one."""

    #: reads any layer's map at a position, so it can be a run's SHO variant (the
    #: renderer of every layer without a period: ``rendering.renderers``)
    any_layer = True

    def __init__(self, layer, predicted: bool, rate_hz: float | None = None):
        self.layer = layer
        self.predicted = predicted
        periodic = rate_hz is not None and layer.is_periodic
        self.band_limit = BandLimit(layer) if periodic else None
        if periodic:
            #: cycles of phase per sample per mm/s along x and y
            self.per_sample = np.array(layer.axis) / (layer.period_mm * rate_hz)

    def initial_state(self):
        return None if self.band_limit is None else ShoState(last={})

    def render(self, block: FingerBlock, state=None):
        """mu' (F, n) and coverage (F, n) of the layer under each finger, and the new state."""
        x, y = (block.x_pred, block.y_pred) if self.predicted else (block.x_held, block.y_held)
        if self.band_limit is None:
            mu, covers = self.layer.mu_and_covers(x, y)
            return mu, covers, state
        covers = self.layer.covers(x, y)
        ax, ay = self.per_sample
        mu, limited, last = self.band_limit.play_since(self.layer.phase_at(x, y), covers, block,
                                                        state.last, block.vx * ax + block.vy * ay)
        return mu, covers, ShoState(last=last, clipped=state.clipped + limited)


class HeldSho(ShoRenderer):
    """The ``sho-held`` renderer: the last measured position (seed 003's plain SHO)."""

    #: what it makes of a period finer than the touch samples can place
    #: (``rendering.perception``)
    fine_period = ("SHO-held reads the map only at each touch sample and aliases it (mu' "
                   "changes at the touch rate, not once per period); render = \"hybrid\" "
                   "plays it from the finger's velocity")

    def __init__(self, layer, rate_hz: float):
        super().__init__(layer, predicted=False, rate_hz=rate_hz)


class PredictedSho(ShoRenderer):
    """The ``sho-predicted`` renderer: the position extrapolated between touch samples."""

    #: what it makes of a period finer than the touch samples can place
    #: (``rendering.perception``)
    fine_period = ("SHO-predicted plays it between touch samples at the predicted position "
                   "and jumps its phase at each sample (felt as extra edges); render = "
                   "\"hybrid\" plays it from the finger's velocity without those jumps")

    def __init__(self, layer, rate_hz: float):
        super().__init__(layer, predicted=True, rate_hz=rate_hz)

"""SHO, the surface haptic object (seed 003, section 4.4.1): mu' read from the map at
the finger's position, sampled only where fingers are.

Two variants: ``held`` uses the last measured position until the next touch sample
arrives (the seed's plain scheme: at 50 Hz it can only render up to 25 Hz, section
4.4.1); ``predicted`` extrapolates the position at the estimated velocity between
samples (see ``rendering.tracking.tracks``).
"""

from __future__ import annotations

from frictex.rendering.tracking.tracks import FingerBlock


class ShoRenderer:
    """Position-map rendering of one layer. Stateless: ``render`` returns state unchanged."""

    #: reads any layer's map at a position, so it can be a run's SHO variant (the
    #: renderer of every layer without a period: ``rendering.renderers``)
    any_layer = True

    def __init__(self, layer, predicted: bool):
        self.layer = layer
        self.predicted = predicted

    def initial_state(self):
        return None

    def render(self, block: FingerBlock, state=None):
        """mu' (F, n) and coverage (F, n) of the layer under each finger."""
        x, y = (block.x_pred, block.y_pred) if self.predicted else (block.x_held, block.y_held)
        mu, covers = self.layer.mu_and_covers(x, y)
        return mu, covers, state


class HeldSho(ShoRenderer):
    """The ``sho-held`` renderer: the last measured position (seed 003's plain SHO)."""

    #: what it makes of a period finer than the touch samples can place
    #: (``rendering.perception``)
    fine_period = ("SHO-held reads the map only at each touch sample and aliases it (mu' "
                   "changes at the touch rate, not once per period); render = \"hybrid\" "
                   "plays it from the finger's velocity")

    def __init__(self, layer, rate_hz: float):
        super().__init__(layer, predicted=False)


class PredictedSho(ShoRenderer):
    """The ``sho-predicted`` renderer: the position extrapolated between touch samples."""

    #: what it makes of a period finer than the touch samples can place
    #: (``rendering.perception``)
    fine_period = ("SHO-predicted plays it between touch samples at the predicted position "
                   "and jumps its phase at each sample (felt as extra edges); render = "
                   "\"hybrid\" plays it from the finger's velocity without those jumps")

    def __init__(self, layer, rate_hz: float):
        super().__init__(layer, predicted=True)

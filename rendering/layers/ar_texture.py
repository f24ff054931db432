"""Recorded textures synthesised from speed and force (``textures.hatt.ArTextureLayer``).

Per finger, over each run of output samples with the same touch, speed and normal force
(a touch sample takes effect at a block boundary, so a block is one run or a few), the
model is blended at (speed, force) (``TextureModel.at``: barycentric weights on LSFs and
variances, as the toolkit renders) and white Gaussian noise of that variance drives
the all-pole filter 1 / A(z) in direct form. The filter carries its last p outputs
between runs and blocks, so a change of speed changes the spectrum without a click. Below ``v_rest_mm_s`` or off the screen the
output is 0 and the history is cleared.

The noise of output sample k is a function of (seed, finger id, touch id, k) only, so
live and replay, and any split into blocks, give the same texture; the kernels are in
``textures.ar_synthesis``.

mu' = clip(mu_mean + gain * y, mu_min, mu_max); the samples the limits clipped where a
finger touches inside the layer's region (those that reach the friction target) are
counted in the state (``clipped``), and so are those where the filter's output was not
finite and it restarted from rest (output 0: mu_mean).
The model is resampled once to the output rate when the renderer is built.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from frictex.device.jit import njit
from frictex.rendering.tracking.tracks import FingerBlock
from frictex.textures.ar_synthesis import render_finger

@dataclass(frozen=True)
class ArState:
    """Per finger id: (touch id, last p outputs, most recent first); and how many
    finger samples so far, touching inside the region, the mu' limits clipped or the filter
    restarted after an output that was not finite."""

    fingers: dict = field(default_factory=dict)
    clipped: int = 0


class ArTextureRenderer:
    """Renders one ``ArTextureLayer``; see the module docstring."""

    def __init__(self, layer, rate_hz: float):
        self.layer = layer
        self.model = layer.model.resampled(rate_hz)
        self.order = self.model.order
        self.arrays = self.model.arrays

    def initial_state(self) -> ArState:
        return ArState()

    def render(self, block: FingerBlock, state: ArState):
        """mu' (F, n) and coverage (F, n) of the layer under each finger."""
        layer = self.layer
        mu = np.empty(block.contact.shape)
        covers = layer.covers(block.x_pred, block.y_pred)
        counted = block.contact & covers
        fingers, clipped = {}, state.clipped
        for i, fid in enumerate(block.ids):
            touch, history = state.fingers.get(fid, (-1, np.zeros(self.order)))
            history = history.copy()  # the state passed in stays as it was
            touch, restarts = render_finger(
                block.contact[i], block.touch_id[i], block.vx[i], block.vy[i], block.force[i],
                layer.v_rest_mm_s, layer.seed, fid, block.index0, self.arrays, touch, history,
                mu[i], counted[i])
            fingers[fid] = (int(touch), history)
            clipped += restarts + _limit(mu[i], layer.mu_mean, layer.gain, layer.mu_min,
                                         layer.mu_max, counted[i])
        return mu, covers, ArState(fingers, clipped)


@njit(cache=True, nogil=True)
def _limit(y, mu_mean, gain, mu_min, mu_max, counted):
    """The model's output y (n,) turned into mu' in place: mu_mean + gain y, limited to
    [mu_min, mu_max] as numpy's ``clip`` (NaN stays NaN). Returns how many of the samples
    where ``counted`` (bool, (n,)) the limits changed (NaN counts)."""
    clipped = 0
    for j in range(y.size):
        raw = mu_mean + gain * y[j]
        mu = mu_min if raw < mu_min else raw
        mu = mu_max if mu > mu_max else mu
        clipped += counted[j] and not mu == raw
        y[j] = mu
    return clipped

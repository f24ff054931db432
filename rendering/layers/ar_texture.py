"""Recorded textures synthesised from speed and force (``textures.hatt.ArTextureLayer``).

Per finger, over each run of output samples with the same touch, speed and normal force
(a touch sample takes effect at a block boundary, so a block is one run or a few), the
model is blended at (speed, force) (``TextureModel.at``: barycentric weights on LSFs and
variances, as the toolkit renders) and white Gaussian noise of that variance drives
the all-pole filter 1 / A(z). The filter carries its last p outputs between runs and
blocks (``scipy.signal.lfiltic`` re-expresses them for new coefficients), so a change of
speed changes the spectrum without a click. Below ``v_rest_mm_s`` or off the screen the
output is 0 and the history is cleared.

The noise of output sample k is a function of (seed, finger id, touch id, k) only
(counter-based Philox, Box-Muller), so live and replay, and any split into blocks,
give the same texture.

mu' = clip(mu_mean + gain * y, mu_min, mu_max); clipped samples are counted in the state.
The model is resampled once to the output rate when the renderer is built.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.random import Generator, Philox
from scipy.signal import lfilter, lfiltic

from rendering.tracking.tracks import FingerBlock


@dataclass(frozen=True)
class ArState:
    """Per finger id: (touch id, last p outputs, most recent first); and how many
    samples so far the mu' limits clipped."""

    fingers: dict = field(default_factory=dict)
    limited: int = 0


def gaussian_noise(seed: int, finger: int, touch: int, index0: int, n: int) -> np.ndarray:
    """Standard normal samples for output indices index0 .. index0 + n - 1 (each a
    function of its index and the keys only)."""
    key = (seed << 64) | ((finger & 0xFFFFFFFF) << 32) | (touch & 0xFFFFFFFF)
    u = Generator(Philox(key=key, counter=index0)).random(4 * n).reshape(n, 4)
    return np.sqrt(-2.0 * np.log1p(-u[:, 0])) * np.cos(2.0 * np.pi * u[:, 1])


def _runs(*rows) -> np.ndarray:
    """Start indices of the runs over which every row is constant (always starts with 0)."""
    n = rows[0].size
    change = np.zeros(n, dtype=bool)
    for r in rows:
        change[1:] |= r[1:] != r[:-1]
    change[0] = True
    return np.flatnonzero(change)


class ArTextureRenderer:
    """Renders one ``ArTextureLayer``; see the module docstring."""

    def __init__(self, layer, rate_hz: float):
        self.layer = layer
        self.model = layer.model.resampled(rate_hz)
        self.order = self.model.order

    def initial_state(self) -> ArState:
        return ArState()

    def _finger(self, block: FingerBlock, i: int, fid: int, carried):
        """Model output y (n,) for finger row i, and its (touch id, history) afterwards."""
        layer, p = self.layer, self.order
        speed = np.sqrt(block.vx[i] ** 2 + block.vy[i] ** 2)
        force = block.force[i]
        tid = block.touch_id[i]
        moving = block.contact[i] & (speed >= layer.v_rest_mm_s)
        y = np.zeros(block.n)
        touch, history = carried if carried is not None else (-1, np.zeros(p))
        starts = _runs(tid, moving, speed, force)
        for a, b in zip(starts, np.append(starts[1:], block.n)):
            if int(tid[a]) != touch or not moving[a]:
                touch, history = int(tid[a]), np.zeros(p)
            if not moving[a]:
                continue
            poly, variance = self.model.at(float(speed[a]), float(force[a]))
            e = np.sqrt(variance) * gaussian_noise(layer.seed, fid, touch, block.index0 + a, b - a)
            y[a:b], _ = lfilter([1.0], poly, e, zi=lfiltic([1.0], poly, history))
            history = np.concatenate([y[a:b][::-1], history])[:p]
        return y, (touch, history)

    def render(self, block: FingerBlock, state: ArState):
        """mu' (F, n) and coverage (F, n) of the layer under each finger."""
        layer = self.layer
        raw = np.full(block.contact.shape, layer.mu_mean)
        fingers = {}
        for i, fid in enumerate(block.ids):
            y, fingers[fid] = self._finger(block, i, fid, state.fingers.get(fid))
            raw[i] += layer.gain * y
        mu = np.clip(raw, layer.mu_min, layer.mu_max)
        limited = state.limited + int((mu != raw).sum())
        covers = layer.covers(block.x_pred, block.y_pred)
        return mu, covers, ArState(fingers, limited)

"""Recorded textures synthesised from speed and force (``textures.hatt.ArTextureLayer``).

Per finger, over each run of output samples with the same touch, speed and normal force
(a touch sample takes effect at a block boundary, so a block is one run or a few), the
model is blended at (speed, force) (``TextureModel.at``: barycentric weights on LSFs and
variances, as the toolkit renders) and white Gaussian noise of that variance drives
the all-pole filter 1 / A(z) in direct form. The filter carries its last p outputs
between runs and blocks, so a change of speed changes the spectrum without a click. Below ``v_rest_mm_s`` or off the screen the
output is 0 and the history is cleared.

The noise of output sample k is a function of (seed, finger id, touch id, k) only (a
counter hashed by the splitmix64 finaliser into two uniforms, then Box-Muller), so live
and replay, and any split into blocks, give the same texture.

mu' = clip(mu_mean + gain * y, mu_min, mu_max); clipped samples are counted in the state.
The model is resampled once to the output rate when the renderer is built.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numba import njit

from rendering.tracking.tracks import FingerBlock
from textures.hatt import blend_at

# The kernels below are cached by numba (cache=True) with textures.hatt's blend_at and
# lsf_to_poly compiled into them, and numba's cache notices changes to this file only:
# after changing those functions, change this file too (the LSF conversion's rewrite on
# the unit circle did not reach the renderer until this comment was added).

_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_M1, _M2 = np.uint64(0xBF58476D1CE4E5B9), np.uint64(0x94D049BB133111EB)
_S30, _S27, _S31, _S11 = np.uint64(30), np.uint64(27), np.uint64(31), np.uint64(11)
_TWO, _ONE = np.uint64(2), np.uint64(1)


@dataclass(frozen=True)
class ArState:
    """Per finger id: (touch id, last p outputs, most recent first); and how many
    samples so far the mu' limits clipped."""

    fingers: dict = field(default_factory=dict)
    limited: int = 0


@njit(cache=True)
def _mix(x):
    """The splitmix64 finaliser: a uint64 hashed to a well-spread uint64."""
    x = (x ^ (x >> _S30)) * _M1
    x = (x ^ (x >> _S27)) * _M2
    return x ^ (x >> _S31)


@njit(cache=True)
def _normal(key, index):
    """A standard normal sample, a function of (key, index) only."""
    c = np.uint64(key) + np.uint64(index) * _TWO * _GOLDEN  # (int64 + uint64 is float64 in numba)
    u1 = (np.float64(_mix(c) >> _S11) + 0.5) * 2.0 ** -53
    u2 = (np.float64(_mix(c + _GOLDEN) >> _S11) + 0.5) * 2.0 ** -53
    return np.sqrt(-2.0 * np.log(u1)) * np.cos(2.0 * np.pi * u2)


@njit(cache=True)
def _synthesise(poly, scale, key, index0, history, out):
    """out[j] = scale * noise(index0 + j) - sum_k poly[k] out[j - k] (poly[0] = 1), the
    earlier outputs taken from ``history`` (most recent first, updated in place)."""
    p = poly.size - 1
    for j in range(out.size):
        acc = scale * _normal(key, index0 + j)
        for k in range(p):
            acc -= poly[k + 1] * history[k]
        for k in range(p - 1, 0, -1):
            history[k] = history[k - 1]
        if p > 0:
            history[0] = acc
        out[j] = acc


@njit(cache=True)
def noise_key(seed, finger, touch):
    """The noise stream of one touch of one finger (uint64)."""
    return _mix(np.uint64(seed) * _GOLDEN + np.uint64(finger) * _M1 + np.uint64(touch) * _M2)


def gaussian_noise(seed: int, finger: int, touch: int, index0: int, n: int) -> np.ndarray:
    """The standard normal samples of output indices index0 .. index0 + n - 1."""
    out = np.empty(n)
    _synthesise(np.ones(1), 1.0, noise_key(seed, finger, touch), index0, np.zeros(0), out)
    return out


@njit(cache=True)
def _render_finger(contact, touch_id, vx, vy, force, v_rest, seed, finger, index0, model,
                   touch, history, y):
    """Model output y (n,) of one finger row; see the module docstring. ``touch`` and
    ``history`` (most recent first) come from the previous block; returns the touch id
    after the block (``history`` is updated in place)."""
    s0, f0, inv, triangles, lsf, variances = model
    n = y.size
    a = 0
    while a < n:
        speed = np.sqrt(vx[a] ** 2 + vy[a] ** 2)
        b = a + 1  # the run of samples with this touch, speed and force
        while (b < n and touch_id[b] == touch_id[a] and contact[b] == contact[a]
               and vx[b] == vx[a] and vy[b] == vy[a] and force[b] == force[a]):
            b += 1
        moving = contact[a] and speed >= v_rest
        if touch_id[a] != touch or not moving:
            touch = touch_id[a]
            history[:] = 0.0
        if moving:
            poly, variance = blend_at(s0, f0, inv, triangles, lsf, variances, speed, force[a])
            _synthesise(poly / poly[0], np.sqrt(variance), noise_key(seed, finger, touch),
                        index0 + a, history, y[a:b])
        else:
            y[a:b] = 0.0
        a = b
    return touch


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
        raw = np.full(block.contact.shape, layer.mu_mean)
        fingers = {}
        y = np.empty(block.n)
        for i, fid in enumerate(block.ids):
            touch, history = state.fingers.get(fid, (-1, np.zeros(self.order)))
            history = history.copy()  # the state passed in stays as it was
            touch = _render_finger(block.contact[i], block.touch_id[i], block.vx[i], block.vy[i],
                                   block.force[i], layer.v_rest_mm_s, layer.seed, fid,
                                   block.index0, self.arrays, touch, history, y)
            fingers[fid] = (int(touch), history)
            raw[i] += layer.gain * y
        mu = np.clip(raw, layer.mu_min, layer.mu_max)
        limited = state.limited + int((mu != raw).sum())
        covers = layer.covers(block.x_pred, block.y_pred)
        return mu, covers, ArState(fingers, limited)

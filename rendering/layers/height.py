"""Height layers rendered by the lateral-force illusion (``textures.heights.HeightLayer``).

Robles-De-La-Torre and Hayward (Nature 2001) showed that the tangential force met
while sliding over a bump, rising with the slope on the way up and reversed on the way
down, is enough to perceive the bump on a flat surface. Kim, Israr and Poupyrev (UIST
2013) render 3D features on a friction display by mapping the local gradient of the
virtual surface to lateral friction force. A friction display can only resist motion,
so the signed rendering here raises mu' above the layer's rest level while the finger
climbs and lowers it while it descends:

    s = (grad h . v) / max(|v|, v_fade)        (signed, "slope")
    s = |grad h| min(1, |v| / v_fade)         ("magnitude", Kim et al.'s unsigned form)

with v the tracker's velocity estimate (mm/s) and grad h taken at the predicted position
(``textures.heights.slope_along_motion``), and mu' the layer's saturation of s (both in
one pass: ``HeightLayer.mu_of_motion``). Where the predicted position moves |v| / rate
per output sample, s changes by at most |d2h/du2| |v| / rate, so a step in mu' is
bounded by gain * max|d2h/du2| * |v| / rate_hz (plus what a change of the velocity
estimate at a touch sample adds: gain * |grad h| * |dv| / max(|v|, v_fade)). That bound
does not hold where the position jumps: at a touch sample the tracker corrects its
prediction (by 29 mm in one sample for a 2.5 m/s swipe sampled at 120 Hz), and s is
taken at each sample's point, so what lies between two samples' positions is not
rendered: a step whose chamfer is narrower than a sample's travel (0.004 mm at 40 mm/s
and 10 kHz) falls on one sample or none.

Stateless: the slope depends on this sample's position and velocity only. Where s is 0
(flat ground, a finger at rest, motion along a straight contour: a ridge's crest) mu' is
mu_rest exactly (mu_rest + span tanh(+-0)). Along a curved contour the tracker predicts
straight on between touch samples, off the curve, so s is not 0 there: a circle round
height-bump's centre at r = sigma (8 mm, 40 mm/s, 50 Hz touch samples) drifts out to
8.13 mm between samples and reads as a descent, mu' 0.7705 to 0.7849 for mu_rest 0.8. A shape with a ``slope_band`` (a ridge, a step, a button's
rim) has a gradient of exactly 0 outside it, so there mu' is mu_rest without evaluating
the shape (unless the velocity is not finite: 0 times it is NaN).
"""

from __future__ import annotations

from dataclasses import astuple

import numpy as np

from frictex.device.jit import njit
from frictex.rendering.tracking.tracks import FingerBlock


@njit(cache=True, nogil=True)
def _in_band(x, y, vx, vy, ring, x0, y0, nx, ny, lo, hi):
    """bool (m,): the samples among positions (x, y) (mm, (m,)) and velocities (vx, vy)
    (mm/s, (m,)) that must be evaluated for a shape with that ``SlopeBand``
    (``textures.heights``, its fields in order): those in the band (a distance that is not
    finite counts as in) and those whose velocity is not finite. A mask, not indices: a
    loop that stores an index only for some samples took twice as long on a ring."""
    out = np.empty(x.size, dtype=np.bool_)
    for i in range(x.size):
        dx, dy = x[i] - x0, y[i] - y0
        d = np.sqrt(dx * dx + dy * dy) if ring else nx * dx + ny * dy
        out[i] = lo <= d <= hi or not abs(d) < np.inf or not abs(vx[i]) + abs(vy[i]) < np.inf
    return out


class HeightRenderer:
    """Renders one ``HeightLayer`` from positions and velocities; see the module docstring."""

    def __init__(self, layer, rate_hz: float = 10_000.0):
        self.layer = layer
        band = layer.shape.slope_band
        self.band = None if band is None else astuple(band)

    def initial_state(self):
        return None

    def render(self, block: FingerBlock, state=None):
        """mu' (F, n) and coverage (F, n) of the layer under each finger."""
        layer = self.layer
        # the block's arrays already share one shape
        x, y, vx, vy = (a.ravel() for a in (block.x_pred, block.y_pred, block.vx, block.vy))
        at = None
        if self.band is not None:
            at = np.flatnonzero(_in_band(x, y, vx, vy, *self.band))
            if not at.size:  # no finger near the shape: mu_rest everywhere
                return (np.full(block.x_pred.shape, layer.mu_rest),
                        layer.covers(block.x_pred, block.y_pred), state)
            x, y, vx, vy = x[at], y[at], vx[at], vy[at]
        gx, gy = layer.shape.gradient(x, y)
        mu = layer.mu_of_motion(gx, gy, vx, vy)
        if at is not None:  # mu_rest outside the band
            mu, inside = np.full(block.x_pred.size, layer.mu_rest), mu
            mu[at] = inside
        return mu.reshape(block.x_pred.shape), layer.covers(block.x_pred, block.y_pred), state

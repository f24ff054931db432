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

with v the tracker's velocity estimate (mm/s) and grad h taken at the predicted position;
mu' = ``layer.mu_of_slope(s)``. Along the finger's path s changes by at most
|d2h/du2| |v| / rate per output sample, so a step in mu' is bounded by
gain * max|d2h/du2| * |v| / rate_hz (plus what a change of the velocity estimate at a
touch sample adds: gain * |grad h| * |dv| / max(|v|, v_fade)).

Stateless: the slope depends on this sample's position and velocity only.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from rendering.tracking.tracks import FingerBlock


def slope_along_motion(gx, gy, vx, vy, v_fade_mm_s: float, signed: bool) -> np.ndarray:
    """The slope a moving finger feels (dimensionless), faded to 0 at rest.

    Parameters
    ----------
    gx, gy : height gradient (mm per mm), any broadcastable shape.
    vx, vy : finger velocity (mm/s).
    v_fade_mm_s : below this speed the slope is scaled by speed / v_fade_mm_s (> 0).
    signed : the directional derivative along the motion; else |grad h| (unsigned).
    """
    arrays = [np.asarray(a, dtype=np.float64) for a in (gx, gy, vx, vy)]
    if len({a.shape for a in arrays}) > 1:
        arrays = np.broadcast_arrays(*arrays)
    shape = arrays[0].shape
    return _slope_kernel(*(a.ravel() for a in arrays), v_fade_mm_s, signed).reshape(shape)


@njit(cache=True, nogil=True)
def _slope_kernel(gx, gy, vx, vy, v_fade_mm_s, signed):
    """:func:`slope_along_motion` on (m,) arrays, one pass (NaN propagates as numpy's
    ``maximum`` and ``minimum`` would)."""
    out = np.empty(gx.size)
    for i in range(gx.size):
        speed = np.sqrt(vx[i] * vx[i] + vy[i] * vy[i])
        if signed:
            along = gx[i] * vx[i] + gy[i] * vy[i]
            out[i] = along / (v_fade_mm_s if speed < v_fade_mm_s else speed)
        else:
            fade = speed / v_fade_mm_s
            out[i] = np.sqrt(gx[i] * gx[i] + gy[i] * gy[i]) * (1.0 if fade > 1.0 else fade)
    return out


class HeightRenderer:
    """Renders one ``HeightLayer`` from positions and velocities; see the module docstring."""

    def __init__(self, layer, rate_hz: float = 10_000.0):
        self.layer = layer
        self.signed = layer.rendering == "slope"

    def initial_state(self):
        return None

    def render(self, block: FingerBlock, state=None):
        """mu' (F, n) and coverage (F, n) of the layer under each finger."""
        layer, x, y = self.layer, block.x_pred, block.y_pred
        _, gx, gy = layer.shape.height_and_gradient(x, y)
        # slope_along_motion's kernel: the block's arrays already share one shape
        s = _slope_kernel(gx.ravel(), gy.ravel(), block.vx.ravel(), block.vy.ravel(),
                          layer.v_fade_mm_s, self.signed)
        return layer.mu_of_slope(s).reshape(x.shape), layer.covers(x, y), state

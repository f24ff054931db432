"""The scope's traces as a ring of pixel columns in a texture, written as time passes.

Each column of the texture is a fixed time bin of ``scope_s / columns`` seconds (bin b
in column b mod the ring's length) holding, for each finger's mu' and amplitude, the
pixels between the least and greatest value the trace reaches in the bin (its samples
and its values at the bin's edges, as an oscilloscope draws). A frame writes only the
bins that ended since the last frame and the one still filling; the texture is drawn
as one quad over the two plots whose texture coordinate runs with time (the ring wraps:
REPEAT), so the traces scroll without being drawn again. Everything is drawn again when
the plots, the amplitude's full scale, the window or the overlay's history (a clear)
change.
"""

from __future__ import annotations

import math

import moderngl
import numpy as np

from frictex.device.jit import njit
from frictex.rendering.visual.overlay import FINGER_RGB, SCOPE_LINE_PX, OverlayState, plot_y


@njit(cache=True, nogil=True)
def bin_spans(t: np.ndarray, values: np.ndarray, bin_s: float, first: int,
              count: int) -> tuple[np.ndarray, np.ndarray]:
    """Least and greatest value (``count``,) of the polyline (t, values) in each of the
    time bins ``first`` .. ``first + count - 1`` ([b bin_s, (b + 1) bin_s)): its samples
    in the bin and its values, interpolated, at the bin's edges within [t[0], t[-1]];
    NaN for a bin the polyline does not reach. A NaN value is left out of its bin (an
    edge interpolated from it is NaN, and left out too).

    Parameters
    ----------
    t : (n,) s, non-decreasing, n >= 1. values : (n,). bin_s : s.
    """
    edges = (first + np.arange(count + 1)) * bin_s
    at_edges = np.interp(edges, t, values)
    lo, hi = np.full(count, np.nan), np.full(count, np.nan)
    for j in range(count + 1):
        if t[0] <= edges[j] <= t[-1]:
            for k in (j - 1, j):  # the bins this edge closes and opens
                if 0 <= k < count:
                    lo[k] = np.fmin(lo[k], at_edges[j])
                    hi[k] = np.fmax(hi[k], at_edges[j])
    for i in range(t.size):
        k = int(math.floor(t[i] / bin_s)) - first
        if 0 <= k < count:
            lo[k] = np.fmin(lo[k], values[i])
            hi[k] = np.fmax(hi[k], values[i])
    return lo, hi


@njit(cache=True, nogil=True)
def paint_spans(image: np.ndarray, lo: np.ndarray, hi: np.ndarray, top_px: float,
                half_px: float, rgba: np.ndarray) -> None:
    """Paint ``rgba`` into column j of ``image`` (height, count, 4) wherever a pixel's
    centre (row + 0.5 + ``top_px``) lies within [lo[j] - half_px, hi[j] + half_px] px
    (none where lo[j] is NaN)."""
    for j in range(lo.size):
        if np.isnan(lo[j]):
            continue
        for row in range(image.shape[0]):
            centre = row + 0.5 + top_px
            if lo[j] - half_px <= centre <= hi[j] + half_px:
                image[row, j] = rgba


def scope_columns(overlay: OverlayState, plots, amplitude_max_um: float, bin_s: float,
                  first: int, count: int, top: float, height: int) -> np.ndarray:
    """RGBA uint8 (``height``, ``count``) of the bins ``first`` .. ``first + count - 1``
    (``bin_s`` s each) of ``overlay``'s traces in ``plots`` (mu' plot, amplitude plot,
    each (x, y, w, h) px; amplitude full scale ``amplitude_max_um``), row 0 at ``top``
    px: each trace covers the pixels whose centres lie within its span, widened by
    ``SCOPE_LINE_PX``, in its finger's colour (the later finger on top)."""
    image = np.zeros((height, count, 4), dtype=np.uint8)
    for fid, hist in sorted(overlay.fingers.items()):
        # the samples in the bins and one either side (for the values at their edges)
        i0 = max(int(np.searchsorted(hist.t, first * bin_s)) - 1, 0)
        i1 = int(np.searchsorted(hist.t, (first + count) * bin_s)) + 1
        t, data = hist.t[i0:i1], hist.data[:, i0:i1]
        if t.size == 0:
            continue
        rgba = np.array([*(round(255 * c) for c in FINGER_RGB[fid % len(FINGER_RGB)]), 255],
                        dtype=np.uint8)
        for values, rect in ((data[3], plots[0]), (data[4] / amplitude_max_um, plots[1])):
            lo, hi = bin_spans(t, plot_y(values, rect), bin_s, first, count)
            paint_spans(image, lo, hi, float(top), SCOPE_LINE_PX / 2, rgba)
    return image


class ScopeRing:
    """The traces of an :class:`OverlayState` in the scope's two plots (``draw``)."""

    def __init__(self, ctx: moderngl.Context):
        self.ctx = ctx
        self.texture: moderngl.Texture | None = None
        self._key: tuple | None = None
        self._next_bin = 0  # the first bin not yet final

    def update(self, overlay: OverlayState, plots, amplitude_max_um: float
               ) -> tuple[moderngl.Texture, float, float]:
        """Write the bins that changed; return the texture and the texture coordinates
        (u0, u1) of the plots' left and right edges. ``plots`` = (mu' plot, amplitude
        plot), each (x, y, w, h) px with x and y whole pixels."""
        columns = max(1, math.ceil(plots[0][2]))
        top = plots[0][1]
        height = max(1, math.ceil(plots[1][1] + plots[1][3] - top))
        ring = columns + 2
        bin_s = overlay.scope_s / columns
        now_bin = math.floor(overlay.now_s / bin_s)
        # the overlay itself, not its id: a new overlay may get a dropped one's id
        key = (overlay, overlay.generation, plots, amplitude_max_um, overlay.scope_s)
        if key != self._key or now_bin - self._next_bin >= ring:
            if self.texture is None or self.texture.size != (ring, height):
                if self.texture is not None:
                    self.texture.release()
                self.texture = self.ctx.texture((ring, height), 4, alignment=1)
                self.texture.filter = (moderngl.NEAREST, moderngl.NEAREST)
            self._key = key
            self._next_bin = now_bin - ring + 1
        first, count = self._next_bin, now_bin - self._next_bin + 1
        if count > 0:
            self._write(first, scope_columns(overlay, plots, amplitude_max_um, bin_s, first,
                                             count, top, height))
            self._next_bin = now_bin  # the bin still filling is written again next frame
        position = overlay.now_s / bin_s
        return self.texture, (position - columns) / ring, position / ring

    def _write(self, first: int, image: np.ndarray) -> None:
        """Write the columns of the bins from ``first`` into the ring, wrapping."""
        ring, height = self.texture.size
        start, count = first % ring, image.shape[1]
        head = min(count, ring - start)
        self.texture.write(np.ascontiguousarray(image[:, :head]).tobytes(),
                           viewport=(start, 0, head, height), alignment=1)
        if head < count:
            self.texture.write(np.ascontiguousarray(image[:, head:]).tobytes(),
                               viewport=(0, 0, count - head, height), alignment=1)

    def release(self) -> None:
        if self.texture is not None:
            self.texture.release()
        self.texture, self._key = None, None

"""The static scene as an image: every layer evaluated in mm at sub-pixel positions.

Each pixel is the average (box filter) of ``supersample`` x ``supersample`` evaluations
of the composed colour at a regular grid of cells inside the pixel, so an edge that
falls inside a pixel gives it the matching fractional coverage; square gratings are in
addition averaged exactly across each cell (:func:`layer_mu`). That keeps every
grating edge where the haptic map puts it, and a 0.6 mm grating on a 7.4 px/mm screen
(4.4 px per period) anti-aliased instead of beating into moire.

Colours compose like mu' does (``rendering.compose``): a layer with ``blend =
"multiply"`` multiplies the colour below by its own, ``"replace"`` paints over it where
the layer covers. A layer's colour goes from ``visual.color_low`` at the lowest mu' it
asks for to ``visual.color_high`` at its highest (``VisualHints``); the empty plate is
white (mu' = 1, neutral under multiply). Colours are linear RGB; :func:`to_srgb8`
encodes them for the screen and PNG files.

Outlines (``visual.outline`` in the file, or ``outlines=True`` for every layer with a
region or a shape) are drawn 1.5 px wide on the boundary's signed distance.
"""

from __future__ import annotations

import numpy as np

from rendering.visual.viewport import Viewport
from textures.model import Edge, Grating, Line, Scene, Shape

OUTLINE_RGB = np.array([1.0, 0.35, 0.0])  # orange: visible on black, white and grey
OUTLINE_WIDTH_PX = 1.5


def layer_rgb(layer, mu: np.ndarray) -> np.ndarray:
    """Linear RGB (..., 3) of a layer where its mu' is ``mu`` (...)."""
    lo, hi = layer.mu_range
    u = (mu - lo) / (hi - lo) if hi > lo else np.ones_like(mu)
    low = np.asarray(layer.visual.color_low, dtype=np.float64)
    high = np.asarray(layer.visual.color_high, dtype=np.float64)
    return low + np.clip(u, 0.0, 1.0)[..., None] * (high - low)


def _square_low_fraction(phase_lo, phase_hi, duty: float) -> np.ndarray:
    """Fraction of the phase interval [lo, hi] (cycles) inside the low band [k, k + duty)."""
    def cumulative(p):  # measure of the low band in [0, p]
        k = np.floor(p)
        return k * duty + np.minimum(p - k, duty)
    return (cumulative(phase_hi) - cumulative(phase_lo)) / (phase_hi - phase_lo)


def layer_mu(layer, x, y, cell_mm: tuple[float, float] | None = None) -> np.ndarray:
    """mu' of a layer at (x, y) mm; for a square-edged grating and a sampling cell of
    ``cell_mm`` = (width, height) mm, the exact average of mu' across the cell's extent
    along the grating's axis (a box filter: no aliasing from the square wave's
    harmonics, which 16 point samples per pixel would still fold into moire)."""
    if cell_mm is None or not isinstance(layer, Grating) or (layer.edge != "square"
                                                              and layer.edge_mm > 0):
        return layer.mu_at(x, y)
    ax, ay = layer.axis
    half = 0.5 * (abs(ax) * cell_mm[0] + abs(ay) * cell_mm[1]) / layer.period_mm
    phase = layer.phase_at(x, y)
    low = _square_low_fraction(phase - half, phase + half, layer.duty)
    return layer.mu_high + (layer.mu_low - layer.mu_high) * low


def composed_rgb(scene: Scene, x: np.ndarray, y: np.ndarray,
                 cell_mm: tuple[float, float] | None = None) -> np.ndarray:
    """Linear RGB (..., 3) of the scene at positions (mm), layers composed in order
    (``cell_mm``: the sampling cell each position stands for; see :func:`layer_mu`)."""
    rgb = np.ones(np.shape(x) + (3,))
    for layer in scene.layers:
        colour = layer_rgb(layer, layer_mu(layer, x, y, cell_mm))
        covers = layer.covers(x, y)[..., None]
        rgb = np.where(covers, colour if layer.blend == "replace" else rgb * colour, rgb)
    return rgb


def _outline_distance(layer, x, y) -> np.ndarray | None:
    """Signed distance (mm) to a layer's outline: its shape, its region, its line or
    edge; None for layers without one (a bump, an unbounded grating)."""
    if isinstance(layer, Shape):
        return layer.geometry.signed_distance(x, y)
    if layer.region is not None:
        return layer.region.signed_distance(x, y)
    if isinstance(layer, Line):
        return layer._signed_distance(x, y)
    if isinstance(layer, Edge):
        return layer._distance(x, y)
    return None


def scene_rgb(scene: Scene, viewport: Viewport, supersample: int = 4,
              outlines: bool = False) -> np.ndarray:
    """The active area of ``viewport`` rendered: linear RGB, float64 (height_px, width_px, 3).

    Row 0 is the top of the screen (y = 0 mm). Pixel (i, j) averages
    ``supersample**2`` evaluations at x = (j + (a + 0.5)/s) / px_per_mm_x (and likewise
    in y) for a, b in 0..s-1.
    """
    if supersample < 1:
        raise ValueError(f"supersample {supersample!r}: expected at least 1")
    sx, sy = viewport.px_per_mm
    cols = np.arange(viewport.width_px, dtype=np.float64)
    rows = np.arange(viewport.height_px, dtype=np.float64)
    acc = np.zeros((viewport.height_px, viewport.width_px, 3))
    offsets = (np.arange(supersample) + 0.5) / supersample
    cell = (1.0 / (supersample * sx), 1.0 / (supersample * sy))
    for oy in offsets:
        y = ((rows + oy) / sy)[:, None]
        for ox in offsets:
            x = ((cols + ox) / sx)[None, :]
            xx, yy = np.broadcast_arrays(x, y)
            acc += composed_rgb(scene, xx, yy, cell)
    rgb = acc / supersample ** 2
    if outlines or any(layer.visual.outline for layer in scene.layers):
        rgb = _draw_outlines(scene, rgb, cols, rows, sx, sy, outlines)
    return rgb


def _draw_outlines(scene, rgb, cols, rows, sx, sy, all_layers: bool) -> np.ndarray:
    xx, yy = np.broadcast_arrays(((cols + 0.5) / sx)[None, :], ((rows + 0.5) / sy)[:, None])
    mm_per_px = 1.0 / min(sx, sy)
    for layer in scene.layers:
        if not (all_layers or layer.visual.outline):
            continue
        d = _outline_distance(layer, xx, yy)
        if d is None:
            continue
        alpha = np.clip(OUTLINE_WIDTH_PX / 2 + 0.5 - np.abs(d) / mm_per_px, 0.0, 1.0)[..., None]
        rgb = rgb * (1 - alpha) + OUTLINE_RGB * alpha
    return rgb


def to_srgb8(rgb: np.ndarray) -> np.ndarray:
    """Linear RGB in [0, 1] (float) -> sRGB uint8 (IEC 61966-2-1 transfer curve)."""
    c = np.clip(rgb, 0.0, 1.0)
    s = np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1 / 2.4) - 0.055)
    return np.round(s * 255.0).astype(np.uint8)


def from_srgb8(srgb: np.ndarray) -> np.ndarray:
    """sRGB uint8 -> linear RGB float64 in [0, 1] (inverse of :func:`to_srgb8`)."""
    s = np.asarray(srgb, dtype=np.float64) / 255.0
    return np.where(s <= 0.04045, s / 12.92, np.power((s + 0.055) / 1.055, 2.4))

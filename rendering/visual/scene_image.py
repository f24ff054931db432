"""The static scene as an image: every layer evaluated in mm, box-filtered over each pixel.

Each pixel shows the average (box filter) of the composed colour over its footprint, so
an edge that falls inside a pixel gives it the matching fractional coverage, every edge
stays where the haptic map puts it, and a 0.6 mm grating on a 7.4 px/mm screen
(4.4 px per period) is anti-aliased instead of beating into moire. The image is built
in three steps, all from the layers' own ``covers`` / ``mu_at`` / ``profile``
(``textures.model`` is the one source of geometry):

1. Periodic layers (gratings, waveforms) are exact: their mu' depends only on the phase
   across the lines, so the average of ``profile`` over a pixel is a fixed function of
   the phase, tabulated once per layer and pixel size (:func:`periodic_mean`: the
   profile convolved with the pixel footprint projected on the axis, a trapezoid).
2. Every other layer is evaluated at pixel centres, only inside its bounding box.
3. Pixels crossed by a discontinuity that (1) cannot average exactly (a region or object
   boundary, an edge, two periodic jumps in one pixel) are averaged over
   ``supersample`` x ``supersample`` sub-pixel cells, each cell again exact in (1).

Colours compose like mu' does (``rendering.compose``): a layer with ``blend =
"multiply"`` multiplies the colour below by its own, ``"replace"`` paints over it where
the layer covers. A layer's colour goes from ``visual.color_low`` at the lowest mu' it
asks for to ``visual.color_high`` at its highest (``VisualHints``); the empty plate is
white (mu' = 1, neutral under multiply). Colours are linear RGB; :func:`to_srgb8`
encodes them for the screen and PNG files.

Outlines (``visual.outline`` in the file, or ``outlines=True`` for every layer with a
region or a shape) are drawn 1.5 px wide on the boundary's signed distance; force
layers' targets and directions on top (``force_marks``).
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from frictex.rendering.visual.force_marks import draw_force_marks, has_marks
from frictex.rendering.visual.viewport import Viewport
from frictex.textures.dynamic import DynamicLayer
from frictex.textures.heights import GaussianBump, HeightLayer, HeightMap
from frictex.textures.model import (Bump, Directional, DiscRegion, Edge, Guidance, KeyClick, Line,
                                    RasterMap, RectRegion, Scene, Shape)

OUTLINE_RGB = np.array([1.0, 0.35, 0.0])  # orange: visible on black, white and grey
OUTLINE_WIDTH_PX = 1.5
#: table cells per pixel: a tabulated edge is off by at most 1/(2 * this) px, which
#: keeps a pixel next to a black line within one sRGB code (sRGB is steep near black)
TABLE_CELLS_PER_PX = 2048
TABLE_MIN, TABLE_MAX = 1024, 1 << 20
#: sub-pixel cells composed at once when supersampling (about 100 bytes each at the peak)
SUPERSAMPLE_CELLS = 1 << 18
#: a jump in a periodic profile: a change of more than this fraction of its mu' range
#: between two table cells
JUMP_FRACTION = 0.02


def layer_rgb(layer, mu: np.ndarray, dtype=np.float64) -> np.ndarray:
    """Linear RGB (..., 3) of a layer where its mu' is ``mu`` (...), of ``dtype``."""
    lo, hi = layer.mu_range
    u = (mu - lo) / (hi - lo) if hi > lo else np.ones_like(mu)
    low = np.asarray(layer.visual.color_low, dtype=dtype)
    high = np.asarray(layer.visual.color_high, dtype=dtype)
    return low + np.clip(u, 0.0, 1.0).astype(dtype)[..., None] * (high - low)


# ---------------------------------------------------------------------------
# Periodic layers: exact pixel averages from a table over one period


def _box(table: np.ndarray, half: float) -> np.ndarray:
    """Mean of a periodic function over [p - half, p + half] (cycles), at the table's cell
    centres p = (k + 0.5) / n; ``table`` (n,) holds its cell means. Exact for a function
    constant on each cell (the cumulative integral is then piecewise linear)."""
    n = table.size
    if half * n < 1e-3:
        return table
    cum = np.concatenate(([0.0], np.cumsum(table))) / n  # integral over [0, k / n]

    def integral(shift_cells: float) -> np.ndarray:
        """Integral over [0, (k + 0.5 + shift) / n] for k = 0..n-1, periods unrolled."""
        pos = np.arange(n) + 0.5 + shift_cells
        cell = np.floor(pos)
        turns = np.floor(cell / n)
        k = (cell - turns * n).astype(np.intp)
        frac = pos - cell
        return turns * cum[-1] + cum[k] * (1.0 - frac) + cum[k + 1] * frac

    return (integral(half * n) - integral(-half * n)) / (2.0 * half)


def _table_size(layer, pixel_mm: tuple[float, float]) -> int:
    period_px = layer.period_mm / min(pixel_mm)
    n = max(TABLE_MIN, TABLE_CELLS_PER_PX * period_px)
    return int(min(TABLE_MAX, 1 << math.ceil(math.log2(n))))


def _footprint(layer, cell_mm: tuple[float, float]) -> tuple[float, float]:
    """Half-widths (cycles) of the two boxes whose convolution is the cell (w x h mm)
    projected on the layer's axis: |ax| w and |ay| h."""
    ax, ay = layer.axis
    return (0.5 * abs(ax) * cell_mm[0] / layer.period_mm,
            0.5 * abs(ay) * cell_mm[1] / layer.period_mm)


@lru_cache(maxsize=8)
def _period_tables(layer, cell_mm: tuple[float, float],
                   pixel_mm: tuple[float, float]) -> tuple[np.ndarray, np.ndarray]:
    """At the phases (k + 0.5) / n: mean mu' over the cell (n,) and the layer's colour
    for that mean (n, 3) float32. The table's resolution follows the pixel (a sub-pixel
    cell's error counts for its share of the pixel)."""
    n = _table_size(layer, pixel_mm)
    a, b = _footprint(layer, cell_mm)
    mean = _box(_box(layer.profile((np.arange(n) + 0.5) / n), a), b)
    return mean, layer_rgb(layer, mean, np.float32)


@lru_cache(maxsize=8)
def _jump_table(layer, cell_mm: tuple[float, float]) -> np.ndarray:
    """At the phases (k + 0.5) / n: whether a jump of the profile lies in the cell (n,) bool
    (the cell is a pixel)."""
    n = _table_size(layer, cell_mm)
    profile = layer.profile((np.arange(n) + 0.5) / n)
    lo, hi = layer.mu_range
    jump = (np.abs(np.roll(profile, -1) - profile) > JUMP_FRACTION * (hi - lo)).astype(np.float64)
    return _box(jump, sum(_footprint(layer, cell_mm)) + 1.0 / n) > 0.0


def clear_tables() -> None:
    """Forget the cached period tables (a cold start, for ``frictex bench visual``)."""
    _period_tables.cache_clear()
    _jump_table.cache_clear()


def _phase_index(layer, x, y, n: int) -> np.ndarray:
    """Table cell (0..n-1) of the phase at (x, y) mm."""
    idx = (np.mod(layer.phase_at(x, y), 1.0) * n).astype(np.intp)
    return np.minimum(idx, n - 1, out=idx)


def periodic_mean(layer, x, y, cell_mm: tuple[float, float],
                  pixel_mm: tuple[float, float] | None = None) -> np.ndarray:
    """Average mu' of a periodic layer over cells of ``cell_mm`` = (width, height) mm
    centred on (x, y) mm (an edge placed within 1/4096 of a pixel of ``pixel_mm``,
    default the cell).

    Parameters
    ----------
    layer : a periodic layer (``is_periodic``).
    x, y : arrays (broadcastable), mm.
    cell_mm, pixel_mm : the cell's and the pixel's size (mm), axis-aligned.

    Returns
    -------
    mu' (float64), the broadcast shape of x and y.
    """
    pixel_mm = cell_mm if pixel_mm is None else pixel_mm
    mean, _ = _period_tables(layer, tuple(map(float, cell_mm)), tuple(map(float, pixel_mm)))
    return mean[_phase_index(layer, x, y, mean.size)]


def layer_mu(layer, x, y, cell_mm: tuple[float, float] | None = None,
             pixel_mm: tuple[float, float] | None = None) -> np.ndarray:
    """mu' of a layer at (x, y) mm; for a periodic layer and a cell of ``cell_mm`` =
    (width, height) mm, its exact average over the cell (:func:`periodic_mean`)."""
    if isinstance(layer, HeightLayer):  # shaded relief: a height has no mu' at rest to draw
        return layer.relief_mu(x, y)
    if cell_mm is None or not layer.is_periodic:
        return layer.mu_at(x, y)
    return periodic_mean(layer, x, y, cell_mm, pixel_mm)


def composed_rgb(scene: Scene, x: np.ndarray, y: np.ndarray,
                 cell_mm: tuple[float, float] | None = None,
                 pixel_mm: tuple[float, float] | None = None) -> np.ndarray:
    """Linear RGB (..., 3) of the scene at positions (mm), layers composed in order
    (``cell_mm``: the sampling cell each position stands for, inside a pixel of
    ``pixel_mm``; see :func:`layer_mu`)."""
    rgb = np.ones(np.shape(x) + (3,))
    for layer in scene.layers:
        colour = layer_rgb(layer, layer_mu(layer, x, y, cell_mm, pixel_mm))
        covers = layer.covers(x, y)[..., None]
        rgb = np.where(covers, colour if layer.blend == "replace" else rgb * colour, rgb)
    return rgb


# ---------------------------------------------------------------------------
# Where a layer can change: bounding boxes and discontinuities


def _region_box(region) -> tuple[float, float, float, float]:
    if isinstance(region, DiscRegion):
        r = region.radius_mm
        return region.cx_mm - r, region.cy_mm - r, region.cx_mm + r, region.cy_mm + r
    a = math.radians(region.angle_deg)
    hw = 0.5 * (abs(math.cos(a)) * region.width_mm + abs(math.sin(a)) * region.height_mm)
    hh = 0.5 * (abs(math.sin(a)) * region.width_mm + abs(math.cos(a)) * region.height_mm)
    cx, cy = region.center
    return cx - hw, cy - hh, cx + hw, cy + hh


def _grow(box, by: float):
    return box[0] - by, box[1] - by, box[2] + by, box[3] + by


def _support_box(layer):
    """Box (x0, y0, x1, y1) mm outside which ``layer.covers`` is False; None: unbounded."""
    boxes = [] if layer.region is None else [_region_box(layer.region)]
    if isinstance(layer, Shape):
        boxes.append(_grow(_region_box(layer.geometry), layer.edge_mm / 2))
    elif isinstance(layer, Line):
        reach = layer.width_mm / 2 + layer.edge_mm / 2
        boxes.append(_grow((min(layer.x0_mm, layer.x1_mm), min(layer.y0_mm, layer.y1_mm),
                            max(layer.x0_mm, layer.x1_mm), max(layer.y0_mm, layer.y1_mm)), reach))
    elif isinstance(layer, Bump):
        boxes.append(_grow((layer.cx_mm, layer.cy_mm, layer.cx_mm, layer.cy_mm), 4 * layer.sigma_mm))
    elif isinstance(layer, RasterMap):
        boxes.append(_region_box(layer.sprite))
    elif isinstance(layer, KeyClick):
        boxes.append(_region_box(layer.geometry))
    if not boxes:
        return None
    return (max(b[0] for b in boxes), max(b[1] for b in boxes),
            min(b[2] for b in boxes), min(b[3] for b in boxes))


def _discontinuities(layer, x, y, pixel_mm: tuple[float, float]) -> np.ndarray | None:
    """Where the layer's colour or coverage may jump inside the pixel centred on (x, y):
    bool array, or None where it cannot tell (then every pixel is supersampled)."""
    reach = 0.5 * math.hypot(*pixel_mm)  # a pixel's half diagonal
    smooth_mm = 2.0 * max(pixel_mm)  # a ramp this wide is smooth at the pixel scale

    def band(distance, lo=0.0, hi=0.0):
        return (distance >= lo - reach) & (distance <= hi + reach)

    def soft_edge(distance, edge_mm: float, covers_to: float):
        """A raised-cosine ramp of edge_mm across distance 0, coverage ending at covers_to."""
        if edge_mm < smooth_mm:
            return band(distance, -edge_mm / 2, max(edge_mm / 2, covers_to))
        return band(distance, covers_to, covers_to)

    found = np.zeros(np.broadcast(x, y).shape, dtype=bool)
    if layer.region is not None:
        found |= band(layer.region.signed_distance(x, y))
    if layer.is_periodic or isinstance(layer, (Directional, Guidance)):
        return found
    if isinstance(layer, HeightLayer):
        return found | _relief_jumps(layer.shape, x, y, band, smooth_mm, pixel_mm)
    if isinstance(layer, DynamicLayer):  # drawn at its mu' at rest: uniform
        return found
    if isinstance(layer, Shape):
        return found | soft_edge(layer.geometry.signed_distance(x, y), layer.edge_mm,
                                 layer.edge_mm / 2)
    if isinstance(layer, Line):
        return found | soft_edge(layer._signed_distance(x, y), layer.edge_mm, layer.edge_mm / 2)
    if isinstance(layer, Edge):  # covers everywhere: only the ramp
        if layer.edge_mm >= smooth_mm:
            return found
        return found | band(layer._distance(x, y), -layer.edge_mm / 2, layer.edge_mm / 2)
    if isinstance(layer, Bump):
        r = np.hypot(x - layer.cx_mm, y - layer.cy_mm) - 4 * layer.sigma_mm
        inner = -4 * layer.sigma_mm if layer.sigma_mm < smooth_mm else 0.0
        return found | band(r, inner)
    if isinstance(layer, RasterMap):
        rows, cols = layer.image.shape
        tile_w, tile_h = ((layer.tile_width_mm, layer.tile_height_mm) if layer.mode == "tile"
                          else (layer.width_mm, layer.height_mm))
        inner = -np.inf if min(tile_w / cols, tile_h / rows) < max(pixel_mm) else 0.0
        return found | band(layer.sprite.signed_distance(x, y), inner)
    if isinstance(layer, KeyClick):
        return found | band(layer.geometry.signed_distance(x, y))
    return None


def _relief_jumps(shape, x, y, band, smooth_mm: float, pixel_mm: tuple[float, float]) -> np.ndarray:
    """Where a height's shaded relief (a function of its gradient) may change faster
    than the pixel scale: at a slope band's edges where the gradient jumps (a step's
    chamfer; a raised cosine's slope is continuous there, but kept for safety: the band
    is thin), across the whole band, bump or map when its feature is narrower than
    ``smooth_mm``, and at a map sprite's border. Elsewhere the relief is smooth and a
    pixel's centre stands for its mean."""
    if isinstance(shape, HeightMap):
        rows, cols = shape.heights_mm.shape
        sprite = RectRegion(shape.x_mm, shape.y_mm, shape.width_mm, shape.height_mm)
        fine = min(shape.width_mm / cols, shape.height_mm / rows) < max(pixel_mm)
        return band(sprite.signed_distance(x, y), -np.inf if fine else 0.0)
    if isinstance(shape, GaussianBump):
        r = np.hypot(x - shape.cx_mm, y - shape.cy_mm) - 4 * shape.sigma_mm
        return band(r, -np.inf) if shape.sigma_mm < smooth_mm else np.zeros(r.shape, bool)
    sb = shape.slope_band
    if sb.ring:
        d = np.hypot(x - sb.x0_mm, y - sb.y0_mm)
    else:
        d = sb.nx * (x - sb.x0_mm) + sb.ny * (y - sb.y0_mm)
    if sb.hi_mm - sb.lo_mm < smooth_mm:
        return band(d, sb.lo_mm, sb.hi_mm)
    return band(d, sb.lo_mm, sb.lo_mm) | band(d, sb.hi_mm, sb.hi_mm)


def _pixel_slice(box, sx: float, sy: float, width: int, height: int):
    """Rows and columns of the pixels whose centres may lie in ``box`` (mm)."""
    if box is None:
        return slice(0, height), slice(0, width)
    c0 = max(0, int(math.floor(box[0] * sx - 1)))
    c1 = min(width, int(math.ceil(box[2] * sx + 1)))
    r0 = max(0, int(math.floor(box[1] * sy - 1)))
    r1 = min(height, int(math.ceil(box[3] * sy + 1)))
    return slice(r0, max(r0, r1)), slice(c0, max(c0, c1))


# ---------------------------------------------------------------------------
# The image


def scene_rgb(scene: Scene, viewport: Viewport, supersample: int = 4,
              outlines: bool = False) -> np.ndarray:
    """The active area of ``viewport`` rendered: linear RGB, float32 (height_px, width_px, 3).

    Row 0 is the top of the screen (y = 0 mm). Positions and mu' are float64; colours
    float32 (24-bit mantissa, for 8-bit output). Periodic layers are averaged exactly over
    each pixel; pixels crossed by another discontinuity average ``supersample**2`` cells
    centred at x = (j + (a + 0.5)/s) / px_per_mm_x (and likewise in y), a, b in 0..s-1.
    """
    if supersample < 1:
        raise ValueError(f"supersample {supersample!r}: expected at least 1")
    sx, sy = viewport.px_per_mm
    width, height = viewport.width_px, viewport.height_px
    pixel = (1.0 / sx, 1.0 / sy)
    xs = (np.arange(width) + 0.5) / sx
    ys = (np.arange(height) + 0.5) / sy
    rgb = np.ones((height, width, 3), dtype=np.float32)
    rough = np.zeros((height, width), dtype=bool)  # pixels to supersample
    jumps = np.zeros((height, width), dtype=np.int8)  # periodic jumps per pixel
    count_jumps = sum(layer.is_periodic for layer in scene.layers) > 1
    for layer in scene.layers:
        rows, cols = _pixel_slice(_support_box(layer), sx, sy, width, height)
        # a row and a column of positions: the model's numpy broadcasts them to the block
        x, y = xs[None, cols], ys[rows, None]
        shape = (y.size, x.size)
        if 0 in shape:
            continue
        if layer.is_periodic:
            colours = _period_tables(layer, pixel, pixel)[1]
            idx = _phase_index(layer, x, y, colours.shape[0])
            colour = colours[idx]
            if count_jumps:
                jumps[rows, cols] += _jump_table(layer, pixel)[idx]
        else:
            colour = layer_rgb(layer, np.broadcast_to(layer_mu(layer, x, y), shape), np.float32)
        edges = _discontinuities(layer, x, y, pixel)
        rough[rows, cols] |= True if edges is None else edges
        covers = np.broadcast_to(layer.covers(x, y), shape)
        below = rgb[rows, cols]  # a view: composed in place
        where = True if covers.all() else covers[..., None]
        if layer.blend == "replace":
            np.copyto(below, colour, where=where)
        else:
            np.multiply(below, colour, out=below, where=where)
    rough |= jumps >= 2
    if supersample > 1 and rough.any():
        rgb[rough] = _supersampled(scene, *np.nonzero(rough), sx, sy, supersample)
    if outlines or any(layer.visual.outline for layer in scene.layers):
        rgb = _draw_outlines(scene, rgb, xs, ys, sx, sy, outlines)
    if has_marks(scene):
        rgb = draw_force_marks(scene, rgb, xs, ys, (sx, sy))
    return rgb


def _supersampled(scene, rows, cols, sx, sy, s: int) -> np.ndarray:
    """Mean colour (k, 3) of the pixels (rows, cols) over s x s cells each, composed
    ``SUPERSAMPLE_CELLS`` cells at a time (memory bounded whatever k)."""
    offsets = (np.arange(s) + 0.5) / s
    cell = (1.0 / (s * sx), 1.0 / (s * sy))
    out = np.empty((rows.size, 3), dtype=np.float32)
    step = max(1, SUPERSAMPLE_CELLS // (s * s))
    for lo in range(0, rows.size, step):
        part = slice(lo, lo + step)
        x = (cols[part, None] + offsets[None, :]) / sx  # (k, s)
        y = (rows[part, None] + offsets[None, :]) / sy
        k = x.shape[0]
        xx = np.broadcast_to(x[:, None, :], (k, s, s))
        yy = np.broadcast_to(y[:, :, None], (k, s, s))
        out[part] = composed_rgb(scene, xx, yy, cell, (1.0 / sx, 1.0 / sy)).mean(axis=(1, 2))
    return out


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
    if isinstance(layer, KeyClick):
        return layer.geometry.signed_distance(x, y)
    return None


def _draw_outlines(scene, rgb, xs, ys, sx, sy, all_layers: bool) -> np.ndarray:
    mm_per_px = 1.0 / min(sx, sy)
    reach = (OUTLINE_WIDTH_PX / 2 + 1.0) * mm_per_px
    for layer in scene.layers:
        if not (all_layers or layer.visual.outline):
            continue
        if isinstance(layer, (Shape, KeyClick)):  # the outline is the object's, not its region's
            box = _region_box(layer.geometry)
        else:
            box = _support_box(layer) if layer.region is None else _region_box(layer.region)
        rows, cols = _pixel_slice(None if box is None else _grow(box, reach),
                                  sx, sy, rgb.shape[1], rgb.shape[0])
        x, y = np.broadcast_arrays(xs[None, cols], ys[rows, None])
        d = _outline_distance(layer, x, y) if x.size else None
        if d is None:
            continue
        alpha = np.clip(OUTLINE_WIDTH_PX / 2 + 0.5 - np.abs(d) / mm_per_px, 0.0, 1.0)[..., None]
        rgb[rows, cols] = rgb[rows, cols] * (1 - alpha) + OUTLINE_RGB * alpha
    return rgb


# ---------------------------------------------------------------------------
# sRGB


def _srgb_formula(c: np.ndarray) -> np.ndarray:
    s = np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1 / 2.4) - 0.055)
    return np.round(s * 255.0).astype(np.uint8)


_SRGB_BINS = 1 << 16


@lru_cache(maxsize=1)
def _srgb_lut() -> tuple[np.ndarray, np.ndarray]:
    """(code of each of _SRGB_BINS equal bins of [0, 1], whether the code changes inside
    the bin): bins where it does are encoded with the formula itself."""
    edges = np.linspace(0.0, 1.0, _SRGB_BINS + 1)
    code = _srgb_formula(edges)
    return code[:-1], code[:-1] != code[1:]


def to_srgb8(rgb: np.ndarray) -> np.ndarray:
    """Linear RGB in [0, 1] (float) -> sRGB uint8 (IEC 61966-2-1 transfer curve)."""
    c = np.clip(rgb, 0.0, 1.0)
    code, ambiguous = _srgb_lut()
    idx = np.minimum((c * _SRGB_BINS).astype(np.intp), _SRGB_BINS - 1)
    out = code[idx]
    slow = ambiguous[idx]
    if slow.any():
        out[slow] = _srgb_formula(c[slow])
    return out


def from_srgb8(srgb: np.ndarray) -> np.ndarray:
    """sRGB uint8 -> linear RGB float64 in [0, 1] (inverse of :func:`to_srgb8`)."""
    s = np.asarray(srgb, dtype=np.float64) / 255.0
    return np.where(s <= 0.04045, s / 12.92, np.power((s + 0.055) / 1.055, 2.4))

"""Heights (mm) felt by their slope: analytic shapes, 16-bit height maps, and the height layer.

A flat friction display cannot raise the surface; it renders a shape through the
lateral-force illusion (Robles-De-La-Torre and Hayward, Nature 412:445, 2001): sliding
over a real bump, the finger is opposed by a force that grows with the slope while it
climbs and assists it while it descends, and subjects perceive a bump from that force
alone, even on a flat or hollow surface. Kim, Israr and Poupyrev (UIST 2013, "Tactile
rendering of 3D features on touch surfaces") map the local gradient of a virtual
surface to the lateral friction force of an electrovibration display. Here are the
heights, the slope a moving finger feels (``slope_along_motion``) and the layer's mapping
from slope to mu'; ``rendering.layers.height`` renders them under each finger.

Every shape answers ``height_and_gradient(x, y) -> (h, dh/dx, dh/dy)`` (mm, and mm per
mm) at arrays of positions (mm), ``gradient(x, y) -> (dh/dx, dh/dy)`` (the same
gradient without computing the height: what the haptics and the relief use), and
``support(x, y)``: where its gradient can be non-zero (for drawing and bounds; the
layer itself covers its whole region). A shape whose gradient is 0 away from a strip or
a ring also has a ``slope_band`` (:class:`SlopeBand`), so that a renderer can skip the
samples outside it; the others have ``slope_band = None``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
import numpy as np

from frictex.device.jit import njit
from frictex.textures.dynamic import DynamicLayer
from frictex.textures.model import _hypot
from frictex.textures.raster_io import PixelBudget, read_grey

HEIGHT_RENDERINGS = ("slope", "magnitude")
#: the image a height map takes, for error messages
HEIGHT_PNG = ("16-bit greyscale PNG (height = value / 65535 x rise_mm; 8-bit levels make "
              "slopes of zero or spikes)")
#: Bytes a decoded height map keeps per pixel: its heights and the three float64 planes
#: of :class:`HeightMap` (height, dh/dx, dh/dy).
HEIGHT_MAP_BYTES_PER_PX = 32
#: shaded relief for the visual layer: light from the top-left of the screen, 45 deg up,
#: heights exaggerated this many times (screen shapes are a few tenths of a mm high)
RELIEF_LIGHT = np.array([-1.0, -1.0, math.sqrt(2.0)]) / 2.0
RELIEF_EXAGGERATION = 5.0
#: drawn level per unit of Lambert shade about flat ground's: a slope facing away from the
#: light (shade 0) draws at 0.5 - 0.7 * 0.707 = 0.005 of the colour range, never clipped
RELIEF_CONTRAST = 0.7


#: a :class:`SlopeBand` is widened by this fraction of its width (plus 1e-9 mm) on either
#: side: a band test rounds differently from the shape's kernel near the edge, and the
#: samples it lets in for nothing get their exact (zero) gradient from the kernel
BAND_MARGIN = 1e-6


@dataclass(frozen=True)
class SlopeBand:
    """Where a shape's gradient can be non-zero: positions whose distance d (mm) is within
    [lo_mm, hi_mm], d the distance from (x0_mm, y0_mm) if ``ring``, else the signed
    distance nx (x - x0_mm) + ny (y - y0_mm) from the line through that point with unit
    normal (nx, ny). Outside it the gradient is exactly 0 (a signed zero); a position
    whose d is not finite counts as inside. Made by :func:`_band`."""

    ring: bool
    x0_mm: float
    y0_mm: float
    nx: float
    ny: float
    lo_mm: float
    hi_mm: float


def _band(ring: bool, x0: float, y0: float, nx: float, ny: float, lo: float,
          hi: float) -> SlopeBand:
    """The :class:`SlopeBand` of d in (lo, hi) (mm), widened by ``BAND_MARGIN``."""
    pad = BAND_MARGIN * (hi - lo) + 1e-9
    return SlopeBand(ring, x0, y0, nx, ny, lo - pad, hi + pad)


def _from_centre(x, y, cx: float, cy: float):
    """Offsets (dx, dy) and distance r (mm) of positions from a centre."""
    dx = np.asarray(x, dtype=np.float64) - cx
    dy = np.asarray(y, dtype=np.float64) - cy
    return dx, dy, _hypot(dx, dy)


def _normal(normal_deg: float) -> tuple[float, float]:
    """The unit vector (nx, ny) at ``normal_deg`` from +x."""
    a = math.radians(normal_deg)
    return math.cos(a), math.sin(a)


def _along(x, y, x0: float, y0: float, normal_deg: float):
    """Signed distance (mm) of positions from the line through (x0, y0) whose unit normal
    is at ``normal_deg`` from +x, positive on the normal's side."""
    nx, ny = _normal(normal_deg)
    return nx * (np.asarray(x, dtype=np.float64) - x0) + ny * (np.asarray(y, dtype=np.float64) - y0)


def _broadcast_flat(*values) -> tuple[list[np.ndarray], tuple[int, ...]]:
    """float64 (m,) arrays of the values broadcast to one shape, and that shape."""
    arrays = [np.asarray(a, dtype=np.float64) for a in values]
    if len({a.shape for a in arrays}) > 1:
        arrays = np.broadcast_arrays(*arrays)
    return [a.ravel() for a in arrays], arrays[0].shape


class _Planes:
    """A shape computed by its ``_fill(x, y, out)``: positions (mm) as two float64 (m,)
    arrays, ``out`` the (3, m) planes (h, dh/dx, dh/dy) or, without the height, the
    (2, m) planes (dh/dx, dh/dy); the kernels compute the height only when there is a row
    for it (row 0, above the gradient's two)."""

    def _evaluate(self, x, y, with_height: bool) -> tuple[np.ndarray, ...]:
        (x, y), shape = _broadcast_flat(x, y)
        out = np.empty((3 if with_height else 2, x.size))
        self._fill(x, y, out)
        return tuple(plane.reshape(shape) for plane in out)

    def height_and_gradient(self, x, y):
        return self._evaluate(x, y, True)

    def gradient(self, x, y):
        return self._evaluate(x, y, False)

    @property
    def relief_mm(self) -> float:
        """The span of the shape's heights (mm): 0 for a flat shape, whose slope is 0
        everywhere (nothing of it is felt)."""
        return abs(self.height_mm)


@njit(cache=True, nogil=True)
def _cosine_height(u, height_mm):
    """A raised-cosine fall from ``height_mm`` at u <= 0 to 0 at u >= 1: the height
    h = H (1 + cos(pi u)) / 2 on [0, 1] (mm; NaN stays NaN)."""
    uc = 0.0 if u < 0.0 else (1.0 if u > 1.0 else u)
    return height_mm * 0.5 * (1.0 + np.cos(np.pi * uc))


@njit(cache=True, nogil=True)
def _cosine_slopes(u, height_mm, out):
    """Multiply the gradient planes ``out[-2:]`` (``_Planes``), each (m,), by dh/du of
    :func:`_cosine_height` at u (m,) where 0 < u < 1 (elsewhere the slope is 0: the
    caller has put 0 times the factor there). The sine is taken at those samples only:
    in a loop over every sample the compiler vectorises it and computes it for all."""
    g = out.shape[0] - 2
    on = np.nonzero((0.0 < u) & (u < 1.0))[0]
    for i in on:
        slope = -height_mm * 0.5 * np.pi * np.sin(np.pi * u[i])
        out[g, i], out[g + 1, i] = slope * out[g, i], slope * out[g + 1, i]


@njit(cache=True, nogil=True)
def _sign(d):
    """numpy's sign: -1, 0 (also for -0) or 1; NaN stays NaN."""
    return 1.0 if d > 0.0 else (-1.0 if d < 0.0 else (0.0 if d == 0.0 else d))


@dataclass(frozen=True)
class GaussianBump(_Planes):
    """h = H exp(-r^2 / (2 sigma^2)) about (cx_mm, cy_mm); a negative H is a dip.
    Steepest slope H / sigma * exp(-1/2) at r = sigma."""

    cx_mm: float
    cy_mm: float
    sigma_mm: float
    height_mm: float

    def _fill(self, x, y, out):
        centre, variance = (self.cx_mm, self.cy_mm), self.sigma_mm ** 2
        gauss = _bump_exponent(x, y, centre, 2.0 * variance)
        np.exp(gauss, out=gauss)  # numpy's, not libm's (a kernel's): they differ in the last digit
        _bump(x, y, centre, self.height_mm, variance, gauss, out)

    #: a gaussian's slope is non-zero everywhere
    slope_band = None

    def support(self, x, y):
        return _from_centre(x, y, self.cx_mm, self.cy_mm)[2] <= 4.0 * self.sigma_mm


@njit(cache=True, nogil=True)
def _bump_exponent(x, y, centre, two_variance):
    """-r^2 / (2 sigma^2) (m,) at positions (x, y) (mm, (m,)) about ``centre`` (mm)."""
    cx, cy = centre
    out = np.empty(x.size)
    for i in range(x.size):
        dx, dy = x[i] - cx, y[i] - cy
        r = np.sqrt(dx * dx + dy * dy)
        out[i] = -r * r / two_variance
    return out


@njit(cache=True, nogil=True)
def _bump(x, y, centre, height_mm, variance, gauss, out):
    """Fill the planes (``_Planes``) of a :class:`GaussianBump` about ``centre`` (mm) from
    ``gauss`` = exp(-r^2 / (2 sigma^2)) (m,): h = H gauss, grad h = -h / sigma^2 (dx, dy)."""
    cx, cy = centre
    g = out.shape[0] - 2  # the row of dh/dx; the height is row 0 above it, if there
    for i in range(x.size):
        h = height_mm * gauss[i]
        k = -h / variance
        out[g, i], out[g + 1, i] = k * (x[i] - cx), k * (y[i] - cy)
        if g:
            out[0, i] = h


@dataclass(frozen=True)
class Ridge(_Planes):
    """A straight ridge through (x_mm, y_mm) running at ``angle_deg`` from +x: a raised
    cosine across it, H on the centre line falling to 0 at width_mm / 2 on either side.
    Steepest slope pi H / width_mm."""

    x_mm: float
    y_mm: float
    angle_deg: float
    width_mm: float
    height_mm: float

    def _fill(self, x, y, out):
        line = (self.x_mm, self.y_mm, *_normal(self.angle_deg + 90.0))
        _ridge(x, y, line, self.width_mm / 2, self.height_mm, out)

    @property
    def slope_band(self) -> SlopeBand:
        half = self.width_mm / 2
        return _band(False, self.x_mm, self.y_mm, *_normal(self.angle_deg + 90.0), -half, half)

    def support(self, x, y):
        d = _along(x, y, self.x_mm, self.y_mm, self.angle_deg + 90.0)
        return np.abs(d) <= self.width_mm / 2


@njit(cache=True, nogil=True, inline="always")
def _cosine_sample(out, g, i, u, ax, ay, height_mm):
    """Sample ``i`` of a raised-cosine shape at ``u`` (0 to 1 across its flank) whose
    grad u is (ax, ay) per mm: grad h = dh/du (ax, ay), the dh/du factor applied later
    by ``_cosine_slopes`` (signed zeros off the flank, NaN for a NaN position), and the
    height in row 0 when ``g`` (the row of dh/dx) leaves room for it."""
    if 0.0 < u < 1.0:
        out[g, i], out[g + 1, i] = ax, ay
    else:
        out[g, i], out[g + 1, i] = 0.0 * ax, 0.0 * ay
    if g:
        out[0, i] = _cosine_height(u, height_mm)


@njit(cache=True, nogil=True)
def _ridge(x, y, line, half, height_mm, out):
    """Fill the planes (``_Planes``) of a :class:`Ridge` of half width ``half`` (mm) whose
    centre line passes through (x0, y0) with unit normal (nx, ny), ``line``."""
    x0, y0, nx, ny = line
    g = out.shape[0] - 2  # the row of dh/dx; the height is row 0 above it, if there
    u = np.empty(x.size)
    for i in range(x.size):
        d = nx * (x[i] - x0) + ny * (y[i] - y0)
        sign = _sign(d)
        u[i] = abs(d) / half
        _cosine_sample(out, g, i, u[i], sign * nx / half, sign * ny / half, height_mm)
    _cosine_slopes(u, height_mm, out)


@dataclass(frozen=True)
class Step(_Planes):
    """A step along the line through (x_mm, y_mm): 0 on one side, H on the side the
    normal at ``angle_deg`` from +x points to, joined by a flat chamfer ``chamfer_mm``
    wide centred on the line (slope H / chamfer_mm; a vertical step has no finite slope)."""

    x_mm: float
    y_mm: float
    angle_deg: float
    height_mm: float
    chamfer_mm: float

    def _fill(self, x, y, out):
        line = (self.x_mm, self.y_mm, *_normal(self.angle_deg))
        _step(x, y, line, self.chamfer_mm, self.height_mm, out)

    @property
    def slope_band(self) -> SlopeBand:
        half = self.chamfer_mm / 2
        return _band(False, self.x_mm, self.y_mm, *_normal(self.angle_deg), -half, half)

    def support(self, x, y):
        d = _along(x, y, self.x_mm, self.y_mm, self.angle_deg)
        return np.abs(d) <= self.chamfer_mm / 2


@njit(cache=True, nogil=True)
def _step(x, y, line, chamfer_mm, height_mm, out):
    """Fill the planes (``_Planes``) of a :class:`Step` on the line through (x0, y0) with
    unit normal (nx, ny), ``line``."""
    x0, y0, nx, ny = line
    rise = height_mm / chamfer_mm
    g = out.shape[0] - 2  # the row of dh/dx; the height is row 0 above it, if there
    for i in range(x.size):
        u = (nx * (x[i] - x0) + ny * (y[i] - y0)) / chamfer_mm + 0.5
        slope = rise if 0.0 < u < 1.0 else 0.0
        out[g, i], out[g + 1, i] = slope * nx, slope * ny
        if g:
            out[0, i] = height_mm * (0.0 if u < 0.0 else (1.0 if u > 1.0 else u))


@dataclass(frozen=True)
class ButtonRim(_Planes):
    """A round button: a plateau of height H out to radius_mm - rim_mm, then a rounded
    rim (raised cosine) falling to 0 at radius_mm. Steepest slope pi H / (2 rim_mm)."""

    cx_mm: float
    cy_mm: float
    radius_mm: float
    rim_mm: float
    height_mm: float

    def _fill(self, x, y, out):
        _button(x, y, (self.cx_mm, self.cy_mm), self.radius_mm, self.rim_mm, self.height_mm, out)

    @property
    def slope_band(self) -> SlopeBand:
        return _band(True, self.cx_mm, self.cy_mm, 0.0, 0.0, self.radius_mm - self.rim_mm,
                     self.radius_mm)

    def support(self, x, y):
        return _from_centre(x, y, self.cx_mm, self.cy_mm)[2] <= self.radius_mm


@njit(cache=True, nogil=True)
def _button(x, y, centre, radius_mm, rim_mm, height_mm, out):
    """Fill the planes (``_Planes``) of a :class:`ButtonRim` about ``centre`` (mm)."""
    cx, cy = centre
    plateau = radius_mm - rim_mm
    g = out.shape[0] - 2  # the row of dh/dx; the height is row 0 above it, if there
    u = np.empty(x.size)
    for i in range(x.size):
        dx, dy = x[i] - cx, y[i] - cy
        r = np.sqrt(dx * dx + dy * dy)
        inv = 1.0 / (r * rim_mm) if r > 0 else 0.0
        u[i] = (r - plateau) / rim_mm
        _cosine_sample(out, g, i, u[i], dx * inv, dy * inv, height_mm)
    _cosine_slopes(u, height_mm, out)


@dataclass(frozen=True, eq=False)
class HeightMap(_Planes):
    """A height map placed on the display like a raster sprite (unrotated): pixel value
    v of a 16-bit PNG gives h = v / 65535 * max_height_mm. Height and gradient are
    sampled bilinearly from the map and its central differences (mm per mm, with the
    sprite's pixel size); outside the sprite the height is that of the nearest edge."""

    heights_mm: np.ndarray
    x_mm: float
    y_mm: float
    width_mm: float
    height_mm: float
    _planes: np.ndarray = field(init=False, repr=False)  # (3, rows, cols): h, dh/dx, dh/dy

    def __post_init__(self):
        rows, cols = self.heights_mm.shape
        spacing = (self.height_mm / rows, self.width_mm / cols)
        gy, gx = (np.gradient(self.heights_mm, step, axis=axis) if size > 1  # else flat
                  else np.zeros_like(self.heights_mm)
                  for axis, (size, step) in enumerate(zip((rows, cols), spacing)))
        object.__setattr__(self, "_planes", np.stack((self.heights_mm, gx, gy)))

    @property
    def relief_mm(self) -> float:
        """The span of the map's heights (mm); ``height_mm`` is the sprite's size here."""
        return float(np.ptp(self.heights_mm))

    def _fill(self, x, y, out):
        placement = (self.x_mm, self.y_mm, self.width_mm, self.height_mm)
        _sample_map(self._planes[3 - out.shape[0]:], x, y, placement, out)

    #: a map's slopes are anywhere in its sprite, which usually fills the display
    slope_band = None

    def support(self, x, y):
        x = np.asarray(x, dtype=np.float64)
        y = np.asarray(y, dtype=np.float64)
        return ((x >= self.x_mm) & (x <= self.x_mm + self.width_mm)
                & (y >= self.y_mm) & (y <= self.y_mm + self.height_mm))


@njit(cache=True, nogil=True, error_model="numpy")
def _sample_map(planes, x, y, placement, out):
    """Fill the planes (``_Planes``) of a :class:`HeightMap`, height (mm) and gradient (mm
    per mm) at positions (x, y) (mm, (m,)), from its ``planes``, the same rows each
    (rows, cols), placed at ``placement`` = (x_mm, y_mm, width_mm, height_mm): bilinear
    between pixel centres, clamped to the edge pixels; outside the sprite the gradient
    is 0 (at a NaN position too, where the height is NaN)."""
    x_mm, y_mm, width_mm, height_mm = placement
    n_planes, rows, cols = planes.shape
    g = n_planes - 2  # the plane of dh/dx; the height is plane 0 before it, if there
    # pixel coordinates first, in a pass the compiler vectorises: the divisions took half
    # the time in one pass with the look-ups (and so did a loop over the planes)
    pixel_x, pixel_y = np.empty(x.size), np.empty(x.size)
    for i in range(x.size):
        pixel_x[i] = min(max((x[i] - x_mm) / width_mm * cols - 0.5, 0.0), cols - 1.0)
        pixel_y[i] = min(max((y[i] - y_mm) / height_mm * rows - 0.5, 0.0), rows - 1.0)
    for i in range(x.size):
        fx, fy = pixel_x[i], pixel_y[i]
        if not (fx == fx and fy == fy):  # a NaN position has no pixel (as an index: UB)
            if g:
                out[0, i] = np.nan
            out[g, i], out[g + 1, i] = 0.0, 0.0  # not inside the sprite
            continue
        x0, y0 = int(np.floor(fx)), int(np.floor(fy))
        corners = (x0, min(x0 + 1, cols - 1), y0, min(y0 + 1, rows - 1), fx - x0, fy - y0)
        inside = (x_mm <= x[i] <= x_mm + width_mm) and (y_mm <= y[i] <= y_mm + height_mm)
        if g:
            out[0, i] = _bilinear(planes[0], corners)
        out[g, i] = _bilinear(planes[g], corners) if inside else 0.0
        out[g + 1, i] = _bilinear(planes[g + 1], corners) if inside else 0.0


@njit(cache=True, nogil=True, inline="always")
def _bilinear(plane, corners):
    """``plane`` (rows, cols) between its pixels (x0, x1, y0, y1) at fractions (tx, ty),
    ``corners`` = (x0, x1, y0, y1, tx, ty)."""
    x0, x1, y0, y1, tx, ty = corners
    top = plane[y0, x0] * (1 - tx) + plane[y0, x1] * tx
    bottom = plane[y1, x0] * (1 - tx) + plane[y1, x1] * tx
    return top * (1 - ty) + bottom * ty


def read_height_png(path: str | Path, max_height_mm: float, budget: PixelBudget | None = None) -> np.ndarray:
    """Heights (mm), float64 (rows, cols), from a 16-bit greyscale PNG: value v gives
    v / 65535 * max_height_mm. Read by ``textures.raster_io.read_grey`` (its size and
    file checks apply; ``budget``, the scene's budget of decoded maps, is charged
    :data:`HEIGHT_MAP_BYTES_PER_PX` per pixel). An 8-bit image is refused: 256 levels make
    a staircase whose slope is zero or a spike, which this rendering would feel as clicks."""
    # refused from the header, before decoding (an 8-bit RGB map was decoded whole first)
    grey, _ = read_grey(path, HEIGHT_PNG, budget, HEIGHT_MAP_BYTES_PER_PX, header=(16, 0))
    return grey * max_height_mm


HeightShape = GaussianBump | Ridge | Step | ButtonRim | HeightMap


@dataclass(frozen=True)
class HeightLayer(DynamicLayer):
    """A height felt by its slope (``rendering.layers.height``).

    The slope s is dimensionless (mm of height per mm travelled). ``rendering``:

    - ``"slope"`` (signed, the lateral-force illusion): s is the height's derivative
      along the finger's direction of motion, positive climbing;
    - ``"magnitude"`` (Kim et al. 2013's unsigned rendering): s = |grad h|, the same
      whichever way the finger crosses.

    Either way s is scaled by min(1, speed / v_fade_mm_s), so a finger at rest feels no
    slope and a starting finger feels it grow with its speed. mu' then follows a soft
    saturation about ``mu_rest`` (mu' on flat ground, at rest, or outside the shape)::

        mu' = mu_rest + (mu_max - mu_rest) tanh(gain s / (mu_max - mu_rest))   s >= 0
        mu' = mu_rest + (mu_rest - mu_min) tanh(gain s / (mu_rest - mu_min))   s < 0

    so d mu'/d s = ``gain`` at s = 0, and mu' never leaves [mu_min, mu_max] (a clamp
    only takes back the ulp the sum can round past them at tanh = +-1); mu_min < mu_rest <
    mu_max (the loader checks it; the magnitude rendering never uses the lower branch, so
    mu_min = mu_rest is allowed there). ``mu_rest`` < 1 is what leaves room to raise
    friction while climbing; the layer covers its whole region (the display by default) at
    mu_rest, so that nothing steps at the edge of the shape.
    """

    renderer_kind = "height"
    FILE_TYPE = "height"

    shape: HeightShape = None  # type: ignore[assignment]
    rendering: str = "slope"
    gain: float = 2.0
    mu_rest: float = 0.8
    mu_min: float = 0.6
    mu_max: float = 1.0
    v_fade_mm_s: float = 10.0

    @property
    def mu_range(self) -> tuple[float, float]:
        """The mu' it may ask for: the magnitude rendering never goes below mu_rest."""
        return (self.mu_rest if self.rendering == "magnitude" else self.mu_min), self.mu_max

    @property
    def rest_mu(self) -> float:
        return self.mu_rest

    def relief_mu(self, x, y) -> np.ndarray:
        """Shaded relief for drawing, as a mu' in [mu_min, mu_max] (so the layer's colours
        apply): Lambert shading of the exaggerated height under ``RELIEF_LIGHT``, flat
        ground half way, from the same gradients the haptics use."""
        gx, gy = self.shape.gradient(x, y)
        gx, gy = RELIEF_EXAGGERATION * gx, RELIEF_EXAGGERATION * gy
        lx, ly, lz = RELIEF_LIGHT
        shade = (-gx * lx - gy * ly + lz) / np.sqrt(gx * gx + gy * gy + 1.0)
        u = np.clip(0.5 + RELIEF_CONTRAST * (shade - lz), 0.0, 1.0)
        return self.mu_min + u * (self.mu_max - self.mu_min)

    def mu_of_slope(self, slope) -> np.ndarray:
        """mu' for slope s (the class docstring's saturation), any shape."""
        s = np.asarray(slope, dtype=np.float64)
        arg = _tanh_args(s.ravel(), self.mu_max - self.mu_rest, self.mu_rest - self.mu_min,
                         self.gain)
        return self._mu_of_args(arg).reshape(s.shape)

    def mu_of_motion(self, gx, gy, vx, vy) -> np.ndarray:
        """mu' of a finger moving at velocity (vx, vy) (mm/s) over height gradient (gx, gy)
        (mm per mm), any broadcastable shapes: ``mu_of_slope(slope_along_motion(...))``
        with this layer's rendering and v_fade_mm_s, bit for bit, in one pass and without
        the slope's array."""
        arrays, shape = _broadcast_flat(gx, gy, vx, vy)
        arg = _tanh_args_of_motion(*arrays, self.v_fade_mm_s, self.rendering == "slope",
                                   self.mu_max - self.mu_rest, self.mu_rest - self.mu_min,
                                   self.gain)
        return self._mu_of_args(arg).reshape(shape)

    def _mu_of_args(self, arg: np.ndarray) -> np.ndarray:
        """mu' from the tanh arguments gain s / span (m,), in place."""
        np.tanh(arg, out=arg)  # numpy's, not libm's (a kernel's): 1.7 against 13 ns a value
        _add_spans(arg, self.mu_rest, self.mu_min, self.mu_max)
        return arg


def slope_along_motion(gx, gy, vx, vy, v_fade_mm_s: float, signed: bool) -> np.ndarray:
    """The slope a moving finger feels (dimensionless), faded to 0 at rest (the
    ``HeightLayer`` docstring).

    Parameters
    ----------
    gx, gy : height gradient (mm per mm), any broadcastable shape.
    vx, vy : finger velocity (mm/s).
    v_fade_mm_s : below this speed the slope is scaled by speed / v_fade_mm_s (> 0).
    signed : the directional derivative along the motion; else |grad h| (unsigned).
    """
    arrays, shape = _broadcast_flat(gx, gy, vx, vy)
    return _slope_kernel(*arrays, v_fade_mm_s, signed).reshape(shape)


@njit(cache=True, nogil=True, inline="always")
def _slope(gx, gy, vx, vy, v_fade_mm_s, signed):
    """One sample of :func:`slope_along_motion`, without a branch on the sample's values
    (selects), so that its loops vectorise; NaN propagates as numpy's ``maximum`` and
    ``minimum`` would."""
    if signed:
        speed = np.sqrt(vx * vx + vy * vy)
        return (gx * vx + gy * vy) / (v_fade_mm_s if speed < v_fade_mm_s else speed)
    fade = np.sqrt(vx * vx + vy * vy) / v_fade_mm_s
    return np.sqrt(gx * gx + gy * gy) * (1.0 if fade > 1.0 else fade)


@njit(cache=True, nogil=True, inline="always")
def _tanh_arg(s, up, down, gain):
    """The tanh argument gain s / span of slope s, the span ``up`` for s >= 0, else
    ``down``; a zero span (mu_rest at a limit) is taken as 1e-300, so that the span times
    tanh(+-big) is 0 there, never NaN."""
    return gain * s / max(up if s >= 0.0 else down, 1e-300)


@njit(cache=True, nogil=True, error_model="numpy")
def _slope_kernel(gx, gy, vx, vy, v_fade_mm_s, signed):
    """:func:`slope_along_motion` on (m,) arrays (numpy's error model: no test of each
    divisor for 0, none is)."""
    out = np.empty(gx.size)
    for i in range(gx.size):
        out[i] = _slope(gx[i], gy[i], vx[i], vy[i], v_fade_mm_s, signed)
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def _tanh_args(s, up, down, gain):
    """The tanh arguments (``_tanh_arg``) of slopes s (m,)."""
    out = np.empty(s.size)
    for i in range(s.size):
        out[i] = _tanh_arg(s[i], up, down, gain)
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def _tanh_args_of_motion(gx, gy, vx, vy, v_fade_mm_s, signed, up, down, gain):
    """The tanh arguments of the slopes (``_slope``) of (m,) gradients and velocities."""
    out = np.empty(gx.size)
    for i in range(gx.size):
        out[i] = _tanh_arg(_slope(gx[i], gy[i], vx[i], vy[i], v_fade_mm_s, signed),
                           up, down, gain)
    return out


@njit(cache=True, nogil=True)
def _add_spans(t, mu_rest, mu_min, mu_max):
    """mu' = mu_rest + span tanh in place over t = tanh(gain s / span) (m,): t has the sign
    of s, or is +-0, where the span does not matter (mu_rest + span * +-0 = mu_rest). At
    tanh = +-1 the sum can round one ulp past mu_max or mu_min: it is held to them (NaN
    stays NaN)."""
    up, down = mu_max - mu_rest, mu_rest - mu_min
    for i in range(t.size):
        mu = mu_rest + (up if t[i] >= 0.0 else down) * t[i]
        t[i] = mu_max if mu > mu_max else (mu_min if mu < mu_min else mu)

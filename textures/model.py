"""The validated scene: frozen dataclasses that the rest of frictex trusts.

Everything here is in the units of DESIGN.md: positions in mm (origin top-left of the
active area, x right, y down), angles in degrees, relative friction mu' = mu(w)/mu(0)
in (0, 1] (seed 003, eq 1). Nothing here reads files; ``textures.loader`` builds these
objects from TOML and checks every value once, so the methods below do not re-check.

Every layer answers two vectorised questions at arrays of positions ``x, y`` (mm):

- ``covers(x, y) -> bool array``: where the layer applies (its region, and for objects
  their own support);
- ``mu_at(x, y) -> float64 array``: the layer's mu' there (defined everywhere; callers
  mask it with ``covers``);
- ``mu_and_covers(x, y)``: both at once, sharing the geometry (the renderers' hot path);
  its mu' may be 1 where the layer does not cover (it is not composed there).

Periodic layers (gratings and waveforms) also give their single period for SHT
synthesis (seed 003 section 4.4.2): ``axis`` (unit vector across the lines),
``period_mm``, ``phase_at(x, y)`` in cycles and ``profile(phase)`` -> mu'.
"""

from __future__ import annotations

import math
from dataclasses import Field, dataclass
from pathlib import Path
from typing import Any, ClassVar, Literal, Protocol

import numpy as np
import numpy.typing as npt

from frictex.device.profile import DeviceProfile
from frictex.device.registry import Expect, Registry

#: The renderers a periodic layer may ask for, by name (the ``LayerRenderer`` protocol of
#: ``rendering.renderers``). frictex's own register as entry points of group
#: ``frictex.renderers`` in its pyproject.toml, as another package's would, so that this
#: layer lists them without importing ``rendering``.
#: ``render = "sho"`` (and ``--renderer sho``): SHO, in the run's variant (``sho_variant``);
#: reserved: no plugin may register a renderer under it
SHO = "sho"
#: what a renderer registry's entries must be (``Registry.expect``)
RENDERER_FACTORY = Expect.factory("a renderer class or function (layer, rate_hz) -> "
                                  "LayerRenderer (frictex.rendering.renderers)")
RENDERERS: Registry = Registry("renderer", "frictex.renderers", reserved=(SHO,),
                               expect=RENDERER_FACTORY)


def render_modes() -> tuple[str, ...]:
    """What a layer's ``render`` (or a run's renderer override) may name: :data:`SHO` or
    any renderer of :data:`RENDERERS`."""
    return (SHO, *RENDERERS.names())


def loadable_render_modes() -> tuple[str, ...]:
    """:func:`render_modes` less another package's renderers that cannot be loaded (each
    left out with one warning), as they are now: one registered or installed since
    frictex was imported included."""
    return (SHO, *RENDERERS.loadable_names())

#: ``fingers`` selectors of a layer besides "any" and finger numbers "1", "2", ...
#: (1-based, in order of touch-down among the fingers touching at that sample).
#: Positional selectors pick, at every output sample, the touching finger with the
#: smallest x (left-most), largest x, smallest y (top-most, y points down) or largest y.
POSITIONAL_SELECTORS = ("left-most", "right-most", "top-most", "bottom-most")
BLEND_MODES = ("multiply", "replace")

RGB = tuple[float, float, float]


@dataclass(frozen=True)
class Display:
    """The touchscreen's active area: size in mm and in pixels."""

    width_mm: float
    height_mm: float
    width_px: int
    height_px: int

    @property
    def px_per_mm(self) -> tuple[float, float]:
        """Pixel density (px/mm) along x and y."""
        return self.width_px / self.width_mm, self.height_px / self.height_mm


@dataclass(frozen=True)
class VisualHints:
    """Colours (linear RGB, 0-1) the visual layer uses to draw a layer.

    ``color_low`` is drawn where the layer's mu' is at its lowest (slippery),
    ``color_high`` where it is highest; intermediate mu' blends between them.
    """

    color_low: RGB = (0.0, 0.0, 0.0)
    color_high: RGB = (1.0, 1.0, 1.0)
    outline: bool = False


# ---------------------------------------------------------------------------
# Regions


def _rotate_into(x, y, cx: float, cy: float, angle_deg: float):
    """Coordinates of (x, y) in a frame centred on (cx, cy) rotated by angle_deg."""
    dx = np.asarray(x, dtype=np.float64) - cx
    dy = np.asarray(y, dtype=np.float64) - cy
    if angle_deg == 0.0:  # the rotation below with c = 1, s = 0, up to the sign of zeros
        return dx, dy
    a = math.radians(angle_deg)
    c, s = math.cos(a), math.sin(a)
    return c * dx + s * dy, -s * dx + c * dy


def _hypot(a, b) -> np.ndarray:
    """sqrt(a^2 + b^2) for distances in mm.

    ``np.hypot`` goes through scalar libm and is ~10x slower; its overflow and
    underflow guards never matter at screen scale (squares of 1e-150..1e150 mm), and
    the two agree to an ulp or two (exactly where a or b is 0).
    """
    return np.sqrt(a * a + b * b)


@dataclass(frozen=True)
class RectRegion:
    """A rectangle: top-left corner (x_mm, y_mm) before rotation, rotated about its centre."""

    x_mm: float
    y_mm: float
    width_mm: float
    height_mm: float
    angle_deg: float = 0.0

    @property
    def center(self) -> tuple[float, float]:
        return self.x_mm + self.width_mm / 2, self.y_mm + self.height_mm / 2

    def signed_distance(self, x, y) -> np.ndarray:
        """Signed distance (mm) to the boundary; negative inside."""
        cx, cy = self.center
        u, v = _rotate_into(x, y, cx, cy, self.angle_deg)
        qx = np.abs(u) - self.width_mm / 2
        qy = np.abs(v) - self.height_mm / 2
        outside = _hypot(np.maximum(qx, 0.0), np.maximum(qy, 0.0))
        inside = np.minimum(np.maximum(qx, qy), 0.0)
        return outside + inside

    def contains(self, x, y) -> np.ndarray:
        return self.signed_distance(x, y) <= 0.0


@dataclass(frozen=True)
class DiscRegion:
    """A disc of centre (cx_mm, cy_mm) and radius radius_mm."""

    cx_mm: float
    cy_mm: float
    radius_mm: float

    def signed_distance(self, x, y) -> np.ndarray:
        return _hypot(np.asarray(x, dtype=np.float64) - self.cx_mm,
                      np.asarray(y, dtype=np.float64) - self.cy_mm) - self.radius_mm

    def contains(self, x, y) -> np.ndarray:
        return self.signed_distance(x, y) <= 0.0


Region = RectRegion | DiscRegion


def _where_covered(mu_of, values: np.ndarray, covers: np.ndarray) -> np.ndarray:
    """``mu_of(values)`` (an elementwise mu') where ``covers`` (bool, ``values``' shape), 1
    elsewhere: a renderer's mu' outside its layer is never composed (``rendering.compose``),
    so it is not computed; a finger is outside a small region most of the time."""
    if covers.all():
        return mu_of(values)
    mu = np.ones(values.shape)
    if covers.any():
        mu[covers] = mu_of(values[covers])
    return mu


def _wrap(phase) -> np.ndarray:
    """Phase (cycles) wrapped to [0, 1): ``np.mod(phase, 1.0)`` bit for bit (both round
    the same exact value once), at a fraction of its cost."""
    p = np.asarray(phase, dtype=np.float64)
    return p - np.floor(p)


def _smoothstep_inside(distance, edge_mm: float) -> np.ndarray:
    """Weight 1 inside, 0 outside a boundary at signed distance 0.

    With ``edge_mm == 0`` the step is sharp; otherwise a raised-cosine ramp of
    total width ``edge_mm`` centred on the boundary.
    """
    d = np.asarray(distance, dtype=np.float64)
    if edge_mm <= 0.0:
        return (d <= 0.0).astype(np.float64)
    s = np.clip(0.5 - d / edge_mm, 0.0, 1.0)
    # the cosine only on the ramp: at s = 0 and s = 1 it gives exactly s
    ramp = (s > 0.0) & (s < 1.0)
    c = np.cos(np.pi * s, out=np.zeros_like(s), where=ramp)
    return np.where(ramp, 0.5 - 0.5 * c, s)


# ---------------------------------------------------------------------------
# Layers


@dataclass(frozen=True)
class _LayerBase:
    """Fields every layer has. ``render`` is already resolved (never "auto")."""

    name: str
    render: str
    region: Region | None
    blend: str
    visual: VisualHints
    fingers: str = "any"

    #: the ``type`` a texture file gives the layer, where it is not the class's name
    FILE_TYPE: ClassVar[str] = ""

    @property
    def file_type(self) -> str:
        """The ``type`` a texture file gives this layer (``summary.json`` names it so)."""
        return self.FILE_TYPE or type(self).__name__.lower()

    def in_region(self, x, y) -> np.ndarray:
        if self.region is None:
            return np.ones(np.shape(x), dtype=bool)
        return self.region.contains(x, y)

    def covers(self, x, y) -> np.ndarray:
        return self.in_region(x, y)

    def mu_and_covers(self, x, y) -> tuple[np.ndarray, np.ndarray]:
        """``(mu_at(x, y), covers(x, y))``; layers override it to share work between them
        (and may give mu' 1 where they do not cover)."""
        return self.mu_at(x, y), self.covers(x, y)

    @property
    def is_periodic(self) -> Literal[False]:
        """False: a layer without a period (:class:`_PeriodicBase`'s is True)."""
        return False

    @property
    def mu_range(self) -> tuple[float, float]:
        """The lowest and highest mu' the layer asks for."""
        raise NotImplementedError


@dataclass(frozen=True)
class _PeriodicBase(_LayerBase):
    """A spatially periodic layer: mu' depends on the phase across parallel lines.

    ``angle_deg`` is the direction of the axis across the lines, from +x towards +y
    (screen y points down); 0 gives vertical lines and friction varying with x.
    Phase 0 is at ``offset_mm`` along the axis from the display origin.
    """

    period_mm: float = 1.0
    angle_deg: float = 0.0
    offset_mm: float = 0.0

    # True where the base's is False: what tells a PeriodicLayer from a PlainLayer
    @property
    def is_periodic(self) -> Literal[True]:  # type: ignore[override]
        return True

    @property
    def axis(self) -> tuple[float, float]:
        a = math.radians(self.angle_deg)
        return math.cos(a), math.sin(a)

    def phase_at(self, x, y) -> np.ndarray:
        """Spatial phase (cycles, unwrapped) at positions (x, y) mm."""
        ax, ay = self.axis
        s = ax * np.asarray(x, dtype=np.float64) + ay * np.asarray(y, dtype=np.float64)
        return (s - self.offset_mm) / self.period_mm

    def profile(self, phase) -> np.ndarray:
        """mu' over one period at phase (cycles; any real, wrapped here)."""
        raise NotImplementedError

    def mu_at(self, x, y) -> np.ndarray:
        return self.profile(self.phase_at(x, y))

    def profile_where(self, phase: np.ndarray, covers: np.ndarray) -> np.ndarray:
        """:meth:`profile` where ``covers`` (bool, ``phase``'s shape), 1 elsewhere."""
        return _where_covered(self.profile, phase, covers)


@dataclass(frozen=True)
class Grating(_PeriodicBase):
    """A two-level grating: ``mu_low`` for the first ``duty`` of each period (the
    black line of seed 003 Fig. 6), ``mu_high`` for the rest.

    ``edge = "square"`` steps at the line boundaries; ``"smooth"`` ramps over
    ``edge_mm`` (raised cosine) centred on each boundary.
    """

    duty: float = 0.5
    mu_low: float = 0.6
    mu_high: float = 1.0
    edge: str = "square"
    edge_mm: float = 0.0

    @property
    def mu_range(self) -> tuple[float, float]:
        return self.mu_low, self.mu_high

    def profile(self, phase) -> np.ndarray:
        p = _wrap(phase)
        if self.edge == "square" or self.edge_mm <= 0.0:
            low = p < self.duty
        else:
            # distance (mm) from the nearest edge, signed negative inside the low band
            d_rise = (p - self.duty) * self.period_mm
            d_fall = p * self.period_mm
            dist = np.minimum(np.abs(d_rise), np.abs(d_fall))
            dist = np.minimum(dist, np.abs(self.period_mm - d_fall))
            inside = p < self.duty
            signed = np.where(inside, -dist, dist)
            w = _smoothstep_inside(signed, self.edge_mm)
            return self.mu_high + (self.mu_low - self.mu_high) * w
        return np.where(low, self.mu_low, self.mu_high)


WAVE_SHAPES = ("sine", "square", "triangle", "sawtooth", "samples")


@dataclass(frozen=True)
class Waveform(_PeriodicBase):
    """One period of a texture, replayed by SHT: a standard shape between
    ``mu_min`` and ``mu_max``, or ``samples`` (mu' values over one period,
    linearly interpolated and wrapped)."""

    shape: str = "sine"
    mu_min: float = 0.6
    mu_max: float = 1.0
    duty: float = 0.5
    samples: tuple[float, ...] = ()

    @property
    def mu_range(self) -> tuple[float, float]:
        if self.shape == "samples":
            return min(self.samples), max(self.samples)
        return self.mu_min, self.mu_max

    def profile(self, phase) -> np.ndarray:
        p = _wrap(phase)
        if self.shape == "samples":
            s = np.asarray(self.samples, dtype=np.float64)
            n = s.size
            grid = np.arange(n + 1) / n
            return np.interp(p, grid, np.append(s, s[0]))
        if self.shape == "sine":
            u = 0.5 - 0.5 * np.cos(2 * np.pi * p)  # 0 at phase 0: starts at mu_min
        elif self.shape == "square":
            u = (p < self.duty).astype(np.float64)
            u = 1.0 - u  # low friction for the first duty of the period
        elif self.shape == "triangle":
            u = 1.0 - 2.0 * np.minimum(p, 1.0 - p)
        else:  # sawtooth: friction falls linearly over the period
            u = 1.0 - p
        return self.mu_min + (self.mu_max - self.mu_min) * u


@dataclass(frozen=True)
class _Outlined(_LayerBase):
    """A layer of friction ``mu`` within an outline given by ``_signed_distance(x, y)``
    (mm, negative inside), ramped over ``edge_mm`` across it; it covers the outline
    and half the ramp beyond. Subclasses define the fields ``mu`` and ``edge_mm``."""

    def _signed_distance(self, x, y) -> np.ndarray:
        raise NotImplementedError

    def covers(self, x, y) -> np.ndarray:
        return self._covers(self._signed_distance(x, y), x, y)

    def mu_at(self, x, y) -> np.ndarray:
        return self._mu(self._signed_distance(x, y))

    def mu_and_covers(self, x, y) -> tuple[np.ndarray, np.ndarray]:
        """mu' where the layer covers (1 elsewhere) and the cover."""
        d = self._signed_distance(x, y)
        covers = self._covers(d, x, y)
        return _where_covered(self._mu, d, covers), covers

    def _covers(self, distance, x, y) -> np.ndarray:
        return (distance <= self.edge_mm / 2) & self.in_region(x, y)

    def _mu(self, distance) -> np.ndarray:
        return 1.0 + (self.mu - 1.0) * _smoothstep_inside(distance, self.edge_mm)


@dataclass(frozen=True)
class Shape(_Outlined):
    """A single object for SHO: a region of friction ``mu`` with optional soft edges.

    ``geometry`` is the object's outline (rectangle or disc). ``edge_mm`` > 0 ramps
    mu' across the outline instead of stepping.
    """

    geometry: Region = None  # type: ignore[assignment]
    mu: float = 0.6
    edge_mm: float = 0.0

    @property
    def file_type(self) -> str:
        return "disc" if isinstance(self.geometry, DiscRegion) else "rectangle"

    @property
    def mu_range(self) -> tuple[float, float]:
        return self.mu, 1.0

    def _signed_distance(self, x, y) -> np.ndarray:
        return self.geometry.signed_distance(x, y)


@dataclass(frozen=True)
class Edge(_LayerBase):
    """A straight edge through (x_mm, y_mm): friction ``mu`` on the side the normal
    (at ``angle_deg`` from +x) points to, 1 on the other; ``edge_mm`` softens it."""

    x_mm: float = 0.0
    y_mm: float = 0.0
    angle_deg: float = 0.0
    mu: float = 0.6
    edge_mm: float = 0.0

    @property
    def mu_range(self) -> tuple[float, float]:
        return self.mu, 1.0

    def _distance(self, x, y) -> np.ndarray:
        a = math.radians(self.angle_deg)
        return -(math.cos(a) * (np.asarray(x, dtype=np.float64) - self.x_mm)
                 + math.sin(a) * (np.asarray(y, dtype=np.float64) - self.y_mm))

    def mu_at(self, x, y) -> np.ndarray:
        return 1.0 + (self.mu - 1.0) * _smoothstep_inside(self._distance(x, y), self.edge_mm)


@dataclass(frozen=True)
class Bump(_LayerBase):
    """A gaussian bump in friction: mu' = 1 - (1 - mu) exp(-r^2 / (2 sigma^2)),
    centred on (cx_mm, cy_mm); ``mu`` is mu' at the centre."""

    cx_mm: float = 0.0
    cy_mm: float = 0.0
    sigma_mm: float = 5.0
    mu: float = 0.6

    @property
    def mu_range(self) -> tuple[float, float]:
        return self.mu, 1.0

    def covers(self, x, y) -> np.ndarray:
        r = _hypot(np.asarray(x, dtype=np.float64) - self.cx_mm,
                   np.asarray(y, dtype=np.float64) - self.cy_mm)
        return (r <= 4.0 * self.sigma_mm) & self.in_region(x, y)

    def mu_at(self, x, y) -> np.ndarray:
        r2 = ((np.asarray(x, dtype=np.float64) - self.cx_mm) ** 2
              + (np.asarray(y, dtype=np.float64) - self.cy_mm) ** 2)
        return 1.0 - (1.0 - self.mu) * np.exp(-r2 / (2.0 * self.sigma_mm ** 2))


@dataclass(frozen=True)
class Line(_Outlined):
    """A straight line segment from (x0, y0) to (x1, y1), ``width_mm`` wide, of friction ``mu``."""

    x0_mm: float = 0.0
    y0_mm: float = 0.0
    x1_mm: float = 0.0
    y1_mm: float = 0.0
    width_mm: float = 1.0
    mu: float = 0.6
    edge_mm: float = 0.0

    @property
    def mu_range(self) -> tuple[float, float]:
        return self.mu, 1.0

    def _signed_distance(self, x, y) -> np.ndarray:
        px = np.asarray(x, dtype=np.float64) - self.x0_mm
        py = np.asarray(y, dtype=np.float64) - self.y0_mm
        dx, dy = self.x1_mm - self.x0_mm, self.y1_mm - self.y0_mm
        length2 = dx * dx + dy * dy
        t = np.clip((px * dx + py * dy) / length2, 0.0, 1.0) if length2 > 0 else 0.0
        return _hypot(px - t * dx, py - t * dy) - self.width_mm / 2


RASTER_MODES = ("stretch", "tile", "one-to-one")


@dataclass(frozen=True, eq=False)
class RasterMap(_LayerBase):
    """A greyscale friction map placed like a sprite.

    ``image`` holds grey levels in [0, 1] (row 0 at the top), as read from an 8- or
    16-bit PNG; grey g maps linearly to mu' = mu_black + g (mu_white - mu_black)
    (brighter = more friction, the convention of commercial friction displays).
    The sprite's unrotated top-left is (x_mm, y_mm), its size width_mm x height_mm,
    rotated by rotation_deg about its centre. ``mode``: ``stretch`` fills the sprite
    with the image once; ``tile`` repeats tiles of tile_width_mm x tile_height_mm;
    ``one-to-one`` draws one image pixel per display pixel (the loader sets the size
    from the display's px/mm). Sampling is bilinear.
    """

    FILE_TYPE = "raster"

    image: np.ndarray = None  # type: ignore[assignment]
    image_path: Path | None = None
    x_mm: float = 0.0
    y_mm: float = 0.0
    width_mm: float = 10.0
    height_mm: float = 10.0
    rotation_deg: float = 0.0
    mode: str = "stretch"
    tile_width_mm: float = 10.0
    tile_height_mm: float = 10.0
    mu_black: float = 0.6
    mu_white: float = 1.0

    @property
    def mu_range(self) -> tuple[float, float]:
        g = self.image
        vals = (self.mu_black + float(g.min()) * (self.mu_white - self.mu_black),
                self.mu_black + float(g.max()) * (self.mu_white - self.mu_black))
        return min(vals), max(vals)

    @property
    def sprite(self) -> RectRegion:
        return RectRegion(self.x_mm, self.y_mm, self.width_mm, self.height_mm, self.rotation_deg)

    def covers(self, x, y) -> np.ndarray:
        return self.sprite.contains(x, y) & self.in_region(x, y)

    def _uv(self, x, y):
        """Sprite coordinates in [0, 1) of the image (u across, v down)."""
        cx, cy = self.sprite.center
        u, v = _rotate_into(x, y, cx, cy, self.rotation_deg)
        u = u + self.width_mm / 2
        v = v + self.height_mm / 2
        if self.mode == "tile":
            return np.mod(u / self.tile_width_mm, 1.0), np.mod(v / self.tile_height_mm, 1.0)
        return np.clip(u / self.width_mm, 0.0, 1.0), np.clip(v / self.height_mm, 0.0, 1.0)

    def grey_at(self, x, y) -> np.ndarray:
        """Bilinearly sampled grey level in [0, 1] at positions (x, y) mm."""
        u, v = self._uv(x, y)
        rows, cols = self.image.shape
        fx = np.clip(u * cols - 0.5, 0.0, cols - 1.0)
        fy = np.clip(v * rows - 0.5, 0.0, rows - 1.0)
        x0 = np.floor(fx).astype(np.intp)
        y0 = np.floor(fy).astype(np.intp)
        x1 = np.minimum(x0 + 1, cols - 1)
        y1 = np.minimum(y0 + 1, rows - 1)
        tx, ty = fx - x0, fy - y0
        g = self.image
        top = g[y0, x0] * (1 - tx) + g[y0, x1] * tx
        bottom = g[y1, x0] * (1 - tx) + g[y1, x1] * tx
        return top * (1 - ty) + bottom * ty

    def mu_at(self, x, y) -> np.ndarray:
        return self.mu_black + self.grey_at(x, y) * (self.mu_white - self.mu_black)


# ---------------------------------------------------------------------------
# Force layers (travelling-wave profiles only; rendered by ``rendering.layers.force_layers``)


@dataclass(frozen=True)
class _ForceBase(_LayerBase):
    """A layer whose target is a tangential force or a direction-dependent mu'.

    To the friction path (renderers, composition, ``ideal_mu``) a force layer is neutral:
    mu' = 1 with ``blend = "multiply"``; ``covers`` is where it acts.
    """

    @property
    def mu_range(self) -> tuple[float, float]:
        return 1.0, 1.0

    def mu_at(self, x, y) -> np.ndarray:
        return np.ones(np.broadcast(np.asarray(x), np.asarray(y)).shape)


@dataclass(frozen=True)
class Directional(_ForceBase):
    """Different friction for each direction of travel along an axis (seed 002, eqs 7-8).

    ``angle_deg`` (0 or 180: the waves run along the display's x axis) points the
    forward direction. ``target = "mu"``: ``forward`` / ``backward`` are mu', the net
    tangential force over mu0 F_n (a travelling wave reaches below any standing wave's
    floor); ``target = "force"``: they are net tangential forces in N, positive resisting
    the finger, zero or negative allowed (negative drags the finger along).
    """

    angle_deg: float = 0.0
    target: str = "mu"
    forward: float = 1.0
    backward: float = 1.0

    @property
    def axis_sign(self) -> int:
        """+1 if forward is +x, -1 if it is -x."""
        return 1 if math.cos(math.radians(self.angle_deg)) > 0 else -1

    def value(self, motion_x) -> np.ndarray:
        """``forward`` where the finger moves forward (``motion_x`` +1/-1 along x), else ``backward``."""
        return np.where(np.asarray(motion_x) * self.axis_sign > 0, self.forward, self.backward)


@dataclass(frozen=True)
class Guidance(_ForceBase):
    """An active pull towards a target point (or line through it at ``line_angle_deg``):
    gain_n_per_mm times the distance, at most max_force_n (N)."""

    x_mm: float = 0.0
    y_mm: float = 0.0
    line: bool = False
    line_angle_deg: float = 90.0
    gain_n_per_mm: float = 0.01
    max_force_n: float = 0.1

    def pull(self, x, y) -> tuple[np.ndarray, np.ndarray]:
        """The wanted force (N) on a finger at (x, y) mm, as (fx, fy) arrays."""
        dx = self.x_mm - np.asarray(x, dtype=np.float64)
        dy = self.y_mm - np.asarray(y, dtype=np.float64)
        if self.line:  # towards the nearest point of the line: drop the along-line part
            a = math.radians(self.line_angle_deg)
            along = dx * math.cos(a) + dy * math.sin(a)
            dx, dy = dx - along * math.cos(a), dy - along * math.sin(a)
        dist = np.hypot(dx, dy)
        scale = np.minimum(self.gain_n_per_mm, np.divide(self.max_force_n, dist, out=np.zeros_like(dist),
                                                         where=dist > 0))
        return scale * dx, scale * dy


@dataclass(frozen=True)
class KeyClick(_ForceBase):
    """A key-click button (seed 004, Fig. 5): inside ``geometry``, a push of ``force_n``
    (N) towards ``first_push`` (+1: +x) once the normal force reaches ``press_n``, reversed
    when it reaches ``click_n``; released (reset) when it falls below ``release_n``.
    Each change needs its condition held for ``dwell_s`` (``rendering.layers.keyclick``)."""

    geometry: RectRegion = None  # type: ignore[assignment]
    press_n: float = 0.5
    click_n: float = 0.8
    release_n: float = 0.4
    dwell_s: float = 0.01
    force_n: float = 0.1
    first_push: int = 1

    def covers(self, x, y) -> np.ndarray:
        return self.geometry.contains(x, y) & self.in_region(x, y)


FORCE_LAYERS = (Directional, Guidance, KeyClick)


class _LayerAnswers(Protocol):
    """What every layer answers, as a renderer or a user's code reads it: its ``name``,
    ``render`` (a renderer's name), ``blend``, ``fingers``, and at arrays of positions
    ``x, y`` (mm) its mu' (``mu_at``), where it applies (``covers``) and both at once
    (``mu_and_covers``). Protocols, not this module's classes: the layers of
    textures/heights.py, clips.py and hatt.py are layers too, and they import this module.
    Every layer is a frozen dataclass, changed with ``dataclasses.replace``."""

    __dataclass_fields__: ClassVar[dict[str, Field[Any]]]

    @property
    def name(self) -> str: ...

    @property
    def render(self) -> str: ...

    @property
    def blend(self) -> str: ...

    @property
    def fingers(self) -> str: ...

    def mu_at(self, x: npt.ArrayLike, y: npt.ArrayLike) -> np.ndarray: ...

    def covers(self, x: npt.ArrayLike, y: npt.ArrayLike) -> np.ndarray: ...

    def mu_and_covers(self, x: npt.ArrayLike,
                      y: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray]: ...


class PlainLayer(_LayerAnswers, Protocol):
    """A layer without a period (``is_periodic`` False)."""

    @property
    def is_periodic(self) -> Literal[False]: ...


class PeriodicLayer(_LayerAnswers, Protocol):
    """A grating or a waveform (``is_periodic`` True) and its single period (seed 003
    section 4.4.2): ``axis`` (unit vector across the lines), ``period_mm`` (mm),
    ``phase_at(x, y)`` (cycles) and ``profile(phase)`` (mu')."""

    @property
    def is_periodic(self) -> Literal[True]: ...

    @property
    def axis(self) -> tuple[float, float]: ...

    @property
    def period_mm(self) -> float: ...

    def phase_at(self, x: npt.ArrayLike, y: npt.ArrayLike) -> np.ndarray: ...

    def profile(self, phase: npt.ArrayLike) -> np.ndarray: ...


#: a scene's layer, whatever its class: ``if layer.is_periodic:`` tells a type checker
#: that it is a :class:`PeriodicLayer` (its ``is_periodic`` is Literal[True])
Layer = PeriodicLayer | PlainLayer


@dataclass(frozen=True)
class Scene:
    """One texture file, validated: the display, the device and the layers in
    drawing order (later layers on top). ``control``: one of :data:`CONTROL_MODES`."""

    format: int
    name: str
    description: str
    display: Display
    device: DeviceProfile
    layers: tuple[Layer, ...]
    source: Path | None = None
    control: str = "open"

    @property
    def renderers_used(self) -> frozenset[str]:
        """The render modes the scene's layers need (the pipeline builds only these)."""
        return frozenset(layer.render for layer in self.layers)

    @property
    def grating_period_mm(self) -> float | None:
        """The period of the scene's single periodic layer, if it has exactly one."""
        periods = [layer.period_mm for layer in self.layers if layer.is_periodic]
        return periods[0] if len(periods) == 1 else None


#: friction control modes (``rendering.control.loop``): open loop (the inverse model
#: alone), feedback on the device's model, feedback on the model adapted online; the loop
#: modes need a plate-seed003 device with seed 003's model and the lateral force sensed
CONTROL_MODES = ("open", "closed", "adaptive")


def auto_render_mode(period_mm: float | None) -> str:
    """The renderer ``render = "auto"`` picks: SHO for layers without a period (objects,
    maps), the hybrid for every periodic layer whatever its period.

    ``frictex report`` measures the hybrid against SHO and SHT on seed 003's 15, 5 and
    0.6 mm gratings over paired draws of human-like strokes and constant-speed swipes,
    and states which of its claims hold with 95 % confidence; what the hybrid does
    between touch samples, and what it costs (edges re-crossed on coarse gratings), is in
    ``rendering/RENDERERS.md``.
    """
    return "sho" if period_mm is None else "hybrid"

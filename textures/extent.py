"""Where shapes and layers lie on the display: boxes, clipping, and where a layer lowers mu'.

A box is ``(x0, y0, x1, y1)`` in mm (x0 <= x1, y0 <= y1), positions as everywhere in
frictex (origin top-left of the active area, x right, y down). A polygon is a list of
its corners ``(x, y)`` (mm) in order around it.

- :func:`shares_display` answers the loader's question about a shape (a rectangle, a
  disc, a line of some width): does any of it lie on the display? A shape partly off the
  display is clipped there, as every renderer evaluates a layer per position.
- :func:`lowering` gives, for one layer, the boxes on the display where it may ask for a
  mu' below 1 and the lowest mu' it may ask for in each: what ``textures.overlap``
  multiplies where boxes of several layers overlap. The boxes are never smaller than
  the places they stand for, so a product over them never understates how low layers
  take mu' together.
"""

from __future__ import annotations

import math

from frictex.textures import model
from frictex.textures.clips import ClipLayer
from frictex.textures.heights import ButtonRim, GaussianBump, HeightLayer, HeightMap, Ridge, Step

Box = tuple[float, float, float, float]
Polygon = list[tuple[float, float]]

#: The fastest a finger is taken to slide (mm/s) while a clip started under it plays: a
#: quick flick across a touch screen. A clip can be felt this far times its duration
#: from the region where it was triggered.
FAST_FINGER_MM_S = 1000.0


def display_box(display: model.Display) -> Box:
    """The display's active area as a box (mm)."""
    return 0.0, 0.0, display.width_mm, display.height_mm


def box_polygon(box: Box) -> Polygon:
    """The four corners of ``box``."""
    x0, y0, x1, y1 = box
    return [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]


def clip_half_plane(polygon: Polygon, nx: float, ny: float, c: float) -> Polygon:
    """The part of a convex ``polygon`` where nx x + ny y <= c (one Sutherland-Hodgman pass)."""
    out: Polygon = []
    for k, p in enumerate(polygon):
        q = polygon[k - 1]
        dp, dq = nx * p[0] + ny * p[1] - c, nx * q[0] + ny * q[1] - c
        if (dp <= 0.0) != (dq <= 0.0):  # the edge q -> p crosses the line
            t = dq / (dq - dp)
            out.append((q[0] + t * (p[0] - q[0]), q[1] + t * (p[1] - q[1])))
        if dp <= 0.0:
            out.append(p)
    return out


def clip_to_box(polygon: Polygon, box: Box) -> Polygon:
    """The part of a convex ``polygon`` inside ``box``."""
    x0, y0, x1, y1 = box
    for nx, ny, c in ((-1.0, 0.0, -x0), (1.0, 0.0, x1), (0.0, -1.0, -y0), (0.0, 1.0, y1)):
        polygon = clip_half_plane(polygon, nx, ny, c)
    return polygon


def area(polygon: Polygon) -> float:
    """The area (mm^2) of a polygon (shoelace formula)."""
    return 0.5 * abs(sum(q[0] * p[1] - p[0] * q[1] for q, p in zip(polygon[-1:] + polygon, polygon)))


def bounds(polygon: Polygon) -> Box | None:
    """The smallest box holding ``polygon``; None for an empty one."""
    if not polygon:
        return None
    xs, ys = [p[0] for p in polygon], [p[1] for p in polygon]
    return min(xs), min(ys), max(xs), max(ys)


def intersect(a: Box | None, b: Box | None) -> Box | None:
    """The common part of two boxes; None if they share no area."""
    if a is None or b is None:
        return None
    box = max(a[0], b[0]), max(a[1], b[1]), min(a[2], b[2]), min(a[3], b[3])
    return box if box[0] < box[2] and box[1] < box[3] else None


def grow(box: Box, margin: float) -> Box:
    """``box`` widened by ``margin`` (mm) on every side."""
    return box[0] - margin, box[1] - margin, box[2] + margin, box[3] + margin


def rect_corners(rect: model.RectRegion) -> Polygon:
    """The corners of a (rotated) rectangle, in order around it."""
    cx, cy = rect.center
    a = math.radians(rect.angle_deg)
    ca, sa = math.cos(a), math.sin(a)
    hw, hh = rect.width_mm / 2, rect.height_mm / 2
    return [(cx + ca * u - sa * v, cy + sa * u + ca * v)
            for u, v in ((-hw, -hh), (hw, -hh), (hw, hh), (-hw, hh))]


def line_corners(x0: float, y0: float, x1: float, y1: float, half_width: float) -> Polygon:
    """The rectangle around a segment widened by ``half_width`` (mm) on every side (it
    holds the segment's rounded outline of that half width)."""
    length = math.hypot(x1 - x0, y1 - y0)
    ux, uy = ((x1 - x0) / length, (y1 - y0) / length) if length > 0 else (1.0, 0.0)
    ax, ay = ux * half_width, uy * half_width  # along, outwards at each end
    nx, ny = -ay, ax  # across
    return [(x0 - ax + nx, y0 - ay + ny), (x1 + ax + nx, y1 + ay + ny),
            (x1 + ax - nx, y1 + ay - ny), (x0 - ax - nx, y0 - ay - ny)]


def region_box(region: model.Region) -> Box:
    """The smallest box holding a region (a rectangle or a disc)."""
    if isinstance(region, model.DiscRegion):
        r = region.radius_mm
        return region.cx_mm - r, region.cy_mm - r, region.cx_mm + r, region.cy_mm + r
    return bounds(rect_corners(region))  # type: ignore[return-value]


def _distance_to_box(x: float, y: float, box: Box) -> float:
    """Distance (mm) from a point to a box (0 inside it)."""
    return math.hypot(max(box[0] - x, 0.0, x - box[2]), max(box[1] - y, 0.0, y - box[3]))


def _distance_to_segment(p, a, b) -> float:
    """Distance (mm) from point ``p`` to the segment from ``a`` to ``b``."""
    dx, dy = b[0] - a[0], b[1] - a[1]
    length2 = dx * dx + dy * dy
    t = 0.0 if length2 == 0 else min(1.0, max(0.0, ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / length2))
    return math.hypot(p[0] - a[0] - t * dx, p[1] - a[1] - t * dy)


def segment_box_distance(a, b, box: Box) -> float:
    """Distance (mm) between the segment from ``a`` to ``b`` and a box (0 if they meet)."""
    if len(clip_to_box([a, b], box)) > 0:  # a two-corner polygon: the segment, clipped
        return 0.0
    return min([_distance_to_box(*a, box), _distance_to_box(*b, box)]
               + [_distance_to_segment(c, a, b) for c in box_polygon(box)])


def shares_display(shape, display: model.Display) -> bool:
    """True if some area of ``shape`` lies on the display: a ``RectRegion``, a
    ``DiscRegion``, or a line given as ``(x0, y0, x1, y1, width_mm)``."""
    box = display_box(display)
    if isinstance(shape, model.DiscRegion):
        return _distance_to_box(shape.cx_mm, shape.cy_mm, box) < shape.radius_mm
    if isinstance(shape, model.RectRegion):
        return area(clip_to_box(rect_corners(shape), box)) > 0.0
    x0, y0, x1, y1, width = shape
    return segment_box_distance((x0, y0), (x1, y1), box) < width / 2


# ---------------------------------------------------------------------------
# Where a layer lowers mu'


def _band_box(display: Box, x0: float, y0: float, normal_deg: float, lo: float, hi: float) -> Box | None:
    """The box of the display's positions whose distance along the unit normal at
    ``normal_deg`` from the point (x0, y0) lies in [lo, hi] (mm)."""
    a = math.radians(normal_deg)
    nx, ny = math.cos(a), math.sin(a)
    c = nx * x0 + ny * y0
    band = clip_half_plane(clip_half_plane(box_polygon(display), nx, ny, c + hi), -nx, -ny, -(c + lo))
    return bounds(band)


def _disc_box(cx: float, cy: float, radius: float) -> Box:
    return cx - radius, cy - radius, cx + radius, cy + radius


def _height_box(shape, display: Box) -> Box | None:
    """Where a height shape's slope can be non-zero (its ``support``), as a box."""
    if isinstance(shape, GaussianBump):
        return _disc_box(shape.cx_mm, shape.cy_mm, 4.0 * shape.sigma_mm)
    if isinstance(shape, ButtonRim):
        return _disc_box(shape.cx_mm, shape.cy_mm, shape.radius_mm)
    if isinstance(shape, Ridge):
        half = shape.width_mm / 2
        return _band_box(display, shape.x_mm, shape.y_mm, shape.angle_deg + 90.0, -half, half)
    if isinstance(shape, Step):
        half = shape.chamfer_mm / 2
        return _band_box(display, shape.x_mm, shape.y_mm, shape.angle_deg, -half, half)
    if isinstance(shape, HeightMap):
        return shape.x_mm, shape.y_mm, shape.x_mm + shape.width_mm, shape.y_mm + shape.height_mm
    return display


def _own_box(layer, display: Box) -> Box | None:
    """Where ``layer`` may lower mu' below 1 before its region confines it (mm)."""
    if isinstance(layer, model.Shape):
        return grow(region_box(layer.geometry), layer.edge_mm / 2)
    if isinstance(layer, model.Line):
        return bounds(line_corners(layer.x0_mm, layer.y0_mm, layer.x1_mm, layer.y1_mm,
                                   layer.width_mm / 2 + layer.edge_mm / 2))
    if isinstance(layer, model.Bump):
        return _disc_box(layer.cx_mm, layer.cy_mm, 4.0 * layer.sigma_mm)
    if isinstance(layer, model.Edge):  # mu on the normal's side, the ramp half beyond
        return _band_box(display, layer.x_mm, layer.y_mm, layer.angle_deg, -layer.edge_mm / 2,
                         math.inf)
    if isinstance(layer, model.RasterMap):
        return region_box(layer.sprite)
    return display


def lowering(layer, display: model.Display) -> list[tuple[Box, float]]:
    """Where on the display ``layer`` may ask for a mu' below 1, as (box, lowest mu' in
    it) pairs; elsewhere it asks for 1 or does not apply. A height layer has two: its
    region at ``mu_rest`` and, where its shape slopes, ``mu_min``; a clip plays under a
    finger that keeps moving, :data:`FAST_FINGER_MM_S` times its duration beyond its
    region. A layer of a kind not known here is taken to lower mu' anywhere on the
    display."""
    screen = display_box(display)
    region = screen if layer.region is None else intersect(region_box(layer.region), screen)
    low = layer.mu_range[0]
    if isinstance(layer, ClipLayer):
        pieces = [(intersect(grow(region_box(layer.region), FAST_FINGER_MM_S * layer.clip.duration_s),
                             screen) if layer.region is not None else screen, low)]
    elif isinstance(layer, HeightLayer):
        pieces = [(region, layer.rest_mu),
                  (intersect(_height_box(layer.shape, screen), region), low)]
    else:
        pieces = [(intersect(_own_box(layer, screen), region), low)]
    return [(box, mu) for box, mu in pieces if box is not None and mu < 1.0]

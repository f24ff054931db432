"""Marks for force layers in the static scene image (seeds 002, 004).

A force layer changes no friction under a resting finger, so the scene's colours alone
show nothing of it. Drawn on top of the scene, in one colour (``MARK_RGB``):

- ``guidance``: its target, a ring ``RING_MM`` in radius with a dot at the point, or,
  for a line, a dashed line through the point at ``line_angle_deg``;
- ``directional``: a row of chevrons along the middle of where the layer acts, pointing
  the way the finger glides (the direction with the lower force or mu'); none when both
  directions are the same.

Anti-aliased on the signed distance (mm) to each mark, as the outlines are.
"""

from __future__ import annotations

import math

import numpy as np

from frictex.textures.model import Directional, DiscRegion, Guidance, Scene

MARK_RGB = np.array([0.85, 0.05, 0.55], dtype=np.float32)  # magenta: unlike any texture colour
MARK_WIDTH_PX = 2.5
RING_MM = 3.0
DASH_MM, GAP_MM = 3.0, 2.0
CHEVRON_MM = 4.0  # half-height of a chevron; chevrons every CHEVRON_SPACING_MM
CHEVRON_SPACING_MM = 20.0


def has_marks(scene: Scene) -> bool:
    """Whether ``scene`` has a force layer drawn by :func:`draw_force_marks`."""
    return any(isinstance(layer, (Guidance, Directional)) for layer in scene.layers)


def draw_force_marks(scene: Scene, rgb: np.ndarray, xs: np.ndarray, ys: np.ndarray,
                     px_per_mm: tuple[float, float]) -> np.ndarray:
    """``rgb`` (height, width, 3) with the marks of ``scene``'s force layers drawn in
    place; ``xs``, ``ys`` the pixel centres (mm) of its columns and rows."""
    mm_per_px = 1.0 / min(px_per_mm)
    x, y = np.broadcast_arrays(xs[None, :], ys[:, None])
    for layer in scene.layers:
        if isinstance(layer, Guidance):
            d = _guidance_distance(layer, x, y, mm_per_px)
        elif isinstance(layer, Directional):
            d = _chevron_distance(layer, scene, x, y)
        else:
            continue
        if d is None:
            continue
        alpha = np.clip(MARK_WIDTH_PX / 2 + 0.5 - d / mm_per_px, 0.0, 1.0)
        alpha *= layer.in_region(x, y)
        rgb += (MARK_RGB - rgb) * alpha[..., None].astype(np.float32)
    return rgb


def _guidance_distance(layer: Guidance, x, y, mm_per_px: float) -> np.ndarray:
    """Distance (mm) to the target's mark: the ring and its dot, or the dashes."""
    dx, dy = x - layer.x_mm, y - layer.y_mm
    if not layer.line:
        r = np.hypot(dx, dy)
        return np.minimum(np.abs(r - RING_MM), np.maximum(r - 1.5 * mm_per_px, 0.0))
    a = math.radians(layer.line_angle_deg)
    across = np.abs(-dx * math.sin(a) + dy * math.cos(a))
    along = np.mod(dx * math.cos(a) + dy * math.sin(a), DASH_MM + GAP_MM)
    past_dash = np.maximum(along - DASH_MM, 0.0)  # in a gap: distance to the nearer dash end
    return np.hypot(across, np.minimum(past_dash, DASH_MM + GAP_MM - along))


def _chevron_distance(layer: Directional, scene: Scene, x, y) -> np.ndarray | None:
    """Distance (mm) to the chevrons (">" shapes pointing the way the finger glides) on
    the middle line of the layer's region (or the display)."""
    if layer.forward == layer.backward:
        return None
    glide = layer.axis_sign * (1 if layer.forward < layer.backward else -1)  # +1: +x
    region = layer.region
    if region is None:
        y_mid = scene.display.height_mm / 2
    else:
        y_mid = region.cy_mm if isinstance(region, DiscRegion) else region.center[1]
    # local coordinates: u along the glide, from each chevron's tip; v across
    u = glide * (np.mod(x - CHEVRON_SPACING_MM / 2, CHEVRON_SPACING_MM) - CHEVRON_SPACING_MM / 2)
    v = np.abs(y - y_mid)
    # the arm from the tip (0, 0) to (-h, h): distance to a segment
    h = CHEVRON_MM
    t = np.clip((-u + v) / (2 * h), 0.0, 1.0)
    return np.hypot(u + t * h, v - t * h)


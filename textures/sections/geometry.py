"""Where things lie on the display: regions, points and spans that must stay on it."""

from __future__ import annotations

import math

from frictex.textures import model
from frictex.textures.errors import KeyPath
from frictex.textures.keys import DISC_REGION, RECT_REGION
from frictex.textures.schema import BAD, Reader, kind


def span_problem(r: Reader, path: KeyPath, what: str, xs, ys, display: model.Display) -> bool:
    """Report (and return False) if the points (xs, ys) leave the display."""
    tol = 1e-9 * max(display.width_mm, display.height_mm)
    x0, x1, y0, y1 = min(xs), max(xs), min(ys), max(ys)
    if x0 < -tol or y0 < -tol or x1 > display.width_mm + tol or y1 > display.height_mm + tol:
        span = (f"x {x0:g} to {x1:g} mm, y {y0:g} to {y1:g} mm" if (x0, y0) != (x1, y1)
                else f"({x0:g}, {y0:g}) mm")
        r.report(path, f"{what} at {span} is off the display "
                       f"(0 to {display.width_mm:g} mm by 0 to {display.height_mm:g} mm)")
        return False
    return True


def region_on_display(r: Reader, path: KeyPath, region, display: model.Display, what: str) -> bool:
    if isinstance(region, model.DiscRegion):
        c, rad = (region.cx_mm, region.cy_mm), region.radius_mm
        return span_problem(r, path, what, (c[0] - rad, c[0] + rad), (c[1] - rad, c[1] + rad), display)
    cx, cy = region.center
    a = math.radians(region.angle_deg)
    ca, sa = math.cos(a), math.sin(a)
    corners = [(cx + ca * u - sa * v, cy + sa * u + ca * v)
               for u in (-region.width_mm / 2, region.width_mm / 2)
               for v in (-region.height_mm / 2, region.height_mm / 2)]
    return span_problem(r, path, what, [p[0] for p in corners], [p[1] for p in corners], display)


def parse_region(r: Reader, raw, path: KeyPath, display: model.Display | None):
    if not isinstance(raw, dict):
        return r.report(path, f"expected a table {{x_mm, y_mm, width_mm, height_mm}} or "
                              f"{{cx_mm, cy_mm, radius_mm}}, got {kind(raw)}")
    disc_keys = [k for k in raw if k in DISC_REGION]
    rect_keys = [k for k in raw if k in RECT_REGION]
    if disc_keys and rect_keys:
        return r.report(path, f"mixes rectangle keys ({', '.join(rect_keys)}) and disc keys "
                              f"({', '.join(disc_keys)}); a region is one or the other")
    spec = DISC_REGION if disc_keys else RECT_REGION
    v = r.table(raw, path, spec)
    if v is None or BAD in v.values():
        return BAD
    region = model.DiscRegion(**v) if disc_keys else model.RectRegion(**v)
    if display is not None and not region_on_display(r, path, region, display, "region"):
        return BAD
    return region



def fits(r, path, key: str, edge_mm: float, limit: float, what: str) -> bool:
    if edge_mm > limit:
        r.report(path + (key,), f"{edge_mm:g} mm is more than {what} ({limit:g} mm): "
                                f"mu' would never reach mu inside")
        return False
    return True


def on_display(r, path, ctx, what, xs, ys) -> bool:
    return ctx.display is None or span_problem(r, path, what, xs, ys, ctx.display)


"""Where things lie on the display: shapes and regions must share some of its area (a
shape partly off it is clipped at its edge, as every renderer evaluates layers per
position); points that place a line or a target must lie on it."""

from __future__ import annotations

from frictex.textures import model
from frictex.textures.errors import KeyPath
from frictex.textures.extent import line_corners, rect_corners, shares_display
from frictex.textures.keys import DISC_REGION, RECT_REGION
from frictex.textures.schema import BAD, Reader, kind


def _area(display: model.Display) -> str:
    return f"(x 0 to {display.width_mm:g} mm, y 0 to {display.height_mm:g} mm)"


def _span(xs, ys) -> str:
    x0, x1, y0, y1 = min(xs), max(xs), min(ys), max(ys)
    return (f"x {x0:g} to {x1:g} mm, y {y0:g} to {y1:g} mm" if (x0, y0) != (x1, y1)
            else f"({x0:g}, {y0:g}) mm")


def span_problem(r: Reader, path: KeyPath, what: str, xs, ys, display: model.Display) -> bool:
    """Report (and return False) if the points (xs, ys) leave the display."""
    tol = 1e-9 * max(display.width_mm, display.height_mm)
    x0, x1, y0, y1 = min(xs), max(xs), min(ys), max(ys)
    if x0 < -tol or y0 < -tol or x1 > display.width_mm + tol or y1 > display.height_mm + tol:
        r.report(path, f"{what} at {_span(xs, ys)} is off the display {_area(display)}")
        return False
    return True


def shape_on_display(r: Reader, path: KeyPath, shape, display: model.Display, what: str) -> bool:
    """Report (and return False) if ``shape`` (``extent.shares_display``'s) lies wholly
    off the display; a shape partly on it is clipped there."""
    if shares_display(shape, display):
        return True
    if isinstance(shape, model.DiscRegion):
        c, rad = (shape.cx_mm, shape.cy_mm), shape.radius_mm
        xs, ys = (c[0] - rad, c[0] + rad), (c[1] - rad, c[1] + rad)
    else:
        corners = (rect_corners(shape) if isinstance(shape, model.RectRegion)
                   else line_corners(*shape[:4], shape[4] / 2))
        xs, ys = [p[0] for p in corners], [p[1] for p in corners]
    r.report(path, f"{what} at {_span(xs, ys)} lies wholly off the display {_area(display)}")
    return False


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
    if display is not None and not shape_on_display(r, path, region, display, "region"):
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


"""Builders of the friction layers drawn from geometry: gratings, waveforms, objects
(rectangle, disc, edge, bump, line) and raster maps (``textures.model``)."""

from __future__ import annotations

from frictex.textures import model
from frictex.textures.keys import DISC_REGION, RECT_REGION
from frictex.textures.raster_io import read_grey
from frictex.textures.sections.common import forbid, ordered
from frictex.textures.sections.geometry import fits, on_display, shape_on_display


def build_grating(r, path, v, given, ctx):
    ok = ordered(r, path, "mu_low", "mu_high", v)
    narrow = min(v["duty"], 1.0 - v["duty"]) * v["period_mm"]
    if v["edge"] == "square":
        ok &= forbid(r, path, given, ["edge_mm"], 'with edge = "square"')
    elif v["edge_mm"] <= 0.0:
        key = "edge_mm" if "edge_mm" in given else "edge"
        r.report(path + (key,), f'edge = "smooth" needs edge_mm > 0 (the width of its ramps, mm), '
                                f'got {v["edge_mm"]:g}')
        ok = False
    elif v["edge_mm"] > narrow:
        r.report(path + ("edge_mm",), f"{v['edge_mm']:g} mm is wider than the narrower band "
                                      f"({narrow:g} mm = min(duty, 1 - duty) x period_mm)")
        ok = False
    return (model.Grating(**ctx.common, **v), "mu_low") if ok else None


def build_waveform(r, path, v, given, ctx):
    if v["shape"] == "samples":
        ok = forbid(r, path, given, ["mu_min", "mu_max", "duty"], 'with shape = "samples"')
        if not v["samples"]:
            r.report(path + ("samples",), 'missing: shape = "samples" needs samples = '
                                    "[mu', ...] over one period")
            ok = False
        v = {k: x for k, x in v.items() if k not in ("mu_min", "mu_max", "duty")}
        low_key = "samples"
    else:
        ok = forbid(r, path, given, ["samples"], f'with shape = "{v["shape"]}"')
        if v["shape"] != "square":
            ok &= forbid(r, path, given, ["duty"], f'with shape = "{v["shape"]}" (only "square")')
        if v["mu_min"] is None:
            r.report(path + ("mu_min",), "missing (required for a standard shape)")
            ok = False
        else:
            ok &= ordered(r, path, "mu_min", "mu_max", v)
        low_key = "mu_min"
    return (model.Waveform(**ctx.common, **v), low_key) if ok else None



def build_rectangle(r, path, v, given, ctx):
    geometry = model.RectRegion(*(v[k] for k in RECT_REGION))
    ok = fits(r, path, "edge_mm", v["edge_mm"], min(v["width_mm"], v["height_mm"]), "the shorter side")
    ok &= ctx.display is None or shape_on_display(r, path + ("x_mm",), geometry, ctx.display, "rectangle")
    return (model.Shape(**ctx.common, geometry=geometry, mu=v["mu"], edge_mm=v["edge_mm"]), "mu") if ok else None


def build_disc(r, path, v, given, ctx):
    geometry = model.DiscRegion(*(v[k] for k in DISC_REGION))
    ok = fits(r, path, "edge_mm", v["edge_mm"], 2 * v["radius_mm"], "the diameter")
    ok &= ctx.display is None or shape_on_display(r, path + ("cx_mm",), geometry, ctx.display, "disc")
    return (model.Shape(**ctx.common, geometry=geometry, mu=v["mu"], edge_mm=v["edge_mm"]), "mu") if ok else None


def build_edge(r, path, v, given, ctx):
    ok = on_display(r, path + ("x_mm",), ctx, "edge point", [v["x_mm"]], [v["y_mm"]])
    return (model.Edge(**ctx.common, **v), "mu") if ok else None


def build_bump(r, path, v, given, ctx):
    support = model.DiscRegion(v["cx_mm"], v["cy_mm"], 4.0 * v["sigma_mm"])
    ok = ctx.display is None or shape_on_display(r, path + ("cx_mm",), support, ctx.display,
                                                 "bump (to 4 sigma)")
    return (model.Bump(**ctx.common, **v), "mu") if ok else None


def build_line(r, path, v, given, ctx):
    ok = True
    if (v["x0_mm"], v["y0_mm"]) == (v["x1_mm"], v["y1_mm"]):
        r.report(path + ("x0_mm",), f"line has zero length: both ends at ({v['x0_mm']:g}, {v['y0_mm']:g}) mm "
                 f"(use a disc for a dot)")
        ok = False
    ok &= fits(r, path, "edge_mm", v["edge_mm"], v["width_mm"], "width_mm")
    line = (v["x0_mm"], v["y0_mm"], v["x1_mm"], v["y1_mm"], v["width_mm"])
    ok &= ctx.display is None or shape_on_display(r, path + ("x0_mm",), line, ctx.display, "line")
    return (model.Line(**ctx.common, **v), "mu") if ok else None


def build_raster(r, path, v, given, ctx):
    mode = v["mode"]
    ok = True
    if mode == "one-to-one":
        ok &= forbid(r, path, given, ["width_mm", "height_mm", "tile_width_mm", "tile_height_mm"],
                      'with mode = "one-to-one" (the size comes from the image and the display px/mm)')
    else:
        for key in ("width_mm", "height_mm"):
            if v[key] is None:
                r.report(path + (key,), f'missing (required with mode = "{mode}")')
                ok = False
        if mode == "stretch":
            ok &= forbid(r, path, given, ["tile_width_mm", "tile_height_mm"], 'with mode = "stretch"')
    got = ctx.files.read(r, path + ("image",), v["image"],
                         lambda f: read_grey(f, budget=ctx.files.budget)[0])
    if got is None:
        return None
    image_path, grey = got
    if not ok or ctx.display is None:
        return None
    px_x, px_y = ctx.display.px_per_mm
    rows, cols = grey.shape
    v = {**v, "image": grey, "image_path": image_path}
    if mode == "one-to-one":
        v["width_mm"], v["height_mm"] = cols / px_x, rows / px_y
    v["tile_width_mm"] = v["tile_width_mm"] or cols / px_x
    v["tile_height_mm"] = v["tile_height_mm"] or rows / px_y
    layer = model.RasterMap(**ctx.common, **v)
    if not shape_on_display(r, path + ("x_mm",), layer.sprite, ctx.display, "image"):
        return None
    low_key = "mu_black" if v["mu_black"] <= v["mu_white"] else "mu_white"
    return layer, low_key

"""Builders of the dynamic layers: heights felt by their slope (``textures.heights``),
recorded textures (``textures.hatt``) and effect clips (``textures.clips``,
``textures.ahap``)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from frictex.textures import model
from frictex.textures.ahap import read_ahap
from frictex.textures.clips import Clip, ClipEvent, ClipLayer
from frictex.textures.errors import TextureError
from frictex.textures.heights import (ButtonRim, GaussianBump, HeightLayer, HeightMap, Ridge, Step,
                                      read_height_png)
from frictex.textures.keys import CLIP_SHAPES, HEIGHT_SHAPES
from frictex.textures.schema import show
from frictex.textures.sections.common import chosen_keys, forbid, strictly_increasing
from frictex.textures.sections.files import file_read
from frictex.textures.sections.geometry import on_display, shape_on_display


def build_height(r, path, v, given, ctx):
    kind = v["shape"]
    ok = chosen_keys(r, path, v, given, HEIGHT_SHAPES, "shape",
                      optional=("x_mm", "y_mm") if kind == "map" else ())
    low = "<=" if v["rendering"] == "magnitude" else "<"
    if not ((v["mu_min"] <= v["mu_rest"] if low == "<=" else v["mu_min"] < v["mu_rest"])
            and v["mu_rest"] < v["mu_max"]):
        r.report(path + ("mu_rest",), f"mu_min {v['mu_min']:g} {low} mu_rest {v['mu_rest']:g} "
                                      f"< mu_max {v['mu_max']:g} does not hold")
        ok = False
    if not ok:
        return None
    if kind == "bump":
        shape = GaussianBump(v["cx_mm"], v["cy_mm"], v["sigma_mm"], v["rise_mm"])
        support = model.DiscRegion(v["cx_mm"], v["cy_mm"], 4.0 * v["sigma_mm"])
        ok = ctx.display is None or shape_on_display(r, path + ("cx_mm",), support, ctx.display,
                                                     "bump (to 4 sigma)")
    elif kind == "ridge":
        shape = Ridge(v["x_mm"], v["y_mm"], v["angle_deg"], v["width_mm"], v["rise_mm"])
        ok = on_display(r, path + ("x_mm",), ctx, "ridge point", [v["x_mm"]], [v["y_mm"]])
    elif kind == "step":
        shape = Step(v["x_mm"], v["y_mm"], v["angle_deg"], v["rise_mm"], v["chamfer_mm"])
        ok = on_display(r, path + ("x_mm",), ctx, "step point", [v["x_mm"]], [v["y_mm"]])
    elif kind == "button":
        if not v["rim_mm"] < v["radius_mm"]:
            r.report(path + ("rim_mm",), f"{v['rim_mm']:g} mm is not below radius_mm {v['radius_mm']:g}")
            return None
        shape = ButtonRim(v["cx_mm"], v["cy_mm"], v["radius_mm"], v["rim_mm"], v["rise_mm"])
        ok = ctx.display is None or shape_on_display(
            r, path + ("cx_mm",), model.DiscRegion(v["cx_mm"], v["cy_mm"], v["radius_mm"]),
            ctx.display, "button")
    else:
        x, y = v["x_mm"] or 0.0, v["y_mm"] or 0.0
        sprite = model.RectRegion(x, y, v["width_mm"], v["height_mm"])
        ok = ctx.display is None or shape_on_display(r, path + ("x_mm",), sprite, ctx.display,
                                                        "height map")
        heights = file_read(r, path, "image", v["image"], ctx,
                             lambda f: read_height_png(f, v["rise_mm"], ctx.files.budget))
        if heights is None:
            return None
        shape = HeightMap(heights, x, y, v["width_mm"], v["height_mm"])
    keys = ("rendering", "gain", "mu_rest", "mu_min", "mu_max", "v_fade_mm_s")
    return (HeightLayer(**ctx.common, shape=shape, **{k: v[k] for k in keys}), "mu_min") if ok else None


def build_recorded(r, path, v, given, ctx):
    if not v["mu_min"] < v["mu_mean"] < v["mu_max"]:
        r.report(path + ("mu_mean",), f"mu_min {v['mu_min']:g} < mu_mean {v['mu_mean']:g} < "
                                      f"mu_max {v['mu_max']:g} does not hold")
        return None
    from frictex.textures.dynamic import OUTPUT_RATE_HZ
    from frictex.textures.hatt import ArTextureLayer, read_hatt_xml  # numba: only for scenes that use it

    texture = file_read(r, path, "model", v["model"], ctx, read_hatt_xml)
    if texture is None:
        return None
    # errors met when the model is played at another rate name the key that names it
    where = str(r.problem(path + ("model",), f"{show(v['model'])}: {texture.source}"))
    texture = replace(texture, source=where)
    try:  # a warning, not a problem: it plays at its own rate (replay --rate)
        texture.check_rate(OUTPUT_RATE_HZ)
    except TextureError as exc:
        r.report(path + ("model",), f"{show(v['model'])}: cannot be played at "
                                    f"{OUTPUT_RATE_HZ:g} Hz, the default output rate "
                                    f"({str(exc)[len(texture.source) + 2:]}); it plays at "
                                    f"--rate {texture.rate_hz:g}", warning=True)
    layer = ArTextureLayer(**ctx.common, **{**v, "model": texture})
    _clipping_warning(r, path, layer)
    return layer, "mu_min"


def _gaussian_outside(std: float, below: float, above: float) -> float:
    """The share of a zero-mean Gaussian of standard deviation ``std`` that lies below
    -``below`` or above ``above``."""
    tail = lambda room: 0.5 * math.erfc(room / (std * math.sqrt(2.0)))  # noqa: E731
    return tail(below) + tail(above)


def _percent(share: float) -> str:
    """A share as a percentage for "at least": one above 99.9% (a Gaussian's never
    reaches 100%, though its float may) is 99.9%."""
    return "99.9%" if share > 0.999 else f"{share:.1%}"


def _output_variances(model) -> np.ndarray:
    """(M,) the variance ((m/s^2)^2) of each vertex model's output: its excitation's
    variance times the power gain of 1 / A(z) (81 to 685 for HaTT's resonant models)."""
    from frictex.textures.ar_synthesis import lsf_to_poly, output_power_gain  # numba, as above

    return np.array([var * output_power_gain(lsf_to_poly(lsf))
                     for lsf, var in zip(model.lsf, model.variances)])


def _clipping_warning(r, path, layer) -> None:
    """Warn where the recorded layer's ``gain`` times the output standard deviation
    (m/s^2) of its loudest vertex passes the room mu' has about mu_mean: the model's
    output there, a Gaussian of that deviation, would be clipped to [mu_min, mu_max] on
    a large share of the samples played near that vertex."""
    model = layer.model
    variances = _output_variances(model)
    loudest = int(np.argmax(variances))
    output_std = math.sqrt(variances[loudest])  # m/s^2
    std = layer.gain * output_std  # mu'
    below, above = layer.mu_mean - layer.mu_min, layer.mu_max - layer.mu_mean
    if std <= min(below, above):
        return
    share = _gaussian_outside(std, below, above)
    r.report(path + ("gain",),
             f"layer {show(layer.name)}: gain {layer.gain:g} times the output of the model's "
             f"loudest vertex (model {loudest + 1}, {model.speeds_mm_s[loudest]:g} mm/s and "
             f"{model.forces_n[loudest]:g} N: standard deviation {output_std:.3g} m/s^2) is "
             f"{std:.3g} of mu', more than its room about mu_mean ({below:g} down to mu_min, "
             f"{above:g} up to mu_max): at least {_percent(share)} of the samples played near "
             f"that vertex will be clipped; lower gain to "
             f"{min(below, above) / (3.0 * std) * layer.gain:.3g} or less (3 output standard "
             f"deviations of room), or check the model's <var>", warning=True)


def _clip_shape(r, path, v, ctx) -> Clip | None:
    kind, depth = v["clip"], v["depth"]
    sharp = v["sharpness"] if v["sharpness"] is not None else (0.5 if kind == "tick" else 0.0)
    if kind == "tick":
        return Clip((ClipEvent("transient", 0.0, v["intensity"], sharp),), depth)
    if kind == "ramp":
        envelope = ((0.0, v["level_from"]), (v["duration_s"], v["level_to"]))
        return Clip((ClipEvent("continuous", 0.0, 1.0, sharp, v["duration_s"], envelope),), depth)
    if kind == "envelope":
        times, levels = v["times_s"], v["levels"]
        if len(times) != len(levels) or times[0] != 0.0 or not strictly_increasing(times):
            r.report(path + ("times_s",), f"{show(list(times))}: expected times from 0, strictly "
                                          f"increasing, one per level ({len(levels)})")
            return None
        return Clip((ClipEvent("continuous", 0.0, v["intensity"], sharp, times[-1],
                               tuple(zip(times, levels))),), depth)
    got = file_read(r, path, "file", v["file"], ctx, lambda f: read_ahap(f, depth))
    if got is None:
        return None
    clip, notes = got
    for note in notes[:3]:
        r.report(path + ("file",), note, warning=True)
    return clip


def build_clip(r, path, v, given, ctx):
    shape_ok = chosen_keys(r, path, v, given, CLIP_SHAPES, "clip", optional=("sharpness",))
    ok = True
    trigger = v["trigger"]
    needs = {"edge": ("x_mm", "y_mm"), "force": ("force_n",)}.get(trigger, ())
    for key in needs:
        if v[key] is None:
            r.report(path + (key,), f'missing (required with trigger = "{trigger}")')
            ok = False
    unused = [k for k in ("x_mm", "y_mm", "angle_deg", "force_n") if k not in needs
              and not (k == "angle_deg" and trigger == "edge")]
    ok &= forbid(r, path, given, unused, f'with trigger = "{trigger}"')
    if ok and trigger == "edge":
        ok = on_display(r, path + ("x_mm",), ctx, "edge point", [v["x_mm"]], [v["y_mm"]])
    clip = _clip_shape(r, path, v, ctx) if shape_ok else None  # its problems too
    if clip is None or not ok:
        return None
    place = {k: v[k] for k in ("x_mm", "y_mm", "angle_deg", "force_n") if v[k] is not None}
    return ClipLayer(**ctx.common, clip=clip, trigger=trigger, **place), "depth"

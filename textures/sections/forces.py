"""Builders of the force layers (travelling-wave profiles only): directional, guidance and
keyclick (``textures.model.FORCE_LAYERS``)."""

from __future__ import annotations

import math

from frictex.textures import model
from frictex.textures.sections.common import forbid
from frictex.textures.sections.geometry import on_display, shape_on_display


def force_common(r, path, given) -> bool:
    return forbid(r, path, given, ["blend"], "on a force layer (mu' targets multiply, force "
                                              "targets replace: rendering.layers.force_layers)")


def build_directional(r, path, v, given, ctx):
    ok = force_common(r, path, given)
    if abs(math.sin(math.radians(v["angle_deg"]))) > 1e-9:
        r.report(path + ("angle_deg",), f"{v['angle_deg']:g} deg: the waves push only along x; "
                                        f"expected 0 (forward = +x) or 180 (forward = -x)")
        ok = False
    pairs = {"mu": ("mu_forward", "mu_backward"), "force": ("force_forward_n", "force_backward_n")}
    given_pairs = [kind for kind, keys in pairs.items() if any(k in given for k in keys)]
    if len(given_pairs) != 1:
        found = "both mu_* and force_*_n" if given_pairs else "neither"
        r.report(path + ("type",), f"{found}: give mu_forward and mu_backward (mu') or "
                                   f"force_forward_n and force_backward_n (N)")
        return None
    target = given_pairs[0]
    for key in pairs[target]:
        if v[key] is None:
            r.report(path + (key,), f"missing (required with {' and '.join(pairs[target])})")
            ok = False
    if not ok:
        return None
    forward, backward = (v[k] for k in pairs[target])
    layer = model.Directional(**ctx.common, angle_deg=v["angle_deg"], target=target,
                              forward=forward, backward=backward)
    return layer, pairs[target][0]


def build_guidance(r, path, v, given, ctx):
    ok = force_common(r, path, given)
    if not v["line"]:
        ok &= forbid(r, path, given, ["line_angle_deg"], "with line = false (a point target)")
    ok &= on_display(r, path + ("x_mm",), ctx, "guidance target", [v["x_mm"]], [v["y_mm"]])
    return (model.Guidance(**ctx.common, **v), "gain_n_per_mm") if ok else None


def build_keyclick(r, path, v, given, ctx):
    ok = force_common(r, path, given)
    ok &= _thresholds_in_order(r, path, v, given)
    geometry = model.RectRegion(v["x_mm"], v["y_mm"], v["width_mm"], v["height_mm"])
    ok &= ctx.display is None or shape_on_display(r, path + ("x_mm",), geometry, ctx.display, "button")
    if not ok:
        return None
    keys = ("press_n", "click_n", "release_n", "dwell_s", "force_n")
    layer = model.KeyClick(**ctx.common, geometry=geometry, first_push=1 if v["first_push"] == "+x" else -1,
                           **{k: v[k] for k in keys})
    return layer, "force_n"


#: the key-click's normal-force thresholds, lowest first (seed 004, Fig. 5a)
_THRESHOLDS = ("release_n", "press_n", "click_n")


def _thresholds_in_order(r, path, v, given) -> bool:
    """Check release_n < press_n < click_n; report a break at the keys to blame.

    A key is blamed if the other two are in order without it, but only a key the file
    wrote (a default is not what went wrong); where no one key explains the break (all
    three reversed), every written key of an out-of-order pair. True if the order holds.
    """
    values = [v[k] for k in _THRESHOLDS]
    if values[0] < values[1] < values[2]:
        return True
    without = [(k, values[:i] + values[i + 1:]) for i, k in enumerate(_THRESHOLDS)]
    blamed = [k for k, (a, b) in without if a < b and k in given]
    if not blamed:
        pairs = zip(_THRESHOLDS, _THRESHOLDS[1:], values, values[1:])
        blamed = sorted({k for low, high, a, b in pairs if not a < b for k in (low, high)
                         if k in given}, key=_THRESHOLDS.index)
    got = ", ".join(f"{k} {v[k]:g}" + ("" if k in given else " (default)") for k in _THRESHOLDS)
    for key in blamed:
        r.report(path + (key,), f"{v[key]:g} N is out of order: expected release_n < press_n "
                                f"< click_n (N), got {got}")
    return False

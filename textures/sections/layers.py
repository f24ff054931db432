"""``[[layer]]`` tables: the keys every layer takes (type, name, render, blend, fingers,
region, visual), then the builder of its type; and the warnings about layers a device
cannot serve as written."""

from __future__ import annotations

from typing import Callable

from frictex.device import profile as profiles
from frictex.textures import model
from frictex.textures.clips import ClipLayer
from frictex.textures.dynamic import OUTPUT_RATE_HZ, DynamicLayer
from frictex.textures.heights import HeightLayer, HeightMap
from frictex.textures.errors import KeyPath
from frictex.textures.keys import COMMON, LAYER_KEYS, LAYER_TABLES, LAYER_TYPES, MAX_LAYERS, PERIODIC_TYPES, VISUAL
from frictex.textures.schema import BAD, Reader, kind, show
from frictex.textures.sections import dynamic, forces, shapes
from frictex.textures.sections.common import Context
from frictex.textures.sections.files import Files
from frictex.textures.sections.geometry import parse_region

BUILDERS: dict[str, Callable] = {
    "grating": shapes.build_grating, "waveform": shapes.build_waveform,
    "rectangle": shapes.build_rectangle, "disc": shapes.build_disc, "edge": shapes.build_edge,
    "bump": shapes.build_bump, "line": shapes.build_line, "raster": shapes.build_raster,
    "directional": forces.build_directional, "guidance": forces.build_guidance,
    "keyclick": forces.build_keyclick, "height": dynamic.build_height,
    "recorded": dynamic.build_recorded, "clip": dynamic.build_clip,
}


def default_layer_name(layer_type: str, index: int) -> str:
    """The name of a layer without ``name``: its type and its place among the
    ``[[layer]]`` tables, from 1 ("grating-2" for the second table)."""
    return f"{layer_type}-{index + 1}"


def report_bad_name(r: Reader, path: KeyPath, name: str, index: int, names: dict,
                    shown: Callable[[int], str]) -> None:
    """Report at ``path`` the ``name`` of layer ``index`` where it is blank or an earlier
    layer has it (``names``: name -> the index of the first layer of that name; this one
    is added); ``shown(i)`` is layer i as the message names it (``layer[2]`` in a file,
    1-based; ``layers[1]`` in a Scene made in code)."""
    if not name.strip():
        r.report(path, 'is empty; give the layer a name or leave the key out')
        return
    first = names.setdefault(name, index)
    if first != index:
        r.report(path, f"{show(name)} is already the name of {shown(first)}")


def parse_layer(r: Reader, raw, index: int, display, files: Files, names: dict):
    """One [[layer]] -> (layer, key of its lowest mu') or None (problems reported)."""
    path: KeyPath = ("layer", index)
    if not isinstance(raw, dict):
        r.report(path, f"expected a table, got {kind(raw)}")
        return None
    if "type" not in raw:
        r.report(path + ("type",), f"missing (required): one of {', '.join(LAYER_TYPES)}")
        return None
    layer_type = COMMON["type"].check(r, raw["type"], path + ("type",))
    if layer_type is BAD:
        return None
    v = r.table(raw, path, {**COMMON, **LAYER_KEYS[layer_type]}, tables=LAYER_TABLES)
    region = parse_region(r, raw["region"], path + ("region",), display) if "region" in raw else None
    visual = r.table(raw.get("visual", {}), path + ("visual",), VISUAL)
    name = v["name"] if v["name"] is not None else default_layer_name(layer_type, index)
    if name is not BAD:
        report_bad_name(r, path + ("name",), name, index, names,
                        lambda first: f"layer[{first + 1}]")
    render = v["render"]
    if render not in (BAD, "auto", model.SHO) and layer_type not in PERIODIC_TYPES:
        render = r.report(path + ("render",), needs_a_period(render, layer_type))
    values = {k: v[k] for k in LAYER_KEYS[layer_type]}
    if BAD in values.values():
        return None
    common_ok = not (BAD in (name, render, v["blend"], v["fingers"], region) or visual is None
                     or BAD in visual.values())
    if render == "auto":
        render = model.auto_render_mode(values["period_mm"] if layer_type in PERIODIC_TYPES else None)
    # with problems in the common keys the type's own checks still run (every problem
    # is reported) on placeholder hints, and the layer is dropped afterwards
    hints = model.VisualHints(**visual) if common_ok else model.VisualHints()
    common = dict(name=name, render=render, blend=v["blend"], region=region, visual=hints,
                  fingers=v["fingers"])
    built = BUILDERS[layer_type](r, path, values, set(raw), Context(display, files, common))
    return built if common_ok else None


def needs_a_period(render: str, kind: str) -> str:
    """Why a renderer of periods, ``render``, cannot render a layer of ``kind`` (a word
    saying which layer), which has no period."""
    return (f'"{render}" needs a periodic layer (grating or waveform); a {kind} renders with '
            '"sho" (or "auto")')


def parse_layers(r: Reader, doc: dict, display, files: Files):
    raw = doc.get("layer")
    if raw is None:
        r.report(("layer",), "no [[layer]] tables: a scene needs at least one layer")
        return None
    if not isinstance(raw, list) or not all(isinstance(x, dict) for x in raw):
        r.report(("layer",), f"expected [[layer]] tables (an array of tables), got {kind(raw)}; "
                             f"start each layer with [[layer]]")
        return None
    if len(raw) > MAX_LAYERS:
        r.report(("layer", MAX_LAYERS), f"{len(raw)} [[layer]] tables; a scene holds at most "
                                        f"{MAX_LAYERS} (every layer is evaluated for every "
                                        f"finger at every output sample)")
        return None
    names: dict[str, int] = {}
    built = [parse_layer(r, item, i, display, files, names) for i, item in enumerate(raw)]
    return None if None in built else built


def selector_warnings(r: Reader, device: profiles.DeviceProfile, built) -> None:
    if device.profile != profiles.DEFAULT_PROFILE:
        return
    for index, (layer, _) in enumerate(built):
        if layer.fingers != "any":
            r.report(("layer", index, "fingers"),
                     f"{show(layer.fingers)} on profile {show(device.profile)}: one channel "
                     f"serves only the finger touching longest, so other fingers feel its "
                     f"amplitude, not this layer (a modal profile gives each finger its own: "
                     f"{', '.join(profiles.MODAL_PROFILES)})", warning=True)


def lift_warnings(r: Reader, built) -> None:
    """Warn at each ``trigger = "lift"`` clip: it starts as a touch ends, and friction
    modulation is felt only by a finger on the plate, so only other fingers still
    touching feel it (with one finger, nothing is felt)."""
    for index, (layer, _) in enumerate(built):
        if isinstance(layer, ClipLayer) and layer.trigger == "lift":
            r.report(("layer", index, "trigger"),
                     f'"lift" on layer {show(layer.name)}: the clip starts as a touch ends, and '
                     f"friction is felt only by a finger on the plate, so it is felt only by other "
                     f"fingers still touching (with one finger, never)", warning=True)


def unfelt_warnings(r: Reader, built) -> None:
    """Warn at each layer nothing of which can be felt: a height layer whose shape is flat
    (``rise_mm = 0``, or a map whose pixels all have one height: its slope is 0
    everywhere), and a clip that never lowers mu' at the default output rate
    (``textures.dynamic.OUTPUT_RATE_HZ``: a level or intensity of 0 throughout, or a
    clip over before its second sample), and a multiplying layer of fixed friction that
    asks for mu' 1 everywhere (a grating with mu_low = 1: no lower friction anywhere). A
    ``replace`` layer at 1 is felt (it takes away what the layers before it lower), and so
    are force layers (their mu' is 1: they push the finger)."""
    for index, (layer, low_key) in enumerate(built):
        if isinstance(layer, HeightLayer) and layer.shape.relief_mm == 0.0:
            _flat_height_warning(r, index, layer)
        elif isinstance(layer, ClipLayer) and layer.clip.deepest_mu >= 1.0:
            _silent_clip_warning(r, index, layer)
        elif (not isinstance(layer, (DynamicLayer, *model.FORCE_LAYERS))
              and layer.blend == "multiply" and layer.mu_range[0] >= 1.0):
            r.report(("layer", index, low_key),
                     f"layer {show(layer.name)}: asks for mu' 1 everywhere (friction as the "
                     "plate has it, never lower), so nothing of it is felt; give it a mu' "
                     "below 1", warning=True)


def _flat_height_warning(r: Reader, index: int, layer: HeightLayer) -> None:
    """The warning for a height layer whose shape is flat (:func:`unfelt_warnings`)."""
    if isinstance(layer.shape, HeightMap):
        rows, cols = layer.shape.heights_mm.shape
        key, why, fix = ("image", f"every pixel of the {cols} x {rows} map has one height",
                         "give the map pixels of different greys")
    else:
        key, why, fix = "rise_mm", "rise_mm = 0 makes the shape flat", "give rise_mm a height"
    r.report(("layer", index, key),
             f"layer {show(layer.name)}: {why}, so its slope is 0 everywhere and nothing of "
             f"it is felt (mu' stays mu_rest = {layer.mu_rest:g} where it covers); {fix}",
             warning=True)


def _silent_clip_warning(r: Reader, index: int, layer: ClipLayer) -> None:
    """The warning for a clip that never lowers mu' (:func:`unfelt_warnings`)."""
    sample_s = 1.0 / OUTPUT_RATE_HZ
    duration = layer.clip.duration_s
    why = (f"it lasts {duration:g} s, under one output sample of {sample_s:g} s at "
           f"{OUTPUT_RATE_HZ:g} Hz, and is at level 0 on its first"
           if duration < sample_s else "its levels times its intensity are 0 throughout")
    r.report(("layer", index, "clip"),
             f"layer {show(layer.name)}: the clip never lowers mu' ({why}), so nothing of it "
             f"is felt; give it a level above 0 for at least one output sample", warning=True)


def reach_warnings(r: Reader, device: profiles.DeviceProfile, display: model.Display,
                   built) -> None:
    """A warning for each layer whose own lowest mu' is below the device's floor at the
    nominal force, and for each clip that goes below it where it plays over layers fixed
    in place (``textures.overlap.under_clips``): a clip plays its deepest at every trigger,
    so a typical stroke, which seldom fires it, does not show it (``rendering.reach``)."""
    from frictex.device.friction import mu_floor
    from frictex.textures.overlap import under_clips

    force = device.normal_force_n
    floor = mu_floor(device, force)
    reaches = (f"the device reaches only {floor:.4g} at the nominal {force:g} N ("
               + ("the calibration table" if device.calibration is not None
                  else f"seed 003 eq 2, amplitude_limit_um {device.amplitude_limit_um:g}")
               + "); lower values will be clamped")
    layers = [layer for layer, _ in built]
    for index, (layer, low_key) in enumerate(built):
        low = layer.mu_range[0]
        if low < floor - 1e-12:
            r.report(("layer", index, low_key), f"asks for mu' down to {low:.4g}, but {reaches}",
                     warning=True)
    for index, overlap in under_clips(display, layers):
        clip = layers[index]
        under = [name for name in overlap.names if name != clip.name]
        if under and clip.mu_range[0] >= floor - 1e-12 and overlap.lowest < floor - 1e-12:
            named = ", ".join(f"layer {show(name)}" for name in under)
            r.report(("layer", index, built[index][1]),
                     f"playing over {named} it may ask for mu' down to {overlap.lowest:.4g} (its "
                     f"deepest, {clip.mu_range[0]:.4g}, times theirs), but {reaches}",
                     warning=True)


"""The key tables of texture files (format 1): every table, its keys, their types, ranges
and defaults. ``textures.loader`` checks files against them (``textures.schema``) and
``textures.format_doc`` prints them as ``textures/FORMAT.md``; the grammar's overview is
at the top of ``textures.loader``.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import replace

from frictex.device import profile as profiles
from frictex.device.calibration_identity import B_BOUNDS, K_BOUNDS
from frictex.device.profile import METHODS, THEORIES
from frictex.textures import model
from frictex.textures.clips import CLIP_TRIGGERS, FORCE_REARM, MAX_CLIP_S
from frictex.textures.heights import HEIGHT_RENDERINGS
from frictex.textures.schema import (Choice, Colour, Flag, Int, Num, NumList, Retired, Rows,
                                     Selector, Spec, Text)

FORMAT_VERSION = 1

LAYER_TYPES = ("grating", "waveform", "rectangle", "disc", "edge", "bump", "line", "raster",
               "directional", "guidance", "keyclick", "height", "recorded", "clip")
FORCE_TYPES = ("directional", "guidance", "keyclick")
PERIODIC_TYPES = ("grating", "waveform")


class RenderChoices(Sequence[str]):
    """What a layer's ``render`` may name, read each time it is asked (a check, an error
    listing them): ``auto`` and :func:`model.loadable_render_modes`, so that a renderer
    registered or installed after frictex was imported is taken, and one that cannot be
    loaded is not offered; checking a name imports nothing."""

    def now(self) -> tuple[str, ...]:
        """The names as they are now."""
        return ("auto", *model.loadable_render_modes())

    def __getitem__(self, index):
        return self.now()[index]

    def __len__(self) -> int:
        return len(self.now())

    def __iter__(self) -> Iterator[str]:
        return iter(self.now())

    def __contains__(self, name: object) -> bool:
        """A check imports no plugin (listing them all, :meth:`now`, imports each): a
        registered name is taken, and one that cannot be loaded is refused where the
        scene's renderers are built, with why."""
        return name in ("auto", model.SHO) or name in model.RENDERERS

    def __repr__(self) -> str:
        return f"RenderChoices({self.now()})"


RENDER_CHOICES = RenderChoices()

_DEVICE = profiles.DeviceProfile()
_FRICTION = profiles.FrictionParams()
_VISUAL = model.VisualHints()

#: Sensible ranges (texture files are written by hand; a value beyond these is a typo or a
#: wrong unit, and refusing it keeps every later stage finite):
MAX_MM = 1e4           # 10 m: larger than any touchscreen or vibrating structure
MIN_SIZE_MM = 1e-3     # 1 um: smaller than any feature a fingertip can feel
MIN_PERIOD_MM = 0.01   # 10 um: seed 003's finest gratings are 0.6 mm
MAX_ANGLE_DEG = 360.0
MAX_FORCE_N = 100.0    # a fingertip presses with 0.1 to 5 N
MAX_UM = 100.0         # plates vibrate at a few um
MAX_PX = 8192          # display pixels per side (an 8K screen has 7680)
MAX_MODE_ORDER = 100
MAX_LAYERS = 32
#: Longest path a texture file may name (characters).
MAX_PATH_CHARS = 1000

MU = Num("relative friction mu'", gt=0.0, le=1.0)
MU_HIGH = Num("relative friction mu'", default=1.0, gt=0.0, le=1.0)
POS = Num("mm", ge=-MAX_MM, le=MAX_MM)
SIZE = Num("mm", ge=MIN_SIZE_MM, le=MAX_MM)
PERIOD = Num("mm", ge=MIN_PERIOD_MM, le=MAX_MM)
ANGLE = Num("deg", default=0.0, ge=-MAX_ANGLE_DEG, le=MAX_ANGLE_DEG)
EDGE_MM = Num("mm", default=0.0, ge=0.0, le=MAX_MM)
UM = Num("um zero-to-peak", gt=0.0, le=MAX_UM)
FORCE = Num("N", gt=0.0, le=MAX_FORCE_N)
DUTY = Num("fraction of the period", default=0.5, gt=0.0, lt=1.0)

TOP = {"format": Int("format version"), "name": Text(None),
       "description": Text("", max_len=10_000, lines=True),
       "control": Choice(model.CONTROL_MODES, "open")}
DISPLAY = {"width_mm": SIZE, "height_mm": SIZE,
           "width_px": Int("px", ge=1, le=MAX_PX), "height_px": Int("px", ge=1, le=MAX_PX)}
DEVICE = {"profile": Choice(profiles.DEVICE_PROFILES, _DEVICE.profile),
          "amplitude_limit_um": replace(UM, default=_DEVICE.amplitude_limit_um),
          "normal_force_n": replace(FORCE, default=_DEVICE.normal_force_n)}
FRICTION = {"b_per_um": Num("1/um", _FRICTION.b_per_um, gt=0.0),
            # k = 0: friction independent of the normal force, A = 0 (eqs 2-3 hold)
            "asymptote_per_n": Num("1/N", _FRICTION.asymptote_per_n, ge=0.0),
            # was a cap on seed 003's asymptote (relative friction, default 0.95)
            "asymptote_cap": Retired("the friction model holds up to an asymptote of 1 "
                                     "(seed 003, eq 2) and frictex warns where a force takes "
                                     "it there; delete the key")}
FITTED = {"device": Text(), "finger": Int("person number", None, ge=0),
          "speed_mm_s": Num("mm/s", None, gt=0.0, le=10_000.0)}
CALIBRATION = {"amplitudes_um": NumList(Num("um zero-to-peak", ge=0.0, le=MAX_UM), min_len=2),
               "forces_n": NumList(Num("N", ge=0.0, le=MAX_FORCE_N)),
               "mu": Rows(MU)}
_BEAM = profiles.BeamStructure()
_PLATE = profiles.PlateStructure()
MATERIAL = {"youngs_gpa": Num("GPa", _BEAM.youngs_gpa, gt=0.0),
            "density_kg_m3": Num("kg/m^3", _BEAM.density_kg_m3, gt=0.0),
            "poisson": Num("Poisson's ratio", _BEAM.poisson, gt=-1.0, lt=0.5)}
SOLVER = {"method": Choice(METHODS, _BEAM.method),
          "rcond": Num("relative to the largest singular value", _BEAM.rcond, gt=0.0, lt=1.0)}
#: the keys of ``[device.structure]`` by the structure a modal profile has
STRUCTURE_KEYS: dict[type, dict[str, Spec]] = {
    profiles.BeamStructure: {"length_mm": replace(SIZE, default=_BEAM.length_mm),
                             "width_mm": replace(SIZE, default=_BEAM.width_mm),
                             "thickness_mm": replace(SIZE, default=_BEAM.thickness_mm), **MATERIAL,
                             "theory": Choice(THEORIES, _BEAM.theory),
                             "orders": NumList(Num("mode order", ge=1.0, le=MAX_MODE_ORDER),
                                               default=_BEAM.orders),
                             "actuators_mm": NumList(POS, default=_BEAM.actuators_mm),
                             "x0_mm": replace(POS, default=_BEAM.x0_mm),
                             "channel_limit_um": replace(UM, default=_BEAM.channel_limit_um),
                             **SOLVER, "modes_file": Text(None, max_len=MAX_PATH_CHARS)},
    profiles.PlateStructure: {"width_mm": replace(SIZE, default=_PLATE.width_mm),
                              "height_mm": replace(SIZE, default=_PLATE.height_mm),
                              "thickness_mm": replace(SIZE, default=_PLATE.thickness_mm),
                              **MATERIAL,
                              "order": Int("mode order k", _PLATE.order, ge=1, le=MAX_MODE_ORDER),
                              "x0_mm": replace(POS, default=_PLATE.x0_mm),
                              "y0_mm": replace(POS, default=_PLATE.y0_mm),
                              "channel_limit_um": replace(UM, default=None), **SOLVER},
}
#: the keys of ``[device.structure]`` by modal profile, read from the profiles each time
#: (a profile registered late is in it)
STRUCTURES = profiles.ProfileTable(lambda spec: STRUCTURE_KEYS.get(spec.structure))
COMMON = {"type": Choice(LAYER_TYPES), "name": Text(None),
          "render": Choice(RENDER_CHOICES, "auto"), "blend": Choice(model.BLEND_MODES, "multiply"),
          "fingers": Selector("any")}
LAYER_TABLES = ("region", "visual")
RECT_REGION = {"x_mm": POS, "y_mm": POS, "width_mm": SIZE, "height_mm": SIZE, "angle_deg": ANGLE}
DISC_REGION = {"cx_mm": POS, "cy_mm": POS, "radius_mm": SIZE}
VISUAL = {"color_low": Colour(_VISUAL.color_low), "color_high": Colour(_VISUAL.color_high),
          "outline": Flag(_VISUAL.outline)}
PERIODIC = {"period_mm": PERIOD, "angle_deg": ANGLE, "offset_mm": replace(POS, default=0.0)}
LAYER_KEYS: dict[str, dict[str, Spec]] = {
    "grating": {**PERIODIC, "duty": DUTY, "mu_low": MU, "mu_high": MU_HIGH,
                "edge": Choice(("square", "smooth"), "square"), "edge_mm": EDGE_MM},
    "waveform": {**PERIODIC, "shape": Choice(model.WAVE_SHAPES, "sine"),
                 "mu_min": Num(MU.unit, None, gt=0.0, le=1.0), "mu_max": MU_HIGH, "duty": DUTY,
                 "samples": NumList(MU, min_len=2, default=())},
    "rectangle": {**RECT_REGION, "mu": MU, "edge_mm": EDGE_MM},
    "disc": {**DISC_REGION, "mu": MU, "edge_mm": EDGE_MM},
    "edge": {"x_mm": POS, "y_mm": POS, "angle_deg": ANGLE, "mu": MU, "edge_mm": EDGE_MM},
    "bump": {"cx_mm": POS, "cy_mm": POS, "sigma_mm": SIZE, "mu": MU},
    "line": {"x0_mm": POS, "y0_mm": POS, "x1_mm": POS, "y1_mm": POS, "width_mm": SIZE,
             "mu": MU, "edge_mm": EDGE_MM},
    "raster": {"image": Text(max_len=MAX_PATH_CHARS), "mode": Choice(model.RASTER_MODES, "stretch"),
               "x_mm": replace(POS, default=0.0), "y_mm": replace(POS, default=0.0),
               "rotation_deg": ANGLE, "width_mm": replace(SIZE, default=None),
               "height_mm": replace(SIZE, default=None),
               "tile_width_mm": replace(SIZE, default=None),
               "tile_height_mm": replace(SIZE, default=None),
               "mu_black": MU, "mu_white": MU_HIGH},
    "directional": {"angle_deg": ANGLE, "mu_forward": Num(MU.unit, None, gt=0.0, le=1.0),
                    "mu_backward": Num(MU.unit, None, gt=0.0, le=1.0),
                    "force_forward_n": Num("N, positive resisting the finger", None,
                                           ge=-MAX_FORCE_N, le=MAX_FORCE_N),
                    "force_backward_n": Num("N, positive resisting the finger", None,
                                            ge=-MAX_FORCE_N, le=MAX_FORCE_N)},
    "guidance": {"x_mm": POS, "y_mm": POS, "line": Flag(False), "line_angle_deg": replace(ANGLE, default=90.0),
                 "gain_n_per_mm": Num("N/mm", gt=0.0), "max_force_n": FORCE},
    "keyclick": {"x_mm": POS, "y_mm": POS, "width_mm": SIZE, "height_mm": SIZE,
                 "press_n": replace(FORCE, default=0.5), "click_n": replace(FORCE, default=0.8),
                 "release_n": Num("N", 0.4, ge=0.0, le=MAX_FORCE_N),
                 "dwell_s": Num("s", 0.01, ge=0.0), "force_n": replace(FORCE, default=0.1),
                 "first_push": Choice(("+x", "-x"), "+x")},
}
_OPTIONAL_POS = replace(POS, default=None)
_OPTIONAL_SIZE = replace(SIZE, default=None)
#: the keys each height shape takes (besides rise_mm and the rendering keys)
HEIGHT_SHAPES = {"bump": ("cx_mm", "cy_mm", "sigma_mm"),
                 "ridge": ("x_mm", "y_mm", "angle_deg", "width_mm"),
                 "step": ("x_mm", "y_mm", "angle_deg", "chamfer_mm"),
                 "button": ("cx_mm", "cy_mm", "radius_mm", "rim_mm"),
                 "map": ("image", "x_mm", "y_mm", "width_mm", "height_mm")}
#: the keys each clip shape takes (besides depth)
CLIP_SHAPES = {"tick": ("intensity", "sharpness"),
               "ramp": ("duration_s", "level_from", "level_to", "sharpness"),
               "envelope": ("times_s", "levels", "intensity", "sharpness"),
               "ahap": ("file",)}
LEVEL = Num("level, 0 to 1", ge=0.0, le=1.0)
LAYER_KEYS["height"] = {
    "shape": Choice(tuple(HEIGHT_SHAPES)), "rise_mm": Num("mm", ge=-100.0, le=100.0),
    **{k: _OPTIONAL_POS for k in ("cx_mm", "cy_mm", "x_mm", "y_mm")},
    **{k: _OPTIONAL_SIZE for k in ("sigma_mm", "width_mm", "height_mm", "chamfer_mm",
                                   "radius_mm", "rim_mm")},
    "angle_deg": ANGLE, "image": Text(None, max_len=MAX_PATH_CHARS),
    "rendering": Choice(HEIGHT_RENDERINGS, "slope"),
    "gain": Num("mu' per unit slope", 2.0, gt=0.0), "mu_rest": replace(MU, default=0.8),
    "mu_min": replace(MU, default=0.6), "mu_max": MU_HIGH,
    "v_fade_mm_s": Num("mm/s", 10.0, gt=0.0)}
LAYER_KEYS["recorded"] = {
    "model": Text(max_len=MAX_PATH_CHARS), "mu_mean": replace(MU, default=0.8),
    "gain": Num("mu' per m/s^2", 0.02, gt=0.0), "mu_min": replace(MU, default=0.6),
    "mu_max": MU_HIGH, "v_rest_mm_s": Num("mm/s", 2.0, ge=0.0),
    "seed": Int("noise seed", 0, ge=0, le=2**31 - 1)}
LAYER_KEYS["clip"] = {
    "trigger": Choice(CLIP_TRIGGERS), "x_mm": _OPTIONAL_POS, "y_mm": _OPTIONAL_POS,
    "angle_deg": ANGLE, "force_n": replace(FORCE, default=None),
    "depth": Num("drop in mu' at full level", 0.4, gt=0.0, lt=1.0),
    "clip": Choice(tuple(CLIP_SHAPES)), "intensity": replace(LEVEL, default=1.0),
    "sharpness": replace(LEVEL, default=None),
    "duration_s": Num("s", None, gt=0.0, le=MAX_CLIP_S),
    "level_from": replace(LEVEL, default=0.0), "level_to": replace(LEVEL, default=1.0),
    "times_s": NumList(Num("s", ge=0.0, le=MAX_CLIP_S), min_len=2, default=None),
    "levels": NumList(LEVEL, min_len=2, default=None), "file": Text(None, max_len=MAX_PATH_CHARS)}

_DRIVING = profiles.DrivingForceParams()
DRIVING = {"mu0": Num("friction coefficient", _DRIVING.mu0, gt=0.0),
           "slope_per_um": Num("N per um per N", _DRIVING.slope_per_um, gt=0.0),
           "threshold_um": Num("um zero-to-peak", _DRIVING.threshold_um, ge=0.0, le=MAX_UM),
           "v_hold_mm_s": Num("mm/s", _DRIVING.v_hold_mm_s, gt=0.0)}


# ---- what each key means (printed on the format page, textures/FORMAT.md) ------------------
# A value is the key's meaning, or (meaning, rule) for a key whose default depends on
# other keys: the rule says how it is derived or when it is required.

def documented(table: dict, docs: dict) -> None:
    """Attach ``docs`` (key -> meaning or (meaning, rule)) to the specs of ``table``, in place."""
    for key, text in docs.items():
        doc, rule = text if isinstance(text, tuple) else (text, "")
        table[key] = replace(table[key], doc=doc, rule=rule)


_MU_TXT = "relative friction mu' = mu(w)/mu(0): 1 is the plate at rest, lower is more slippery"
_EDGE_MM = ("width (mm) of a raised-cosine ramp centred on the outline, from mu inside to 1 "
            "outside; 0 is a sharp step")
_PERIOD = "length (mm) of one period, measured across the lines (along the axis at angle_deg)"
_ANGLE = ("direction of the axis *across* the lines (their normal), in degrees from +x "
          "towards +y; y points down, so positive angles turn clockwise on the screen. "
          "0: vertical lines, mu' varies with x; 90: horizontal lines, mu' varies with y "
          "(see Angles)")
_OFFSET = ("where phase 0 lies: this many mm along the axis from the display's origin "
           "(top-left); shifts the pattern across its lines")
_MU_MAX = "highest mu' of the pattern"
_DUTY = "share of each period, from phase 0, at the low level (mu_low / mu_min)"

documented(TOP, {
    "format": "version of this grammar; write 1",
    "name": ("the scene's name in titles, reports and `frictex library`",
             "the file name without `.toml`"),
    "description": "one line shown by `frictex library`",
    "control": ("friction control: `open` (the model's inversion), `closed` (a loop on the "
                "lateral force the device reports) or `adaptive` (that loop, corrected by "
                "seed 003's model fitted to the same reports); `closed` and `adaptive` need "
                "plate-seed003 with seed 003's model"),
})
documented(DISPLAY, {
    "width_mm": "width of the touchscreen's active area (mm): x runs 0 to width_mm, left to right",
    "height_mm": "height of the active area (mm): y runs 0 to height_mm, top to bottom",
    "width_px": "the screen's pixels across (see Display pixels and millimetres)",
    "height_px": "the screen's pixels down (see Display pixels and millimetres)",
})
documented(DEVICE, {
    "profile": "the vibrating structure and its actuation (device/profile.py): `plate-seed003` "
               "is one plate, one channel; the others are modal or travelling-wave devices",
    "amplitude_limit_um": "largest vibration amplitude asked under a finger (um, zero-to-peak); "
                          "with the normal force it sets the lowest reachable mu' (the floor); "
                          "`validate` warns where it is above what one channel's drive of a "
                          "one-channel or travelling-wave profile reaches (um_per_volt at "
                          "voltage_limit_v, device/profile.py; see What the drive reaches)",
    "normal_force_n": "the finger's nominal normal force (N): used for traces without a force "
                      "column and for the floor `validate` and `preview` check against",
})
documented(FRICTION, {
    "b_per_um": "b of seed 003 eq 2, mu'(w) = (1 - A) exp(-b w) + A (1/um); `validate` warns "
                f"outside the {B_BOUNDS[0]:g} to {B_BOUNDS[1]:g} /um `frictex calibrate`'s fit "
                "allows",
    "asymptote_per_n": "k of seed 003 eq 2, the asymptote A = k F_n (1/N): the lowest mu' "
                       "any amplitude gives at normal force F_n; 0 is friction that does not "
                       "depend on the force (mu' = exp(-b w)); `validate` warns above the "
                       f"{K_BOUNDS[1]:g} /N the fit allows",
})
documented(FITTED, {
    "device": "the device `frictex calibrate` fitted [device.friction] on: its name from the "
              "link's handshake; a replay to a device of another name warns",
    "finger": ("with the simulated device: the simulated finger (person number) it was "
               "fitted on; a replay with another --sim-finger warns",
               "none: fitted on a real finger"),
    "speed_mm_s": ("the finger's sliding speed (mm/s) during the sweep; the b of "
                   "[device.friction] holds at it", "none: not recorded"),
})
documented(CALIBRATION, {
    "amplitudes_um": "measured amplitudes (um, zero-to-peak), from 0, strictly increasing",
    "forces_n": "normal forces (N) of the rows of `mu`, strictly increasing",
    "mu": "one row per force, one mu' per amplitude; each row starts at 1 and strictly "
          "decreases. Each row is inverted by monotone cubic (PCHIP) interpolation, not "
          "linearly (mu' 0.7 on the row 1, 0.8, 0.65, 0.55 at 0, 1, 2, 3 um: 1.624 um, not "
          "1.667); between two forces the amplitudes for one mu' are interpolated linearly "
          "in force, and outside them the nearest row is used. Replaces the model of "
          "[device.friction] (`validate` warns at its keys "
          "given beside the table, which change nothing unless a force layer uses them)",
})
_STRUCTURE_COMMON = {
    "thickness_mm": "thickness of the structure (mm)",
    "youngs_gpa": "Young's modulus of its material (GPa)",
    "density_kg_m3": "density of its material (kg/m^3)",
    "poisson": "Poisson's ratio of its material",
    "x0_mm": "display x (mm) of the structure's left end (beam) or corner (plate); the "
             "display must lie on the structure",
    "method": "how channel commands are solved from the fingers' targets (device.actuation."
              "modal): `exact` inverse, `regularised` (continuous across singular places) or "
              "`bounded` (within channel_limit_um)",
    "rcond": "regularisation threshold, relative to the largest singular value",
}
documented(STRUCTURE_KEYS[profiles.BeamStructure], {
    **_STRUCTURE_COMMON,
    "length_mm": "length of the beam (mm), along display x",
    "width_mm": "width of the beam (mm)",
    "theory": "beam theory of the mode shapes and frequencies",
    "orders": "the flexural mode orders driven (distinct, 1 to 100, at most 26)",
    "actuators_mm": "positions of the transducers along the beam (mm from its end), one per mode",
    "channel_limit_um": ("largest command per transducer (um, zero-to-peak); `validate` "
                         "warns above what one channel's drive reaches (see What the drive "
                         "reaches)"),
    "modes_file": ("a measured mode table (CSV, one column per mode, deflections in any "
                   "one unit: the table is scaled to 1 at its largest; path relative to this "
                   "file) replacing `orders`",
                   "none: mode shapes computed from `theory` and `orders`"),
})
documented(STRUCTURE_KEYS[profiles.PlateStructure], {
    **_STRUCTURE_COMMON,
    "width_mm": "width of the plate (mm), along display x",
    "height_mm": "height of the plate (mm), along display y",
    "order": "k of seed 001 eq 6: the X and Y modes driven",
    "y0_mm": "display y (mm) of the plate's corner",
    "channel_limit_um": ("largest command per channel (um, zero-to-peak); `validate` warns "
                         "above what one channel's drive reaches (see What the drive reaches)",
                         "amplitude_limit_um of [device]"),
})
documented(DRIVING, {
    "mu0": "friction coefficient at rest: the friction force is mu0 F_n mu'",
    "slope_per_um": "N of driving force per um of travelling-wave amplitude per N of normal "
                    "force (seed 004)",
    "threshold_um": "amplitude (um) below which the travelling wave drives no force",
    "v_hold_mm_s": "speed (mm/s) below which a finger counts as held still",
})
documented(COMMON, {
    "type": "what the layer is; each type's own keys are in its table below",
    "name": ("the layer's name in messages, titles and the demo's panel; unique in the file",
             "the type and the layer's number, e.g. `grating-2`"),
    "render": "how the haptics render it (rendering/RENDERERS.md): `auto` is the hybrid for a "
              "grating or waveform and `sho` (the map at the finger's position) for every "
              "other layer; `hybrid`, `sht` and `sho-*` need a grating or waveform",
    "blend": "how it composes with the layers above it in the file: `multiply` (mu' values "
             "multiply) or `replace` (where it covers, its mu' replaces theirs)",
    "fingers": "which touching fingers feel it, decided at every output sample",
})
documented(RECT_REGION, {
    "x_mm": "x (mm) of the rectangle's top-left corner before rotation",
    "y_mm": "y (mm) of the rectangle's top-left corner before rotation",
    "width_mm": "width (mm), along x before rotation",
    "height_mm": "height (mm), along y before rotation",
    "angle_deg": "rotation (degrees) about the rectangle's centre, from +x towards +y "
                 "(clockwise on the screen)",
})
documented(DISC_REGION, {"cx_mm": "x (mm) of the centre", "cy_mm": "y (mm) of the centre",
                         "radius_mm": "radius (mm)"})
documented(VISUAL, {
    "color_low": "colour drawn where the layer's mu' is lowest",
    "color_high": "colour drawn where the layer's mu' is highest",
    "outline": "draw the layer's outline",
})
documented(LAYER_KEYS["grating"], {
    "period_mm": _PERIOD, "angle_deg": _ANGLE, "offset_mm": _OFFSET, "duty": _DUTY,
    "mu_low": "mu' of the lines (the first `duty` of each period)",
    "mu_high": "mu' between the lines",
    "edge": "`square`: mu' steps at the line boundaries; `smooth`: raised-cosine ramps",
    "edge_mm": "width (mm) of each smooth ramp, centred on the boundary; only with "
               "edge = \"smooth\", > 0 and at most the narrower band",
})
documented(LAYER_KEYS["waveform"], {
    "period_mm": _PERIOD, "angle_deg": _ANGLE, "offset_mm": _OFFSET,
    "shape": "one period's profile from phase 0: `sine` (mu_min at 0, mu_max at half a "
             "period), `square` (mu_min for the first duty), `triangle` (mu_max at 0 down to "
             "mu_min at half a period and back), `sawtooth` (mu_max falling linearly to "
             "mu_min), `samples` (your own values)",
    "mu_min": ("lowest mu' of the shape",
               "required with a standard shape; not allowed with shape = \"samples\""),
    "mu_max": _MU_MAX + "; not with shape = \"samples\"",
    "duty": "share of the period at mu_min; only with shape = \"square\"",
    "samples": "mu' values over one period, evenly spaced from phase 0, linearly "
               "interpolated and wrapped; only (and required) with shape = \"samples\"",
})
documented(LAYER_KEYS["rectangle"], {
    **{k: RECT_REGION[k].doc for k in RECT_REGION}, "mu": "mu' inside the rectangle",
    "edge_mm": _EDGE_MM + "; at most the shorter side"})
documented(LAYER_KEYS["disc"], {
    **{k: DISC_REGION[k].doc for k in DISC_REGION}, "mu": "mu' inside the disc",
    "edge_mm": _EDGE_MM + "; at most the diameter"})
documented(LAYER_KEYS["edge"], {
    "x_mm": "x (mm) of a point on the edge (on the display)",
    "y_mm": "y (mm) of a point on the edge",
    "angle_deg": "direction of the edge's normal, from +x towards +y: the side it points to "
                 "has mu', the other side 1. 0: a vertical edge, mu' to its right; 90: a "
                 "horizontal edge, mu' below it",
    "mu": "mu' on the side the normal points to",
    "edge_mm": "width (mm) of the raised-cosine ramp across the edge; 0 is a step"})
documented(LAYER_KEYS["bump"], {
    "cx_mm": "x (mm) of the centre (the disc r <= 4 sigma must reach the display)", "cy_mm": "y (mm) of the centre",
    "sigma_mm": "standard deviation (mm) of the gaussian: mu' = 1 - (1 - mu) "
                "exp(-r^2 / (2 sigma^2)); the layer covers r <= 4 sigma",
    "mu": "mu' at the centre"})
documented(LAYER_KEYS["line"], {
    "x0_mm": "x (mm) of one end", "y0_mm": "y (mm) of one end",
    "x1_mm": "x (mm) of the other end", "y1_mm": "y (mm) of the other end",
    "width_mm": "width (mm) across the segment (round ends)", "mu": "mu' on the line",
    "edge_mm": _EDGE_MM + "; at most width_mm"})
documented(LAYER_KEYS["raster"], {
    "image": "PNG (8- or 16-bit grey, or colour read as grey), path relative to this file: "
             "grey g in [0, 1] gives mu' = mu_black + g (mu_white - mu_black); row 0 at the top; "
             "sampled bilinearly between pixel centres (held at the edge pixels, of each tile "
             "with `tile`), so a one-pixel stripe becomes a ramp, a triangle two pixels wide",
    "mode": "`stretch`: the image fills width_mm x height_mm once; `tile`: tiles of "
            "tile_width_mm x tile_height_mm repeat over it; `one-to-one`: one image pixel "
            "per display pixel",
    "x_mm": "x (mm) of the image's top-left corner before rotation",
    "y_mm": "y (mm) of the image's top-left corner before rotation",
    "rotation_deg": "rotation (degrees) about the image's centre, from +x towards +y",
    "width_mm": ("width (mm) of the area the image covers",
                 "required with `stretch` and `tile`; with `one-to-one` not allowed: image "
                 "columns / (width_px / width_mm of [display])"),
    "height_mm": ("height (mm) of the area the image covers",
                  "required with `stretch` and `tile`; with `one-to-one` not allowed: image "
                  "rows / (height_px / height_mm of [display])"),
    "tile_width_mm": ("width (mm) of one tile (`tile` only)",
                      "image columns / (width_px / width_mm): one image pixel per display pixel"),
    "tile_height_mm": ("height (mm) of one tile (`tile` only)",
                       "image rows / (height_px / height_mm)"),
    "mu_black": "mu' where the image is black",
    "mu_white": "mu' where the image is white"})
_PAIR = ("give mu_forward and mu_backward, or force_forward_n and force_backward_n: one pair, "
         "both of its keys")
documented(LAYER_KEYS["directional"], {
    "angle_deg": "the forward direction: 0 (+x) or 180 (-x); the waves run along display x",
    "mu_forward": ("mu' (net tangential force over mu0 F_n) moving forward", _PAIR),
    "mu_backward": ("mu' moving backward", _PAIR),
    "force_forward_n": ("net tangential force (N) moving forward, positive resisting the "
                        "finger; zero or negative (dragging it along) only at light presses "
                        "(F_n up to 0.46 N at 3 um of envelope, 0.36 N mid-span on seed 002's "
                        "beam), else clamped to the lowest reachable force and counted as "
                        "clamps.unreachable", _PAIR),
    "force_backward_n": ("net tangential force (N) moving backward", _PAIR)})
documented(LAYER_KEYS["guidance"], {
    "x_mm": "x (mm) of the target point (on the display)", "y_mm": "y (mm) of the target point",
    "line": "pull towards the line through the point instead of the point itself",
    "line_angle_deg": "direction of that line (not its normal), from +x towards +y; 90 is "
                      "vertical; only with line = true",
    "gain_n_per_mm": "pull (N) per mm of distance to the target",
    "max_force_n": "largest pull (N)"})
documented(LAYER_KEYS["keyclick"], {
    "x_mm": "x (mm) of the button's top-left corner", "y_mm": "y (mm) of its top-left corner",
    "width_mm": "the button's width (mm)", "height_mm": "the button's height (mm)",
    "press_n": "normal force (N) at which the first push starts",
    "click_n": "normal force (N) at which the push reverses (the click)",
    "release_n": "normal force (N) below which the button resets; release_n < press_n < click_n",
    "dwell_s": ("how long (s) each condition must hold before it changes the state; a touch "
                "sample holds until the next, so over one sample period (10 ms at 100 Hz) "
                "for a lone sample not to count"),
    "force_n": "the push's tangential force (N)",
    "first_push": "direction of the first push, along display x"})
_BY_SHAPE = "required with shape = {}; not allowed with other shapes"
documented(LAYER_KEYS["height"], {
    "shape": "the height field: `bump` (gaussian), `ridge` (raised cosine across a line), "
             "`step` (a chamfered step), `button` (a plateau with a rounded rim), `map` (a "
             "16-bit PNG)",
    "rise_mm": "height of the shape (mm); negative for a dip or a step down; 0 is flat, "
               "felt nowhere (validate warns, as for a map of one grey)",
    "cx_mm": ("x (mm) of the centre", _BY_SHAPE.format("`bump` or `button`")),
    "cy_mm": ("y (mm) of the centre", _BY_SHAPE.format("`bump` or `button`")),
    "x_mm": ("x (mm) of a point on the crest (ridge) or edge (step), or of the map's "
             "top-left corner", _BY_SHAPE.format("`ridge` or `step`") + "; with `map` "
                                                                         "optional, default 0"),
    "y_mm": ("y (mm) of that point or corner", _BY_SHAPE.format("`ridge` or `step`")
             + "; with `map` optional, default 0"),
    "sigma_mm": ("standard deviation (mm) of the bump, h = rise exp(-r^2 / (2 sigma^2))",
                 _BY_SHAPE.format("`bump`")),
    "width_mm": ("width (mm) across a ridge, or of a map", _BY_SHAPE.format("`ridge` or `map`")),
    "height_mm": ("height (mm) of a map", _BY_SHAPE.format("`map`")),
    "chamfer_mm": ("width (mm) of the step's flat chamfer", _BY_SHAPE.format("`step`")),
    "radius_mm": ("radius (mm) of the button", _BY_SHAPE.format("`button`")),
    "rim_mm": ("width (mm) of the button's rounded rim, below radius_mm",
               _BY_SHAPE.format("`button`")),
    "angle_deg": "ridge: the direction the crest runs; step: its normal, pointing up the step "
                 "(from +x towards +y)",
    "image": ("16-bit greyscale PNG of heights, path relative to this file: level v gives "
              "h = v / 65535 rise_mm", _BY_SHAPE.format("`map`")),
    "rendering": "`slope`: the height's slope along the finger's motion, signed (climbing "
                 "raises mu', descending lowers it); `magnitude`: the slope's size, "
                 "whichever way (raises mu' only)",
    "gain": "d mu' / d slope at flat ground",
    "mu_rest": "mu' on flat ground and at rest, over the layer's whole region (the display "
               "if none): mu_min < mu_rest < mu_max (mu_min = mu_rest allowed with magnitude)",
    "mu_min": "lowest mu' (descending steeply)",
    "mu_max": "highest mu' (climbing steeply)",
    "v_fade_mm_s": "below this speed (mm/s) the slope fades in proportion to speed"})
documented(LAYER_KEYS["recorded"], {
    "model": "a HaTT texture model (XML), path relative to this file",
    "mu_mean": "mu' about which the recorded texture varies",
    "gain": "mu' per m/s^2 of the model's synthesised acceleration; validate warns where "
            "gain times the output standard deviation of the model's loudest vertex (its "
            "filtered noise, not sqrt(var)) passes the room about mu_mean",
    "mu_min": "lowest mu' (mu_min < mu_mean < mu_max)", "mu_max": "highest mu'",
    "v_rest_mm_s": "below this speed (mm/s) the texture is silent (mu_mean)",
    "seed": "seed of the model's noise: the same seed, the same texture"})
_CLIP = "required with clip = {}; not allowed with other clips"
documented(LAYER_KEYS["clip"], {
    "trigger": "what starts the clip: `down` (a touch begins), `lift` (a touch ends: felt "
               "only by other fingers still touching, since friction is felt only by a finger "
               "on the plate; with one finger, never; validate warns), `edge` (a finger "
               "crosses a line), `force` (a finger's normal force rises through force_n, "
               f"having fallen below {FORCE_REARM:g} x force_n since it last did, so that a force's "
               "noise about force_n triggers once); "
               "always inside the layer's region",
    "x_mm": ("x (mm) of a point on the trigger line", "required with trigger = \"edge\"; "
                                                      "not allowed with other triggers"),
    "y_mm": ("y (mm) of a point on the trigger line", "required with trigger = \"edge\"; "
                                                      "not allowed with other triggers"),
    "angle_deg": "the trigger line's normal, from +x towards +y (0: a vertical line); only "
                 "with trigger = \"edge\"; crossing either way triggers (only reaching the line does not)",
    "force_n": ("the normal force (N) whose rising crossing triggers",
                "required with trigger = \"force\"; not allowed with other triggers"),
    "depth": "drop in mu' at level 1: mu' = 1 - depth x level",
    "clip": "the clip: `tick` (a transient), `ramp` (level_from to level_to over "
            "duration_s), `envelope` (levels at times_s), `ahap` (an Apple AHAP file)",
    "intensity": "peak level of a tick or scale of an envelope (`tick`, `envelope`); a clip "
                 "that never lowers mu' at 10 kHz (intensity or levels 0, or over within one "
                 "sample) is felt nowhere: validate warns",
    "sharpness": ("a tick's pulse length (30 ms at 0 down to 5 ms at 1), or a ramp's or "
                  "envelope's carrier frequency (250 Hz x sharpness; 0: a smooth drop)",
                  "0.5 for `tick`, 0 for `ramp` and `envelope`"),
    "duration_s": ("length (s) of the ramp", _CLIP.format("`ramp`")),
    "level_from": "level at the ramp's start (`ramp`)",
    "level_to": "level at the ramp's end (`ramp`)",
    "times_s": ("times (s) of the envelope's points, from 0, strictly increasing",
                _CLIP.format("`envelope`")),
    "levels": ("level at each of times_s", _CLIP.format("`envelope`")),
    "file": ("an AHAP file, path relative to this file", _CLIP.format("`ahap`"))})

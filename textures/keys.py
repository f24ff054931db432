"""The key tables of texture files (format 1): every table, its keys, their types, ranges
and defaults. ``textures.loader`` checks files against them (``textures.schema``) and
``textures.format_doc`` prints them as ``textures/FORMAT.md``; the grammar's overview is
at the top of ``textures.loader``.
"""

from __future__ import annotations

from dataclasses import replace

from frictex.device import profile as profiles
from frictex.device.profile import METHODS, THEORIES
from frictex.textures import model
from frictex.textures.clips import CLIP_TRIGGERS, MAX_CLIP_S
from frictex.textures.heights import HEIGHT_RENDERINGS
from frictex.textures.schema import (Choice, Colour, Flag, Int, Num, NumList, Retired, Rows,
                                     Selector, Spec, Text)

FORMAT_VERSION = 1

LAYER_TYPES = ("grating", "waveform", "rectangle", "disc", "edge", "bump", "line", "raster",
               "directional", "guidance", "keyclick", "height", "recorded", "clip")
FORCE_TYPES = ("directional", "guidance", "keyclick")
PERIODIC_TYPES = ("grating", "waveform")
RENDER_CHOICES = ("auto",) + model.RENDER_MODES

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
DEVICE = {"profile": Choice(tuple(profiles.DEVICE_PROFILES), _DEVICE.profile),
          "amplitude_limit_um": replace(UM, default=_DEVICE.amplitude_limit_um),
          "normal_force_n": replace(FORCE, default=_DEVICE.normal_force_n)}
FRICTION = {"b_per_um": Num("1/um", _FRICTION.b_per_um, gt=0.0),
            "asymptote_per_n": Num("1/N", _FRICTION.asymptote_per_n, gt=0.0),
            # was a cap on seed 003's asymptote (relative friction, default 0.95)
            "asymptote_cap": Retired("the friction model holds up to an asymptote of 1 "
                                     "(seed 003, eq 2) and frictex warns where a force takes "
                                     "it there; delete the key")}
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
#: the keys of ``[device.structure]`` by modal profile
STRUCTURES = {name: STRUCTURE_KEYS[profiles.PROFILES.get(name).structure]
              for name in profiles.MODAL_PROFILES}
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

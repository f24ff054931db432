"""Texture files: TOML, one scene per file, checked once into ``textures.model.Scene``.

Grammar (format 1). Units are in the key names; every key not marked *required* has the
default shown. Layers are drawn and composed in file order (later on top).
::

    format = 1                        # required; the version of this grammar
    name = "..."                      # default: the file name without .toml
    description = "..."               # one line for `frictex library`; default ""
    control = "open"                  # | "closed" | "adaptive": friction control (closed
                                      #   loop on the lateral force; plate-seed003 with
                                      #   seed 003's model only)

    [display]                         # required: the touchscreen's active area
    width_mm, height_mm               # required, 0.001 to 10000
    width_px, height_px               # required integers 1 to 8192 (visual layer, one-to-one maps)

    [device]                          # optional table
    profile = "plate-seed003"         # one of device.profile.DEVICE_PROFILES: plate-seed003
                                      #   (one channel), beam-seed000, plate-seed001 (modal)
    amplitude_limit_um = 2.5          # > 0, <= 100, zero-to-peak; the host never asks for more
                                      #   under a finger
    normal_force_n = 0.5              # > 0, <= 100; nominal force for warnings and force-less traces
    [device.friction]                 # optional: seed 003 eq 2 constants
    b_per_um = 1.67                   # > 0
    asymptote_per_n = 1.13            # > 0 (asymptote A = asymptote_per_n * F_n)
    [device.calibration]              # optional measured table, replaces the model
    amplitudes_um = [0, ...]          # >= 2 values, starting at 0, strictly increasing
    forces_n = [...]                  # >= 1 value, >= 0, strictly increasing
    mu = [[1, ...], ...]              # one row per force, one value per amplitude: each row
                                      # starts at 1 and strictly decreases, values in (0, 1]
    [device.structure]                # modal profiles only; every key optional (defaults
                                      #   from the papers, see textures.model)
      # profile = "beam-seed000" (seed 000, Table I; the beam lies along display x):
    length_mm = 350, width_mm = 6, thickness_mm = 6    # > 0
    youngs_gpa = 57, density_kg_m3 = 2561              # > 0
    poisson = 0.33                    # in (-1, 0.5)
    theory = "euler-bernoulli"        # | "timoshenko"
    orders = [16, 17]                 # distinct flexural mode orders 1 to 100, at most 26 of them
    actuators_mm = [60, 290]          # one per mode, on the beam (from its end x = 0)
    x0_mm = 0                         # display x of the beam's end; the display's x span
                                      #   must lie on the beam
    channel_limit_um = 0.75           # > 0, per transducer, zero-to-peak
    modes_file = "modes.csv"          # optional measured shapes (device.structures.measured_modes,
                                      #   path relative to this file): one column per mode,
                                      #   replacing orders (do not give both)
      # profile = "plate-seed001" (seed 001, section 4; channels V_AC, V_BD):
    width_mm = 140, height_mm = 140, thickness_mm = 4, youngs_gpa = 57,
    density_kg_m3 = 2561, poisson = 0.33
    order = 8                         # k of seed 001 eq 6, integer 1 to 100
    x0_mm = 0, y0_mm = 0              # display position of the plate's corner; the
                                      #   display must lie on the plate
    channel_limit_um                  # > 0; default: amplitude_limit_um
      # both:
    method = "regularised"            # exact | regularised | bounded (device.actuation.modal)
    rcond = 0.1                       # in (0, 1), the regularisation threshold
    [device.driving]                  # travelling-wave profiles only (travelling-beam-seed002,
                                      #   ring-seed004): the driving-force model
    mu0 = 0.5                         # > 0, friction coefficient at rest (F_f = mu0 F_n mu')
    slope_per_um = 0.13               # > 0, N of drive per um per N of normal force (seed 004)
    threshold_um = 1.0                # >= 0, travelling amplitude with no drive (seed 004)
    v_hold_mm_s = 2.0                 # > 0, below this speed a finger is still

    [[layer]]                         # one to 32
    type = "grating"                  # required: grating | waveform | rectangle | disc |
                                      #   edge | bump | line | raster | directional |
                                      #   guidance | keyclick (the last three: force layers)
    name = "..."                      # unique in the file; default "<type>-<n>"
    render = "auto"                   # sho | sht | hybrid | auto. auto: periodic layers use
                                      #   the hybrid (textures.model.auto_render_mode: it beats
                                      #   SHO and SHT on seed 003's gratings, frictex report);
                                      #   objects and rasters use sho. sht and hybrid need a
                                      #   periodic layer.
    blend = "multiply"                # multiply | replace (opaque where the layer covers)
    fingers = "any"                   # which fingers feel the layer: "any" | "1" | "2" | ...
                                      #   (1-based, in order of touch-down among the fingers
                                      #   touching at that sample) | "left-most" |
                                      #   "right-most" | "top-most" | "bottom-most" (evaluated
                                      #   per output sample; y points down)
    region = { x_mm, y_mm, width_mm, height_mm, angle_deg = 0 }   # optional rectangle, or
    region = { cx_mm, cy_mm, radius_mm }                          # a disc; on the display
    [layer.visual]                    # optional colours for the visual layer
    color_low = "#000000"             # "#rrggbb" or "#rgb" (sRGB) where mu' is lowest
    color_high = "#ffffff"            # ... where it is highest (stored as linear RGB)
    outline = false

Layer keys by type (mu' is relative friction in (0, 1]; positions in mm, angles in deg):

- ``grating``: period_mm (0.01 to 10000), duty = 0.5 (in (0, 1): the fraction at mu_low, the black
  line), angle_deg = 0 (axis across the lines, 0 = vertical lines), offset_mm = 0,
  mu_low (required), mu_high = 1 (>= mu_low), edge = "square" | "smooth",
  edge_mm (smooth only: > 0, at most the narrower band).
- ``waveform`` (one period for SHT): period_mm, angle_deg, offset_mm, shape = "sine" |
  "square" | "triangle" | "sawtooth" | "samples"; standard shapes take mu_min (required)
  and mu_max = 1, square also duty = 0.5; "samples" takes samples = [mu', ...] (>= 2
  values over one period, linearly interpolated, wrapped) instead.
- ``rectangle``: x_mm, y_mm (top-left before rotation), width_mm, height_mm, angle_deg = 0,
  mu, edge_mm = 0 (soft edge, at most the shorter side).
- ``disc``: cx_mm, cy_mm, radius_mm, mu, edge_mm = 0 (at most the diameter).
- ``edge``: x_mm, y_mm (a point on the edge, on the display), angle_deg = 0 (the normal,
  pointing to the side at mu), mu, edge_mm = 0.
- ``bump`` (gaussian): cx_mm, cy_mm, sigma_mm, mu (at the centre).
- ``line``: x0_mm, y0_mm, x1_mm, y1_mm (distinct ends), width_mm, mu, edge_mm = 0 (at most width_mm).
- ``raster``: image (required; path relative to the TOML file; see ``textures.raster_io``
  for the image kinds), mode = "stretch" | "tile" | "one-to-one", x_mm = 0, y_mm = 0
  (sprite top-left before rotation), rotation_deg = 0, mu_black (required), mu_white = 1
  (grey g gives mu_black + g (mu_white - mu_black)). stretch and tile need width_mm and
  height_mm; tile also takes tile_width_mm / tile_height_mm (default: the image at the
  display's pixel size); one-to-one takes neither (one image pixel per display pixel).

Shapes, recorded textures and effect clips (textures/AUTHORING.md says what each renders):

- ``height`` (felt by its slope: ``textures.heights``): shape = "bump" | "ridge" | "step" |
  "button" | "map" (required); rise_mm (required, -100 to 100: the height, negative a dip;
  for a map the height at white). bump: cx_mm, cy_mm, sigma_mm. ridge: x_mm, y_mm (on the
  crest), angle_deg = 0 (the way it runs), width_mm. step: x_mm, y_mm, angle_deg = 0 (the
  normal, pointing up), chamfer_mm. button: cx_mm, cy_mm, radius_mm, rim_mm (< radius_mm).
  map: image (16-bit greyscale PNG, path relative to this file), x_mm = 0, y_mm = 0,
  width_mm, height_mm. All: rendering = "slope" | "magnitude", gain = 2 (mu' per unit
  slope, > 0), mu_rest = 0.8, mu_min = 0.6, mu_max = 1 (mu_min < mu_rest < mu_max;
  "magnitude" allows mu_min = mu_rest), v_fade_mm_s = 10 (> 0).
- ``recorded`` (a Penn Haptic Texture Toolkit model: ``textures.hatt``): model (required: the
  toolkit's XML model file, path relative to this file), mu_mean = 0.8, gain = 0.02 (mu'
  per m/s^2 of the model's output, > 0), mu_min = 0.6, mu_max = 1 (mu_min < mu_mean <
  mu_max), v_rest_mm_s = 2 (>= 0), seed = 0 (integer 0 to 2147483647).
- ``clip`` (mu' against time: ``textures.clips``): trigger = "down" | "lift" | "edge" |
  "force" (required; down and lift: inside ``region``, the whole display without one);
  edge: x_mm, y_mm (a point on the line), angle_deg = 0 (its normal); force: force_n.
  depth = 0.4 (the drop in mu' at full level, in (0, 1)); clip = "tick" | "ramp" |
  "envelope" | "ahap" (required). tick: intensity = 1, sharpness = 0.5. ramp:
  duration_s, level_from = 0, level_to = 1, sharpness = 0. envelope: times_s (from 0,
  increasing), levels (0 to 1, one per time), intensity = 1, sharpness = 0. ahap: file
  (AHAP JSON, path relative to this file; ``textures.ahap``). Clips last at most 60 s.

Force layers (``textures.model.FORCE_LAYERS``; only on the travelling-wave profiles, whose
waves run along display x; they take no ``blend``: see ``rendering.layers.force_layers``):

- ``directional``: angle_deg = 0 (the forward direction: 0 = +x, 180 = -x), and either
  mu_forward and mu_backward (mu' in (0, 1] for each direction of travel) or
  force_forward_n and force_backward_n (net tangential force in N, positive resisting
  the finger; zero and negative allowed).
- ``guidance``: x_mm, y_mm (target point, on the display), line = false (true: pull to
  the line through the point at line_angle_deg = 90), gain_n_per_mm (> 0),
  max_force_n (> 0).
- ``keyclick`` (seed 004, Fig. 5): x_mm, y_mm, width_mm, height_mm (the button, on the
  display), press_n = 0.5, click_n = 0.8, release_n = 0.4 (normal-force thresholds,
  release_n < press_n < click_n), dwell_s = 0.01 (>= 0), force_n = 0.1 (push, N),
  first_push = "+x" | "-x" (direction of the push before the click).

Limits, so that every later stage stays finite and bounded (a value beyond them is a typo
or a wrong unit): lengths and positions within +-10000 mm, sizes (widths, radii, sigma)
from 0.001 mm, periods from 0.01 mm; angles -360 to 360 deg; forces at most 100 N;
amplitudes at most 100 um; any other number at most 1e6 in magnitude. Strings hold no
control characters (``description`` may hold line breaks and tabs); names at most 200
characters, paths 1000. A file is UTF-8 (a leading byte order mark is dropped), at most
1 MiB, a regular file (never a FIFO or a device: checked before opening), with arrays and
inline tables nested at most 16 deep.

Objects, points, regions and sprites must lie on the display. Every problem in a file is
reported (not only the first) as ``file:line: field: message``; ``frictex validate`` also
warns, without failing, where a layer asks for a mu' the device cannot reach at its
nominal normal force (``device.friction.mu_floor``), and where a layer is for one
finger on a one-channel device (which serves only the finger touching longest).
"""

from __future__ import annotations

import difflib
import math
import os
import re
import sys
import tomllib
import unicodedata
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Callable

import numpy as np

from frictex.device.structures.beam import THEORIES, ModesError
from frictex.device import profile as profiles
from frictex.device.friction import ASYMPTOTE_MARGIN
from frictex.device.profile import METHODS
from frictex.textures import model
from frictex.textures.ahap import read_ahap
from frictex.textures.clips import CLIP_TRIGGERS, MAX_CLIP_S, Clip, ClipEvent, ClipLayer
from frictex.textures.heights import (HEIGHT_RENDERINGS, ButtonRim, GaussianBump, HeightLayer, HeightMap,
                              Ridge, Step, read_height_png)
from frictex.textures.errors import KeyPath, Locator, Problem, TextureError, bracket_peak, field_name
from frictex.textures.library import UnreadableText, file_problem, read_utf8
from frictex.textures.raster_io import read_grey

FORMAT_VERSION = 1

LAYER_TYPES = ("grating", "waveform", "rectangle", "disc", "edge", "bump", "line", "raster",
               "directional", "guidance", "keyclick", "height", "recorded", "clip")
FORCE_TYPES = ("directional", "guidance", "keyclick")
PERIODIC_TYPES = ("grating", "waveform")
RENDER_CHOICES = ("auto",) + model.RENDER_MODES

REQUIRED = object()  # spec default: the key must be given
_BAD = object()      # parsed value of a key that had a problem (already reported)

_DEVICE = profiles.DeviceProfile()
_FRICTION = profiles.FrictionParams()
_VISUAL = model.VisualHints()


@dataclass(frozen=True)
class Num:
    """A finite real number with optional bounds; ``unit`` is shown in messages."""

    unit: str
    default: Any = REQUIRED
    gt: float | None = None
    ge: float | None = None
    lt: float | None = None
    le: float | None = None


@dataclass(frozen=True)
class Int:
    unit: str
    default: Any = REQUIRED
    ge: int | None = None
    le: int | None = None


@dataclass(frozen=True)
class Choice:
    options: tuple[str, ...]
    default: Any = REQUIRED


@dataclass(frozen=True)
class Text:
    """A string of at most ``max_len`` characters; ``lines``: may hold line breaks and tabs.
    Other control characters (NUL, escape, ...) are refused everywhere."""

    default: Any = REQUIRED
    max_len: int = 200
    lines: bool = False


@dataclass(frozen=True)
class Flag:
    default: Any = REQUIRED


@dataclass(frozen=True)
class Colour:
    default: Any = REQUIRED


@dataclass(frozen=True)
class Selector:
    """A layer's ``fingers`` selector (see ``rendering.tracking.finger_select``)."""

    default: Any = REQUIRED


@dataclass(frozen=True)
class NumList:
    """A list of numbers, each checked like ``item``; at least ``min_len`` of them."""

    item: Num
    min_len: int = 1
    default: Any = REQUIRED


@dataclass(frozen=True)
class Rows:
    """A list of lists of numbers (a table), each checked like ``item``."""

    item: Num
    default: Any = REQUIRED


@dataclass(frozen=True)
class Retired:
    """A key an earlier release documented and this one no longer uses: accepted with any
    value and ignored, with one warning saying ``why`` (format 1 files written for that
    release keep loading)."""

    why: str


Spec = Num | Int | Choice | Text | Flag | Colour | Selector | NumList | Rows | Retired

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
#: Any other number: at most this in magnitude.
MAX_MAGNITUDE = 1e6

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
STRUCTURES: dict[str, dict[str, Spec]] = {
    "beam-seed000": {"length_mm": replace(SIZE, default=_BEAM.length_mm),
                     "width_mm": replace(SIZE, default=_BEAM.width_mm),
                     "thickness_mm": replace(SIZE, default=_BEAM.thickness_mm), **MATERIAL,
                     "theory": Choice(THEORIES, _BEAM.theory),
                     "orders": NumList(Num("mode order", ge=1.0, le=MAX_MODE_ORDER),
                                       default=_BEAM.orders),
                     "actuators_mm": NumList(POS, default=_BEAM.actuators_mm),
                     "x0_mm": replace(POS, default=_BEAM.x0_mm),
                     "channel_limit_um": replace(UM, default=_BEAM.channel_limit_um),
                     **SOLVER, "modes_file": Text(None, max_len=1000)},
    "plate-seed001": {"width_mm": replace(SIZE, default=_PLATE.width_mm),
                      "height_mm": replace(SIZE, default=_PLATE.height_mm),
                      "thickness_mm": replace(SIZE, default=_PLATE.thickness_mm), **MATERIAL,
                      "order": Int("mode order k", _PLATE.order, ge=1, le=MAX_MODE_ORDER),
                      "x0_mm": replace(POS, default=_PLATE.x0_mm),
                      "y0_mm": replace(POS, default=_PLATE.y0_mm),
                      "channel_limit_um": replace(UM, default=None), **SOLVER},
}
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
    "raster": {"image": Text(max_len=1000), "mode": Choice(model.RASTER_MODES, "stretch"),
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
    "angle_deg": ANGLE, "image": Text(None, max_len=1000),
    "rendering": Choice(HEIGHT_RENDERINGS, "slope"),
    "gain": Num("mu' per unit slope", 2.0, gt=0.0), "mu_rest": replace(MU, default=0.8),
    "mu_min": replace(MU, default=0.6), "mu_max": MU_HIGH,
    "v_fade_mm_s": Num("mm/s", 10.0, gt=0.0)}
LAYER_KEYS["recorded"] = {
    "model": Text(max_len=1000), "mu_mean": replace(MU, default=0.8),
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
    "levels": NumList(LEVEL, min_len=2, default=None), "file": Text(None, max_len=1000)}

_DRIVING = profiles.DrivingForceParams()
DRIVING = {"mu0": Num("friction coefficient", _DRIVING.mu0, gt=0.0),
           "slope_per_um": Num("N per um per N", _DRIVING.slope_per_um, gt=0.0),
           "threshold_um": Num("um zero-to-peak", _DRIVING.threshold_um, ge=0.0, le=MAX_UM),
           "v_hold_mm_s": Num("mm/s", _DRIVING.v_hold_mm_s, gt=0.0)}

_NUMBER_WITH_UNIT = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*([^\d\s].*)?$")
_HEX = re.compile(r"^#(?:[0-9a-fA-F]{3}|[0-9a-fA-F]{6})$")


def _show(value) -> str:
    """A value as the TOML author wrote it (short)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return '"' + (value if len(value) <= 40 else value[:37] + "...") + '"'
    if isinstance(value, dict):
        return "a table"
    if isinstance(value, list):
        text = "[" + ", ".join(_show(v) for v in value[:4]) + (", ...]" if len(value) > 4 else "]")
        return text if len(text) <= 60 else f"a list of {len(value)} values"
    return repr(value)


def _kind(value) -> str:
    """The TOML type and value, for 'expected X, got Y' messages."""
    if isinstance(value, dict):
        return "a table"
    for types, name in ((bool, "the boolean"), (str, "the string"), ((int, float), "the number"),
                        (list, "the list")):
        if isinstance(value, types):
            return f"{name} {_show(value)}"
    return f"the date/time {value!s}"


def _did_you_mean(word: str, options) -> str:
    close = difflib.get_close_matches(word, list(options), n=1, cutoff=0.6)
    return f" (did you mean {close[0]}?)" if close else ""


def _bounds_text(spec: Num) -> str:
    lower = f"{'(' if spec.gt is not None else '['}{spec.gt if spec.gt is not None else spec.ge:g}"
    upper = f"{spec.lt if spec.lt is not None else spec.le:g}{')' if spec.lt is not None else ']'}"
    return f"{lower}, {upper}"


def _srgb_to_linear(c: float) -> float:
    """sRGB transfer function, inverted (IEC 61966-2-1)."""
    return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4


class _Reader:
    """Collects problems while turning parsed TOML into checked values."""

    def __init__(self, label: str, locator: Locator | None):
        self.label = label
        self.locator = locator
        self.problems: list[Problem] = []
        self.warnings: list[Problem] = []

    def report(self, path: KeyPath, message: str, warning: bool = False) -> object:
        found = self.warnings if warning else self.problems
        if len(found) < MAX_PROBLEMS:
            line = self.locator.line(path) if self.locator is not None else None
            found.append(Problem(self.label, line, field_name(path), message, warning))
        elif len(found) == MAX_PROBLEMS:
            found.append(Problem(self.label, None, "", f"more than {MAX_PROBLEMS} "
                                                       f"{'warnings' if warning else 'problems'}; "
                                                       f"the rest are not listed", warning))
        return _BAD

    def table(self, value, path: KeyPath, spec: dict[str, Spec], tables=()) -> dict | None:
        """Check that ``value`` is a table with only known keys; parse the ``spec`` keys.

        Returns key -> value (defaults filled in, ``_BAD`` for problems), or None if
        ``value`` is not a table. Keys in ``tables`` are allowed but left to the caller.
        """
        if not isinstance(value, dict):
            self.report(path, f"expected a table, got {_kind(value)}")
            return None
        known = list(spec) + list(tables)
        for key in value:
            if len(self.problems) > MAX_PROBLEMS:
                break  # no more are listed; spare the spelling suggestions
            if key not in known:
                self.report(path + (key,), f"unknown key{_did_you_mean(key, known)}; "
                                           f"known here: {', '.join(known)}")
        for key, s in spec.items():
            if isinstance(s, Retired) and key in value:
                self.report(path + (key,), f"no longer used, ignored: {s.why}", warning=True)
        return {key: self.value(value[key], path + (key,), s) if key in value
                else self.missing(path + (key,), s) for key, s in spec.items()
                if not isinstance(s, Retired)}

    def missing(self, path: KeyPath, spec: Spec):
        if spec.default is REQUIRED:
            return self.report(path, "missing (required)")
        return spec.default

    def value(self, value, path: KeyPath, spec: Spec):
        if isinstance(spec, Num):
            return self.number(value, path, spec)
        if isinstance(spec, Int):
            if isinstance(value, bool) or not isinstance(value, int):
                return self.report(path, f"expected an integer ({spec.unit}), got {_kind(value)}")
            if spec.ge is not None and spec.le is not None and not spec.ge <= value <= spec.le:
                return self.report(path, f"{_show(value)} is outside [{spec.ge}, {spec.le}] "
                                         f"({spec.unit})")
            if spec.ge is not None and value < spec.ge:
                return self.report(path, f"{value} is not >= {spec.ge} ({spec.unit})")
            return value
        if isinstance(spec, Choice):
            if not isinstance(value, str):
                return self.report(path, f"expected one of {', '.join(spec.options)}, got {_kind(value)}")
            if value not in spec.options:
                return self.report(path, f"{_show(value)} is not one of {', '.join(spec.options)}"
                                         f"{_did_you_mean(value, spec.options)}")
            return value
        if isinstance(spec, Text):
            return self.text(value, path, spec)
        if isinstance(spec, Flag):
            if not isinstance(value, bool):
                return self.report(path, f"expected true or false, got {_kind(value)}")
            return value
        if isinstance(spec, Colour):
            if not isinstance(value, str) or not _HEX.match(value):
                return self.report(path, f'expected a colour "#rrggbb" or "#rgb", got {_kind(value)}')
            digits = value[1:] if len(value) == 7 else "".join(2 * d for d in value[1:])
            return tuple(_srgb_to_linear(int(digits[i:i + 2], 16) / 255.0) for i in (0, 2, 4))
        if isinstance(spec, Selector):
            return self.selector(value, path)
        if isinstance(spec, NumList):
            return self.number_list(value, path, spec.item, spec.min_len)
        return self.rows(value, path, spec.item)

    def text(self, value, path: KeyPath, spec: Text):
        if not isinstance(value, str):
            return self.report(path, f"expected a string, got {_kind(value)}")
        allowed = "\t\n\r" if spec.lines else ""
        bad = next((c for c in value if unicodedata.category(c) == "Cc" and c not in allowed), None)
        if bad is not None:
            where = f"at character {value.index(bad) + 1}"
            return self.report(path, f"holds the control character {bad!r} {where}; expected "
                                     f"{'text' if spec.lines else 'one line of text'}")
        if len(value) > spec.max_len:
            return self.report(path, f"is {len(value):,} characters long; expected at most "
                                     f"{spec.max_len:,}")
        return value

    def selector(self, value, path: KeyPath):
        words = ("any",) + model.POSITIONAL_SELECTORS
        expected = f'one of {", ".join(words)} or a finger number "1", "2", ...'
        if isinstance(value, int) and not isinstance(value, bool):
            value = str(value)  # fingers = 2 means what fingers = "2" means
        if not isinstance(value, str):
            return self.report(path, f"expected {expected}, got {_kind(value)}")
        if value in words:
            return value
        if value.isdigit() and value.isascii():
            digits = value.lstrip("0")
            if not digits:
                return self.report(path, f'{_show(value)}: finger numbers start at "1" '
                                         f"(the finger touching longest)")
            if len(digits) > 2:
                return self.report(path, f'{_show(value)}: finger numbers go up to "99"')
            return digits
        return self.report(path, f"{_show(value)} is not {expected}{_did_you_mean(value, words)}")

    def number(self, value, path: KeyPath, spec: Num):
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            hint = ""
            m = _NUMBER_WITH_UNIT.match(value) if isinstance(value, str) else None
            if m:
                key = next(p for p in reversed(path) if isinstance(p, str))
                hint = (f"; write the number without quotes{' or units' if m.group(2) else ''}: "
                        f"{key} = {m.group(1)}")
            return self.report(path, f"expected a number ({spec.unit}), got {_kind(value)}{hint}")
        v = float(value)
        if not math.isfinite(v):
            return self.report(path, f"{_show(value)} is not a finite number ({spec.unit})")
        lower = spec.gt if spec.gt is not None else spec.ge
        upper = spec.lt if spec.lt is not None else spec.le
        if (lower is None or upper is None) and abs(v) > MAX_MAGNITUDE:
            return self.report(path, f"{_show(value)} is beyond {MAX_MAGNITUDE:g} in magnitude "
                                     f"({spec.unit}); no sensible value is that large")
        bad_low = (spec.gt is not None and not v > spec.gt) or (spec.ge is not None and not v >= spec.ge)
        bad_high = (spec.lt is not None and not v < spec.lt) or (spec.le is not None and not v <= spec.le)
        if (bad_low or bad_high) and lower is not None and upper is not None:
            return self.report(path, f"{_show(value)} is outside {_bounds_text(spec)} ({spec.unit})")
        if bad_low:
            op = ">" if spec.gt is not None else ">="
            return self.report(path, f"{_show(value)} is not {op} {lower:g} ({spec.unit})")
        if bad_high:
            op = "<" if spec.lt is not None else "<="
            return self.report(path, f"{_show(value)} is not {op} {upper:g} ({spec.unit})")
        return v

    def number_list(self, value, path: KeyPath, item: Num, min_len: int):
        if not isinstance(value, list):
            return self.report(path, f"expected a list of numbers ({item.unit}), got {_kind(value)}")
        if len(value) < min_len:
            return self.report(path, f"has {len(value)} value{'s' * (len(value) != 1)}, "
                                     f"needs at least {min_len}")
        out = [self.number(v, path + (i,), item) for i, v in enumerate(value)]
        return _BAD if _BAD in out else tuple(out)

    def rows(self, value, path: KeyPath, item: Num):
        if not isinstance(value, list) or not all(isinstance(r, list) for r in value) or not value:
            return self.report(path, f"expected a list of rows (lists of numbers), got {_kind(value)}")
        out = [self.number_list(row, path + (i,), item, 1) for i, row in enumerate(value)]
        return _BAD if _BAD in out else tuple(out)


# ---------------------------------------------------------------------------
# Sections


def _display(r: _Reader, doc: dict) -> model.Display | None:
    if "display" not in doc:
        r.report(("display",), "missing [display] table (width_mm, height_mm, width_px, height_px)")
        return None
    v = r.table(doc["display"], ("display",), DISPLAY)
    if v is None or _BAD in v.values():
        return None
    return model.Display(**v)


def _device(r: _Reader, doc: dict, display, base_dir: Path) -> profiles.DeviceProfile | None:
    raw = doc.get("device", {})
    v = r.table(raw, ("device",), DEVICE, tables=("friction", "calibration", "structure", "driving"))
    if v is None:
        return None
    friction = r.table(raw.get("friction", {}), ("device", "friction"), FRICTION)
    calibration = None
    if "calibration" in raw:
        calibration = _calibration(r, raw["calibration"], ("device", "calibration"))
    structure = None
    if v["profile"] in STRUCTURES:
        structure = _structure(r, v["profile"], raw.get("structure", {}), display, base_dir)
    elif "structure" in raw and v["profile"] is not _BAD:
        r.report(("device", "structure"), f"not used with profile {_show(v['profile'])}; only "
                                          f"the modal profiles have one: "
                                          f"{', '.join(profiles.MODAL_PROFILES)}")
        structure = _BAD
    if (friction is None or _BAD in friction.values() or _BAD in v.values()
            or _BAD in (calibration, structure)):
        return None
    device = profiles.DeviceProfile(friction=profiles.FrictionParams(**friction), calibration=calibration,
                                 structure=structure, **v)
    if structure is not None and not _actuation_builds(r, device):
        return None
    return device


def _structure(r: _Reader, profile: str, raw, display, base_dir: Path):
    """``[device.structure]`` of a modal profile -> BeamStructure | PlateStructure, or _BAD."""
    path: KeyPath = ("device", "structure")
    v = r.table(raw, path, STRUCTURES[profile])
    if v is None or _BAD in v.values():
        return _BAD
    if profile == "plate-seed001":
        ok = _structure_holds_display(r, path, display, ("x0_mm", "width_mm", "width_mm"),
                                      v["x0_mm"], v["width_mm"])
        ok &= _structure_holds_display(r, path, display, ("y0_mm", "height_mm", "height_mm"),
                                       v["y0_mm"], v["height_mm"])
        return profiles.PlateStructure(**v) if ok else _BAD
    ok = _structure_holds_display(r, path, display, ("x0_mm", "length_mm", "width_mm"),
                                  v["x0_mm"], v["length_mm"])
    orders, actuators = v["orders"], v["actuators_mm"]
    if any(o != int(o) for o in orders) or len(set(orders)) != len(orders) or len(orders) > 26:
        r.report(path + ("orders",), f"{_show(list(orders))}: expected distinct whole mode "
                                     f"orders (at most 26)")
        ok = False
    modes = None
    if v["modes_file"] is not None:
        modes = _modes_table(r, path, v["modes_file"], raw, base_dir)
        ok &= modes is not None
    n_modes = len(modes.names) if modes is not None else len(orders)
    if len(actuators) != n_modes:
        r.report(path + ("actuators_mm",), f"has {len(actuators)} positions, expected one per mode "
                                           f"({n_modes})")
        ok = False
    off = [a for a in actuators if not 0.0 <= a <= v["length_mm"]]
    if off:
        r.report(path + ("actuators_mm",), f"{off[0]:g} mm is off the {v['length_mm']:g} mm beam")
        ok = False
    if not ok:
        return _BAD
    modes_file = v.pop("modes_file")
    modes_path = _real_path(base_dir, modes_file) if modes_file is not None else None
    return profiles.BeamStructure(**{**v, "orders": tuple(int(o) for o in orders)},
                               modes_path=modes_path, modes=modes)


def _structure_holds_display(r: _Reader, path: KeyPath, display, keys, start: float, size: float) -> bool:
    """Report (False) if the display's span along one axis leaves the structure."""
    offset_key, size_key, display_key = keys
    if display is None:
        return True
    extent = getattr(display, display_key)
    if start <= 1e-9 and start + size >= extent - 1e-9:
        return True
    r.report(path + (offset_key,), f"the display's {display_key} (0 to {extent:g} mm) must lie on "
                                   f"the structure, which spans {start:g} to {start + size:g} mm "
                                   f"({offset_key} {start:g}, {size_key} {size:g})")
    return False


def _modes_table(r: _Reader, path: KeyPath, name: str, raw: dict, base_dir: Path):
    from frictex.device.structures.measured_modes import MeasuredModes

    if "orders" in raw:
        r.report(path + ("orders",), "not used with modes_file (the table's columns are the "
                                     "modes); remove one of them")
        return None
    modes_path = _real_path(base_dir, name)
    problem = file_problem(modes_path, MAX_FILE_BYTES)
    try:
        if problem is not None:
            raise ModesError(problem)
        # the table's reader checks its grammar; binary content and values that overflow
        # the spline fit come out as ValueError or (with errstate) FloatingPointError
        with np.errstate(all="raise"):
            return MeasuredModes.from_csv(modes_path)
    except (OSError, ModesError, ValueError, FloatingPointError) as exc:
        text = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
        if isinstance(exc, UnicodeDecodeError):
            text = f"not UTF-8 text (byte {exc.object[exc.start]:#04x} at offset {exc.start})"
        elif isinstance(exc, FloatingPointError):
            text = f"deflections too large to fit splines through ({exc})"
        r.report(path + ("modes_file",), f"{_show(name)} ({modes_path}): {text}")
        return None


def _real_path(base_dir: Path, name: str) -> Path:
    """``name`` relative to the texture file's folder, links followed as far as they go
    (``Path.resolve`` raises on a link loop; ``os.path.realpath`` stops there)."""
    return Path(os.path.realpath(base_dir / name))


def _actuation_builds(r: _Reader, device: profiles.DeviceProfile) -> bool:
    """Build the modal actuation once (modes solved, actuator matrix checked)."""
    from frictex.device.actuation.modal_actuation import make_modal_actuation

    try:
        make_modal_actuation(device)
    except ModesError as exc:
        r.report(("device", "structure"), str(exc))
        return False
    return True


def _strictly_increasing(values) -> bool:
    return all(b > a for a, b in zip(values, values[1:]))


def _calibration(r: _Reader, raw, path: KeyPath):
    v = r.table(raw, path, CALIBRATION)
    if v is None or _BAD in v.values():
        return _BAD
    amps, forces, mu = v["amplitudes_um"], v["forces_n"], v["mu"]
    ok = True
    if amps[0] != 0.0:
        r.report(path + ("amplitudes_um",), f"starts at {amps[0]:g}, expected 0 (um)")
        ok = False
    if not _strictly_increasing(amps):
        r.report(path + ("amplitudes_um",), f"{_show(list(amps))} is not strictly increasing")
        ok = False
    if not _strictly_increasing(forces):
        r.report(path + ("forces_n",), f"{_show(list(forces))} is not strictly increasing")
        ok = False
    if len(mu) != len(forces):
        r.report(path + ("mu",), f"has {len(mu)} rows, expected one per force ({len(forces)})")
        ok = False
    for i, row in enumerate(mu):
        where = path + ("mu",)
        label = f"row {i + 1}"
        if len(row) != len(amps):
            r.report(where, f"{label} has {len(row)} values, expected one per amplitude ({len(amps)})")
            ok = False
        elif row[0] != 1.0:
            r.report(where, f"{label} starts at {row[0]:g}, expected 1 (mu' at amplitude 0)")
            ok = False
        elif not _strictly_increasing([-m for m in row]):
            r.report(where, f"{label} {_show(list(row))} is not strictly decreasing")
            ok = False
    if not ok:
        return _BAD
    return profiles.Calibration(amps, forces, mu)


def _device_warnings(r: _Reader, device: profiles.DeviceProfile) -> None:
    a = device.friction.asymptote_per_n * device.normal_force_n
    if device.calibration is None and a >= 1.0 - ASYMPTOTE_MARGIN:
        r.report(("device", "normal_force_n"),
                 f"{device.normal_force_n:g} N puts seed 003's asymptote (eq 2) at {a:.3g}: the "
                 f"model does not hold there (it needs A < 1) and friction cannot be modulated",
                 warning=True)


# ---------------------------------------------------------------------------
# Geometry on the display


def _span_problem(r: _Reader, path: KeyPath, what: str, xs, ys, display: model.Display) -> bool:
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


def _region_on_display(r: _Reader, path: KeyPath, region, display: model.Display, what: str) -> bool:
    if isinstance(region, model.DiscRegion):
        c, rad = (region.cx_mm, region.cy_mm), region.radius_mm
        return _span_problem(r, path, what, (c[0] - rad, c[0] + rad), (c[1] - rad, c[1] + rad), display)
    cx, cy = region.center
    a = math.radians(region.angle_deg)
    ca, sa = math.cos(a), math.sin(a)
    corners = [(cx + ca * u - sa * v, cy + sa * u + ca * v)
               for u in (-region.width_mm / 2, region.width_mm / 2)
               for v in (-region.height_mm / 2, region.height_mm / 2)]
    return _span_problem(r, path, what, [p[0] for p in corners], [p[1] for p in corners], display)


def _region(r: _Reader, raw, path: KeyPath, display: model.Display | None):
    if not isinstance(raw, dict):
        return r.report(path, f"expected a table {{x_mm, y_mm, width_mm, height_mm}} or "
                              f"{{cx_mm, cy_mm, radius_mm}}, got {_kind(raw)}")
    disc_keys = [k for k in raw if k in DISC_REGION]
    rect_keys = [k for k in raw if k in RECT_REGION]
    if disc_keys and rect_keys:
        return r.report(path, f"mixes rectangle keys ({', '.join(rect_keys)}) and disc keys "
                              f"({', '.join(disc_keys)}); a region is one or the other")
    spec = DISC_REGION if disc_keys else RECT_REGION
    v = r.table(raw, path, spec)
    if v is None or _BAD in v.values():
        return _BAD
    region = model.DiscRegion(**v) if disc_keys else model.RectRegion(**v)
    if display is not None and not _region_on_display(r, path, region, display, "region"):
        return _BAD
    return region


# ---------------------------------------------------------------------------
# Layers: one builder per type, (reader, path, values, given keys, context) -> (layer, low key)


@dataclass
class _Context:
    display: model.Display | None
    base_dir: Path
    common: dict  # name, render, blend, region, visual, resolved


def _forbid(r: _Reader, path: KeyPath, given, keys, reason: str) -> bool:
    """Report keys that make no sense here; True if none was given."""
    extra = [k for k in keys if k in given]
    for k in extra:
        r.report(path + (k,), f"not used {reason}; remove it")
    return not extra


def _ordered(r: _Reader, path: KeyPath, low_key: str, high_key: str, v: dict) -> bool:
    if v[low_key] > v[high_key]:
        r.report(path + (low_key,), f"{v[low_key]:g} is above {high_key} {v[high_key]:g}")
        return False
    return True


def _build_grating(r, path, v, given, ctx):
    ok = _ordered(r, path, "mu_low", "mu_high", v)
    narrow = min(v["duty"], 1.0 - v["duty"]) * v["period_mm"]
    if v["edge"] == "square":
        ok &= _forbid(r, path, given, ["edge_mm"], 'with edge = "square"')
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


def _build_waveform(r, path, v, given, ctx):
    if v["shape"] == "samples":
        ok = _forbid(r, path, given, ["mu_min", "mu_max", "duty"], 'with shape = "samples"')
        if not v["samples"]:
            r.report(path + ("samples",), 'missing: shape = "samples" needs samples = '
                                    "[mu', ...] over one period")
            ok = False
        v = {k: x for k, x in v.items() if k not in ("mu_min", "mu_max", "duty")}
        low_key = "samples"
    else:
        ok = _forbid(r, path, given, ["samples"], f'with shape = "{v["shape"]}"')
        if v["shape"] != "square":
            ok &= _forbid(r, path, given, ["duty"], f'with shape = "{v["shape"]}" (only "square")')
        if v["mu_min"] is None:
            r.report(path + ("mu_min",), "missing (required for a standard shape)")
            ok = False
        else:
            ok &= _ordered(r, path, "mu_min", "mu_max", v)
        low_key = "mu_min"
    return (model.Waveform(**ctx.common, **v), low_key) if ok else None


def _fits(r, path, key: str, edge_mm: float, limit: float, what: str) -> bool:
    if edge_mm > limit:
        r.report(path + (key,), f"{edge_mm:g} mm is more than {what} ({limit:g} mm): "
                                f"mu' would never reach mu inside")
        return False
    return True


def _on_display(r, path, ctx, what, xs, ys) -> bool:
    return ctx.display is None or _span_problem(r, path, what, xs, ys, ctx.display)


def _build_rectangle(r, path, v, given, ctx):
    geometry = model.RectRegion(*(v[k] for k in RECT_REGION))
    ok = _fits(r, path, "edge_mm", v["edge_mm"], min(v["width_mm"], v["height_mm"]), "the shorter side")
    ok &= ctx.display is None or _region_on_display(r, path + ("x_mm",), geometry, ctx.display, "rectangle")
    return (model.Shape(**ctx.common, geometry=geometry, mu=v["mu"], edge_mm=v["edge_mm"]), "mu") if ok else None


def _build_disc(r, path, v, given, ctx):
    geometry = model.DiscRegion(*(v[k] for k in DISC_REGION))
    ok = _fits(r, path, "edge_mm", v["edge_mm"], 2 * v["radius_mm"], "the diameter")
    ok &= ctx.display is None or _region_on_display(r, path + ("cx_mm",), geometry, ctx.display, "disc")
    return (model.Shape(**ctx.common, geometry=geometry, mu=v["mu"], edge_mm=v["edge_mm"]), "mu") if ok else None


def _build_edge(r, path, v, given, ctx):
    ok = _on_display(r, path + ("x_mm",), ctx, "edge point", [v["x_mm"]], [v["y_mm"]])
    return (model.Edge(**ctx.common, **v), "mu") if ok else None


def _build_bump(r, path, v, given, ctx):
    ok = _on_display(r, path + ("cx_mm",), ctx, "bump centre", [v["cx_mm"]], [v["cy_mm"]])
    return (model.Bump(**ctx.common, **v), "mu") if ok else None


def _build_line(r, path, v, given, ctx):
    ok = True
    if (v["x0_mm"], v["y0_mm"]) == (v["x1_mm"], v["y1_mm"]):
        r.report(path + ("x0_mm",), f"line has zero length: both ends at ({v['x0_mm']:g}, {v['y0_mm']:g}) mm "
                 f"(use a disc for a dot)")
        ok = False
    ok &= _fits(r, path, "edge_mm", v["edge_mm"], v["width_mm"], "width_mm")
    ok &= _on_display(r, path + ("x0_mm",), ctx, "line", [v["x0_mm"], v["x1_mm"]], [v["y0_mm"], v["y1_mm"]])
    return (model.Line(**ctx.common, **v), "mu") if ok else None


def _build_raster(r, path, v, given, ctx):
    mode = v["mode"]
    ok = True
    if mode == "one-to-one":
        ok &= _forbid(r, path, given, ["width_mm", "height_mm", "tile_width_mm", "tile_height_mm"],
                      'with mode = "one-to-one" (the size comes from the image and the display px/mm)')
    else:
        for key in ("width_mm", "height_mm"):
            if v[key] is None:
                r.report(path + (key,), f'missing (required with mode = "{mode}")')
                ok = False
        if mode == "stretch":
            ok &= _forbid(r, path, given, ["tile_width_mm", "tile_height_mm"], 'with mode = "stretch"')
    image_path = _real_path(ctx.base_dir, v["image"]) if v["image"] else None
    grey = None
    try:
        if image_path is None:
            raise TextureError("empty image path")
        grey, _ = read_grey(image_path)
    except OSError as exc:
        r.report(path + ("image",), f"{_show(v['image'])}: {image_path}: {exc.strerror or exc}")
        ok = False
    except TextureError as exc:  # its message starts with the image's path
        r.report(path + ("image",), f"{_show(v['image'])}: {exc}")
        ok = False
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
    if not _region_on_display(r, path + ("x_mm",), layer.sprite, ctx.display, "image sprite"):
        return None
    low_key = "mu_black" if v["mu_black"] <= v["mu_white"] else "mu_white"
    return layer, low_key


def _force_common(r, path, given) -> bool:
    return _forbid(r, path, given, ["blend"], "on a force layer (mu' targets multiply, force "
                                              "targets replace: rendering.layers.force_layers)")


def _build_directional(r, path, v, given, ctx):
    ok = _force_common(r, path, given)
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


def _build_guidance(r, path, v, given, ctx):
    ok = _force_common(r, path, given)
    if not v["line"]:
        ok &= _forbid(r, path, given, ["line_angle_deg"], "with line = false (a point target)")
    ok &= _on_display(r, path + ("x_mm",), ctx, "guidance target", [v["x_mm"]], [v["y_mm"]])
    return (model.Guidance(**ctx.common, **v), "gain_n_per_mm") if ok else None


def _build_keyclick(r, path, v, given, ctx):
    ok = _force_common(r, path, given)
    if not v["release_n"] < v["press_n"] < v["click_n"]:
        r.report(path + ("press_n",), f"thresholds release_n {v['release_n']:g} < press_n "
                                      f"{v['press_n']:g} < click_n {v['click_n']:g} (N) do not hold")
        ok = False
    geometry = model.RectRegion(v["x_mm"], v["y_mm"], v["width_mm"], v["height_mm"])
    ok &= ctx.display is None or _region_on_display(r, path + ("x_mm",), geometry, ctx.display, "button")
    if not ok:
        return None
    keys = ("press_n", "click_n", "release_n", "dwell_s", "force_n")
    layer = model.KeyClick(**ctx.common, geometry=geometry, first_push=1 if v["first_push"] == "+x" else -1,
                           **{k: v[k] for k in keys})
    return layer, "force_n"


def _chosen_keys(r, path, v, given, table: dict, choice_key: str, optional=()) -> bool:
    """Keys of the chosen variant (``table[v[choice_key]]``) without a default are
    required unless ``optional``; keys only other variants take are refused."""
    choice = v[choice_key]
    ok = True
    for key in table[choice]:
        if v[key] is None and key not in optional:
            r.report(path + (key,), f'missing (required with {choice_key} = "{choice}")')
            ok = False
    others = {k for keys in table.values() for k in keys} - set(table[choice])
    return _forbid(r, path, given, sorted(others), f'with {choice_key} = "{choice}"') and ok


def _file_read(r, path, key, name, ctx, reader):
    """``reader(path)`` of the file ``name`` relative to the texture file, or None (reported)."""
    file_path = _real_path(ctx.base_dir, name) if name else None
    try:
        if file_path is None:
            raise TextureError("empty path")
        return reader(file_path)
    except OSError as exc:
        r.report(path + (key,), f"{_show(name)}: {file_path}: {exc.strerror or exc}")
    except TextureError as exc:  # its message starts with the file's path
        r.report(path + (key,), f"{_show(name)}: {exc}")
    return None


def _build_height(r, path, v, given, ctx):
    kind = v["shape"]
    ok = _chosen_keys(r, path, v, given, HEIGHT_SHAPES, "shape",
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
        ok = _on_display(r, path + ("cx_mm",), ctx, "bump centre", [v["cx_mm"]], [v["cy_mm"]])
    elif kind == "ridge":
        shape = Ridge(v["x_mm"], v["y_mm"], v["angle_deg"], v["width_mm"], v["rise_mm"])
        ok = _on_display(r, path + ("x_mm",), ctx, "ridge point", [v["x_mm"]], [v["y_mm"]])
    elif kind == "step":
        shape = Step(v["x_mm"], v["y_mm"], v["angle_deg"], v["rise_mm"], v["chamfer_mm"])
        ok = _on_display(r, path + ("x_mm",), ctx, "step point", [v["x_mm"]], [v["y_mm"]])
    elif kind == "button":
        if not v["rim_mm"] < v["radius_mm"]:
            r.report(path + ("rim_mm",), f"{v['rim_mm']:g} mm is not below radius_mm {v['radius_mm']:g}")
            return None
        shape = ButtonRim(v["cx_mm"], v["cy_mm"], v["radius_mm"], v["rim_mm"], v["rise_mm"])
        ok = ctx.display is None or _region_on_display(
            r, path + ("cx_mm",), model.DiscRegion(v["cx_mm"], v["cy_mm"], v["radius_mm"]),
            ctx.display, "button")
    else:
        x, y = v["x_mm"] or 0.0, v["y_mm"] or 0.0
        sprite = model.RectRegion(x, y, v["width_mm"], v["height_mm"])
        ok = ctx.display is None or _region_on_display(r, path + ("x_mm",), sprite, ctx.display,
                                                        "height map")
        heights = _file_read(r, path, "image", v["image"], ctx,
                             lambda f: read_height_png(f, v["rise_mm"]))
        if heights is None:
            return None
        shape = HeightMap(heights, x, y, v["width_mm"], v["height_mm"])
    keys = ("rendering", "gain", "mu_rest", "mu_min", "mu_max", "v_fade_mm_s")
    return (HeightLayer(**ctx.common, shape=shape, **{k: v[k] for k in keys}), "mu_min") if ok else None


def _build_recorded(r, path, v, given, ctx):
    if not v["mu_min"] < v["mu_mean"] < v["mu_max"]:
        r.report(path + ("mu_mean",), f"mu_min {v['mu_min']:g} < mu_mean {v['mu_mean']:g} < "
                                      f"mu_max {v['mu_max']:g} does not hold")
        return None
    from frictex.textures.hatt import ArTextureLayer, read_hatt_xml  # numba: only for scenes that use it

    texture = _file_read(r, path, "model", v["model"], ctx, read_hatt_xml)
    if texture is None:
        return None
    return ArTextureLayer(**ctx.common, **{**v, "model": texture}), "mu_min"


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
        if len(times) != len(levels) or times[0] != 0.0 or not _strictly_increasing(times):
            r.report(path + ("times_s",), f"{_show(list(times))}: expected times from 0, strictly "
                                          f"increasing, one per level ({len(levels)})")
            return None
        return Clip((ClipEvent("continuous", 0.0, v["intensity"], sharp, times[-1],
                               tuple(zip(times, levels))),), depth)
    got = _file_read(r, path, "file", v["file"], ctx, lambda f: read_ahap(f, depth))
    if got is None:
        return None
    clip, notes = got
    for note in notes[:3]:
        r.report(path + ("file",), note, warning=True)
    return clip


def _build_clip(r, path, v, given, ctx):
    shape_ok = _chosen_keys(r, path, v, given, CLIP_SHAPES, "clip", optional=("sharpness",))
    ok = True
    trigger = v["trigger"]
    needs = {"edge": ("x_mm", "y_mm"), "force": ("force_n",)}.get(trigger, ())
    for key in needs:
        if v[key] is None:
            r.report(path + (key,), f'missing (required with trigger = "{trigger}")')
            ok = False
    unused = [k for k in ("x_mm", "y_mm", "angle_deg", "force_n") if k not in needs
              and not (k == "angle_deg" and trigger == "edge")]
    ok &= _forbid(r, path, given, unused, f'with trigger = "{trigger}"')
    if ok and trigger == "edge":
        ok = _on_display(r, path + ("x_mm",), ctx, "edge point", [v["x_mm"]], [v["y_mm"]])
    clip = _clip_shape(r, path, v, ctx) if shape_ok else None  # its problems too
    if clip is None or not ok:
        return None
    place = {k: v[k] for k in ("x_mm", "y_mm", "angle_deg", "force_n") if v[k] is not None}
    return ClipLayer(**ctx.common, clip=clip, trigger=trigger, **place), "depth"


BUILDERS: dict[str, Callable] = {
    "grating": _build_grating, "waveform": _build_waveform, "rectangle": _build_rectangle,
    "disc": _build_disc, "edge": _build_edge, "bump": _build_bump, "line": _build_line,
    "raster": _build_raster, "directional": _build_directional, "guidance": _build_guidance,
    "keyclick": _build_keyclick, "height": _build_height, "recorded": _build_recorded,
    "clip": _build_clip,
}


def _force_device(r: _Reader, doc: dict, device, display, built):
    """``[device.driving]`` and the force layers: only on a travelling-wave profile whose
    surface holds the display. Returns the device with its driving model, or None."""
    raw = doc.get("device", {})
    force_profile = device is not None and device.profile in profiles.FORCE_PROFILES
    if device is not None and not force_profile:
        if isinstance(raw, dict) and "driving" in raw:
            r.report(("device", "driving"), f"not used with profile {_show(device.profile)}, which "
                                            f"cannot push; travelling-wave profiles: "
                                            f"{', '.join(profiles.FORCE_PROFILES)}")
        for index, (layer, _) in enumerate(built or ()):
            if isinstance(layer, model.FORCE_LAYERS):
                kind = type(layer).__name__.lower()
                r.report(("layer", index, "type"),
                         f'"{kind}" needs a travelling wave to push the finger; profile '
                         f"{_show(device.profile)} only modulates friction (use one of "
                         f"{', '.join(profiles.FORCE_PROFILES)})")
        return device
    if not force_profile:
        return device
    surface = profiles.SURFACE_LENGTH_MM[device.profile]
    if display is not None and display.width_mm > surface + 1e-9:
        r.report(("display", "width_mm"), f"{display.width_mm:g} mm is longer than the "
                                          f"{surface:g} mm surface of {device.profile} (display "
                                          f"x runs along it from its end)")
    driving = r.table(raw.get("driving", {}), ("device", "driving"), DRIVING)
    if driving is None or _BAD in driving.values():
        return None
    return replace(device, driving=profiles.DrivingForceParams(**driving))


def _layer(r: _Reader, raw, index: int, display, base_dir: Path, names: dict):
    """One [[layer]] -> (layer, key of its lowest mu') or None (problems reported)."""
    path: KeyPath = ("layer", index)
    if not isinstance(raw, dict):
        r.report(path, f"expected a table, got {_kind(raw)}")
        return None
    if "type" not in raw:
        r.report(path + ("type",), f"missing (required): one of {', '.join(LAYER_TYPES)}")
        return None
    kind = r.value(raw["type"], path + ("type",), COMMON["type"])
    if kind is _BAD:
        return None
    v = r.table(raw, path, {**COMMON, **LAYER_KEYS[kind]}, tables=LAYER_TABLES)
    region = _region(r, raw["region"], path + ("region",), display) if "region" in raw else None
    visual = r.table(raw.get("visual", {}), path + ("visual",), VISUAL)
    name = v["name"] if v["name"] is not None else f"{kind}-{index + 1}"
    if name is not _BAD:
        if not name.strip():
            r.report(path + ("name",), 'is empty; give the layer a name or leave the key out')
        elif name in names:
            r.report(path + ("name",), f"{_show(name)} is already the name of layer[{names[name] + 1}]")
        names.setdefault(name, index)
    render = v["render"]
    if render in ("sht", "hybrid") and kind not in PERIODIC_TYPES:
        render = r.report(path + ("render",), f'"{render}" needs a periodic layer (grating or '
                                               f'waveform); a {kind} renders with "sho" (or "auto")')
    values = {k: v[k] for k in LAYER_KEYS[kind]}
    if _BAD in values.values():
        return None
    common_ok = not (_BAD in (name, render, v["blend"], v["fingers"], region) or visual is None
                     or _BAD in visual.values())
    if render == "auto":
        render = model.auto_render_mode(values["period_mm"] if kind in PERIODIC_TYPES else None)
    # with problems in the common keys the type's own checks still run (every problem
    # is reported) on placeholder hints, and the layer is dropped afterwards
    hints = model.VisualHints(**visual) if common_ok else model.VisualHints()
    common = dict(name=name, render=render, blend=v["blend"], region=region, visual=hints,
                  fingers=v["fingers"])
    built = BUILDERS[kind](r, path, values, set(raw), _Context(display, base_dir, common))
    return built if common_ok else None


def _layers(r: _Reader, doc: dict, display, base_dir: Path):
    raw = doc.get("layer")
    if raw is None:
        r.report(("layer",), "no [[layer]] tables: a scene needs at least one layer")
        return None
    if not isinstance(raw, list) or not all(isinstance(x, dict) for x in raw):
        r.report(("layer",), f"expected [[layer]] tables (an array of tables), got {_kind(raw)}; "
                             f"start each layer with [[layer]]")
        return None
    if len(raw) > MAX_LAYERS:
        r.report(("layer",), f"{len(raw)} [[layer]] tables; a scene holds at most {MAX_LAYERS} "
                             f"(every layer is evaluated for every finger at every output sample)")
        return None
    names: dict[str, int] = {}
    built = [_layer(r, item, i, display, base_dir, names) for i, item in enumerate(raw)]
    return None if None in built else built


def _selector_warnings(r: _Reader, device: profiles.DeviceProfile, built) -> None:
    if device.profile != "plate-seed003":
        return
    for index, (layer, _) in enumerate(built):
        if layer.fingers != "any":
            r.report(("layer", index, "fingers"),
                     f"{_show(layer.fingers)} on profile {_show(device.profile)}: one channel "
                     f"serves only the finger touching longest, so other fingers feel its "
                     f"amplitude, not this layer (a modal profile gives each finger its own: "
                     f"{', '.join(profiles.MODAL_PROFILES)})", warning=True)


def _reach_warnings(r: _Reader, device: profiles.DeviceProfile, built) -> None:
    from frictex.device.friction import mu_floor

    force = device.normal_force_n
    floor = mu_floor(device, force)
    source = ("the calibration table" if device.calibration is not None
              else f"seed 003 eq 2, amplitude_limit_um {device.amplitude_limit_um:g}")
    for index, (layer, low_key) in enumerate(built):
        low = layer.mu_range[0]
        if low < floor - 1e-12:
            r.report(("layer", index, low_key),
                     f"asks for mu' down to {low:.4g}, but the device reaches only {floor:.4g} at "
                     f"the nominal {force:g} N ({source}); lower values will be clamped",
                     warning=True)


# ---------------------------------------------------------------------------
# Entry points


#: Largest texture file read (bytes): scenes are a few kB; a long ``samples`` list fits.
MAX_FILE_BYTES = 1 << 20
#: Deepest nesting of arrays and inline tables accepted (the grammar needs 3: rows of a
#: calibration table inside [device.calibration]).
MAX_NESTING = 16
#: Problems (and warnings) listed per file at most: beyond, the file is not a texture file.
MAX_PROBLEMS = 100


def _read_text(path: Path, r: _Reader) -> str | None:
    """The file's text (``textures.library.read_utf8``), or None with the problem reported."""
    try:
        return read_utf8(path, MAX_FILE_BYTES)
    except UnreadableText as exc:
        r.problems.append(Problem(r.label, exc.line, "", f"{exc}; expected a .toml texture file"))
        return None


_TOML_POSITION = re.compile(r"\s*\(at line (\d+), column (\d+)\)\s*$")
_LONG_DIGITS = re.compile(r"\d{%d,}" % (sys.get_int_max_str_digits() or 4300))


def _parse_toml(text: str, r: _Reader) -> dict | None:
    too_deep = (f"arrays, inline tables or dotted keys nested more than {MAX_NESTING} deep; "
                f"a texture file needs at most 4 levels")
    # checked before parsing: tomllib recurses on brackets and takes quadratic time on
    # long dotted keys (a 20,000-part key: 9 s)
    deep = _deepest_line(text)
    if deep is not None:
        r.problems.append(Problem(r.label, deep, "TOML syntax", too_deep))
        return None
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        message = str(exc)
        m = _TOML_POSITION.search(message)
        line = int(m.group(1)) if m else None
        if m:
            message = f"{message[:m.start()]} (column {m.group(2)})"
        r.problems.append(Problem(r.label, line, "TOML syntax", message))
        return None
    except RecursionError:  # should the bracket scan above ever miss a nesting
        r.problems.append(Problem(r.label, None, "TOML syntax", too_deep))
        return None
    except ValueError:  # tomllib reads integers through int(), which refuses very long ones
        m = _LONG_DIGITS.search(text)
        line = text.count("\n", 0, m.start()) + 1 if m else None
        r.problems.append(Problem(r.label, line, "TOML syntax",
                                  f"a number with {len(m.group()) if m else 'too many'} digits; "
                                  f"expected a number of at most 20 digits"))
        return None
    if _depth(doc) > MAX_NESTING:
        r.problems.append(Problem(r.label, _deepest_line(text), "TOML syntax", too_deep))
        return None
    return doc


def _depth(doc) -> int:
    """How deep tables and arrays nest in parsed TOML (the document itself is 1)."""
    deepest, stack = 0, [(doc, 1)]
    while stack:
        value, depth = stack.pop()
        deepest = max(deepest, depth)
        if deepest > MAX_NESTING:
            break
        children = value.values() if isinstance(value, dict) else value
        stack.extend((v, depth + 1) for v in children if isinstance(v, (dict, list)))
    return deepest


_KEY_PART = r"""(?:[A-Za-z0-9_-]++|"[^"\n]*+"|'[^'\n]*+')"""
#: a dotted key of more than MAX_NESTING parts (possessive, and starting only where a key
#: can start, so that the search stays linear on any text)
_LONG_DOTTED = re.compile(rf"(?<![A-Za-z0-9_-]){_KEY_PART}(?:\s*+\.\s*+{_KEY_PART}){{{MAX_NESTING},}}")


def _deepest_line(text: str) -> int | None:
    """The first line where brackets and braces open more than MAX_NESTING deep, or that
    holds a dotted key of more parts than that (outside strings, or inside a string that
    looks like one: a false alarm only for a string of 17 dot-separated words)."""
    long_key = _LONG_DOTTED.search(text)
    key_line = text.count("\n", 0, long_key.start()) + 1 if long_key else None
    depth, in_string = 0, None
    for number, line in enumerate(text.splitlines(), start=1):
        if number == key_line:
            return number
        depth, in_string, peak = bracket_peak(line, depth, in_string)
        if peak > MAX_NESTING:
            return number
    return key_line


def check_scene(path: str | Path) -> tuple[model.Scene | None, list[Problem], list[Problem]]:
    """Read and check a texture file.

    Returns ``(scene, problems, warnings)``: ``scene`` is None if there is any problem;
    ``problems`` lists every problem found, ``warnings`` things that are legal but
    probably not what the author wants (unreachable mu'). Never raises for bad input.
    """
    path = Path(path)
    r = _Reader(str(path), None)
    text = _read_text(path, r)
    if text is None:
        return None, r.problems, r.warnings
    if not text.strip():
        r.report((), "is empty; expected a texture file (format = 1, [display], [[layer]])")
        return None, r.problems, r.warnings
    doc = _parse_toml(text, r)
    if doc is None:
        return None, r.problems, r.warnings
    r.locator = Locator(text)
    top = r.table(doc, (), TOP, tables=("display", "device", "layer"))
    fmt = top["format"]
    if fmt is not _BAD and fmt != FORMAT_VERSION:
        newer = "is newer than this frictex reads" if fmt > FORMAT_VERSION else "is not a format"
        r.report(("format",), f"{fmt} {newer}; this frictex reads format = {FORMAT_VERSION}")
        return None, r.problems, r.warnings
    name = top["name"] if top["name"] is not None else path.stem
    display = _display(r, doc)
    device = _device(r, doc, display, path.parent)
    built = _layers(r, doc, display, path.parent)
    device = _force_device(r, doc, device, display, built)
    r.problems.sort(key=lambda p: p.line or 0)
    if r.problems or display is None or device is None or built is None:
        return None, r.problems, r.warnings
    _device_warnings(r, device)
    _reach_warnings(r, device, built)
    _selector_warnings(r, device, built)
    if top["control"] != "open" and (device.profile != "plate-seed003"
                                     or device.calibration is not None):
        r.report(("control",), f"{top['control']!r} needs profile = \"plate-seed003\" with seed "
                               f"003's model (no [device.calibration]); expected \"open\" here")
        return None, r.problems, r.warnings
    scene = model.Scene(format=fmt, name=name, description=top["description"], display=display,
                        device=device, layers=tuple(layer for layer, _ in built), source=path,
                        control=top["control"])
    return scene, r.problems, r.warnings


def load_scene(path: str | Path) -> model.Scene:
    """The scene in a texture file; raises :class:`TextureError` listing every problem."""
    scene, problems, _ = check_scene(path)
    if scene is None:
        raise TextureError(problems)
    return scene


__all__ = ["FORMAT_VERSION", "LAYER_TYPES", "TextureError", "check_scene", "load_scene"]
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
    profile = "plate-seed003"         # one of device.profile.PROFILES: plate-seed003
                                      #   (one channel), beam-seed000, plate-seed001 (modal), ...
    amplitude_limit_um = 2.5          # > 0, <= 100, zero-to-peak; the host never asks for more
                                      #   under a finger
    normal_force_n = 0.5              # > 0, <= 100; nominal force for warnings and force-less traces
    [device.friction]                 # optional: seed 003 eq 2 constants
    b_per_um = 1.67                   # > 0
    asymptote_per_n = 1.13            # >= 0 (asymptote A = asymptote_per_n * F_n;
                                      # 0: friction not depending on F_n)
    [device.calibration]              # optional measured table, replaces the model
                                      #   (validate warns at [device.friction] keys beside it)
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
    render = "auto"                   # auto | sho | a renderer (frictex replay --help lists
                                      #   them: sho-held, sht, ...). auto: periodic layers use
                                      #   the hybrid (textures.model.auto_render_mode: it beats
                                      #   SHO and SHT on seed 003's gratings, frictex report);
                                      #   objects and rasters use sho. Other renderers need a
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
control characters (``description`` may hold line breaks and tabs), and names and file
names no format characters (Unicode Cf: U+202E, U+200B, U+2066...); names at most 200
characters, paths 1000. A file is UTF-8 (a leading byte order mark is dropped), at most
1 MiB, a regular file (never a FIFO or a device: checked before opening), with arrays and
inline tables nested at most 16 deep. The files it names (``image``, ``model``, ``file``,
``modes_file``) lie in its own folder or below unless ``allow_outside`` (``--allow-outside``,
``FRICTEX_ALLOW_OUTSIDE=1``); images are PNG only, within a per-image and per-scene budget
of decoded pixels checked from their headers (``textures.sections.files``,
``textures.raster_io``; FORMAT.md states the figures).

Objects, points, regions and sprites must lie on the display. Every problem in a file is
reported (not only the first) as ``file:line: field: message``; ``frictex validate`` also
warns, without failing, where a layer asks for a mu' the device cannot reach at its
nominal normal force (``device.friction.mu_floor``), where a layer is for one
finger on a one-channel device (which serves only the finger touching longest), where a
clip starts on a lift (felt only by other fingers still touching), where nothing of a
layer can be felt (a flat height: ``rise_mm = 0`` or a map of one grey; a clip that never
lowers mu' at the 10 kHz output rate: level or intensity 0, or over within one sample), where a
display's pixel pitch is no screen's (:data:`PIXEL_PITCH_MM`: a size in metres, most
often), and where a layer's region never meets the area the layer acts on (the layer
would cover nothing).
"""


from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from frictex.device.profile import FRICTION_LOOP_PROFILES
from frictex.textures import model
from frictex.textures.extent import lowering
from frictex.textures.errors import Locator, Problem, TextureError
from frictex.textures.keys import FORMAT_VERSION, LAYER_KEYS, LAYER_TYPES, TOP
from frictex.textures.schema import BAD, Reader
from frictex.textures.sections.device import (device_warnings, force_device, parse_device,
                                              parse_display, unused_friction_warnings)
from frictex.textures.outside import outside_allowed
from frictex.textures.sections.files import Files
from frictex.textures.sections.layers import (lift_warnings, parse_layers, reach_warnings,
                                              selector_warnings, unfelt_warnings)
from frictex.textures.toml_safe import parse_toml, read_text

#: The pixel pitch (mm per pixel) of a plausible touch screen: an 800-ppi phone has
#: 0.03 mm, a 1080p 84-inch touch table about 1 mm; outside these bounds (2540 to 12.7
#: ppi) a [display] is warned about, as a size given in metres or in pixels would give.
PIXEL_PITCH_MM = (0.01, 2.0)


def _pixel_pitch_warnings(r: Reader, display: model.Display) -> None:
    """Warn where ``display``'s mm per pixel lies outside :data:`PIXEL_PITCH_MM`, with
    the size in mm that the value would be if it were written in metres."""
    lo, hi = PIXEL_PITCH_MM
    for axis, mm, px in (("width", display.width_mm, display.width_px),
                         ("height", display.height_mm, display.height_px)):
        pitch = mm / px
        if lo <= pitch <= hi:
            continue
        hint = (f"; in metres? {mm:g} m = {mm * 1000:g} mm" if lo <= mm * 1000 / px <= hi
                else "")
        r.report(("display", f"{axis}_mm"),
                 f"{mm:g} mm over {axis}_px = {px} is {pitch:.3g} mm per pixel "
                 f"({25.4 / pitch:,.6g} ppi); touch screens have about 0.03 (an 800-ppi phone) "
                 f"to 1 mm per pixel (a 1080p 84-inch table), and values outside {lo:g} to "
                 f"{hi:g} mm per pixel are warned about{hint}", warning=True)


def _covers_nothing_warnings(r: Reader, display: model.Display, built) -> None:
    """Warn where a layer's region never meets the area the layer lowers mu' on
    (``textures.extent.lowering``, whose boxes never understate it): the layer would
    cover nothing."""
    for index, (layer, _) in enumerate(built):
        if layer.region is None or lowering(layer, display):
            continue
        own = lowering(replace(layer, region=None), display)
        if not own:  # it lowers mu' nowhere, region or not
            continue
        x0, y0 = min(b[0] for b, _ in own), min(b[1] for b, _ in own)
        x1, y1 = max(b[2] for b, _ in own), max(b[3] for b, _ in own)
        r.report(("layer", index, "region"),
                 f"never meets where the layer acts (within x {x0:g} to {x1:g} mm, y {y0:g} "
                 f"to {y1:g} mm): the layer covers nothing; move the region onto it, or "
                 f"leave the region out", warning=True)


def check_scene(path: str | Path, *, allow_outside: bool = False, text: str | None = None,
                ) -> tuple[model.Scene | None, list[Problem], list[Problem]]:
    """Read and check a texture file.

    Parameters
    ----------
    path : the texture file.
    allow_outside : let the file name files outside its own folder (absolute paths,
        ``..``, links leading out); also allowed by ``FRICTEX_ALLOW_OUTSIDE=1``
        (``textures.sections.files``).
    text : the file's text as an editor holds it (not saved yet), read in place of the
        file's; ``path`` still names the file (messages, and the folder its references
        are relative to).

    Returns ``(scene, problems, warnings)``: ``scene`` is None if there is any problem;
    ``problems`` lists every problem found, ``warnings`` things that are legal but
    probably not what the author wants (unreachable mu'). Never raises for bad input.
    """
    path = Path(path)
    r = Reader(str(path), None)
    text = read_text(path, r) if text is None else text
    if text is None:
        return None, r.problems, r.warnings
    if not text.strip():
        r.report((), "is empty; expected a texture file (format = 1, [display], [[layer]])")
        return None, r.problems, r.warnings
    doc = parse_toml(text, r)
    if doc is None:
        return None, r.problems, r.warnings
    r.locator = Locator(text)
    return _check_document(path, doc, r, allow_outside)


def check_document(path: str | Path, doc: dict, *, allow_outside: bool = False,
                   ) -> tuple[model.Scene | None, list[Problem], list[Problem]]:
    """:func:`check_scene` of a file's text already parsed: ``doc`` as ``tomllib``
    gives it (an editor's trial values), ``path`` the file it stands for. Its problems
    name no line (there is no text)."""
    return _check_document(Path(path), doc, Reader(str(path), None), allow_outside)


def format_refusal(fmt: int) -> str | None:
    """Why a texture file's ``format`` (an integer) cannot be read, or None where it can."""
    if fmt == FORMAT_VERSION:
        return None
    newer = "is newer than this frictex reads" if fmt > FORMAT_VERSION else "is not a format"
    return f"{fmt} {newer}; this frictex reads format = {FORMAT_VERSION}"


def _check_document(path: Path, doc: dict, r: Reader, allow_outside: bool,
                    ) -> tuple[model.Scene | None, list[Problem], list[Problem]]:
    """The scene ``doc`` (parsed TOML of the file ``path``) gives, with the problems and
    warnings reported through ``r``."""
    top = r.table(doc, (), TOP, tables=("display", "device", "layer"))
    fmt = top["format"]
    if fmt is not BAD and (refusal := format_refusal(fmt)):
        r.report(("format",), refusal)
        return None, r.problems, r.warnings
    name = top["name"] if top["name"] is not None else path.stem
    display = parse_display(r, doc)
    files = Files(path.parent, allow_outside or outside_allowed())
    device = parse_device(r, doc, display, files)
    built = parse_layers(r, doc, display, files)
    device = force_device(r, doc, device, display, built)
    r.problems.sort(key=lambda p: p.line or 0)
    if r.problems or display is None or device is None or built is None:
        return None, r.problems, r.warnings
    device_warnings(r, device)
    unused_friction_warnings(r, doc, device, built)
    reach_warnings(r, device, display, built)
    selector_warnings(r, device, built)
    lift_warnings(r, built)
    unfelt_warnings(r, built)
    _pixel_pitch_warnings(r, display)
    _covers_nothing_warnings(r, display, built)
    if top["control"] != "open" and (device.profile not in FRICTION_LOOP_PROFILES
                                     or device.calibration is not None):
        loop = " or ".join(f'"{name}"' for name in FRICTION_LOOP_PROFILES)
        r.report(("control",), f"{top['control']!r} needs profile = {loop} with seed "
                               f"003's model (no [device.calibration]); expected \"open\" here")
        return None, r.problems, r.warnings
    scene = model.Scene(format=fmt, name=name, description=top["description"], display=display,
                        device=device, layers=tuple(layer for layer, _ in built), source=path,
                        control=top["control"])
    return scene, r.problems, r.warnings


def read_scene(path: str | Path, *, allow_outside: bool = False, text: str | None = None,
               ) -> tuple[model.Scene, list[Problem]]:
    """The scene in a texture file and the warnings its check gave (values frictex can
    play that look wrong: ``frictex validate`` prints the same); raises
    :class:`TextureError` listing every problem. ``allow_outside``, ``text``: as
    :func:`check_scene`'s."""
    scene, problems, warnings = check_scene(path, allow_outside=allow_outside, text=text)
    if scene is None:
        raise TextureError(problems)
    return scene, warnings


def load_scene(path: str | Path, *, allow_outside: bool = False,
               text: str | None = None) -> model.Scene:
    """The scene in a texture file (:func:`read_scene` without its warnings)."""
    return read_scene(path, allow_outside=allow_outside, text=text)[0]


__all__ = ["FORMAT_VERSION", "LAYER_KEYS", "LAYER_TYPES", "TextureError", "check_document",
           "check_scene", "load_scene", "read_scene"]

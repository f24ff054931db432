"""The texture file format's reference page, generated from the loader's own key tables.

``textures/FORMAT.md`` is this module's output; a test compares the two, so the page
cannot drift from what ``textures.loader`` accepts. Regenerate it after changing a key:

    .venv/bin/python -m frictex.textures.format_doc > textures/FORMAT.md
"""

from __future__ import annotations

import math
import textwrap

from frictex.textures import keys as K
from frictex.textures import model
from frictex.textures import schema as S
from frictex.textures.extent import FAST_FINGER_MM_S
from frictex.textures.format_examples import EXAMPLES, PLANK
from frictex.textures.loader import PIXEL_PITCH_MM

INTRO = """# Texture files: every table and key

One scene per TOML file. This page is all an author needs: how to start, the conventions
(coordinates, angles, regions, colours, pixels), every key the loader accepts with its
meaning, unit, range and default (or the rule that derives it), and a complete example
of every layer type. It is generated from the loader's key tables (`textures/keys.py`)
by `python -m frictex.textures.format_doc`, and tests keep it equal to them, validate and
replay every example on it, and check each convention stated here against the friction
map the loader builds (`tests/test_format_doc.py`).

Units are in the key names (`_mm`, `_um` zero-to-peak, `_n`, `_deg`, `_s`, `_px`);
relative friction μ' = μ(w)/μ(0) in (0, 1]: 1 is the plate at rest, lower is more
slippery (seed 003, eq 1). A file asks for μ' targets, never for amplitudes.
*required* means the key has no default. Ranges are inclusive unless written with `<`
or `>`. `frictex validate FILE` checks a file and names the file, line and field of
every problem; a field's `[n]` counts from 1, as `[[layer]]` tables are numbered:
`layer[2].levels[3]` is the third value of the second layer's `levels` (a place inside a
JSON file a layer names, an AHAP clip's `Pattern[0]`, counts from 0, as JSON does). What the loader
accepts at most is under "Limits".
"""

FIRST = """## Your first texture: a wood plank

From an empty file to a scene you can feel, in six steps. Each block below is a whole
file.

1. **The display.** Every file starts with `format = 1` and the touchscreen's active
   area: its size in mm (the positions of everything else are in mm from its top-left
   corner, x right, y down) and in pixels (what the demo draws the scene at).
2. **The grain**: fine lines of a triangle profile, 1.5 mm apart, running 5 degrees
   below horizontal to the right. A periodic layer's `angle_deg` is the direction
   *across* its lines (see Angles): lines running at 5 degrees take angle_deg = 5 + 90 = 95.
3. **The growth rings**: a grating 9 mm apart along the grain, with narrow slippery
   bands (`duty` = 0.15 of each period at `mu_low`).
4. **The knot**: a height layer, a bump 0.6 mm high felt by the size of its slope
   (`rendering = "magnitude"`: rougher where steeper, whichever way the finger crosses).
   Confining it to a disc with a `[layer.region]` seems natural; see step 5.
5. **Validate.** `frictex validate plank.toml`:

<!-- example: plank-first -->
```toml
{plank_first}```

   says that about 13 % of a typical stroke asks for a friction the device cannot reach:

       frictex: warning: plank.toml: layers: 12.9% of a typical stroke (4 s) and 13.8% of
       the display ask for mu' below the device's floor 0.5717 at the nominal 0.5 N, from
       layers "grain", "rings"; lowest where layers overlap: 0.346, the product of layers
       "grain", "rings", "knot"; those targets will be clamped to the floor

   Each layer is within reach alone, but layers multiply (see Composition). "from" names
   the layers that lower mu' most where the stroke and the display fall below the floor;
   "lowest where layers overlap" multiplies the lowest mu' of the layers whose extents
   overlap, at the place where that product is least: in the knot's disc the grain
   (0.72), the rings (0.6) and the knot at rest (0.8) give 0.72 x 0.6 x 0.8 = 0.346,
   where the plate at 0.5 N and 2.5 um goes no lower than 0.572. Layers that never
   overlap are never multiplied. The region
   adds a step too: a height layer covers its region at `mu_rest` (0.8), so the knot's
   disc is a step of 0.8 against 1 outside it (see Regions). `frictex preview plank.toml -o
   plank.png` hatches the places below the floor: 13.2% of the display, not 13.8%, as
   it averages mu' over each pixel (a pixel across the edge of a band below the floor
   can average above it) where `validate` reads mu' at points. The fix: shallower grain
   and rings, and the knot without a region (a bump's slope vanishes beyond about 3
   sigma, so it is confined already; its rest level then covers the whole display
   evenly, no step):

<!-- example: plank -->
```toml
{plank}```

6. **Feel it.** `frictex validate plank.toml` prints `ok`; `frictex demo plank.toml` opens
   it on the device (or a mouse stands in for a finger); `frictex replay plank.toml
   swipe-40mms-50hz --out run` plays a bundled trace over it headless and writes the
   amplitudes asked of the device (`run/friction.csv`).
"""


def _angle_figure() -> str:
    return """## Conventions

### Coordinates and angles

Positions are in mm from the top-left corner of the active area, **x to the right, y
down**. Every angle is in degrees from +x towards +y: because y points down, a positive
angle turns **clockwise** on the screen.

A grating's or a waveform's `angle_deg` is the direction of the axis **across** its lines
(the lines' normal, along which μ' varies and `period_mm` is measured), not the direction
of the lines: lines running at θ take angle_deg = θ + 90. The same holds for an `edge`
layer, a height `step` and a clip's trigger line (their `angle_deg` is the normal), while
a height `ridge`'s `angle_deg` and a guidance `line_angle_deg` give the direction the
line itself runs.

```
 (0,0) ------------------------------------------------------------> +x
   |
   |   angle_deg = 0          angle_deg = 90          angle_deg = 45
   |   axis --->              axis |                  axis \\
   |                               v                        v  (+x and +y)
   |   |  |  |  |  |                                     /   /   /   /
   |   |  |  |  |  |          ================          /   /   /   /
   |   |  |  |  |  |          ================         /   /   /   /
   |   vertical lines:        horizontal lines:     lines rising to the
   |   mu' varies with x      mu' varies with y     right on the screen
   v
  +y
```

Phase 0 of a periodic layer lies `offset_mm` along its axis from the origin; its profile
starts there (a grating's `mu_low` band, a waveform's shape from phase 0).

### Display pixels and millimetres

`width_mm` x `height_mm` is the active area; every position is in mm on it. `width_px`
x `height_px` is the screen's pixel count: the demo draws the scene at it (its window
adds the scope's strip below, cut to the screen's work area; fullscreen at those pixels
it fills the screen, the scope hidden; README "Using it") and `preview` writes the scene
image fitted in it keeping the mm aspect (all of it where the pixels are square; 800 x
480 px on 120 x 64.8 mm gives 800 x 432, and it prints why), and the pixel density along
each axis, width_px / width_mm and height_px / height_mm (px/mm), sizes what is counted
in pixels: a raster with `mode = "one-to-one"` (one image pixel per display pixel) and
the default tile of `mode = "tile"`. In a window or an image of another shape the scene
keeps its millimetre proportions: the area is fitted at one scale, centred, with bars on
two sides. `frictex demo --fullscreen` on a screen of `width_px` x `height_px` (or
fullscreen with a touch screen) draws it over the whole screen at the two densities, so
that every drawn mm is the felt mm even where a pixel is not square. Where the pixel
aspect (width_px / height_px) differs from the millimetre aspect, the two densities
differ and a pixel is not square: a one-to-one image is stretched along the axis of
lower density (nothing else changes, and nothing warns). A pixel pitch (mm per pixel:
width_mm / width_px, height_mm / height_px) outside <PITCH_LO> to <PITCH_HI> mm is no touch
screen's (an 800-ppi phone has 0.03 mm, a 1080p 84-inch table about 1 mm): `frictex
validate` warns about it, and names the size in mm where the value would fit written in
metres (`width_mm = 0.108` over 800 px: "in metres? 0.108 m = 108 mm").

### Colours

`color_low` and `color_high` of `[layer.visual]` are sRGB colours written `"#rrggbb"` or
`"#rgb"` (hexadecimal, as in CSS: `"#fa0"` is `"#ffaa00"`); nothing else is accepted.
The visual layer draws a layer's lowest μ' in `color_low`, its highest in `color_high`,
and blends between them in linear light: both colours decoded from sRGB, mixed as
color_low + u (color_high - color_low) with u = (μ' - lowest) / (highest - lowest) of the
layer's μ', layers multiplied, then encoded to sRGB again. With black and white, u =
0.25, 0.5, 0.75 are sRGB greys 137, 188, 225 (μ' 0.7, 0.8, 0.9 in a layer from 0.6 to
1.0): equal steps of μ' look larger towards color_low. A raster is drawn the same way,
by the μ' its greys give, not as its file's greys: on the bundled raster-map (μ' 0.651
to 1.0) a pixel of grey 38 (μ' 0.702) is drawn as grey 107. A height layer is drawn as a
shaded relief in its colours, not by the μ' felt (see AUTHORING.md).

### Composition

Layers are drawn and composed in file order, later on top. With `blend = "multiply"`
(the default) the μ' of every layer covering a finger multiply: two layers at 0.6 give
0.36. With `blend = "replace"` a layer's μ' replaces what the layers before it gave,
where it covers. The product can go below the device's floor (the lowest μ' it reaches
at the normal force, `[device]`) even where every layer alone stays above it:
`frictex validate` measures that share of the display and of a typical stroke, names
the layers causing it, and gives the lowest product where the layers' extents overlap
(a clip counts as far beyond its region as a finger sliding at <FAST> mm/s goes while
it plays); `--strict` fails such a file (exit 2), and `frictex preview` hatches those
places on the friction map.

### Regions

Every layer type takes an optional `[layer.region]`: a rectangle (`x_mm`, `y_mm`,
`width_mm`, `height_mm`, `angle_deg`) or a disc (`cx_mm`, `cy_mm`, `radius_mm`). Outside
its region a layer is not composed (as if its μ' were 1 there); a region that never
meets the area its layer acts on (a disc's region beside the disc) leaves the layer
covering nothing, and `frictex validate` warns. What a region does to each type:

| layer type | covers without a region | with a region |
|---|---|---|
| `grating`, `waveform`, `edge` | the whole display | the pattern is cut at the region's outline: a step from the pattern's μ' to 1 |
| `rectangle`, `disc`, `line`, `bump` | the shape (a bump: r <= 4 sigma) | the part of the shape inside the region |
| `raster` | the image's area | the part of the image inside the region |
| `height` | the whole display, at `mu_rest` on flat ground; a height map's height goes on beyond its rectangle, level, at its nearest edge pixel's height (no slope there, so nothing is felt: a map whose edge is high does not drop at its border; draw the fall inside the image) | the region, at `mu_rest`: **a step** from mu_rest to 1 at its outline, felt and seen. To confine a shape without a step, leave the region out (a bump's or ridge's slope is ~0 beyond 3 sigma or its width: the rest level then covers the display evenly), or raise `mu_rest` towards 1 (the step is 1 - mu_rest) |
| `recorded` | the whole display, about `mu_mean` | the region: a step from about mu_mean to 1 at its outline |
| `clip` | triggers anywhere | triggers only inside the region (the clip, once started, plays until it ends) |
| `directional`, `guidance`, `keyclick` | the whole display (a keyclick: its button) | acts only inside the region |

### At the display's edge

A shape may run off the display: a `rectangle`, `disc`, `line` (with its width), `bump`
(to 4 sigma), `raster` image, height `button` or height map, a keyclick's button or a
region partly off the display is cut at its edge, drawn and felt where it lies on the
display (every layer is evaluated per position). One wholly off the display is refused
(`... lies wholly off the display (x 0 to W mm, y 0 to H mm)`): it would do nothing.
A point that places a line or a target (an `edge`'s, a height `ridge`'s or `step`'s
`x_mm`, `y_mm`, a clip's trigger line, a `guidance` target) must lie on the display
itself, edges included.

### What the drive reaches

A device profile (device/profile.py) gives its drive's um per volt and voltage limit: one
channel's drive reaches their product (plate-seed003 and travelling-beam-seed002: 0.02
um/V x 150 V = 3 um; ring-seed004: 0.0375 um/V x 80 V = 3 um; beam-seed000 and
plate-seed001: 0.005125 um/V x 150 V = 0.769 um). `frictex validate` warns where a scene
asks one channel for more: `amplitude_limit_um` on a one-channel or travelling-wave
profile, `[device.structure] channel_limit_um` on a modal one. Seed 001's plate without
one is not compared, though its channels then take `amplitude_limit_um`: seed 001 gives no
um per volt for its plate, which borrows the beam's (0.769 um at 150 V), and the bundled
two-finger-plate-seed001 asks the 1 um seed 001's experiments used; the warning would
rest on a borrowed figure. What the plate then gets depends on the output: the audio output
clamps each channel at the voltage limit (and counts the clamps); a link device (`--device
sim`, a serial device) clamps only at the limit it declares (the simulated device's 4 um
by default), so the plate may be asked for more than the profile's figures allow.
""".replace("<FAST>", f"{FAST_FINGER_MM_S:g}").replace(
    "<PITCH_LO>", f"{PIXEL_PITCH_MM[0]:g}").replace("<PITCH_HI>", f"{PIXEL_PITCH_MM[1]:g}")


def files_section() -> str:
    """What a texture file may name and how those files are read (from the readers' limits)."""
    from frictex.device.safe_text import MAX_SHOWN
    from frictex.textures import ahap, dynamic, hatt, heights, raster_io, schema, toml_safe
    from frictex.textures.outside import ALLOW_OUTSIDE_ENV

    mib = 1 << 20
    paragraphs = [
        "`image` (raster and height-map layers), `model` (recorded layers), `file` (AHAP "
        "clips) and `[device.structure] modes_file` name files by a path relative to the "
        "texture file, **in its own folder or below**. An absolute path, a path whose `..` "
        "leads out of the folder, or a symbolic link that leads out is an error naming the key. "
        "Only for files you trust: `--allow-outside` (on `validate`, `replay`, `preview`, "
        f"`demo` and `batch`), or `{ALLOW_OUTSIDE_ENV}=1` in the environment, lifts the rule.",
        "A file is checked and opened once: the path is opened with its last part never "
        "followed, where the opened file really lies is checked again, and the file is read "
        "from what was opened, so a path swapped for a link after the check reads nothing "
        "outside. A **hard link** is not caught: it is a second name of the same file, not a "
        "link that leads anywhere, so a hard link in the folder to a file outside it is read "
        "like any file of the folder. It is not refused (files with more than one link) "
        "because package managers and backups make hard links of ordinary files (the caches "
        "of uv and pip, `cp -al`, `rsync --link-dest`), and only someone who can write to "
        "the file system it is read on, and could read the file already, can make one: a "
        "folder unpacked from a stranger's archive should be checked for them (`find DIR "
        "-type f -links +1`).",
        "Every file is opened only if it is a regular file (never a FIFO, a device such as "
        "`/dev/zero`, a socket or a folder), and read up to a size: the texture file "
        f"{toml_safe.MAX_FILE_BYTES // mib} MiB, an image or height map "
        f"{raster_io.MAX_FILE_BYTES // mib} MiB, a HaTT model {hatt.MAX_HATT_BYTES // mib} MiB, "
        f"an AHAP clip {ahap.MAX_AHAP_BYTES // mib} MiB, a mode table "
        f"{toml_safe.MAX_FILE_BYTES // mib} MiB.",
        "Images and height maps are PNG files and nothing else: the PNG signature is checked "
        "before any image library sees the bytes (an EPS or TIFF file named `.png` is "
        "refused), and one whose image data is shorter than its header says is refused as "
        "truncated (never padded). Their size and kind are read from the PNG header before "
        "decoding (a height map that is not 16-bit greyscale is refused there): at most "
        f"{raster_io.MAX_PIXELS:,} pixels per image, and at most "
        f"{raster_io.MAX_SCENE_BYTES // mib} MiB of decoded maps per scene, a raster map "
        f"keeping {raster_io.RASTER_BYTES_PER_PX} bytes per pixel and a height map "
        f"{heights.HEIGHT_MAP_BYTES_PER_PX} (so at most "
        f"{raster_io.MAX_SCENE_BYTES / raster_io.RASTER_BYTES_PER_PX / 1e6:.1f} Mpx of raster "
        f"maps, or {raster_io.MAX_SCENE_BYTES / heights.HEIGHT_MAP_BYTES_PER_PX / 1e6:.1f} Mpx "
        "of height maps, in one scene).",
        f"A HaTT model holds at most {hatt.MAX_MODELS:,} vertices, and at most "
        f"{hatt.MAX_FIT_VERTICES} where each vertex must be refitted as an AR model (an ARMA "
        "model, when read; any model played at a sample rate other than its own): its size is "
        "bounded by the cost of the fits, checked before the first. A model made at a rate "
        f"other than {dynamic.OUTPUT_RATE_HZ:g} Hz (replay's default output rate) with more "
        "vertices gets a warning at the layer's `model` key when the file is read (it plays "
        "at its own rate, `--rate`); a replay at a rate that would refit it fails naming "
        "that key.",
        "Messages never carry a file's contents: the values they show are escaped (a control "
        "character such as ESC is shown as the four characters `\\x1b`) and cut to "
        f"{schema.MAX_SHOWN} characters (keys and strings of the texture file) or {MAX_SHOWN} "
        "(cells of the files it names), ending with `...`; a row that is not what the file "
        "should hold is described, not printed.",
    ]
    return "\n\n".join(["## Files a texture file names"]
                        + [textwrap.fill(p, 90, break_on_hyphens=False) for p in paragraphs]) + "\n"


def _size(value) -> str:
    """A limit as the page shows it: bytes in MiB, counts with thousands separators."""
    if isinstance(value, int) and value >= 1 << 20 and value % (1 << 20) == 0:
        return f"{value >> 20} MiB"
    return f"{value:,}" if isinstance(value, int) else f"{value:g}"


def limits() -> list[tuple[str, str, object, str]]:
    """Every limit the loader and its readers enforce: (module, constant, value, what it
    bounds, with ``{}`` for the value). A test checks that every ``MAX_`` constant of
    ``frictex.textures`` is here."""
    from frictex.device.structures import beam
    from frictex.textures import ahap, clips, hatt, keys, raster_io, schema, toml_safe
    table = [
        (toml_safe, "MAX_FILE_BYTES", "a texture file (and a mode table): at most {}"),
        (toml_safe, "MAX_NESTING", "arrays and inline tables nested at most {} deep"),
        (keys, "MAX_LAYERS", "at most {} `[[layer]]` tables in a scene"),
        (keys, "MAX_MM", "positions and sizes: at most {} mm in magnitude"),
        (keys, "MAX_ANGLE_DEG", "angles: -{0} to {0} degrees"),
        (keys, "MAX_FORCE_N", "forces: at most {} N"),
        (keys, "MAX_UM", "vibration amplitudes: at most {} um"),
        (keys, "MAX_PX", "the display: at most {} px along each side"),
        (keys, "MAX_MODE_ORDER", "a structure's mode orders: at most {}"),
        (beam, "MAX_MODES", "a structure's modes (`orders`, or a mode table's columns): at most {}"),
        (schema, "MAX_MAGNITUDE", "any other number without a range of its own: at most {} in "
                                  "magnitude"),
        (keys, "MAX_PATH_CHARS", "a path to a file the scene names: at most {} characters"),
        (raster_io, "MAX_FILE_BYTES", "an image or height map file: at most {}"),
        (raster_io, "MAX_PIXELS", "an image or height map: at most {} pixels"),
        (raster_io, "MAX_SCENE_BYTES", "decoded images and height maps of one scene together: "
                                       "at most {}"),
        (clips, "MAX_CLIP_S", "a clip: at most {} s long"),
        (ahap, "MAX_AHAP_BYTES", "an AHAP file: at most {}"),
        (ahap, "MAX_ITEMS", "an AHAP file: at most {} pattern entries and as many curve points"),
        (ahap, "MAX_EVENTS_S", "an AHAP clip's events: at most {} s of playing in all"),
        (hatt, "MAX_HATT_BYTES", "a HaTT model file: at most {}"),
        (hatt, "MAX_MODELS", "a HaTT model: at most {} vertices"),
        (hatt, "MAX_FIT_VERTICES", "a HaTT model: at most {} vertices refitted"),
        (hatt, "MAX_ORDER", "a HaTT model's AR or MA order: at most {}"),
        (hatt, "MAX_VARIANCE", "a HaTT model's excitation variance: at most {} (m/s^2)^2"),
        (hatt, "MAX_RING_S", "a HaTT model vertex's filter: poles within radius exp(-1 / ({} s "
                             "x rate)), 0.9999 at 10 kHz (a resonance ringing at most that long)"),
        (schema, "MAX_PROBLEMS", "`frictex validate` lists at most {} problems and as many "
                                 "warnings of a file, then says the rest are not listed"),
        (schema, "MAX_SHOWN", "a value shown in a message: cut to {} characters"),
        (toml_safe, "MAX_TOML_MESSAGE", "a TOML syntax error: the parser's message cut to {} "
                                        "characters"),
    ]
    return [(module.__name__, name, getattr(module, name), text) for module, name, text in table]


def limits_section() -> str:
    """The loader's limits, one line each, from their constants."""
    lines = ["### Limits", "", "What the loader accepts at most (beyond a limit, an error "
             "names the file and the key), and how much its messages show:", ""]
    lines += [f"- {text.format(_size(value))}" for _, _, value, text in limits()]
    return "\n".join(lines) + "\n"


def _range(spec) -> str:
    low = (f"> {spec.gt:g}" if getattr(spec, "gt", None) is not None
           else f">= {spec.ge:g}" if getattr(spec, "ge", None) is not None else "")
    high = (f"< {spec.lt:g}" if getattr(spec, "lt", None) is not None
            else f"<= {spec.le:g}" if getattr(spec, "le", None) is not None else "")
    return ", ".join(part for part in (low, high) if part)


def _hex(rgb) -> str:
    """A linear RGB colour (the loader's form) as the ``"#rrggbb"`` sRGB a file writes."""
    def encode(c: float) -> int:
        v = 12.92 * c if c <= 0.0031308 else 1.055 * c ** (1 / 2.4) - 0.055
        return round(min(max(v, 0.0), 1.0) * 255)
    return '"#' + "".join(f"{encode(c):02x}" for c in rgb) + '"'


def _default(spec) -> str:
    value = spec.default
    if value is S.REQUIRED:
        return "*required*"
    if value is None:
        return spec.rule
    if isinstance(spec, S.Colour):
        return _hex(value)
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float) and math.isfinite(value):
        return f"{value:g}"
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, tuple):
        return "[" + ", ".join(f"{v:g}" if isinstance(v, float) else str(v) for v in value) + "]"
    return str(value)


def _kind(spec) -> str:
    if isinstance(spec, S.Num):
        return f"number ({spec.unit})"
    if isinstance(spec, S.Int):
        return f"integer ({spec.unit})"
    if isinstance(spec, S.Choice):
        return "one of " + ", ".join(f"`{o}`" for o in spec.options)
    if isinstance(spec, S.Text):
        return f"text (at most {spec.max_len} characters{', may span lines' if spec.lines else ''})"
    if isinstance(spec, S.Flag):
        return "true or false"
    if isinstance(spec, S.Colour):
        return 'colour: "#rrggbb" or "#rgb" (sRGB, hexadecimal)'
    if isinstance(spec, S.Selector):
        return ("finger selector: `any`, a finger number `1`, `2`, ... (order of touch-down), "
                "or " + ", ".join(f"`{s}`" for s in model.POSITIONAL_SELECTORS))
    if isinstance(spec, S.NumList):
        return f"list of at least {spec.min_len} numbers ({spec.item.unit})"
    if isinstance(spec, S.Rows):
        return f"list of rows of numbers ({spec.item.unit})"
    raise TypeError(f"no description for {type(spec).__name__}")


def _table(title: str, specs: dict) -> list[str]:
    lines = [f"### {title}", "", "| key | meaning | value | range | default |",
             "|---|---|---|---|---|"]
    for key, spec in specs.items():
        if isinstance(spec, S.Retired):
            lines.append(f"| `{key}` | no longer used: accepted, ignored, with a warning "
                         f"({spec.why}) | - | - | - |")
            continue
        inner = spec.item if isinstance(spec, (S.NumList, S.Rows)) else spec
        lines.append(f"| `{key}` | {spec.doc} | {_kind(spec)} | {_range(inner) or '-'} "
                     f"| {_default(spec)} |")
    return lines + [""]


def sections() -> list[tuple[str, dict]]:
    """(title, key table) for every table a texture file may hold, in file order."""
    out = [("Top level", K.TOP), ("[display]", K.DISPLAY), ("[device]", K.DEVICE),
           ("[device.friction]", K.FRICTION), ("[device.fitted]", K.FITTED),
           ("[device.calibration]", K.CALIBRATION)]
    out += [(f"[device.structure] for profile = \"{profile}\"", specs)
            for profile, specs in K.STRUCTURES.items()]
    out.append(("[device.driving] (travelling-wave profiles)", K.DRIVING))
    out.append(("[[layer]]: every layer", K.COMMON))
    out += [(f"[[layer]] type = \"{kind}\"", specs) for kind, specs in K.LAYER_KEYS.items()]
    out += [("[layer.region]: a rectangle", K.RECT_REGION), ("[layer.region]: a disc", K.DISC_REGION),
            ("[layer.visual]", K.VISUAL)]
    return out


def example_files() -> dict[str, str]:
    """Every example file on the page, by name (the walk-through's and one per layer type)."""
    return {**PLANK, **{f"{kind}-example": text for kind, text in EXAMPLES.items()}}


def examples_section() -> str:
    """A complete file per layer type, as the tests validate and replay them."""
    lines = ["## Worked examples, one per layer type", "",
             "Each is a whole file; tests validate and replay every one (the files they name, "
             "`raster-map.png`, `clips/tick-then-buzz.ahap`, are in `textures/library/`; "
             "`wood.xml` is any HaTT model: its elements, and a complete one to copy, are in "
             "[`AUTHORING.md`](AUTHORING.md#recorded-textures-type--recorded), \"The model "
             "file, element by element\").", ""]
    for kind, text in EXAMPLES.items():
        lines += [f"### `{kind}`", "", f"<!-- example: {kind}-example -->", "```toml",
                  text.rstrip("\n"), "```", ""]
    return "\n".join(lines)


def render() -> str:
    """The whole page (Markdown)."""
    lines = INTRO.splitlines() + [""]
    lines += FIRST.format(plank_first=PLANK["plank-first"], plank=PLANK["plank"]).splitlines()
    lines += [""] + _angle_figure().splitlines() + [""]
    lines += files_section().splitlines() + [""] + limits_section().splitlines() + [""]
    lines += ["## Every table and key", ""]
    for title, specs in sections():
        lines += _table(title, specs)
    lines += examples_section().splitlines()
    return "\n".join(lines).rstrip() + "\n"


if __name__ == "__main__":
    print(render(), end="")

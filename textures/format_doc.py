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

INTRO = """# Texture files: every table and key

One scene per TOML file. This page is generated from the loader's key tables
(`textures/keys.py`) by `python -m frictex.textures.format_doc`, and a test keeps the two equal:
every key the loader accepts is here, with its unit, range and default, and no other.
`frictex validate FILE` checks a file against it and names the file, line and field of
every problem. The grammar's overview and its worked examples are at the top of
`textures/loader.py` and in `textures/library/*.toml`.

Units are in the key names (`_mm`, `_um` zero-to-peak, `_n`, `_deg`, `_s`); relative
friction μ' = μ(w)/μ(0) in (0, 1] (seed 003, eq 1). *required* means the key has no
default. Ranges are inclusive unless written with `<` or `>`.
"""


def files_section() -> str:
    """What a texture file may name and how those files are read (from the readers' limits)."""
    from frictex.device.safe_text import MAX_SHOWN
    from frictex.textures import ahap, hatt, heights, raster_io, schema, toml_safe
    from frictex.textures.outside import ALLOW_OUTSIDE_ENV

    mib = 1 << 20
    paragraphs = [
        "`image` (raster and height-map layers), `model` (recorded layers), `file` (AHAP "
        "clips) and `[device.structure] modes_file` name files by a path relative to the "
        "texture file, **in its own folder or below**. An absolute path, a path whose `..` "
        "leads out of the folder, or a symbolic link that leads out is an error naming the key. "
        "Only for files you trust: `--allow-outside` (on `validate`, `replay`, `preview`, "
        f"`demo` and `batch`), or `{ALLOW_OUTSIDE_ENV}=1` in the environment, lifts the rule.",
        "Every file is opened only if it is a regular file (never a FIFO, a device such as "
        "`/dev/zero`, a socket or a folder), and read up to a size: the texture file "
        f"{toml_safe.MAX_FILE_BYTES // mib} MiB, an image or height map "
        f"{raster_io.MAX_FILE_BYTES // mib} MiB, a HaTT model {hatt.MAX_HATT_BYTES // mib} MiB, "
        f"an AHAP clip {ahap.MAX_AHAP_BYTES // mib} MiB, a mode table "
        f"{toml_safe.MAX_FILE_BYTES // mib} MiB.",
        "Images and height maps are PNG files and nothing else: the PNG signature is checked "
        "before any image library sees the bytes (an EPS or TIFF file named `.png` is "
        "refused). Their size is read from the PNG header before decoding: at most "
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
        "bounded by the cost of the fits, checked before the first.",
        "Messages never carry a file's contents: the values they show are escaped (a control "
        "character such as ESC is shown as the four characters `\\x1b`) and cut to "
        f"{schema.MAX_SHOWN} characters (keys and strings of the texture file) or {MAX_SHOWN} "
        "(cells of the files it names), ending with `...`; a row that is not what the file "
        "should hold is described, not printed.",
    ]
    return "\n\n".join(["## Files a texture file names"]
                        + [textwrap.fill(p, 90, break_on_hyphens=False) for p in paragraphs]) + "\n"


def _range(spec) -> str:
    low = (f"> {spec.gt:g}" if getattr(spec, "gt", None) is not None
           else f">= {spec.ge:g}" if getattr(spec, "ge", None) is not None else "")
    high = (f"< {spec.lt:g}" if getattr(spec, "lt", None) is not None
            else f"<= {spec.le:g}" if getattr(spec, "le", None) is not None else "")
    return ", ".join(part for part in (low, high) if part)


def _default(spec) -> str:
    value = spec.default
    if value is S.REQUIRED:
        return "*required*"
    if value is None:
        return "none (derived, see the loader's grammar)"
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
        return "colour: [r, g, b] in 0..1 or \"#rrggbb\""
    if isinstance(spec, S.Selector):
        return ("finger selector: `any`, a finger number `1`, `2`, ... (order of touch-down), "
                "or " + ", ".join(f"`{s}`" for s in model.POSITIONAL_SELECTORS))
    if isinstance(spec, S.NumList):
        return f"list of at least {spec.min_len} numbers ({spec.item.unit})"
    if isinstance(spec, S.Rows):
        return f"list of rows of numbers ({spec.item.unit})"
    raise TypeError(f"no description for {type(spec).__name__}")


def _table(title: str, specs: dict) -> list[str]:
    lines = [f"## {title}", "", "| key | value | range | default |", "|---|---|---|---|"]
    for key, spec in specs.items():
        if isinstance(spec, S.Retired):
            lines.append(f"| `{key}` | no longer used: accepted, ignored, with a warning ({spec.why}) "
                         f"| - | - |")
            continue
        inner = spec.item if isinstance(spec, (S.NumList, S.Rows)) else spec
        lines.append(f"| `{key}` | {_kind(spec)} | {_range(inner) or '-'} | {_default(spec)} |")
    return lines + [""]


def sections() -> list[tuple[str, dict]]:
    """(title, key table) for every table a texture file may hold, in file order."""
    out = [("Top level", K.TOP), ("[display]", K.DISPLAY), ("[device]", K.DEVICE),
           ("[device.friction]", K.FRICTION), ("[device.calibration]", K.CALIBRATION)]
    out += [(f"[device.structure] for profile = \"{profile}\"", specs)
            for profile, specs in K.STRUCTURES.items()]
    out.append(("[device.driving] (travelling-wave profiles)", K.DRIVING))
    out.append(("[[layer]]: every layer", K.COMMON))
    out += [(f"[[layer]] type = \"{kind}\"", specs) for kind, specs in K.LAYER_KEYS.items()]
    out += [("[layer.region]: a rectangle", K.RECT_REGION), ("[layer.region]: a disc", K.DISC_REGION),
            ("[layer.visual]", K.VISUAL)]
    return out


def render() -> str:
    """The whole page (Markdown)."""
    lines = INTRO.splitlines() + [""] + files_section().splitlines() + [""]
    for title, specs in sections():
        lines += _table(title, specs)
    return "\n".join(lines).rstrip() + "\n"


if __name__ == "__main__":
    print(render(), end="")

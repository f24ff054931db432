"""The texture file format's reference page, generated from the loader's own key tables.

``textures/FORMAT.md`` is this module's output; a test compares the two, so the page
cannot drift from what ``textures.loader`` accepts. Regenerate it after changing a key:

    .venv/bin/python -m frictex.textures.format_doc > textures/FORMAT.md
"""

from __future__ import annotations

import math

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
    lines = INTRO.splitlines() + [""]
    for title, specs in sections():
        lines += _table(title, specs)
    return "\n".join(lines).rstrip() + "\n"


if __name__ == "__main__":
    print(render(), end="")

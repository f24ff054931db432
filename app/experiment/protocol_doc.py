"""The protocol format's reference page, generated from the parser's own key tables.

``app/experiment/PROTOCOL_FORMAT.md`` is this module's output; a test compares the two,
so the page cannot drift from what ``app.experiment.protocol`` accepts. Regenerate it
after changing a key:

    .venv/bin/python -m frictex.app.experiment.protocol_doc > app/experiment/PROTOCOL_FORMAT.md
"""

from __future__ import annotations

from frictex.app.experiment import protocol as P
from frictex.textures.format_doc import _default, _kind, _range

INTRO = """# Protocol files: every table and key

One experiment per TOML file (`frictex experiment PROTOCOL.toml`). This page is generated
from the parser's key tables (`app/experiment/protocol.py`) by
`python -m frictex.app.experiment.protocol_doc`, and a test keeps the two equal. The
grammar's overview, the methods and how trials are drawn are at the top of
`app/experiment/protocol.py`; worked examples are in `app/experiment/protocols/*.toml`.
`frictex experiment PROTOCOL.toml --check` checks a file and names the file, line and
field of every problem.

*required* means the key has no default. Ranges are inclusive unless written with `<` or
`>`. Scenes are texture files (`textures/FORMAT.md`): a bundled name or a path relative
to the protocol file.
"""


def _describe(spec) -> tuple[str, str, str]:
    if isinstance(spec, P.Names):
        return ("list of distinct names, each one of " + ", ".join(f"`{o}`" for o in spec.options),
                "-", "none")
    inner = spec.item if isinstance(spec, P.NumList) else spec
    span = _range(inner) or "-"
    if isinstance(spec, P.Int):
        span = ", ".join(part for part in (f">= {spec.ge}" if spec.ge is not None else "",
                                           f"<= {spec.le}" if spec.le is not None else "") if part)
    default = ("none (see the grammar in `app/experiment/protocol.py`)" if spec.default is None
               else _default(spec))
    return _kind(spec), span or "-", default


def sections() -> list[tuple[str, dict]]:
    """(title, key table) for every table a protocol file may hold, in file order."""
    return [("Top level", P.TOP), ("[stimuli]: one scene, a parameter varied", P.STIMULI),
            ("[[stimulus]]: a list of scenes (magnitude only)", P.STIMULUS),
            ("[presentation]", P.PRESENTATION), ("[staircase]", P.STAIRCASE),
            ("[scale] (magnitude only)", P.SCALE), ("[analysis]", P.ANALYSIS)]


def render() -> str:
    """The whole page (Markdown)."""
    lines = INTRO.splitlines() + [""]
    for title, specs in sections():
        lines += [f"## {title}", "", "| key | value | range | default |", "|---|---|---|---|"]
        for key, spec in specs.items():
            kind, span, default = _describe(spec)
            lines.append(f"| `{key}` | {kind} | {span} | {default} |")
        lines.append("")
    return "\n".join(lines).rstrip() + "\n"


if __name__ == "__main__":
    print(render(), end="")

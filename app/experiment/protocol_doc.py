"""The protocol format's reference page, generated from the parser's own key tables.

``app/experiment/PROTOCOL_FORMAT.md`` is this module's output; a test compares the two,
so the page cannot drift from what ``app.experiment.protocol`` accepts. Regenerate it
after changing a key:

    .venv/bin/python -m frictex.app.experiment.protocol_doc > app/experiment/PROTOCOL_FORMAT.md
"""

from __future__ import annotations

from dataclasses import replace

from frictex.app.experiment import protocol as P
from frictex.textures.schema import REQUIRED

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

`levels` are distinct and none is the reference (magnitude rates the reference as a
stimulus of its own; a same-different pair of the two would be "same"). 2afc asks which
of two is larger, so its levels lie above the reference; same-different's may lie on
either side (d' per level does not depend on the sign of the difference). Stimuli are
named by their value to 10 significant digits (`depth=0.3`), so levels (and a
staircase's `start` and `min` added to the reference) must differ from the reference
and each other within those digits.

`frictex validate --perception` and the simulated participant
(`--participant simulated:weber=K`) do not measure a `depth` or a clip `level` alike.
The check compares the friction levels the two stimuli play (mu' = mu_high - depth on a
grating), dmu'/mu' of the higher, with the Weber fraction 0.11 of Gueorguiev et al. 2017,
which is a change of friction relative to its level: on grating-5mm, depths 0.3 and 0.35
play mu' 0.7 and 0.65, 7.14 % apart, and are warned of. The simulated participant judges
the contrast felt (max - min of mu', the depth itself) and tells apart 75 % of the time
contrasts in the ratio 1 + K: 0.35 / 0.3 = 1.17 is beyond 1.11, so with
`simulated:weber=0.11` it answers that pair correctly more often than 75 %. The check
follows the threshold's source; the simulated participant's answers for `depth` and
`level` overstate what a finger tells apart wherever mu' stays well above 0. Periods are
compared alike by both (dp/p of the smaller).

At the window (`--participant window`) a `[scale]` of one key per value (1 to 10, 0 for
10; 0 to 9) is answered by a key or a button; any wider one (0 to 10, 0 to 100, one
below 0) by typing the rating, shown as typed (Backspace or the left arrow corrects,
minus changes the sign; a rating off the scale is refused on screen), and Enter: no
scale has values out of reach. A scale spans at most 1000 steps (max - min <= 1000).

A session folder (`--out DIR`) keeps a copy of the protocol (`DIR/protocol.toml`) and of
the scenes it names by a path in its folder or below, under the same relative names
(with the files they name), so `frictex experiment DIR/protocol.toml --out DIR --resume`
goes on after the originals moved; a scene outside the protocol's folder
(`--allow-outside`) or named like a file of the session (`protocol.toml`, `stimuli/`,
`trials/` ...) is not copied. session.json keeps each scene's sha256 (`scene_sha256`),
and `--resume` refuses a scene that changed since the session started, naming it.
"""


#: results.csv's columns (``session.RESULT_COLUMNS``): what each holds, and its unit
RESULT_COLUMNS = {
    "trial": "the trial's 1-based position in the session, practice included",
    "practice": "1 for a practice trial (neither adapting a staircase nor analysed), else 0",
    "stimuli": "the stimulus names in presentation order (first or left interval first), "
               "separated by `\\|`",
    "value": "the comparison's value of `vary` (magnitude estimation: the stimulus's; "
             "same-different: level B's, in AA and BB pairs too), in `vary`'s unit; blank "
             "where nothing is varied (a list of scenes)",
    "difference": "`value` minus `reference`, in `vary`'s unit; 0 for a same-different AA "
                  "or BB pair; blank for magnitude estimation",
    "answer": "the correct response: the interval holding the comparison (`1` or `2`) for "
              "2afc and staircase, `same` or `different` for same-different; blank for "
              "magnitude estimation",
    "response": "the participant's response: `1` or `2`, `same` or `different`, or the "
                "rating (an integer of [scale])",
    "correct": "1 when `response` is `answer`, else 0; blank where no answer is correct "
               "(magnitude estimation)",
    "rt_s": "the response time: from the end of the trial's last interval to the answer (s)",
    "ended_utc": "when the trial was answered (ISO 8601, UTC, to the millisecond)",
    "contact_1_s": "how long interval 1 was touched, a finger down (s); blank for an "
                   "interval the trial has not",
    "contact_2_s": "how long interval 2 was touched, a finger down (s); blank for an "
                   "interval the trial has not (a magnitude trial has one)",
}


def _columns() -> list[str]:
    """The results.csv section: a table of its columns and the units of `vary`."""
    units = ", ".join(f"`{vary}`: {unit}" for vary, unit in P.VARY_UNITS.items())
    lines = ["## results.csv: one row per trial answered", "",
             f"The unit of `vary` (so of `value` and `difference`): {units}; session.json "
             f"keeps it as `design.vary_unit`.", "", "| column | holds |", "|---|---|"]
    return lines + [f"| `{name}` | {text} |" for name, text in RESULT_COLUMNS.items()] + [""]


def _number(value) -> str:
    return str(value) if isinstance(value, int) else f"{value:g}"


def _range(spec) -> str:
    """The bounds of a number: ``> 0, <= 600``; "-" for none."""
    low = (f"> {_number(spec.gt)}" if getattr(spec, "gt", None) is not None
           else f">= {_number(spec.ge)}" if getattr(spec, "ge", None) is not None else "")
    high = (f"< {_number(spec.lt)}" if getattr(spec, "lt", None) is not None
            else f"<= {_number(spec.le)}" if getattr(spec, "le", None) is not None else "")
    return ", ".join(part for part in (low, high) if part) or "-"


def _default(spec) -> str:
    value = spec.default
    if value is REQUIRED:
        return "*required*"
    if value is None:
        return "none (see the grammar in `app/experiment/protocol.py`)"
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, tuple):
        return "[" + ", ".join(f"{v:g}" for v in value) + "]" if value else "none"
    return f"{value:g}"


def _describe(spec) -> tuple[str, str, str]:
    """(what the value is, its range, its default) of a key."""
    if spec is P.STIMULI["reference"]:  # no default, but required wherever `vary` is given
        kind, span, _ = _describe(replace(spec, default=REQUIRED))
        return kind, span, "*required* with `vary`"
    if isinstance(spec, P.Names):
        return ("list of distinct names, each one of " + ", ".join(f"`{o}`" for o in spec.options),
                "-", _default(spec))
    if isinstance(spec, P.NumList):
        return (f"list of at least {spec.min_len} numbers ({spec.item.unit})", _range(spec.item),
                _default(spec) if spec.default != () else "[]")
    if isinstance(spec, P.Num):
        return f"number ({spec.unit})", _range(spec), _default(spec)
    if isinstance(spec, P.Int):
        return f"integer ({spec.unit})", _range(spec), _default(spec)
    if isinstance(spec, P.Choice):
        return "one of " + ", ".join(f"`{o}`" for o in spec.options), "-", _default(spec)
    if isinstance(spec, P.Flag):
        return f"true or false: {spec.doc}", "-", str(spec.default).lower()
    if isinstance(spec, P.Text):
        lines = ", may span lines" if spec.lines else ""
        return f"text (at most {spec.max_len} characters{lines})", "-", _default(spec)
    raise TypeError(f"no description for {type(spec).__name__}")


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
    lines += _columns()
    return "\n".join(lines).rstrip() + "\n"


if __name__ == "__main__":
    print(render(), end="")

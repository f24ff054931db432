"""TOML hardened for files from strangers: size, encoding and nesting checked before
``tomllib`` sees the text, and its errors turned into problems with a line.

``tomllib`` recurses on nested brackets (a deep file raises RecursionError), takes
quadratic time on long dotted keys (a 20,000-part key: 9 s) and refuses integers of more
than 4300 digits with a bare ValueError; each is caught here first, as a one-line problem.
"""

from __future__ import annotations

import ast
import os
import re
import sys
import tomllib
from pathlib import Path

from frictex.device.safe_text import escape
from frictex.textures.errors import Problem, bracket_peak
from frictex.textures.library import UnreadableText, read_utf8
from frictex.textures.schema import Reader

#: Largest texture file read (bytes): scenes are a few kB; a long ``samples`` list fits.
MAX_FILE_BYTES = 1 << 20
#: Deepest nesting of arrays and inline tables accepted (the grammar needs 3: rows of a
#: calibration table inside [device.calibration]).
MAX_NESTING = 16
#: Longest part of tomllib's own message shown (characters, escaped).
MAX_TOML_MESSAGE = 120


def read_text(path: Path, r: Reader) -> str | None:
    """The file's text (``textures.library.read_utf8``), or None with the problem reported."""
    try:
        return read_utf8(path, MAX_FILE_BYTES)
    except UnreadableText as exc:
        r.problems.append(Problem(r.label, exc.line, "", f"{exc}; expected a .toml texture file"))
        return None


_TOML_POSITION = re.compile(r"\s*\(at line (\d+), column (\d+)\)\s*$")
_AT_END = "(at end of document)"
#: tomllib's words for an array whose closing bracket never came
_UNCLOSED = "Unclosed array"
#: a single character as tomllib quotes it, by its repr (``'\\n'``, ``'\\x1b'``, ``'a'``)
_REPR_CHAR = re.compile(r"'(?:\\(?:x[0-9a-f]{2}|u[0-9a-f]{4}|U[0-9a-f]{8}|[nrt\\'])|[^'\\])'")
_LONG_DIGITS = re.compile(r"\d{%d,}" % (sys.get_int_max_str_digits() or 4300))


def parse_toml(text: str, r: Reader) -> dict | None:
    too_deep = (f"arrays, inline tables or dotted keys nested more than {MAX_NESTING} deep; "
                f"a texture file needs at most 4 levels")
    # checked before parsing: tomllib recurses on brackets and takes quadratic time on
    # long dotted keys (a 20,000-part key: 9 s)
    deep = deepest_line(text)
    if deep is not None:
        r.problems.append(Problem(r.label, deep, "TOML syntax", too_deep))
        return None
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        # a line is quoted only from a TOML file (its real name, links followed): a path
        # mistaken for a texture or protocol file (/etc/passwd) must not have its text shown
        toml_file = os.path.realpath(str(r.label)).lower().endswith(".toml")
        line, message = syntax_problem(str(exc), text, quote=toml_file)
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
        r.problems.append(Problem(r.label, deepest_line(text), "TOML syntax", too_deep))
        return None
    return doc


def syntax_problem(message: str, text: str, quote: bool = True) -> tuple[int | None, str]:
    """(line, message) of tomllib's error ``message`` about ``text``: its position as a
    line number (for one at the end of the document, the last line that is not blank),
    the column and the line's own text after the message (escaped and cut,
    ``device.safe_text.escape``), and a character it quotes by its Python repr shown
    escaped once (``'\\n'``, not ``'\\\\n'``). An array left open is placed at the line
    that opened it, where tomllib's position (the line where the file went on without
    closing it) is given in the message. ``quote``: whether the line's text is shown."""
    lines = text.splitlines()
    m = _TOML_POSITION.search(message)
    if m:
        line, where = int(m.group(1)), f" (column {m.group(2)})"
    elif message.endswith(_AT_END):
        line = max((k for k, part in enumerate(lines, start=1) if part.strip()), default=1)
        where = " (at the end of the file)"
    else:
        line, where = None, ""
    head = message[:m.start()] if m else message.removesuffix(_AT_END).rstrip()
    if head == _UNCLOSED and line is not None:  # tomllib stops where the file goes on
        opened = opened_line(lines, line if m else len(lines) + 1)
        if opened is not None and opened < line:
            stop = f"line {line}, column {m.group(2)}" if m else "the end of the file"
            line, where = opened, f" (opened here; still open at {stop})"
    # tomllib's message may quote a key of the file (a duplicate table): escaped and cut
    shown = escape(_REPR_CHAR.sub(lambda c: f"'{ast.literal_eval(c.group())}'", head),
                   MAX_TOML_MESSAGE) + where
    if quote and line is not None and line <= len(lines) and lines[line - 1].strip():
        shown += f": {escape(lines[line - 1].strip())}"
    return line, shown


def opened_line(lines: list[str], before: int) -> int | None:
    """The line (from 1) that opened the innermost bracket still open at the start of line
    ``before`` (comments and strings skipped, as :func:`deepest_line` reads them); None
    when none is open there."""
    depth, in_string, opened = 0, None, []  # opened: a line per bracket open
    for number, line in enumerate(lines[:before - 1], start=1):
        depth, in_string, _ = bracket_peak(line, depth, in_string)
        del opened[max(depth, 0):]
        opened += [number] * (depth - len(opened))
    return opened[-1] if opened else None


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


def deepest_line(text: str) -> int | None:
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


"""Problems found in texture files, where they are, and the package's exception root.

A :class:`Problem` names the file, the line and the field (``layer[2].period_mm``) and
says what is wrong; ``str(problem)`` is the one-line form ``frictex validate`` prints
after ``frictex: error:`` (or ``frictex: warning:``)::

    grating.toml:14: layer[2].period_mm: -5.0 is outside [0.01, 10000] (mm)
    grating.toml:9: layer[1].mu_low: asks for mu' down to 0.4, but the device ...

``tomllib`` gives no line numbers for values, so :class:`Locator` rebuilds a map from
key paths to lines by scanning the source text: ``[table]`` and ``[[array]]`` headers,
``key = value`` lines (dotted keys included), skipping the insides of multi-line
strings and arrays. Keys inside inline tables and arrays have no line of their own and
resolve to their parent's line.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from frictex.device.errors import InputError
from frictex.device.safe_text import escape, escape_path

#: A key path into parsed TOML: table keys (str) and array-of-tables indices (int, 0-based).
KeyPath = tuple[str | int, ...]


def field_name(path: KeyPath) -> str:
    """The field as a user reads it: ``("layer", 1, "period_mm")`` -> ``layer[2].period_mm``.

    Array indices are shown 1-based: ``layer[1]`` is the first ``[[layer]]`` in the file.
    The empty path (the file as a whole) gives "". Keys are escaped and cut to 40
    characters (``device.safe_text.escape``): an unknown key can be as long as the file,
    and made of terminal escapes.
    """
    out = ""
    for part in path:
        if isinstance(part, int):
            out += f"[{part + 1}]"
        else:
            out += ("." if out else "") + escape(part, 40)
    return out


@dataclass(frozen=True)
class Problem:
    """One problem (or warning) in a texture file.

    ``line`` is 1-based, or None when the thing is missing from the file altogether.
    """

    file: str
    line: int | None
    field: str
    message: str
    warning: bool = False

    def __str__(self) -> str:
        file = escape_path(self.file)
        where = f"{file}:{self.line}:" if self.line is not None else f"{file}:"
        field = f" {self.field}:" if self.field else ""
        return f"{where}{field} {self.message}"


class TextureError(InputError):
    """A texture file (or bundled name) that cannot be used.

    ``problems`` lists every problem found in the file (empty when the error is not
    about a file's contents, e.g. an unknown bundled name). ``str()`` is one line: the
    first problem and how many more there are.
    """

    def __init__(self, message_or_problems: str | list[Problem]):
        if isinstance(message_or_problems, str):
            self.problems: list[Problem] = []
            message = message_or_problems
        else:
            self.problems = list(message_or_problems)
            message = str(self.problems[0])
            more = len(self.problems) - 1
            if more:
                message += (f" (and {more} more problem{'s' if more > 1 else ''}; "
                            f"frictex validate {escape_path(self.problems[0].file)} lists them all)")
        super().__init__(message)


_BARE = r"[A-Za-z0-9_-]+"
_BASIC = r'"(?:[^"\\]|\\.)*"'
_LITERAL = r"'[^']*'"
_SIMPLE_KEY = f"(?:{_BARE}|{_BASIC}|{_LITERAL})"
_DOTTED_KEY = rf"{_SIMPLE_KEY}(?:\s*\.\s*{_SIMPLE_KEY})*"
_KEY_PART = re.compile(rf"\s*({_SIMPLE_KEY})\s*(?:\.|$)")
_ARRAY_HEADER = re.compile(rf"^\s*\[\[\s*({_DOTTED_KEY})\s*\]\]")
_TABLE_HEADER = re.compile(rf"^\s*\[\s*({_DOTTED_KEY})\s*\]")
_KEY_VALUE = re.compile(rf"^\s*({_DOTTED_KEY})\s*=(.*)$")


def _split_key(dotted: str) -> list[str]:
    """``a."b.c".d`` -> ``["a", "b.c", "d"]`` (quoted parts unquoted; escapes kept simple)."""
    parts, pos = [], 0
    while pos < len(dotted):
        m = _KEY_PART.match(dotted, pos)
        if m is None:
            break
        key = m.group(1)
        parts.append(key[1:-1] if key[0] in "\"'" else key)
        pos = m.end()
    return parts


def bracket_peak(text: str, depth: int, in_string: str | None) -> tuple[int, str | None, int]:
    """Carry bracket depth and multi-line-string state across ``text`` (one line).

    Comments, single-line strings and brackets inside strings are skipped. Returns the
    depth and string state after the line, and the deepest the line went.
    """
    i, n, peak = 0, len(text), depth
    while i < n:
        if in_string is not None:
            end = text.find(in_string, i)
            while end > 0 and in_string == '"""' and _escaped(text, end):
                end = text.find(in_string, end + 1)
            if end < 0:
                return depth, in_string, peak
            i, in_string = end + 3, None
            continue
        ch = text[i]
        if ch == "#":
            break
        if text.startswith('"""', i) or text.startswith("'''", i):
            in_string, i = text[i:i + 3], i + 3
        elif ch in "\"'":
            i = _string_end(text, i)
        else:
            depth += (ch in "[{") - (ch in "]}")
            peak = max(peak, depth)
            i += 1
    return depth, in_string, peak


def _escaped(text: str, pos: int) -> bool:
    """Whether the character at ``pos`` is preceded by an odd number of backslashes."""
    count = 0
    while pos - count - 1 >= 0 and text[pos - count - 1] == "\\":
        count += 1
    return count % 2 == 1


def _string_end(text: str, start: int) -> int:
    """Index just past the single-line string opening at ``start``."""
    quote = text[start]
    i = start + 1
    while i < len(text):
        if text[i] == quote and (quote == "'" or not _escaped(text, i)):
            return i + 1
        i += 1
    return len(text)


class Locator:
    """Key path -> 1-based line number, rebuilt from the source text of a TOML file."""

    def __init__(self, text: str):
        self._lines: dict[KeyPath, int] = {}
        arrays: dict[KeyPath, int] = {}
        table: KeyPath = ()
        depth, in_string = 0, None
        for number, line in enumerate(text.splitlines(), start=1):
            if depth > 0 or in_string is not None:
                depth, in_string, _ = bracket_peak(line, depth, in_string)
                continue
            if m := _ARRAY_HEADER.match(line):
                keys = _split_key(m.group(1))
                array = self._resolve(keys, arrays)
                arrays[array] = arrays.get(array, 0) + 1
                table = array + (arrays[array] - 1,)
                self._lines.setdefault(table, number)
            elif m := _TABLE_HEADER.match(line):
                table = self._resolve(_split_key(m.group(1)), arrays)
                self._lines.setdefault(table, number)
            elif m := _KEY_VALUE.match(line):
                path = table
                for key in _split_key(m.group(1)):
                    path = path + (key,)
                    self._lines.setdefault(path, number)
                depth, in_string, _ = bracket_peak(m.group(2), 0, None)

    @staticmethod
    def _resolve(keys: list[str], arrays: dict[KeyPath, int]) -> KeyPath:
        """Header keys -> path, stepping into the latest element of any array of tables."""
        path: KeyPath = ()
        for i, key in enumerate(keys):
            path = path + (key,)
            if i < len(keys) - 1 and path in arrays:
                path = path + (arrays[path] - 1,)
        return path

    def line(self, path: KeyPath) -> int | None:
        """The line defining ``path``; for a table only implied by its sub-tables' headers
        (``[layer.visual]`` makes ``layer`` a table), the first of those; else its nearest
        ancestor's; None if none is in the file."""
        if path and path not in self._lines:
            inside = [n for p, n in self._lines.items() if p[:len(path)] == path]
            if inside:
                return min(inside)
        while path:
            if path in self._lines:
                return self._lines[path]
            path = path[:-1]
        return None

"""The schema language of texture files: key types that check themselves, and the reader
that walks a parsed TOML table against a table of them.

A key table maps each key to its type (:class:`Num`, :class:`Int`, :class:`Choice`,
:class:`Text`, :class:`Flag`, :class:`Colour`, :class:`Selector`, :class:`NumList`,
:class:`Rows`, :class:`Retired`). Each type also carries its documentation for the
format page: ``doc`` (what the key means, with its convention) and, for a key whose
default depends on other keys (``default`` None), ``rule`` (how it is derived, or when it
is required). Each type's ``check(reader, value, path)`` returns the
checked value, or reports the problem to the :class:`Reader` and returns :data:`BAD`.
:meth:`Reader.table` checks a whole table: unknown keys (with a spelling suggestion),
missing required keys, defaults filled in. The key tables themselves are in
``textures.keys``; ``textures.format_doc`` prints them as ``textures/FORMAT.md``.

Values shown in messages come from :func:`show`, which escapes control characters and
cuts long values (``device.safe_text.escape``): a message never carries a file's
contents or a terminal escape.
"""

from __future__ import annotations

import datetime
import difflib
import math
import re
import unicodedata
from dataclasses import dataclass
from typing import Any

from frictex.device.safe_text import escape
from frictex.textures import model
from frictex.textures.errors import KeyPath, Locator, Problem, field_name

REQUIRED = object()  # spec default: the key must be given
BAD = object()       # parsed value of a key that had a problem (already reported)

#: Any number without its own bounds: at most this in magnitude.
MAX_MAGNITUDE = 1e6
#: Problems (and warnings) listed per file at most: beyond, the file is not a texture file.
MAX_PROBLEMS = 100
#: Longest value shown in a message (characters, escaped, the ellipsis included).
MAX_SHOWN = 40

_NUMBER_WITH_UNIT = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*([^\d\s].*)?$")
_HEX = re.compile(r"^#(?:[0-9a-fA-F]{3}|[0-9a-fA-F]{6})$")


def show(value) -> str:
    """A value as the TOML author wrote it, escaped and short (strings: at most
    :data:`MAX_SHOWN` characters inside the quotes)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return '"' + escape(value, MAX_SHOWN) + '"'
    if isinstance(value, dict):
        return "a table"
    if isinstance(value, list):
        text = "[" + ", ".join(show(v) for v in value[:4]) + (", ...]" if len(value) > 4 else "]")
        return text if len(text) <= 60 else f"a list of {len(value)} values"
    return escape(repr(value), MAX_SHOWN)


def kind(value) -> str:
    """The TOML type and value, for 'expected X, got Y' messages (or the Python type of
    a value no TOML gives, from a Scene built in code: ``frictex._inputs.checked_scene``)."""
    if isinstance(value, dict):
        return "a table"
    for types, name in ((bool, "the boolean"), (str, "the string"), ((int, float), "the number"),
                        (list, "the list")):
        if isinstance(value, types):
            return f"{name} {show(value)}"
    if isinstance(value, datetime.date | datetime.time):
        return f"the date/time {escape(value, MAX_SHOWN)}"
    return "None" if value is None else f"a value of type {escape(type(value).__name__, MAX_SHOWN)}"


def header(path: KeyPath) -> str:
    """The TOML header of the table at ``path``: ``[layer.region]`` for ("layer", 0,
    "region")."""
    return "[" + ".".join(p for p in path if isinstance(p, str)) + "]"


def did_you_mean(word: str, options) -> str:
    """`` (did you mean X?)`` for the closest of ``options`` (which are the program's own
    names, safe to print), or ""."""
    close = difflib.get_close_matches(word, list(options), n=1, cutoff=0.6)
    return f" (did you mean {close[0]}?)" if close else ""


def _srgb_to_linear(c: float) -> float:
    """sRGB transfer function, inverted (IEC 61966-2-1)."""
    return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4


@dataclass(frozen=True)
class Num:
    """A finite real number with optional bounds; ``unit`` is shown in messages."""

    unit: str
    default: Any = REQUIRED
    gt: float | None = None
    ge: float | None = None
    lt: float | None = None
    le: float | None = None
    doc: str = ""
    rule: str = ""

    def bounds_text(self) -> str:
        """The closed or open interval, e.g. ``(0, 1]``."""
        lower = f"{'(' if self.gt is not None else '['}{self.gt if self.gt is not None else self.ge:g}"
        upper = f"{self.lt if self.lt is not None else self.le:g}{')' if self.lt is not None else ']'}"
        return f"{lower}, {upper}"

    def _not_a_number(self, r: "Reader", value, path: KeyPath, items: list | None):
        hint = ""
        m = _NUMBER_WITH_UNIT.match(value) if isinstance(value, str) else None
        if m:
            key = next(p for p in reversed(path) if isinstance(p, str))
            number = escape(m.group(1), MAX_SHOWN)
            if items is not None:  # an element of a list: the list, that element unquoted
                i = path[-1]
                shown = [number if k == i else show(v) for k, v in enumerate(items)]
                lo, hi = max(0, i - 2), min(len(items), i + 3)
                number = ("[" + "..., " * (lo > 0) + ", ".join(shown[lo:hi])
                          + ", ..." * (hi < len(items)) + "]")
            lhs = f"{escape(key, MAX_SHOWN)} = " if items is None or isinstance(path[-2], str) else ""
            hint = f"; write the number without quotes{' or units' if m.group(2) else ''}: {lhs}{number}"
        return r.report(path, f"expected a number ({self.unit}), got {kind(value)}{hint}")

    def _out_of_bounds(self, v: float) -> str | None:
        lower = self.gt if self.gt is not None else self.ge
        upper = self.lt if self.lt is not None else self.le
        if (lower is None or upper is None) and abs(v) > MAX_MAGNITUDE:
            return (f"is beyond {MAX_MAGNITUDE:g} in magnitude ({self.unit}); no sensible "
                    f"value is that large")
        bad_low = (self.gt is not None and not v > self.gt) or (self.ge is not None and not v >= self.ge)
        bad_high = (self.lt is not None and not v < self.lt) or (self.le is not None and not v <= self.le)
        if (bad_low or bad_high) and lower is not None and upper is not None:
            return f"is outside {self.bounds_text()} ({self.unit}){self._in_metres(v, bad_low)}"
        if bad_low:
            return f"is not {'>' if self.gt is not None else '>='} {lower:g} ({self.unit})"
        if bad_high:
            return f"is not {'<' if self.lt is not None else '<='} {upper:g} ({self.unit})"
        return None

    def _in_metres(self, v: float, too_low: bool) -> str:
        """A hint for a length in mm too small that would fit written in metres."""
        if self.unit != "mm" or not too_low or v <= 0.0 or self._out_of_bounds(v * 1000.0):
            return ""
        return f"; in metres? {v:g} m = {v * 1000.0:g} mm"

    def check(self, r: "Reader", value, path: KeyPath, items: list | None = None):
        """``value`` checked (a float) or BAD (reported); ``items``: the list that holds
        it at ``path[-1]``, if it is an element of one (for the hint of a quoted number)."""
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            return self._not_a_number(r, value, path, items)
        v = float(value)
        if not math.isfinite(v):
            return r.report(path, f"{show(value)} is not a finite number ({self.unit})")
        problem = self._out_of_bounds(v)
        if problem is not None:
            return r.report(path, f"{show(value)} {problem}")
        return v


@dataclass(frozen=True)
class Int:
    """A whole number (a TOML integer) with optional bounds."""

    unit: str
    default: Any = REQUIRED
    ge: int | None = None
    le: int | None = None
    doc: str = ""
    rule: str = ""

    def check(self, r: "Reader", value, path: KeyPath):
        if isinstance(value, bool) or not isinstance(value, int):
            return r.report(path, f"expected an integer ({self.unit}), got {kind(value)}")
        if self.ge is not None and self.le is not None and not self.ge <= value <= self.le:
            return r.report(path, f"{show(value)} is outside [{self.ge}, {self.le}] ({self.unit})")
        if self.ge is not None and value < self.ge:
            return r.report(path, f"{show(value)} is not >= {self.ge} ({self.unit})")
        return value


@dataclass(frozen=True)
class Choice:
    """One of a fixed set of words."""

    options: tuple[str, ...]
    default: Any = REQUIRED
    doc: str = ""
    rule: str = ""

    def check(self, r: "Reader", value, path: KeyPath):
        if not isinstance(value, str):
            return r.report(path, f"expected one of {', '.join(self.options)}, got {kind(value)}")
        if value not in self.options:
            return r.report(path, f"{show(value)} is not one of {', '.join(self.options)}"
                                  f"{did_you_mean(value, self.options)}")
        return value


@dataclass(frozen=True)
class Text:
    """A string of at most ``max_len`` characters; ``lines``: may hold line breaks and tabs.
    Other control characters (NUL, escape, ...) are refused everywhere; a one-line string
    (a name, a file name) refuses format characters too (Unicode category Cf: bidi
    overrides such as U+202E, zero-width spaces, isolates), which make a name shown in a
    terminal or a table read other than it is."""

    default: Any = REQUIRED
    max_len: int = 200
    lines: bool = False
    doc: str = ""
    rule: str = ""

    def check(self, r: "Reader", value, path: KeyPath):
        if not isinstance(value, str):
            return r.report(path, f"expected a string, got {kind(value)}")
        allowed = "\t\n\r" if self.lines else ""
        bad = next((c for c in value if unicodedata.category(c) == "Cc" and c not in allowed), None)
        invisible = None if self.lines else next(
            (c for c in value if unicodedata.category(c) == "Cf"), None)
        if bad is None and invisible is not None:
            where = f"at character {value.index(invisible) + 1}"
            return r.report(path, f"holds the format character '{escape(invisible)}' {where} "
                                  "(invisible, or reorders the text shown); expected one line "
                                  "of visible text")
        if bad is not None:
            where = f"at character {value.index(bad) + 1}"
            return r.report(path, f"holds the control character '{escape(bad)}' {where}; expected "
                                  f"{'text' if self.lines else 'one line of text'}")
        if len(value) > self.max_len:
            return r.report(path, f"is {len(value):,} characters long; expected at most "
                                  f"{self.max_len:,}")
        return value


@dataclass(frozen=True)
class Flag:
    """true or false."""

    default: Any = REQUIRED
    doc: str = ""
    rule: str = ""

    def check(self, r: "Reader", value, path: KeyPath):
        if not isinstance(value, bool):
            return r.report(path, f"expected true or false, got {kind(value)}")
        return value


@dataclass(frozen=True)
class Colour:
    """``"#rrggbb"`` or ``"#rgb"`` (sRGB), checked into linear RGB in [0, 1]."""

    default: Any = REQUIRED
    doc: str = ""
    rule: str = ""

    def check(self, r: "Reader", value, path: KeyPath):
        if not isinstance(value, str) or not _HEX.match(value):
            return r.report(path, f'expected a colour "#rrggbb" or "#rgb", got {kind(value)}')
        digits = value[1:] if len(value) == 7 else "".join(2 * d for d in value[1:])
        return tuple(_srgb_to_linear(int(digits[i:i + 2], 16) / 255.0) for i in (0, 2, 4))


@dataclass(frozen=True)
class Selector:
    """A layer's ``fingers`` selector (see ``rendering.tracking.finger_select``)."""

    default: Any = REQUIRED
    doc: str = ""
    rule: str = ""

    def check(self, r: "Reader", value, path: KeyPath):
        words = ("any",) + model.POSITIONAL_SELECTORS
        expected = f'one of {", ".join(words)} or a finger number "1", "2", ...'
        if isinstance(value, int) and not isinstance(value, bool):
            value = str(value)  # fingers = 2 means what fingers = "2" means
        if not isinstance(value, str):
            return r.report(path, f"expected {expected}, got {kind(value)}")
        if value in words:
            return value
        if value.isdigit() and value.isascii():
            digits = value.lstrip("0")
            if not digits:
                return r.report(path, f'{show(value)}: finger numbers start at "1" '
                                      f"(the finger touching longest)")
            if len(digits) > 2:
                return r.report(path, f'{show(value)}: finger numbers go up to "99"')
            return digits
        return r.report(path, f"{show(value)} is not {expected}{did_you_mean(value, words)}")


@dataclass(frozen=True)
class NumList:
    """A list of numbers, each checked like ``item``; at least ``min_len`` of them."""

    item: Num
    min_len: int = 1
    default: Any = REQUIRED
    doc: str = ""
    rule: str = ""

    def check(self, r: "Reader", value, path: KeyPath):
        if not isinstance(value, list):
            return r.report(path, f"expected a list of numbers ({self.item.unit}), got {kind(value)}")
        if len(value) < self.min_len:
            return r.report(path, f"has {len(value)} value{'s' * (len(value) != 1)}, "
                                  f"needs at least {self.min_len}")
        out = [self.item.check(r, v, path + (i,), value) for i, v in enumerate(value)]
        return BAD if BAD in out else tuple(out)


@dataclass(frozen=True)
class Rows:
    """A list of lists of numbers (a table), each checked like ``item``."""

    item: Num
    default: Any = REQUIRED
    doc: str = ""
    rule: str = ""

    def check(self, r: "Reader", value, path: KeyPath):
        if not isinstance(value, list) or not all(isinstance(row, list) for row in value) or not value:
            return r.report(path, f"expected a list of rows (lists of numbers), got {kind(value)}")
        row_spec = NumList(self.item, 1)
        out = [row_spec.check(r, row, path + (i,)) for i, row in enumerate(value)]
        return BAD if BAD in out else tuple(out)


@dataclass(frozen=True)
class Retired:
    """A key an earlier release documented and this one no longer uses: accepted with any
    value and ignored, with one warning saying ``why`` (format 1 files written for that
    release keep loading)."""

    why: str


Spec = Num | Int | Choice | Text | Flag | Colour | Selector | NumList | Rows | Retired


class Reader:
    """Collects problems while turning parsed TOML into checked values.

    ``label`` names the file in every problem; ``locator`` (set once the text is parsed)
    finds the line of a key path.
    """

    def __init__(self, label: str, locator: Locator | None):
        self.label = label
        self.locator = locator
        self.problems: list[Problem] = []
        self.warnings: list[Problem] = []
        #: the keys of the table holding each sub-table read so far (``tables`` of
        #: :meth:`table`), by the sub-table's path: for the hint on a key written under
        #: a [sub.table] header that belongs above it
        self._outer: dict[KeyPath, list[str]] = {}

    def problem(self, path: KeyPath, message: str, warning: bool = False) -> Problem:
        """The problem (or warning) ``message`` at ``path``, with its line, unrecorded."""
        line = self.locator.line(path) if self.locator is not None else None
        return Problem(self.label, line, field_name(path), message, warning)

    def report(self, path: KeyPath, message: str, warning: bool = False) -> object:
        """Record a problem (or a warning) at ``path``; returns :data:`BAD`."""
        found = self.warnings if warning else self.problems
        if len(found) < MAX_PROBLEMS:
            found.append(self.problem(path, message, warning))
        elif len(found) == MAX_PROBLEMS:
            found.append(Problem(self.label, None, "", f"more than {MAX_PROBLEMS} "
                                                       f"{'warnings' if warning else 'problems'}; "
                                                       f"the rest are not listed", warning))
        return BAD

    def table(self, value, path: KeyPath, spec: dict[str, Spec], tables=()) -> dict | None:
        """Check that ``value`` is a table with only known keys; parse the ``spec`` keys.

        Returns key -> value (defaults filled in, :data:`BAD` for problems), or None if
        ``value`` is not a table. Keys in ``tables`` are allowed but left to the caller.
        """
        if not isinstance(value, dict):
            self.report(path, f"expected a table, got {kind(value)}")
            return None
        known = list(spec) + list(tables)
        self._outer.update((path + (t,), known) for t in tables)
        outer = self._outer.get(path, ())
        for key in value:
            if len(self.problems) > MAX_PROBLEMS:
                break  # no more are listed; spare the spelling suggestions
            if key not in known:
                above = (f"; {key} is a key of the table above: did you mean to put it above "
                         f"{header(path)}? (every key after a [table] header belongs to that "
                         "table)" if key in outer else "")
                self.report(path + (key,), f"unknown key{did_you_mean(key, known)}; "
                                           f"known here: {', '.join(known)}{above}")
        for key, s in spec.items():
            if isinstance(s, Retired) and key in value:
                self.report(path + (key,), f"no longer used, ignored: {s.why}", warning=True)
        return {key: s.check(self, value[key], path + (key,)) if key in value
                else self.missing(path + (key,), s) for key, s in spec.items()
                if not isinstance(s, Retired)}

    def missing(self, path: KeyPath, spec: Spec):
        """The default of an absent key, or a problem if it has none."""
        if spec.default is REQUIRED:
            return self.report(path, "missing (required)")
        return spec.default

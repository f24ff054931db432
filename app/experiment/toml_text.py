"""TOML text from a parsed document (what ``tomllib`` gives), for the scene files a
session writes: ``tomllib.loads(toml_text(doc)) == doc`` for any document of strings,
booleans, integers, finite floats, lists and tables (a test holds it to that).

Tables are written as ``[a.b]`` sections, lists of tables as ``[[a]]`` sections, every
other value on a ``key = value`` line; keys that are not bare words are quoted.
"""

from __future__ import annotations

import math
import numbers
import re

_BARE = re.compile(r"^[A-Za-z0-9_-]+$")


def _string(text: str) -> str:
    """A TOML basic string: quote and backslash escaped, control characters (and DEL)
    as \\uXXXX, everything else as itself."""
    out = []
    for ch in text:
        if ch in '"\\':
            out.append("\\" + ch)
        elif ch < " " or ch == "\x7f":
            out.append(f"\\u{ord(ch):04x}")
        else:
            out.append(ch)
    return '"' + "".join(out) + '"'


def _key(key: str) -> str:
    return key if _BARE.match(key) else _string(key)


def _value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, numbers.Integral):
        return str(int(value))
    if isinstance(value, numbers.Real):  # numpy's too: repr(float) is the shortest exact form
        if not math.isfinite(value):
            raise ValueError(f"{value!r}: a scene file holds finite numbers only")
        return repr(float(value))
    if isinstance(value, str):
        return _string(value)
    if isinstance(value, list):
        return "[" + ", ".join(_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{_key(k)} = {_value(v)}" for k, v in value.items()) + "}"
    raise TypeError(f"cannot write {type(value).__name__} as TOML")


def _is_table_list(value) -> bool:
    return isinstance(value, list) and bool(value) and all(isinstance(v, dict) for v in value)


def _section(doc: dict, prefix: tuple[str, ...], lines: list[str]) -> None:
    for key, value in doc.items():
        if not isinstance(value, dict) and not _is_table_list(value):
            lines.append(f"{_key(key)} = {_value(value)}")
    for key, value in doc.items():
        name = ".".join(_key(k) for k in (*prefix, key))
        if isinstance(value, dict):
            lines += ["", f"[{name}]"]
            _section(value, (*prefix, key), lines)
        elif _is_table_list(value):
            for item in value:
                lines += ["", f"[[{name}]]"]
                _section(item, (*prefix, key), lines)


def toml_text(doc: dict) -> str:
    """``doc`` as TOML text (see the module docstring)."""
    lines: list[str] = []
    _section(doc, (), lines)
    return "\n".join(lines).lstrip("\n") + "\n"

"""Text from files and the network, made safe to print: escaped and cut to a length.

Every value that frictex shows in a message and that came from outside (a key, a name,
a cell of a table, a file name) goes through :func:`escape` first, so that a message
never carries a terminal escape (ESC, BEL, CSI), a line break that would forge a second
line, or a whole line of a file that is not what it claims to be.

- Printable characters stay as they are (non-ASCII letters included).
- ``\\``, tab, newline and carriage return become ``\\\\``, ``\\t``, ``\\n``, ``\\r``.
- Every other character that ``str.isprintable`` refuses (controls, format characters,
  separators other than the ASCII space, unassigned code points: ESC, BEL, DEL, C1
  controls, bidirectional overrides, no-break and zero-width spaces, unpaired surrogates)
  becomes ``\\xHH``, ``\\uHHHH`` or ``\\UHHHHHHHH``: ESC is shown as the four characters
  ``\\x1b``.
- The escaped text is cut to at most ``limit`` characters (:data:`MAX_SHOWN`, 60, by
  default), ending with an ellipsis ``...`` where it was cut; an escape is never cut in
  the middle.

This module is in the lowest layer so that every layer (the device's own messages, the
texture and trace readers, the command line's error printer) can use it.
"""

from __future__ import annotations

#: Longest escaped value shown in a message (characters, the ellipsis included).
MAX_SHOWN = 60
#: Longest escaped file path shown in a message (its end is kept: the file's name).
MAX_PATH_SHOWN = 160

_LINE = {"\t": "\\t", "\n": "\\n", "\r": "\\r"}
_ELLIPSIS = "..."


def _escape_char(ch: str) -> str:
    return "\\\\" if ch == "\\" else _control_char(ch)


def _control_char(ch: str) -> str:
    """``ch`` as it is where printable, else its ``\\xHH`` (tab, line breaks named)."""
    if ch in _LINE:
        return _LINE[ch]
    if ch.isprintable():
        return ch
    code = ord(ch)
    if code <= 0xFF:
        return f"\\x{code:02x}"
    return f"\\u{code:04x}" if code <= 0xFFFF else f"\\U{code:08x}"


def escape(value: object, limit: int | None = MAX_SHOWN) -> str:
    """``value`` (``str()`` of it if not a string) escaped and cut for a one-line message.

    Parameters
    ----------
    value : the text (or any object, shown by its ``str()``).
    limit : most characters returned, the ellipsis included (at least 4); None: no cut.

    Returns
    -------
    str
        Printable text on one line: no control character, no line break.

    Examples
    --------
    >>> escape("\\x1b]0;owned\\x07name")
    '\\\\x1b]0;owned\\\\x07name'
    >>> escape("x" * 100, limit=10)
    'xxxxxxx...'
    """
    return _shown(value, limit, _escape_char)


def printable(message: object, limit: int | None = None) -> str:
    """A message (``str()`` of it) on one line that cannot drive a terminal, as
    :func:`escape` makes a value, cut likewise to ``limit`` characters (None: no cut),
    but with the backslashes already in it kept: the values a reader escaped stay as
    they were shown, not escaped twice."""
    return _shown(message, limit, _control_char)


def _shown(value: object, limit: int | None, escaped) -> str:
    """``value``'s text with each character ``escaped(ch)``, cut to ``limit``."""
    text = value if isinstance(value, str) else str(value)
    if limit is not None and limit < len(_ELLIPSIS) + 1:
        raise ValueError(f"limit must be at least {len(_ELLIPSIS) + 1}, got {limit}")
    pieces = [escaped(ch) for ch in (text if limit is None else text[:limit + 1])]
    if limit is None or sum(map(len, pieces)) <= limit and len(text) <= limit:
        return "".join(pieces)
    out, length = [], 0
    for piece in pieces:
        if length + len(piece) > limit - len(_ELLIPSIS):
            break
        out.append(piece)
        length += len(piece)
    return "".join(out) + _ELLIPSIS


def quoted(value: object, limit: int | None = MAX_SHOWN) -> str:
    """:func:`escape` of ``value`` in double quotes (the quotes not counted in ``limit``)."""
    return f'"{escape(value, limit)}"'


def escape_path(path: object, limit: int = MAX_PATH_SHOWN) -> str:
    """A file path for a message: :func:`escape`'d, and where longer than ``limit``
    characters, an ellipsis and its last characters (the file's name is at the end; an
    escape is never cut in the middle)."""
    text = path if isinstance(path, str) else str(path)
    pieces = [_escape_char(ch) for ch in text]
    if sum(map(len, pieces)) <= limit:
        return "".join(pieces)
    tail, length = [], 0
    for piece in reversed(pieces):
        if length + len(piece) > limit - len(_ELLIPSIS):
            break
        tail.append(piece)
        length += len(piece)
    return _ELLIPSIS + "".join(reversed(tail))

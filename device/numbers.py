"""Numbers as frictex's text formats write them: one ASCII grammar for all.

Trace files, batch manifests, device logs, mode tables and HaTT models all take a
number in the same form::

    number := SPACES? sign? (DIGITS ("." DIGITS?)? | "." DIGITS) (("e" | "E") sign? DIGITS)? SPACES?
    sign   := "+" | "-"      DIGITS := { "0".."9" }-      SPACES := { " " | TAB }-

Python's ``float`` alone also takes Unicode digits (``٢١``), underscores between digits
(``0_00.1``), ``nan``, ``inf`` and Unicode spaces: :func:`ascii_float` takes only the
grammar above.
"""

from __future__ import annotations

import re

#: The grammar above. Possessive: a long run of digits fails in linear time.
NUMBER = re.compile(r"[ \t]*+[+-]?+(?:[0-9]++(?:\.[0-9]*+)?+|\.[0-9]++)(?:[eE][+-]?+[0-9]++)?+[ \t]*+")


def ascii_float(text: str) -> float:
    """``float(text)`` for a :data:`NUMBER`; ValueError for anything else (``float``
    alone takes Unicode digits, underscores, ``nan``, ``inf`` and Unicode spaces).

    The result may be infinite where the number overflows (``1e999``): callers that need
    finite values check with ``math.isfinite``."""
    if NUMBER.fullmatch(text) is None:
        raise ValueError(f"not a number: {text!r}")
    return float(text)

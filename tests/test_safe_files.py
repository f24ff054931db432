"""device.safe_text (values escaped and cut for one-line messages) and device.safe_files
(regular files only, never more than a stated size)."""

from __future__ import annotations

import os
import re

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from frictex.device.safe_files import UnsafeFile, file_problem, read_bytes
from frictex.device.safe_text import MAX_SHOWN, escape, escape_path, quoted

_ESCAPE = re.compile(r"\\(x[0-9a-f]{2}|u[0-9a-f]{4}|U[0-9a-f]{8}|\\|t|n|r)")


def _unescape(text: str) -> str:
    named = {"\\": "\\", "t": "\t", "n": "\n", "r": "\r"}
    return _ESCAPE.sub(lambda m: named.get(m.group(1)) or chr(int(m.group(1)[1:], 16)), text)


def test_terminal_escapes_are_shown_as_their_code():
    assert escape("\x1b]0;owned\x07\x1b[2J") == "\\x1b]0;owned\\x07\\x1b[2J"
    assert escape("a\nb\tc\\d") == "a\\nb\\tc\\\\d"
    assert escape("\u202eevil\u200b") == "\\u202eevil\\u200b"  # bidi override, zero width
    assert escape("café ☕") == "café ☕"
    assert quoted("\x07") == '"\\x07"'


@settings(max_examples=300, derandomize=True)
@given(text=st.text(max_size=200), limit=st.integers(4, 120))
def test_any_text_becomes_one_printable_line_within_the_limit(text, limit):
    out = escape(text, limit)
    assert out.isprintable() and len(out) <= limit
    if len(escape(text, None)) <= limit:
        assert _unescape(out) == text  # nothing lost when it fits
    else:
        assert out.endswith("...") and text.startswith(_unescape(out[:-3]))


def test_the_default_cut_is_max_shown():
    assert escape("x" * MAX_SHOWN) == "x" * MAX_SHOWN
    assert escape("x" * (MAX_SHOWN + 1)) == "x" * (MAX_SHOWN - 3) + "..."
    assert escape("\x1b" * 40) == "\\x1b" * 14 + "..."  # never half an escape


def test_a_long_path_keeps_its_file_name():
    shown = escape_path("/srv/" + "d" * 500 + "/\x1bmap.png", limit=40)
    assert shown.startswith("...") and shown.endswith("/\\x1bmap.png") and len(shown) <= 40


def test_special_files_are_refused_without_blocking(tmp_path):
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    for path, phrase in ((fifo, "is a FIFO"), ("/dev/zero", "is a character device"),
                         (tmp_path, "is a folder")):
        assert phrase in file_problem(path, 10)
        with pytest.raises(UnsafeFile, match=phrase):
            read_bytes(path, 10)
    os.symlink("loop", tmp_path / "loop")
    with pytest.raises(UnsafeFile, match="symbolic link loop"):
        read_bytes(tmp_path / "loop", 10)


def test_sizes_are_capped(tmp_path):
    path = tmp_path / "f"
    path.write_bytes(b"x" * 11)
    with pytest.raises(UnsafeFile, match="is 11 bytes, more than the 10 bytes"):
        read_bytes(path, 10)
    assert read_bytes(path, 11) == b"x" * 11
    assert read_bytes(path, 1 << 30) == b"x" * 11

"""The bundled library: texture files in ``textures/library/*.toml`` and touch traces in
``textures/library/traces/*.csv``.

Commands take either a path or a bundled name (``grating-5mm`` or ``grating-5mm.toml``);
a path that exists (or is a symbolic link, even a broken one) wins over a bundled name.
A scene's one-line description is its ``description`` key; a trace's is its first line, a
``# ...`` comment.

Every file frictex reads goes through :func:`file_problem` first: it looks at the path with
``os.stat`` and never opens anything but a regular file, so a FIFO, a device, a folder or a
symbolic link loop is refused with a sentence instead of hanging or raising.
"""

from __future__ import annotations

import codecs
import difflib
import errno
import os
import stat
import tomllib
from dataclasses import dataclass
from pathlib import Path

from frictex.textures.errors import TextureError
from frictex.device.errors import InputError

LIBRARY_DIR = Path(__file__).resolve().parent / "library"
TRACES_DIR = LIBRARY_DIR / "traces"


@dataclass(frozen=True)
class Entry:
    """One bundled file: ``kind`` is "scene" or "trace"."""

    name: str
    kind: str
    path: Path
    description: str


_SPECIAL = ((stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISCHR, "a character device"),
            (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"))


def file_problem(path: str | Path, max_bytes: int | None = None) -> str | None:
    """Why ``path`` cannot be read as a regular file of at most ``max_bytes``, or None.

    Looks with ``os.stat`` only (never opens the path): reading a FIFO or a terminal
    would block, and reading a device can have effects. The answer is a phrase to put
    after the file name, e.g. ``"is a FIFO (named pipe), not a regular file"``.
    """
    try:
        info = os.stat(path)
    except FileNotFoundError as exc:
        return ("is a symbolic link to a missing file" if os.path.islink(path)
                else exc.strerror)
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            return "is a symbolic link loop (a link that leads back to itself)"
        return f"cannot be read ({exc.strerror or exc})"
    except ValueError:  # an embedded NUL: no such path can exist
        return "is not a valid path (it holds a NUL character)"
    if stat.S_ISDIR(info.st_mode):
        return "is a folder, not a file"
    if not stat.S_ISREG(info.st_mode):
        kind = next((name for test, name in _SPECIAL if test(info.st_mode)), "a special file")
        return f"is {kind}, not a regular file (frictex reads only regular files)"
    if max_bytes is not None and info.st_size > max_bytes:
        return (f"is {info.st_size:,} bytes, more than the {max_bytes:,} bytes frictex reads "
                f"for such a file")
    return None


class UnreadableText(InputError):
    """Why a file cannot be read as UTF-8 text; ``line`` (1-based) where that applies."""

    def __init__(self, message: str, line: int | None = None):
        super().__init__(message)
        self.line = line


def read_utf8(path: str | Path, max_bytes: int) -> str:
    """The text of a regular UTF-8 file of at most ``max_bytes`` (a leading BOM dropped).

    Raises :class:`UnreadableText` for anything else: not a regular file (checked before
    opening), too large, UTF-16, bytes that are not UTF-8, NUL bytes (binary content).
    """
    problem = file_problem(path, max_bytes)
    if problem is not None:
        raise UnreadableText(problem)
    try:
        data = Path(path).read_bytes()
    except OSError as exc:
        raise UnreadableText(f"cannot be read ({exc.strerror or exc})") from None
    if data.startswith((codecs.BOM_UTF16_LE, codecs.BOM_UTF16_BE)):
        raise UnreadableText("is UTF-16 text (it starts with a UTF-16 byte order mark); save "
                             "it as UTF-8")
    if data.startswith(codecs.BOM_UTF8):
        data = data[len(codecs.BOM_UTF8):]
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise UnreadableText(f"not UTF-8 text (byte {data[exc.start]:#04x} at offset {exc.start})",
                             data.count(b"\n", 0, exc.start) + 1) from None
    nul = text.find("\0")
    if nul >= 0:
        raise UnreadableText("holds a NUL byte: binary content", text.count("\n", 0, nul) + 1)
    return text


def _scene_description(path: Path) -> str:
    try:
        doc = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        return f"(unreadable: {exc})"
    description = doc.get("description", "")
    return description.splitlines()[0] if isinstance(description, str) and description else ""


def _trace_description(path: Path) -> str:
    try:
        with path.open(encoding="utf-8") as f:
            first = f.readline().strip()
    except (OSError, UnicodeDecodeError) as exc:
        return f"(unreadable: {exc})"
    return first.lstrip("#").strip() if first.startswith("#") else ""


def list_scenes() -> list[Entry]:
    """The bundled scenes, sorted by name."""
    return [Entry(p.stem, "scene", p, _scene_description(p))
            for p in sorted(LIBRARY_DIR.glob("*.toml"))]


def list_traces() -> list[Entry]:
    """The bundled traces, sorted by name."""
    return [Entry(p.stem, "trace", p, _trace_description(p))
            for p in sorted(TRACES_DIR.glob("*.csv"))]


def _resolve(name_or_path: str | Path, folder: Path, suffix: str, kind: str) -> Path:
    path = Path(name_or_path)
    if path.exists() or path.is_symlink():
        return path
    name = str(name_or_path)
    if path.name != name:
        raise TextureError(f"{name}: no such file")
    bundled = folder / (name if name.endswith(suffix) else name + suffix)
    if bundled.is_file():
        return bundled
    names = sorted(p.stem for p in folder.glob(f"*{suffix}"))
    close = difflib.get_close_matches(Path(name).stem, names, n=1, cutoff=0.5)
    hint = f"did you mean {close[0]}? " if close else ""
    raise TextureError(f"{name}: no such file, and no bundled {kind} of that name "
                       f"({hint}frictex library lists them)")


def resolve_scene(name_or_path: str | Path) -> Path:
    """A texture file: ``name_or_path`` if it exists, else the bundled scene of that name."""
    return _resolve(name_or_path, LIBRARY_DIR, ".toml", "scene")


def resolve_trace(name_or_path: str | Path) -> Path:
    """A trace CSV: ``name_or_path`` if it exists, else the bundled trace of that name."""
    return _resolve(name_or_path, TRACES_DIR, ".csv", "trace")

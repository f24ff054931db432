"""The bundled library: texture files in ``textures/library/*.toml`` and touch traces in
``textures/library/traces/*.csv``.

Commands take either a path or a bundled name (``grating-5mm`` or ``grating-5mm.toml``);
a path that exists (or is a symbolic link, even a broken one) wins over a bundled name.
A scene's one-line description is its ``description`` key; a trace's is its first line, a
``# ...`` comment.

Every file frictex reads goes through ``device.safe_files`` (:func:`file_problem`, re-exported
here, and ``read_bytes``): it looks at the path with ``os.stat`` and never opens anything
but a regular file, never reads more than a stated size, so a FIFO, a device, a folder or
a symbolic link loop is refused with a sentence instead of hanging or raising.
"""

from __future__ import annotations

import codecs
import difflib
import os
import tomllib
from dataclasses import dataclass
from pathlib import Path

from frictex.textures.errors import TextureError
from frictex.device.errors import InputError
from frictex.device.safe_files import UnsafeFile, file_problem, read_bytes
from frictex.device.safe_text import escape_path

__all__ = ["Entry", "UnreadableText", "bundled_file", "file_problem", "list_scenes",
           "list_toml_files",
           "list_traces", "read_utf8", "resolve_scene", "resolve_trace"]

LIBRARY_DIR = Path(__file__).resolve().parent / "library"
TRACES_DIR = LIBRARY_DIR / "traces"


@dataclass(frozen=True)
class Entry:
    """One listed file: ``kind`` is "scene", "saved" (a scene saved from the demo),
    "trace" or "protocol" (an experiment's)."""

    name: str
    kind: str
    path: Path
    description: str


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
    try:
        data = read_bytes(path, max_bytes)
    except UnsafeFile as exc:
        raise UnreadableText(str(exc)) from None
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
    return list_toml_files(LIBRARY_DIR, "scene")


def list_toml_files(folder: Path, kind: str) -> list[Entry]:
    """The TOML files of ``folder`` as entries of ``kind``, sorted by name, each described
    by the first line of its ``description``."""
    return [Entry(p.stem, kind, p, _scene_description(p)) for p in sorted(folder.glob("*.toml"))]


def user_scenes_dir() -> Path:
    """Where the demo's layer panel saves a bundled scene the user edited (the bundled
    files are never written to): ``$XDG_DATA_HOME/frictex/scenes``, by default (and
    where it is not an absolute path, which the XDG base directory specification says to
    ignore: a copy saved from one folder would be lost from another)
    ``~/.local/share/frictex/scenes``."""
    base = os.environ.get("XDG_DATA_HOME", "")
    if not os.path.isabs(base):
        base = str(Path.home() / ".local" / "share")
    return Path(base) / "frictex" / "scenes"


def list_saved_scenes() -> list[Entry]:
    """The scenes saved in :func:`user_scenes_dir`, sorted by name, of kind "saved": one
    opens by its path (its name stays the bundled scene's)."""
    folder = user_scenes_dir()
    if not folder.is_dir():
        return []
    return [Entry(p.stem, "saved", p, _scene_description(p))
            for p in sorted(folder.glob("*.toml")) if p.is_file()]


def list_traces() -> list[Entry]:
    """The bundled traces, sorted by name."""
    return [Entry(p.stem, "trace", p, _trace_description(p))
            for p in sorted(TRACES_DIR.glob("*.csv"))]


def _resolve(name_or_path: str | Path, folder: Path, suffix: str, kind: str) -> Path:
    if not str(name_or_path):  # Path("") is the current folder, named "." in what follows
        raise TextureError(f"the name is empty; expected a {SUFFIX_SAID[suffix]} or a bundled "
                           f"{kind}'s name")
    path = Path(name_or_path)
    if path.exists() or path.is_symlink():
        return path
    return _bundled(str(name_or_path), folder, suffix, kind)


def _bundled(name: str, folder: Path, suffix: str, kind: str) -> Path:
    if Path(name).name != name:
        raise TextureError(f"{escape_path(name)}: no such file")
    bundled = folder / (name if name.endswith(suffix) else name + suffix)
    if bundled.is_file():
        return bundled
    names = sorted(p.stem for p in folder.glob(f"*{suffix}"))
    close = difflib.get_close_matches(Path(name).stem, names, n=1, cutoff=0.5)
    hint = f"did you mean {close[0]}? " if close else ""
    raise TextureError(f"{escape_path(name)}: no such file, and no bundled {kind} of that name "
                       f"({hint}frictex library lists them)")


#: a file of each suffix as an empty name's message says it
SUFFIX_SAID = {".toml": "texture file (.toml)", ".csv": "trace CSV file"}

#: where the bundled files of each kind lie, and their suffix
BUNDLED = {"scene": (LIBRARY_DIR, ".toml"), "trace": (TRACES_DIR, ".csv")}


def bundled_file(name: str, kind: str) -> Path:
    """The bundled ``kind`` ("scene" or "trace") of that ``name``, whatever files the
    current folder holds (a TextureError, with the closest name, where there is none):
    for a name read from someone else's file, which must not reach the user's files."""
    folder, suffix = BUNDLED[kind]
    return _bundled(name, folder, suffix, kind)


def resolve_scene(name_or_path: str | Path) -> Path:
    """A texture file: ``name_or_path`` if it exists, else the bundled scene of that name."""
    return _resolve(name_or_path, LIBRARY_DIR, ".toml", "scene")


def resolve_trace(name_or_path: str | Path) -> Path:
    """A trace CSV: ``name_or_path`` if it exists, else the bundled trace of that name."""
    return _resolve(name_or_path, TRACES_DIR, ".csv", "trace")

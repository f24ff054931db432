"""The bundled library: texture files in ``textures/library/*.toml`` and touch traces in
``textures/library/traces/*.csv``.

Commands take either a path or a bundled name (``grating-5mm`` or ``grating-5mm.toml``);
a path that exists wins over a bundled name. A scene's one-line description is its
``description`` key; a trace's is its first line, a ``# ...`` comment.
"""

from __future__ import annotations

import difflib
import tomllib
from dataclasses import dataclass
from pathlib import Path

from textures.errors import TextureError

LIBRARY_DIR = Path(__file__).resolve().parent / "library"
TRACES_DIR = LIBRARY_DIR / "traces"


@dataclass(frozen=True)
class Entry:
    """One bundled file: ``kind`` is "scene" or "trace"."""

    name: str
    kind: str
    path: Path
    description: str


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
    if path.exists():
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

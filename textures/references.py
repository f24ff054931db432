"""The files a texture file refers to, resolved as the loader resolves them.

A scene is built from its texture file and from the files it names, each relative to the
texture file's folder (``textures.loader``): a raster layer's ``image``, a height map's
``image`` (16-bit PNG), a recorded layer's ``model`` (Penn Haptic Texture Toolkit XML),
a clip's ``file`` (AHAP JSON) and a modal structure's ``modes_file`` (CSV). The live
demo watches all of them, so that saving any one reloads the scene.
"""

from __future__ import annotations

import os
import tomllib
from pathlib import Path

from frictex.device.safe_text import escape, escape_path
from frictex.textures.errors import TextureError
from frictex.textures.library import UnreadableText, read_utf8
from frictex.textures.toml_safe import MAX_FILE_BYTES, deepest_line

#: the keys of a ``[[layer]]`` table that name a file, and that of ``[device.structure]``
LAYER_FILE_KEYS = ("image", "model", "file")
STRUCTURE_FILE_KEY = "modes_file"


def referenced_files(scene_path: str | Path) -> tuple[Path, ...]:
    """The files the texture file at ``scene_path`` names, in the order it names them,
    each once, as absolute paths with links followed (those that do not exist too: a
    file that appears is a change). Raises TextureError, with the file's name, when the
    texture file cannot be read as TOML (the loader says why in detail)."""
    scene_path = Path(scene_path)
    try:
        text = read_utf8(scene_path, MAX_FILE_BYTES)
    except UnreadableText as exc:
        raise TextureError(f"{escape_path(scene_path)}: {exc}") from None
    if deepest_line(text) is not None:  # tomllib would recurse or take quadratic time
        raise TextureError(f"{escape_path(scene_path)}: nested too deep to list the files it names")
    try:
        doc = tomllib.loads(text)
    except (tomllib.TOMLDecodeError, RecursionError, ValueError) as exc:
        raise TextureError(f"{escape_path(scene_path)}: not TOML ({escape(exc)})") from None
    names = []
    device = doc.get("device")
    structure = device.get("structure") if isinstance(device, dict) else None
    if isinstance(structure, dict):
        names.append(structure.get(STRUCTURE_FILE_KEY))
    layers = doc.get("layer")
    for layer in layers if isinstance(layers, list) else ():
        if isinstance(layer, dict):
            names += [layer.get(key) for key in LAYER_FILE_KEYS]
    found: dict[Path, None] = {}
    for name in names:
        if isinstance(name, str) and name and "\0" not in name:
            found[Path(os.path.realpath(scene_path.parent / name))] = None
    return tuple(found)

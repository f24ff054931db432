"""The files a texture file names (images, height maps, HaTT models, AHAP clips, mode
tables): confined to the texture file's folder, read only as what they claim to be.

A name is a path relative to the texture file's folder, to a file in that folder or
below it. Anything else is a problem naming the key: an absolute path, a path whose
``..`` parts lead out of the folder, and a path that passes through a symbolic link to
somewhere outside it (links inside the folder are followed). A user who trusts the file
lifts the rule with ``--allow-outside`` on the command line (``allow_outside=True`` of
``textures.loader.load_scene``) or by setting the environment variable
``FRICTEX_ALLOW_OUTSIDE=1``.

Each file is then read by its own reader through ``device.safe_files`` (regular files
only, at most a stated size), and images and height maps charge the scene's budget of
decoded maps (``textures.raster_io.PixelBudget``) from their PNG headers before decoding.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from frictex.device.safe_text import escape, escape_path
from frictex.textures.errors import KeyPath, TextureError
from frictex.textures.outside import HOW
from frictex.textures.raster_io import PixelBudget
from frictex.textures.schema import Reader, show

@dataclass
class Files:
    """Where a texture file's names are resolved: ``base_dir``, its folder; whether they
    may lead outside it; and what is left of the scene's budget of decoded maps."""

    base_dir: Path
    allow_outside: bool = False
    budget: PixelBudget = field(default_factory=PixelBudget)

    def real_path(self, name: str) -> Path:
        """``name`` relative to the texture file's folder, links followed as far as they go
        (``Path.resolve`` raises on a link loop; ``os.path.realpath`` stops there)."""
        return Path(os.path.realpath(self.base_dir / name))

    def locate(self, name: str) -> Path:
        """The real path of ``name``; TextureError (a phrase to follow the key) if it is
        empty or, unless allowed, leads outside the texture file's folder."""
        if not name:
            raise TextureError("is empty; expected a path relative to the texture file")
        real = self.real_path(name)
        if self.allow_outside:
            return real
        if os.path.isabs(name):
            raise TextureError(f"{show(name)} is an absolute path; a texture file names files "
                               f"in its own folder or below ({HOW})")
        root = os.path.realpath(self.base_dir)
        if os.path.normpath(name).split(os.sep)[0] == os.pardir:
            raise TextureError(f"{show(name)} leads out of the texture file's folder through "
                               f"'..'; a texture file names files in its own folder or below "
                               f"({HOW})")
        if os.path.commonpath([root, str(real)]) != root:
            raise TextureError(f"{show(name)} passes through a symbolic link to "
                               f"{escape_path(real)}, outside the texture file's folder; a "
                               f"texture file names files in its own folder or below ({HOW})")
        return real

    def read(self, r: Reader, path: KeyPath, name: str, reader: Callable):
        """``(real path, reader(real path))`` of the file ``name``, or None with the
        problem reported at ``path`` (the key that names the file)."""
        try:
            file_path = self.locate(name)
        except TextureError as exc:
            r.report(path, str(exc))
            return None
        try:
            return file_path, reader(file_path)
        except OSError as exc:
            r.report(path, f"{show(name)}: {escape_path(file_path)}: {escape(exc.strerror or exc)}")
        except TextureError as exc:  # its message starts with the file's path
            r.report(path, f"{show(name)}: {exc}")
        return None


def file_read(r: Reader, path: KeyPath, key: str, name: str, ctx, reader: Callable):
    """``reader(path)`` of the file ``name`` a layer's ``key`` names, or None (reported)."""
    got = ctx.files.read(r, path + (key,), name, reader)
    return None if got is None else got[1]

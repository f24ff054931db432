"""The files a texture file names (images, height maps, HaTT models, AHAP clips, mode
tables), relative to the texture file's folder."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from frictex.textures.errors import TextureError
from frictex.textures.schema import show


@dataclass
class Files:
    """Where a texture file's names are resolved: ``base_dir``, its folder."""

    base_dir: Path

    def real_path(self, name: str) -> Path:
        """``name`` relative to the texture file's folder, links followed as far as they go
        (``Path.resolve`` raises on a link loop; ``os.path.realpath`` stops there)."""
        return Path(os.path.realpath(self.base_dir / name))


def file_read(r, path, key, name, ctx, reader):
    """``reader(path)`` of the file ``name`` relative to the texture file, or None (reported)."""
    file_path = ctx.files.real_path(name) if name else None
    try:
        if file_path is None:
            raise TextureError("empty path")
        return reader(file_path)
    except OSError as exc:
        r.report(path + (key,), f"{show(name)}: {file_path}: {exc.strerror or exc}")
    except TextureError as exc:  # its message starts with the file's path
        r.report(path + (key,), f"{show(name)}: {exc}")
    return None

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

Checked once, opened once: the path that was checked could be swapped for a link to
somewhere else before a reader opens it again. :meth:`Files.read` opens the checked
path itself (the last part not followed if it is a link), checks where the descriptor it
holds really leads (``/proc/self/fd``), and pins the path to that descriptor
(``device.safe_files.pinned``): the reader's ``read_bytes`` reads the file held, not the
path again. Where the system has no ``/proc/self/fd``, the folders on the way are not
checked again.

A hard link is a second name of the same file, not a link that leads anywhere: one in
the folder to a file outside it cannot be told from a file of the folder and is read.
It is not refused (by ``st_nlink > 1``) because package managers and backup tools make
hard links of ordinary files (uv's and pip's caches, ``cp -al``, ``rsync --link-dest``),
and a hard link can only be made on the reader's own file system to a file its maker
could already read; FORMAT.md says so.
"""

from __future__ import annotations

import errno
import os
import stat
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from frictex.device.safe_files import file_problem, pinned
from frictex.device.safe_text import escape, escape_path
from frictex.textures.errors import KeyPath, TextureError
from frictex.textures.outside import HOW, leads_out
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
        how = None if self.allow_outside else leads_out(self.base_dir, name)
        if how is not None:
            raise TextureError(f"{show(name)} {how}: a texture file names files in its own "
                               f"folder or below ({HOW})")
        return real

    def read(self, r: Reader, path: KeyPath, name: str, reader: Callable):
        """``(real path, reader(real path))`` of the file ``name``, or None with the
        problem reported at ``path`` (the key that names the file). The file is opened
        once, here, and the reader reads what was opened (module docstring)."""
        try:
            file_path = self.locate(name)
        except TextureError as exc:
            r.report(path, str(exc))
            return None
        try:
            held = os.open(file_path, _OPEN_FLAGS)  # a descriptor, or why there is none
        except OSError as exc:  # the reader says so in its words, opening nothing
            # ELOOP is a link loop (file_problem says so) or, where the path leads to a
            # file, a link swapped in after realpath
            held = file_problem(file_path) or (
                "became a symbolic link after it was checked" if exc.errno == errno.ELOOP
                else f"cannot be read ({exc.strerror or exc})")
        if isinstance(held, int) and not stat.S_ISREG(os.fstat(held).st_mode):
            # a folder or a FIFO opens (read only, non-blocking) but is no file to read:
            # the reader says so in safe_files' words, as for the texture file itself
            os.close(held)
            held = file_problem(file_path) or "is not a regular file (frictex reads only regular files)"
        try:
            if isinstance(held, int):
                self._check_held(held, name)
            with pinned(file_path, held):
                return file_path, reader(file_path)
        except OSError as exc:
            r.report(path, f"{show(name)}: {escape_path(file_path)}: {escape(exc.strerror or exc)}")
        except TextureError as exc:  # its message starts with the file's path
            r.report(path, f"{show(name)}: {exc}")
        finally:
            if isinstance(held, int):
                os.close(held)
        return None

    def _check_held(self, fd: int, name: str) -> None:
        """Check where the descriptor ``fd`` leads (``/proc/self/fd``): inside the
        folder, unless allowed. Where the system has no ``/proc/self/fd``, the path was
        checked and its last part opened unfollowed; its folders are not checked again."""
        try:
            opened = os.readlink(f"/proc/self/fd/{fd}")
        except OSError:
            return
        root = os.path.realpath(self.base_dir)
        if not self.allow_outside and os.path.commonpath([root, opened]) != root:
            raise TextureError(f"{show(name)} led to {escape_path(opened)}, outside the texture "
                               f"file's folder, when it was opened (it changed after it was "
                               f"checked); a texture file names files in its own folder or "
                               f"below ({HOW})")


#: how a named file is opened: read only, the last part never followed, never blocking
#: (a FIFO swapped in), never a controlling terminal
_OPEN_FLAGS = (os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_NONBLOCK", 0)
               | getattr(os, "O_NOCTTY", 0) | getattr(os, "O_CLOEXEC", 0))


def file_read(r: Reader, path: KeyPath, key: str, name: str, ctx, reader: Callable):
    """``reader(path)`` of the file ``name`` a layer's ``key`` names, or None (reported)."""
    got = ctx.files.read(r, path + (key,), name, reader)
    return None if got is None else got[1]

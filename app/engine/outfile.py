"""One output file (a frame, a preview, a synthesized trace), written all or nothing.

:func:`write_file` checks the file system's room first (``app.engine.tables.check_room``),
writes under ``<name>.partial`` and renames it into place only once it is complete: a
full disk or a killed process never leaves a truncated or empty file under the real
name, and an earlier file of that name stays until the new one replaces it. Errors name
the file.

What the path names decides how: a link is followed, and the file it points to is
replaced (the link stays); a character device or a FIFO (``/dev/null``, ``/dev/stdout``,
``/proc/self/fd/1`` on a terminal or a pipe) is written directly, as a stream has no
earlier contents to keep; anything else that is not a regular file (a folder, a block
device, a socket) is refused, touching nothing.
"""

from __future__ import annotations

import os
import stat
from collections.abc import Callable
from pathlib import Path

from frictex.app.engine.tables import WRITE_ELSEWHERE, check_room
from frictex.device.errors import InputError, OutputSpaceError, disk_full


def write_file(path: str | Path, write: Callable[[Path], object], need_bytes: float) -> None:
    """Write ``path`` through ``write(partial_path)`` (see the module docstring).

    Parameters
    ----------
    path : str or Path
        The file to write.
    write : callable
        Writes the whole file at the path it is given.
    need_bytes : float
        The file's size at most (bytes), for the room check.

    Raises
    ------
    InputError
        ``path`` is a folder, a block device or a socket.
    OutputSpaceError
        Not enough room (before writing), or the disk filled while writing; names ``path``.
    """
    path = Path(path)
    kind = _kind(path)
    if kind == "stream":
        write(path)
        return
    path = Path(os.path.realpath(path))  # a link: the file it points to
    check_room(path.parent, need_bytes, path.name, WRITE_ELSEWHERE)
    partial = path.with_name(path.name + ".partial")
    try:
        write(partial)
        os.replace(partial, path)
    except OSError as exc:
        partial.unlink(missing_ok=True)
        full = disk_full(exc, f"{path}: the disk is full ({exc.strerror}); nothing was written")
        if full is None:
            raise
        raise full from None
    except BaseException:
        partial.unlink(missing_ok=True)
        raise


def check_writable(option: str, path: Path, need_bytes: float) -> None:
    """Refuse, touching nothing, an output path that :func:`write_file` could not write
    ``need_bytes`` (bytes) into, before the work that makes the file: one that names a
    folder or a socket, a folder that does not exist or cannot be written, a path that
    cannot be looked at (a file taken as a folder, a link loop): InputError naming
    ``option`` and ``path``; a file system that holds no files or has too little room
    (``check_room``): OutputSpaceError."""
    try:
        if _kind(path) == "stream":  # a character device or a FIFO: written as it is
            return
        folder = Path(os.path.realpath(path)).parent  # a link: where it points
        if not folder.is_dir():
            missing = "is not a folder" if folder.exists() else "does not exist"
            raise InputError(f"the folder {folder} {missing}; give a file in an existing "
                             "folder")
        if not os.access(folder, os.W_OK):
            raise InputError(f"the folder {folder} cannot be written (no permission, or a "
                             "read-only file system)")
        check_room(folder, need_bytes, f"{option} {path}", WRITE_ELSEWHERE)
    except InputError as exc:
        message = str(exc).removeprefix(f"{path}: ")  # _kind's start with the path
        raise InputError(f"{option} {path}: {message}") from None
    except OutputSpaceError:
        raise
    except OSError as exc:  # the path itself cannot be looked at (/dev/null/x, a link loop)
        raise InputError(f"{option} {path}: cannot be written ({exc.strerror or exc})") from None


def _kind(path: Path) -> str:
    """``stream`` (a character device or FIFO, links followed), else ``file`` (a regular
    file, or nothing yet); :class:`InputError` for anything else."""
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        return "file"
    if stat.S_ISREG(mode):
        return "file"
    if stat.S_ISCHR(mode) or stat.S_ISFIFO(mode):
        return "stream"
    what = ("a folder" if stat.S_ISDIR(mode) else "a block device" if stat.S_ISBLK(mode)
            else "a socket" if stat.S_ISSOCK(mode) else "not a regular file")
    raise InputError(f"{path}: is {what}; give a file to write")

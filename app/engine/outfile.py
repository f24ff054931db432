"""One output file (a frame, a preview, a synthesized trace), written all or nothing.

:func:`write_file` checks the file system's room first (``app.engine.tables.check_room``),
writes under ``<name>.partial`` and renames it into place only once it is complete: a
full disk or a killed process never leaves a truncated or empty file under the real
name, and an earlier file of that name stays until the new one replaces it. Errors name
the file.
"""

from __future__ import annotations

import errno
import os
from collections.abc import Callable
from pathlib import Path

from frictex.app.engine.tables import check_room
from frictex.device.errors import OutputSpaceError


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
    OutputSpaceError
        Not enough room (before writing), or the disk filled while writing; names ``path``.
    """
    path = Path(path)
    check_room(path.parent, need_bytes, path.name, "or write elsewhere")
    partial = path.with_name(path.name + ".partial")
    try:
        write(partial)
        os.replace(partial, path)
    except OSError as exc:
        partial.unlink(missing_ok=True)
        if exc.errno in (errno.ENOSPC, errno.EDQUOT):
            raise OutputSpaceError(f"{path}: the disk is full ({exc.strerror}); nothing "
                                   "was written") from None
        raise
    except BaseException:
        partial.unlink(missing_ok=True)
        raise

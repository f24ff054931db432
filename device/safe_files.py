"""Reading a file someone else wrote: only a regular file, never more than a stated size.

Every file frictex reads (texture files and what they name, traces, manifests, models,
clips, tables) goes through :func:`file_problem` before it is opened, or through
:func:`read_bytes`, which also checks what it opened:

- a FIFO, a terminal, a socket or a device (``/dev/zero``) is refused without reading:
  reading one would block forever or never end;
- a folder, a missing file, a link to a missing file and a link loop are one sentence;
- a file larger than the caller's limit is refused from its size, before reading, and
  :func:`read_bytes` never reads more than the limit plus one byte whatever ``stat``
  said (a file that grows, or is swapped for another between the look and the read).

The answers are phrases to put after the file's name (``"is a FIFO (named pipe), not a
regular file ..."``), so that every reader words them the same way.

A caller that checked where a path leads and opened it itself (a texture file's named
files: ``textures.sections.files``) pins the path to its descriptor with :func:`pinned`;
:func:`read_bytes` of that path then reads the file held open, never the path again, so
the path cannot be swapped between the check and the read.
"""

from __future__ import annotations

import errno
import os
import stat
from contextlib import contextmanager
from contextvars import ContextVar
from pathlib import Path

#: paths pinned to the descriptors they were opened as (:func:`pinned`)
_PINNED: ContextVar[dict[str, int | str]] = ContextVar("frictex_pinned_files", default={})

_SPECIAL = ((stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISCHR, "a character device"),
            (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"))


def _mode_problem(info: os.stat_result, max_bytes: int | None) -> str | None:
    if stat.S_ISDIR(info.st_mode):
        return "is a folder, not a file"
    if not stat.S_ISREG(info.st_mode):
        kind = next((name for test, name in _SPECIAL if test(info.st_mode)), "a special file")
        return f"is {kind}, not a regular file (frictex reads only regular files)"
    if max_bytes is not None and info.st_size > max_bytes:
        return _too_large(info.st_size, max_bytes)
    return None


def _too_large(size: int, max_bytes: int) -> str:
    return f"is {size:,} bytes, more than the {max_bytes:,} bytes frictex reads for such a file"


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
    return _mode_problem(info, max_bytes)


class UnsafeFile(OSError):
    """A file :func:`read_bytes` refused; ``str()`` is the phrase to put after its name."""


@contextmanager
def pinned(path: str | Path, fd: int | str):
    """Within the block, :func:`read_bytes` of ``path`` reads the file open on ``fd``
    (from its start, through a duplicate of the descriptor) instead of opening ``path``;
    ``fd`` a phrase (the caller could not open it: :func:`file_problem`'s words):
    :func:`read_bytes` raises :class:`UnsafeFile` with it, opening nothing."""
    token = _PINNED.set({**_PINNED.get(), os.fspath(path): fd})
    try:
        yield
    finally:
        _PINNED.reset(token)


def _open(path: str | Path, max_bytes: int) -> int:
    """A descriptor to read ``path`` from: the pinned one's duplicate, rewound, or the
    path opened after :func:`file_problem` found nothing wrong."""
    held = _PINNED.get().get(os.fspath(path)) if isinstance(path, (str, os.PathLike)) else None
    if isinstance(held, str):
        raise UnsafeFile(held)
    if held is not None:
        fd = os.dup(held)
        os.lseek(fd, 0, os.SEEK_SET)
        return fd
    problem = file_problem(path, max_bytes)
    if problem is not None:
        raise UnsafeFile(problem)
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0)
    try:
        return os.open(path, flags | getattr(os, "O_CLOEXEC", 0))
    except OSError as exc:
        raise UnsafeFile(f"cannot be read ({exc.strerror or exc})") from None


def read_bytes(path: str | Path, max_bytes: int) -> bytes:
    """The bytes of the regular file ``path``, at most ``max_bytes`` of them.

    Parameters
    ----------
    path : the file.
    max_bytes : the most bytes the caller takes (a larger file is refused).

    Raises
    ------
    UnsafeFile
        With :func:`file_problem`'s phrase: not a regular file (checked before opening,
        and again on the opened descriptor, which is opened non-blocking so that a FIFO
        swapped in between cannot block), larger than ``max_bytes`` (also when it grew
        after the look), or unreadable. A :func:`pinned` path is read from its
        descriptor, with the same checks on it.
    """
    fd = _open(path, max_bytes)
    with os.fdopen(fd, "rb", buffering=0) as fh:
        problem = _mode_problem(os.fstat(fd), max_bytes)
        if problem is not None:
            raise UnsafeFile(problem)
        chunks, size = [], 0
        while size <= max_bytes:
            try:
                chunk = fh.read(min(1 << 20, max_bytes + 1 - size))
            except OSError as exc:
                raise UnsafeFile(f"cannot be read ({exc.strerror or exc})") from None
            if not chunk:
                break
            chunks.append(chunk)
            size += len(chunk)
    if size > max_bytes:
        raise UnsafeFile(_too_large(size, max_bytes) + " (it grew while being read)")
    return b"".join(chunks)

"""A run's output folder replaced as a whole, or not at all.

A replay writes every output (tables, frames, ``summary.json``) into a staging folder
beside ``--out`` (``.<name>.frictex-staging.<pid>``, on the same file system) and, when
the run commits, swaps it with ``--out`` in one ``renameat2(RENAME_EXCHANGE)`` system
call: at every instant ``--out`` is the previous run's folder or the new run's, whatever
kills the process (SIGKILL included). Then the previous run, now under the staging
name, is deleted. Where the file system cannot exchange (not Linux, or a file system
without RENAME_EXCHANGE), ``--out`` is renamed aside (``.<name>.frictex-old.<pid>``) and
the staging folder renamed to ``--out``: two renames, between which a killed run leaves
no ``--out``, and the next run renames the previous one back.

What is not a run's output is kept: files and links in ``--out`` beside the outputs are
hard-linked into the staging folder before the swap (no byte copied, none lost; copied
where the file system has no hard links); a
folder there other than ``frames`` is refused before anything is written, as are an
``--out`` that holds the current folder (the process would be left in the deleted one) and
a mount point (its staging folder would be on another file system).

Leftovers: a staging or set-aside folder whose process is gone is recognised by its
name and removed by the next run into the same ``--out`` (:meth:`Staging.begin`), which
says so (a warning in its summary). A run that is killed therefore never writes a
``summary.json`` of its own: its outputs are only ever seen complete, so no summary
marks an interrupted run.
"""

from __future__ import annotations

import ctypes
import errno
import glob
import os
import shutil
from pathlib import Path

from frictex.device.errors import InputError

#: the entries of an output folder that belong to a run (the rest is kept across runs)
OUTPUT_STEMS = ("commands", "friction")
_RUN_NAMES = ("summary.json", "frames")
_STAGING, _OLD = "frictex-staging", "frictex-old"
_RENAME_EXCHANGE = 2


def is_run_output(name: str) -> bool:
    """Whether ``name`` (an entry of an output folder) is a run's: a table (or a part of
    one being written), ``summary.json`` or ``frames``."""
    return name in _RUN_NAMES or name.split(".", 1)[0] in OUTPUT_STEMS and "." in name


class Staging:
    """The staging folder of one run into ``out`` (see the module docstring)."""

    def __init__(self, out: str | Path):
        self.out = Path(os.path.realpath(out))  # a link to a folder: that folder
        self.folder = self._name(_STAGING, os.getpid())
        self.removed: list[str] = []  # leftovers of killed runs that begin() removed

    def _name(self, kind: str, pid: int) -> Path:
        return self.out.with_name(f".{self.out.name}.{kind}.{pid}")

    def check(self) -> None:
        """Refuse, touching nothing, an ``out`` this run could not replace whole."""
        if self.out.exists() and not self.out.is_dir():
            raise InputError(f"{self.out}: exists and is not a folder")
        cwd = Path.cwd().resolve()
        if self.out.exists() and (cwd == self.out or self.out in cwd.parents):
            raise InputError(f"{self.out}: holds the current folder; a run replaces its output "
                             "folder as a whole: write into a folder of its own")
        if self.out.is_dir() and self.out.stat().st_dev != self.out.parent.stat().st_dev:
            raise InputError(f"{self.out}: a mount point, which a run cannot replace; write "
                             "into a folder inside it")
        if self.out.is_dir():
            foreign = sorted(e.name for e in os.scandir(self.out)
                             if not is_run_output(e.name) and e.is_dir(follow_symlinks=False))
            if foreign:
                raise InputError(f"{self.out}: holds the folder {foreign[0]!r}, not a run's "
                                 "output; a run replaces its output folder as a whole: write "
                                 "into a folder of its own")

    def begin(self) -> Path:
        """Remove the leftovers of killed runs, then create the staging folder."""
        self.check()
        self._recover()
        self.out.parent.mkdir(parents=True, exist_ok=True)
        self.folder.mkdir()
        return self.folder

    def _recover(self) -> None:
        for path in sorted(self.out.parent.glob(f".{glob.escape(self.out.name)}.frictex-*.*")):
            kind, _, pid = path.name[len(self.out.name) + 2:].rpartition(".")
            if kind not in (_STAGING, _OLD) or not pid.isdigit():
                continue
            if int(pid) != os.getpid() and _alive(int(pid)):  # a run going on now
                continue
            if kind == _OLD and not self.out.exists():
                os.rename(path, self.out)  # killed between the two renames: the previous run
                continue
            shutil.rmtree(path, ignore_errors=True)
            self.removed.append(path.name)

    def commit(self) -> None:
        """Swap the staging folder in as ``out``; the previous ``out`` is deleted."""
        if not self.out.exists():
            os.rename(self.folder, self.out)
            return
        for entry in os.scandir(self.out):
            if not is_run_output(entry.name) and not entry.is_dir(follow_symlinks=False):
                _carry(Path(entry.path), self.folder / entry.name)
        if _exchange(self.folder, self.out):
            shutil.rmtree(self.folder)
            return
        old = self._name(_OLD, os.getpid())
        os.rename(self.out, old)
        os.rename(self.folder, self.out)
        shutil.rmtree(old)

    def abort(self) -> None:
        """Delete the staging folder; ``out`` stays as it was."""
        shutil.rmtree(self.folder, ignore_errors=True)


def _exchange(a: Path, b: Path) -> bool:
    """Swap paths ``a`` and ``b`` atomically (Linux renameat2); False where the system or
    the file system cannot."""
    renameat2 = getattr(ctypes.CDLL(None, use_errno=True), "renameat2", None)
    if renameat2 is None:
        return False
    at_cwd = -100
    if renameat2(at_cwd, os.fsencode(a), at_cwd, os.fsencode(b), _RENAME_EXCHANGE) == 0:
        return True
    code = ctypes.get_errno()
    if code in (errno.EINVAL, errno.ENOSYS, errno.ENOTSUP):
        return False
    raise OSError(code, os.strerror(code), str(b))


def _carry(path: Path, to: Path) -> None:
    """``path`` also as ``to``: a hard link, or a copy where the file system has none."""
    try:
        os.link(path, to, follow_symlinks=False)
    except OSError:
        shutil.copy2(path, to, follow_symlinks=False)


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


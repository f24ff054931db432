"""A run's output folder replaced as a whole, or not at all.

A replay writes every output (tables, frames, ``summary.json``) into a staging folder
beside ``--out`` (``.<name>.frictex-staging.<pid>.<token>``, on the same file system;
``<token>`` is random, so two runs of one process into one ``--out`` never share one)
and, when the run commits, swaps it with ``--out`` in one ``renameat2(RENAME_EXCHANGE)``
system call: at every instant ``--out`` is the previous run's folder or the new run's,
whatever kills the process (SIGKILL included). Where the file system cannot exchange
(not Linux, or a file system without RENAME_EXCHANGE), ``--out`` is renamed aside
(``.<name>.frictex-old.<pid>.<token>``) and the staging folder renamed to ``--out``: two
renames, between which a killed run leaves no ``--out``, and the next run renames the
previous one back. A name too long to take the suffix (the file system's 255 bytes) is
shortened in the staging name to its first 100 characters and a hash of the whole. The
new folder gets the old one's permissions, owner and group (where the process may set
them) and extended attributes (ACLs included).

What a run owns in ``--out`` is exactly what it writes there, in a folder that holds a
run's outputs (its ``summary.json``, which every run writes): ``summary.json``,
``commands.<fmt>`` and ``friction.<fmt>`` (``fmt`` csv, npz or parquet; also the
``.partial`` and npz ``.<column>.raw`` files a table is written under), and a ``frames``
folder that holds nothing but ``frame_<number>.png`` files (``frame-<number>.png``: the
demo's; or their ``.partial``). Every
other file or link in ``--out`` (``commands.notes.txt`` included) is the user's: it is
hard-linked into the staging folder before the swap (no byte copied, none lost; copied
where the file system has no hard links). Every other folder (a ``frames`` folder with a
file of the user's in it included) is refused before anything is written, and again at
the commit (a folder created in ``--out`` while the run went on; one holding a
``summary.json`` is said to be another run's, committed there meanwhile): the run then
fails (:class:`~frictex.device.errors.RunFailed`), its outputs are deleted and ``--out``
is left as it was. After the swap only the previous run's own outputs and the files
carried over are deleted from the old folder; anything that appeared in it in between is
moved into the new ``--out`` (or, where a name is taken, the old folder is kept as
``.<name>.frictex-kept.<random>`` and the run fails naming it): a run never deletes a file
it did not write. Also refused before anything is written: ``--out`` the root folder, an
``--out`` that holds the current folder (the process would be left in the deleted one)
and a mount point, bind mounts included (its staging folder would be on another file
system, or the swap would fail with EBUSY). Errors name ``--out``, not the staging
folder, in one line that starts with it (the system's errno kept on the exception). An
``--out`` without a ``summary.json`` that holds a file of those names (a trace saved as
``commands.csv``) holds no run's outputs, and a table file that a
replay's ``summary.json`` does not list (``output.files``) is not that run's: either is
refused before anything is written, as is an input of the run (a trace, a scene) that is
a run's output by its name in ``--out``, which the commit would replace.

Leftovers: a staging or set-aside folder whose process is gone is recognised by its
name and cleared by the next run into the same ``--out`` (:meth:`Staging.begin`), as
above (only a run's own outputs, folders holding nothing else, such as a killed batch's
job folders, and copies of the user's files are deleted), which says
so (a warning in its summary); a staging folder of this process is touched only by the
:class:`Staging` that made it. A run that is killed therefore never writes a
``summary.json`` of its own: its outputs are only ever seen complete, so no summary
marks an interrupted run.
"""

from __future__ import annotations

import ctypes
import errno
import filecmp
import glob
import hashlib
import json
import os
import re
import secrets
import shutil
import stat
from pathlib import Path

from frictex.device.errors import InputError, OutputSpaceError, RunFailed, disk_full

#: the tables' stems, formats, and the other names a run writes into its output folder
OUTPUT_STEMS = ("commands", "friction")
_TABLE = re.compile(r"(?:commands|friction)\.(?:csv|npz|parquet)(?:\.partial|\.\w+\.raw)?")
_FRAME = re.compile(r"frame[_-]\d+\.png(?:\.partial)?")  # replay's frame_N, the demo's frame-N
SUMMARY, FRAMES = "summary.json", "frames"
_STAGING, _OLD, _KEPT = "frictex-staging", "frictex-old", "frictex-kept"
_RENAME_EXCHANGE = 2
#: a longer output folder name is shortened in its staging folders' names
_LONGEST_NAME = 150
#: staging folders this process made and has not yet committed or aborted: the output
#: folder each stands in for
_OWNED: dict[str, Path] = {}


def is_run_output(entry: os.DirEntry | Path) -> bool:
    """Whether ``entry`` (of an output folder) is a run's own (see the module docstring):
    ``summary.json``, a table file, or a ``frames`` folder holding only frame files."""
    path = Path(entry)
    if not path.is_dir() or path.is_symlink():
        return path.name == SUMMARY or _TABLE.fullmatch(path.name) is not None
    if path.name != FRAMES:
        return False
    return all(_FRAME.fullmatch(e.name) and not e.is_dir(follow_symlinks=False)
               for e in os.scandir(path))


def is_run_folder(path: str | Path) -> bool:
    """Whether ``path`` is a folder (not a link) holding nothing but a run's outputs
    (:func:`is_run_output`): a run's output folder, such as a batch's job folder."""
    path = Path(path)
    return (path.is_dir() and not path.is_symlink()
            and all(is_run_output(entry) for entry in os.scandir(path)))


def shown_path(path: str | Path) -> Path:
    """``path`` as an error names it: where it is inside a staging folder of this process,
    the path it will have in the output folder that one stands in for (a batch's job's
    staging folder inside the batch's: the job's folder in the batch's ``--out``)."""
    path = Path(path)
    while True:
        folder = next((f for f in (path, *path.parents) if str(f) in _OWNED), None)
        if folder is None:
            return path
        path = _OWNED[str(folder)] / path.relative_to(folder)


def _short(name: str) -> str:
    """``name`` as it prefixes staging names: itself, or shortened with its hash."""
    if len(os.fsencode(name)) <= _LONGEST_NAME:
        return name
    return name[:100] + "~" + hashlib.sha256(os.fsencode(name)).hexdigest()[:16]


class Staging:
    """The staging folder of one run into ``out`` (see the module docstring)."""

    def __init__(self, out: str | Path, owned: tuple[str, ...] = (),
                 owned_pattern: re.Pattern | None = None, claimed_by_summary: bool = True):
        self.out = Path(os.path.realpath(out))  # a link to a folder: that folder
        #: more names (files or folders) in ``out`` that are this kind of run's own
        #: outputs, besides a replay's (``frictex demo --record``: ``events.csv``), and a
        #: pattern of such names (a batch: its jobs' replays' staging leftovers)
        self.owned = frozenset(owned)
        self.owned_pattern = owned_pattern
        #: whether ``out`` holds a run's outputs only beside its ``summary.json`` (a batch
        #: checks its own ``--out``: ``app.engine.batch_folder.earlier_jobs``)
        self.claimed_by_summary = claimed_by_summary
        if self.out.parent == self.out:
            raise InputError(f"{self.out}: the root folder cannot be an output folder (a run "
                             "replaces its output folder as a whole): name a folder of its own")
        self.token = secrets.token_hex(6)
        self.folder = self._name(_STAGING)
        self.removed: list[str] = []  # leftovers of killed runs that begin() removed

    def _name(self, kind: str) -> Path:
        return self.out.with_name(f".{_short(self.out.name)}.{kind}.{os.getpid()}.{self.token}")

    def above(self) -> Path:
        """The nearest existing folder above ``out``: where its staging folder goes (the
        folders between made first), on its file system."""
        return next(folder for folder in self.out.parents if folder.exists())

    def check(self, inputs: tuple[str | Path | None, ...] = ()) -> None:
        """Refuse, touching nothing, an ``out`` this run could not replace whole, or one
        whose replacing would delete one of the run's ``inputs`` (paths; None: none)."""
        if self.out.exists() and not self.out.is_dir():
            raise InputError(f"{self.out}: exists and is not a folder")
        above = self.above()
        if not above.is_dir():
            raise InputError(f"{self.out}: {above} is not a folder, so no folder can be made "
                             "in it")
        cwd = Path.cwd().resolve()
        if self.out.exists() and (cwd == self.out or self.out in cwd.parents):
            raise InputError(f"{self.out}: holds the current folder; a run replaces its output "
                             "folder as a whole: write into a folder of its own")
        if self.out.is_dir() and _is_mount(self.out):
            raise InputError(f"{self.out}: a mount point, which a run cannot replace; write "
                             "into a folder inside it")
        if self.out.is_dir():
            foreign = self._foreign()
            if foreign:
                raise InputError(f"{self.out}: holds the folder {foreign[0]!r}, not a run's "
                                 "output; a run replaces its output folder as a whole: write "
                                 "into a folder of its own")
            unclaimed = self._unclaimed()
            if unclaimed:
                why = (f"its {SUMMARY} does not list it" if (self.out / SUMMARY).exists()
                       else f"no {SUMMARY}")
                raise InputError(f"{self.out}: holds {unclaimed[0]!r} but {why}, so not a "
                                 "run's output, which a run would replace with its own: move "
                                 "it or write into another folder")
            for path in inputs:
                if path is not None and self._replaces(Path(path)):
                    raise InputError(f"{path}: an input of the run, in --out {self.out}, "
                                     "where the run replaces it with its own output: move it "
                                     "or write into another folder")

    def _unclaimed(self) -> list[str]:
        """The names in ``out`` a run would replace as its own (:meth:`_own`) where no
        ``summary.json`` says a run wrote them (none when not ``claimed_by_summary``): with
        no summary, every such name (an empty folder holds nothing to lose); with a
        replay's, the tables its ``output.files`` does not list (a summary without that
        list, the demo's, claims them by name)."""
        if not self.claimed_by_summary:
            return []
        if not (self.out / SUMMARY).exists():
            return sorted(e.name for e in os.scandir(self.out) if self._own(e) and not (
                e.is_dir(follow_symlinks=False) and not any(os.scandir(e.path))))
        listed = _listed_tables(self.out / SUMMARY)
        if listed is None:
            return []
        return sorted(e.name for e in os.scandir(self.out)
                      if _TABLE.fullmatch(e.name) and e.name not in listed)

    def _replaces(self, path: Path) -> bool:
        """Whether the commit would replace the file ``path`` (a run's output in ``out``)."""
        real = Path(os.path.realpath(path))
        if real.parent != self.out:
            return False
        return any(e.name == real.name and self._own(e) for e in os.scandir(self.out))

    def _foreign(self) -> list[str]:
        """The folders in ``out`` that are not a run's."""
        return sorted(e.name for e in os.scandir(self.out)
                      if e.is_dir(follow_symlinks=False) and not self._own(e))

    def _own(self, entry: os.DirEntry) -> bool:
        """Whether ``entry`` is a run's output (:func:`is_run_output`, or named in ``owned``
        or by ``owned_pattern``)."""
        return (entry.name in self.owned or is_run_output(entry)
                or (self.owned_pattern is not None
                    and self.owned_pattern.fullmatch(entry.name) is not None))

    def begin(self) -> Path:
        """Clear the leftovers of killed runs, then create the staging folder (with the
        output folder's permissions, owner and extended attributes)."""
        self.check()
        self._recover()
        try:
            self.out.parent.mkdir(parents=True, exist_ok=True)
            self.folder.mkdir()
            _OWNED[str(self.folder)] = self.out
            if self.out.is_dir():
                _same_access(self.out, self.folder)
        except OSError as exc:
            self.abort()
            raise self.failed(exc, "create its staging folder beside it") from None
        return self.folder

    def _recover(self) -> None:
        prefix = _short(self.out.name)
        for path in sorted(self.out.parent.glob(f".{glob.escape(prefix)}.frictex-*.*")):
            kind, _, rest = path.name[len(prefix) + 2:].partition(".")
            pid = rest.split(".")[0]
            if kind not in (_STAGING, _OLD) or not pid.isdigit() or str(path) in _OWNED:
                continue
            if int(pid) != os.getpid() and _alive(int(pid)):  # a run going on now
                continue
            if kind == _OLD and not self.out.exists():
                os.rename(path, self.out)  # killed between the two renames: the previous run
                continue
            kept = self._clear(path, leftover=True)
            self.removed.append(path.name if kept is None else f"{path.name} (kept as {kept.name}: "
                                "it held files not a run's)")

    def write_text(self, name: str, text: str) -> Path:
        """Write ``text`` (UTF-8) as the staging folder's file ``name``; its path. A full
        disk is said of ``out`` (:class:`OutputSpaceError`), as the commit's is."""
        path = self.folder / name
        try:
            path.write_text(text, encoding="utf-8")
        except OSError as exc:
            raise self.failed(exc, f"write {name}") from None
        return path

    def commit(self) -> None:
        """Swap the staging folder in as ``out``; the previous run's outputs are deleted,
        the rest kept (module docstring). :class:`RunFailed` if a folder not a run's
        appeared in ``out`` during the run (``out`` left as it was)."""
        try:
            if not self.out.exists() and self._rename_into_place():
                return
            foreign = self._foreign()
            if foreign:
                raise RunFailed(self._appeared(foreign[0]))
            for entry in os.scandir(self.out):
                if not entry.is_dir(follow_symlinks=False) and not self._own(entry):
                    _carry(Path(entry.path), self.folder / entry.name)
            if _exchange(self.folder, self.out):
                old = self.folder
            else:
                old = self._name(_OLD)
                os.rename(self.out, old)
                os.rename(self.folder, self.out)
        except OSError as exc:
            raise self.failed(exc, "replace it with the run's outputs") from None
        _OWNED.pop(str(self.folder), None)
        kept = self._clear(old)
        if kept is not None:
            raise RunFailed(f"{self.out}: holds the new run's outputs, but files appeared "
                            "beside the previous run's while they were swapped, and could not "
                            f"be moved into it: kept in {kept}")

    def _rename_into_place(self) -> bool:
        """Rename the staging folder to ``out``, which did not exist: True; False if
        another run's commit created ``out`` (with files) since it was looked for, which
        the commit then replaces as any existing ``out``."""
        try:
            os.rename(self.folder, self.out)
        except OSError as exc:
            if exc.errno not in (errno.ENOTEMPTY, errno.EEXIST):
                raise
            return False
        _OWNED.pop(str(self.folder), None)
        return True

    def _appeared(self, name: str) -> str:
        """Why the commit refuses the folder ``name`` that appeared in ``out`` during the
        run: another run's output (it holds a ``summary.json``: a batch's job folder,
        committed by a batch into the same ``out`` meanwhile), or a folder not a run's."""
        if (self.out / name / SUMMARY).is_file():
            return (f"{self.out}: another run committed its outputs into it during this run "
                    f"(the folder {name!r}, with a {SUMMARY}); nothing was replaced: run "
                    "again once it has finished, or write into another folder")
        return (f"{self.out}: the folder {name!r}, not a run's output, appeared in it during "
                "the run; nothing was replaced (a run replaces its output folder as a "
                "whole): move it and run again")

    def _clear(self, old: Path, leftover: bool = False) -> Path | None:
        """Delete ``old`` (a previous run's folder, or a ``leftover`` of a killed run): its
        run's outputs and the copies of files that are also in ``out``; anything else is
        moved into ``out``, or ``old`` is kept under a name of its own, returned. A
        leftover's folders that hold only a run's outputs (a killed batch's job folders)
        are deleted too: moved into ``out`` they would be folders not this run's, which
        its commit refuses."""
        left = []
        for entry in os.scandir(old):
            path = Path(entry.path)
            if (self._own(entry) or _same_file(path, self.out / entry.name)
                    or (leftover and is_run_folder(path))):
                if entry.is_dir(follow_symlinks=False):
                    shutil.rmtree(path)
                else:
                    path.unlink()
            elif self.out.is_dir() and not os.path.lexists(self.out / entry.name):
                os.rename(path, self.out / entry.name)
            else:
                left.append(entry.name)
        if not left:
            os.rmdir(old)
            return None
        kept = self.out.with_name(f".{_short(self.out.name)}.{_KEPT}.{secrets.token_hex(6)}")
        os.rename(old, kept)
        return kept

    def abort(self) -> None:
        """Delete the staging folder; ``out`` stays as it was."""
        shutil.rmtree(self.folder, ignore_errors=True)
        _OWNED.pop(str(self.folder), None)

    def failed(self, exc: OSError, doing: str) -> OSError:
        """``exc`` (on the staging folder, while the run did ``doing``) as a one-line error
        naming ``out``, with ``exc``'s errno: a full disk, a folder that cannot be written
        (:class:`OutputSpaceError`) or a mount point (:class:`InputError`)."""
        full = disk_full(exc, f"{self.out}: the disk is full ({exc.strerror}); nothing was "
                              "replaced")
        if full is not None:
            return full
        if exc.errno == errno.EBUSY:
            return InputError(f"{self.out}: a mount point, which a run cannot replace; write "
                              "into a folder inside it")
        if exc.errno is None:
            return exc
        failed = OutputSpaceError(f"{self.out}: cannot {doing} ({exc.strerror})")
        failed.errno = exc.errno  # with a strerror too, str() would start '[Errno N]'
        return failed


#: the largest summary.json read for the tables it lists (a replay's is a few kB)
_SUMMARY_BYTES = 1 << 20


def _listed_tables(summary: Path) -> set[str] | None:
    """The table files a replay's ``summary`` lists (``output.files``); None for a summary
    that lists none (the demo's layout, an unreadable or oversized file)."""
    try:
        with open(summary, "rb") as fh:
            doc = json.loads(fh.read(_SUMMARY_BYTES + 1)[:_SUMMARY_BYTES])
    except (OSError, ValueError):
        return None
    output = doc.get("output") if isinstance(doc, dict) else None
    files = output.get("files") if isinstance(output, dict) else None
    if not isinstance(files, list) or not all(isinstance(f, str) for f in files):
        return None
    return set(files)


def _is_mount(path: Path) -> bool:
    """Whether ``path`` (resolved) is a mount point, a bind mount of a folder of the same
    file system included (``/proc/self/mountinfo``, where there is one)."""
    if os.path.ismount(path):
        return True
    try:
        with open("/proc/self/mountinfo", encoding="utf-8", errors="surrogateescape") as fh:
            points = {_unescape(line.split()[4]) for line in fh if len(line.split()) > 4}
    except OSError:
        return False
    return str(path) in points


def _unescape(field: str) -> str:
    """A mountinfo path: space, tab, newline and backslash are written as octal escapes."""
    return re.sub(r"\\([0-7]{3})", lambda m: chr(int(m.group(1), 8)), field)


def _same_access(src: Path, dst: Path) -> None:
    """Give folder ``dst`` the owner, group, permissions and extended attributes (ACLs)
    of ``src``, each where the process may."""
    st = os.stat(src)
    try:
        os.chown(dst, st.st_uid, st.st_gid)
    except PermissionError:
        pass
    os.chmod(dst, stat.S_IMODE(st.st_mode))
    try:
        names = os.listxattr(src)
    except OSError:  # a file system without them
        return
    for name in names:
        try:
            os.setxattr(dst, name, os.getxattr(src, name))
        except OSError:
            pass


def _same_file(a: Path, b: Path) -> bool:
    """Whether ``a`` is ``b`` carried over: the same file (a hard link), or an equal
    copy (a link with the same target, a file with the same bytes)."""
    try:
        sa, sb = os.lstat(a), os.lstat(b)
    except FileNotFoundError:
        return False
    if os.path.samestat(sa, sb):
        return True
    if stat.S_ISLNK(sa.st_mode) and stat.S_ISLNK(sb.st_mode):
        return os.readlink(a) == os.readlink(b)
    return (stat.S_ISREG(sa.st_mode) and stat.S_ISREG(sb.st_mode)
            and filecmp.cmp(a, b, shallow=False))


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

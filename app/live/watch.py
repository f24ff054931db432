"""Which of a set of files changed and then held still (polled; no threads, no waits).

A file's stamp is its modification time (ns), size and inode, or None while it cannot be
stat'ed: an edit in place, a save by renaming a new file over the old one, a file
appearing and one vanishing all change it. A new stamp is reported only once a second
look finds it unchanged: an editor that truncates a file and then writes it can be
caught in between, and the empty file it leaves for that moment is not the edit.
Polling is the caller's: it calls :meth:`FileWatch.changed` when it wants (the demo:
every ``RELOAD_POLL_S`` on its clock), so a test drives it with the files and the
times it sets.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Callable, Iterable

Stamp = tuple[int, int, int] | None


def stamp(path: Path) -> Stamp:
    """(mtime ns, size bytes, inode) of ``path``, or None if it cannot be stat'ed."""
    try:
        info = os.stat(path)
    except (OSError, ValueError):
        return None
    return info.st_mtime_ns, info.st_size, info.st_ino


class FileWatch:
    """``stamps``: each watched path's stamp as last reported; ``stat`` gives a path's
    stamp now."""

    def __init__(self, paths: Iterable[Path] = (), stat: Callable[[Path], Stamp] = stamp):
        self.stat = stat
        self.stamps: dict[Path, Stamp] = {}
        self._looked: dict[Path, Stamp] = {}  # each path's stamp at the last look
        self.watch(paths)

    @property
    def paths(self) -> tuple[Path, ...]:
        return tuple(self.stamps)

    def watch(self, paths: Iterable[Path]) -> None:
        """Watch ``paths`` from now on: a file already watched keeps its stamps (a change
        not yet reported stays to be reported), a new one is stamped now."""
        paths = [Path(p) for p in paths]
        now = {p: self.stat(p) for p in paths if p not in self.stamps}
        self.stamps = {p: self.stamps[p] if p in self.stamps else now[p] for p in paths}
        self._looked = {p: self._looked[p] if p in self._looked else now[p] for p in paths}

    def changed(self) -> list[Path]:
        """The watched files, in watch order, whose stamp differs from the one last
        reported and is the same as at the previous look (a change held still for one
        look); their new stamps are taken as reported."""
        moved = []
        for path, reported in self.stamps.items():
            now, before = self.stat(path), self._looked[path]
            self._looked[path] = now
            if now != reported and now == before:
                self.stamps[path] = now
                moved.append(path)
        return moved

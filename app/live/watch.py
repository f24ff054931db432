"""Which of a set of files changed since the last look (polled; no threads, no waits).

A file's stamp is its modification time (ns), size and inode, or None while it cannot be
stat'ed: an edit in place, a save by renaming a new file over the old one, a file
appearing and one vanishing all change it. Polling is the caller's: it calls
:meth:`FileWatch.changed` when it wants (the demo: every ``RELOAD_POLL_S`` on its clock),
so a test drives it with the files and the times it sets.
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
    """The stamps of ``paths`` as last seen; ``stat`` gives a path's stamp."""

    def __init__(self, paths: Iterable[Path] = (), stat: Callable[[Path], Stamp] = stamp):
        self.stat = stat
        self.stamps: dict[Path, Stamp] = {}
        self.watch(paths)

    @property
    def paths(self) -> tuple[Path, ...]:
        return tuple(self.stamps)

    def watch(self, paths: Iterable[Path]) -> None:
        """Watch ``paths`` from now on: a file already watched keeps the stamp it was
        last seen with (a change not yet reported stays to be reported), a new one is
        stamped now."""
        self.stamps = {Path(p): self.stamps[Path(p)] if Path(p) in self.stamps else self.stat(Path(p))
                       for p in paths}

    def changed(self) -> list[Path]:
        """The watched files whose stamp differs from the last look, in watch order;
        their new stamps are taken."""
        moved = []
        for path, seen in self.stamps.items():
            now = self.stat(path)
            if now != seen:
                self.stamps[path] = now
                moved.append(path)
        return moved

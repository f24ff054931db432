"""A batch's ``--out`` replaced as a whole: the previous batch's or the new one's, whatever
stops the batch.

The jobs write their folders into a staging folder beside ``--out`` (the one a replay
uses, ``app.engine.staging``: same file system, its leftovers cleared by the next run)
and the batch swaps it in at its end, ``batch.csv`` with it. Until then ``--out`` holds
the previous batch untouched: a SIGKILL, a power cut or a full disk leaves it complete.

What the new ``--out`` holds:

- a batch that ran to its end (some jobs failed or not): ``batch.csv`` and the folders of
  the jobs it lists ``ok``; an earlier job folder holding a file that is not a run's
  output (the user's) is kept as it was and named in a warning;
- a batch stopped by a signal (Ctrl-C, SIGTERM, SIGHUP): the same, and every earlier job
  folder it did not replace, kept as it was and listed in ``batch.csv`` with status
  ``earlier`` and the earlier ``batch.csv``'s scene, trace and figures for it (what that
  folder holds, which the new manifest's line of that name may not), unless its job
  ran and failed: that job's row stays ``failed``, its error saying the earlier
  output was kept. Stopping a rerun deletes nothing that was complete.

What is carried from the previous ``--out`` into the new one is hard-linked (no byte
copied; copied where the file system has no hard links), never moved, so that the
previous ``--out`` stays whole until the swap.
"""

from __future__ import annotations

import csv
import math
import os
import re
import shutil
from pathlib import Path

from frictex.app.engine.batch import (INPUTS, MEASURES, RESERVED, RESULTS, ROW_BYTES,
                                      write_results)
from frictex.app.engine.staging import SUMMARY, Staging, is_run_folder, is_run_output
from frictex.app.engine.tables import WRITE_ELSEWHERE, check_room
from frictex.device.errors import InputError, OutputSpaceError
from frictex.device.safe_text import escape, quoted

#: a killed replay's staging leftover in an earlier batch's ``--out`` (``app.engine.staging``)
_LEFTOVER = re.compile(r"\..+\.frictex-(?:staging|old|kept)\..+")
#: a ``batch.csv`` row's status for a job folder an earlier batch wrote, kept
EARLIER = "earlier"


def earlier_jobs(out_dir: Path) -> list[str]:
    """The job folders an earlier batch left in ``out_dir`` (sorted names; none where it
    does not exist); an InputError, touching nothing, where it holds anything else than
    an earlier batch's outputs: ``batch.csv`` (and ``batch.csv.partial``), job folders (a
    folder with a replay's ``summary.json``) and the staging leftovers of killed replays
    (``.<name>.frictex-*``)."""
    out_dir = Path(out_dir)
    if not out_dir.exists():
        return []
    if not out_dir.is_dir():
        raise InputError(f"{out_dir}: exists and is not a folder; --out is a folder for the "
                         "jobs' folders and batch.csv")
    jobs = []
    for entry in sorted(os.scandir(out_dir), key=lambda e: e.name):
        if entry.name in RESERVED and entry.is_file(follow_symlinks=False):
            continue
        if _LEFTOVER.fullmatch(entry.name):
            continue
        if entry.is_dir(follow_symlinks=False) and os.path.isfile(Path(entry.path) / SUMMARY):
            jobs.append(entry.name)
            continue
        raise InputError(f"{out_dir}: holds {quoted(escape(entry.name, 80))}, which is not an "
                         f"earlier batch's output ({RESULTS}, job folders with a "
                         f"{SUMMARY}); a batch replaces what an earlier one wrote in its "
                         "--out: write into a new folder or move it")
    return jobs


class BatchFolder:
    """``--out`` of a batch of jobs named ``names`` (see the module docstring)."""

    def __init__(self, out_dir: Path, names: list[str]):
        self.out = Path(out_dir)
        self.earlier = earlier_jobs(self.out)
        self.names = list(names)
        self.staging = Staging(self.out, owned=tuple(sorted({*self.names, *self.earlier,
                                                             *RESERVED})),
                               owned_pattern=_LEFTOVER, claimed_by_summary=False)

    def begin(self) -> Path:
        """The folder the jobs write their folders into (the staging folder). Refused
        first, as a replay's output folder is (``tables.check_room``): one on a file
        system that holds no files (/proc), or without room for ``batch.csv``."""
        self.staging.check()
        check_room(self.staging.above(), len(self.names) * ROW_BYTES,
                   f"the rows of {RESULTS}", WRITE_ELSEWHERE)
        return self.staging.begin()

    def commit(self, rows: list[dict], stopped: bool) -> tuple[list[dict], list[str]]:
        """Swap the new ``--out`` in: the jobs' ``rows`` (``batch.csv``'s, in the jobs'
        order), whether a signal ``stopped`` the batch. Returns the rows written (a
        stopped batch's: each earlier folder kept listed, :meth:`_kept_rows`) and the names
        of the earlier folders kept because they hold the user's files."""
        staged = self.staging.folder
        ok = {row["name"] for row in rows if row["status"] == "ok"}
        before = _earlier_rows(self.out / RESULTS)
        rows = list(rows)
        users, kept = [], []
        for name in self.earlier:
            if name in ok:
                _carry_users_files(self.out / name, staged / name)
            elif stopped:
                _link_tree(self.out / name, staged / name)
                kept.append(name)
            elif not is_run_folder(self.out / name):
                _link_tree(self.out / name, staged / name)
                users.append(name)
        if stopped:
            rows = self._kept_rows(rows, kept, before)
        _drop_unlisted(staged, {*ok, *kept, *users})
        try:
            self._write_and_swap(rows)
        except OutputSpaceError as exc:
            raise _not_kept(exc, len(ok)) from None
        return rows, users

    def _write_and_swap(self, rows: list[dict]) -> None:
        """Write ``batch.csv`` into the staging folder (its errors naming ``--out``, as
        the swap's do) and swap the staging folder in."""
        try:
            write_results(self.staging.folder, rows)
        except OSError as exc:
            raise self.staging.failed(exc, f"write {RESULTS}") from None
        self.staging.commit()

    @staticmethod
    def _kept_rows(rows: list[dict], kept: list[str], before: dict) -> list[dict]:
        """``rows`` with each earlier folder ``kept`` by a stopped batch listed: the row
        of its job that did not finish replaced by an ``earlier`` one, that of its job
        that failed saying the folder was kept, or a row of its own (no job number) after
        them."""
        out = [_kept(row, before) if row["name"] in kept else row for row in rows]
        listed = {row["name"] for row in rows}
        return out + [_kept({"job": None, "name": name}, before)
                      for name in kept if name not in listed]

    def abort(self) -> None:
        """Delete the staging folder; ``--out`` stays as it was."""
        self.staging.abort()


def _not_kept(exc: OutputSpaceError, finished: int) -> OutputSpaceError:
    """``exc`` (a full disk or a folder that cannot be written, naming ``--out``) also
    saying that the outputs of the ``finished`` jobs were not kept."""
    if not finished:
        return exc
    said = OutputSpaceError(f"{exc}; the outputs of the jobs that finished ({finished}) were "
                            "not kept either (a batch replaces its --out all or nothing)")
    said.errno = exc.errno
    return said


def _drop_unlisted(staged: Path, listed: set[str]) -> None:
    """Delete from ``staged`` every entry but the job folders ``listed``: what a job left
    that did not finish (a Dask task that runs on after a stopped batch's end writes on
    into its own staging folder, which, deleted here, never reaches ``--out``)."""
    for entry in os.scandir(staged):
        if entry.name in listed:
            continue
        if entry.is_dir(follow_symlinks=False):
            _delete_tree(Path(entry.path))
        else:
            os.unlink(entry.path)


def _delete_tree(path: Path) -> None:
    """Delete folder ``path``, which a job still running may be adding files to."""
    for _ in range(10):
        shutil.rmtree(path, ignore_errors=True)
        if not os.path.lexists(path):
            return
    shutil.rmtree(path)  # the error, where it still cannot be deleted


#: how a failed job's error in a stopped batch ends where its earlier folder was kept
FAILED_KEPT = "; the earlier batch's output of this job was kept (this one was stopped)"


def kept_folder(row: dict) -> bool:
    """Whether ``batch.csv``'s ``row`` lists an earlier job folder a stopped batch kept."""
    return row["status"] == EARLIER or (row["status"] == "failed"
                                        and row["error"].endswith(FAILED_KEPT))


def _kept(row: dict, before: dict) -> dict:
    """The ``batch.csv`` row of an earlier job folder kept, ``row`` that of its job (only
    ``job`` and ``name`` where the new batch has none): the failed job's row, saying so;
    else status ``earlier``, the earlier batch's scene, trace and figures for it (empty
    where its ``batch.csv`` has none)."""
    if row.get("status") == "failed":
        return {**row, "error": f"{row['error']}{FAILED_KEPT}"}
    earlier = before.get(row["name"], {})
    return {"job": row["job"], "name": row["name"], **{key: earlier.get(key) for key in INPUTS},
            "status": EARLIER,
            "error": "kept from an earlier batch: this one was stopped before it replaced it",
            **{key: earlier.get(key) for key in MEASURES}}


def _earlier_rows(path: Path) -> dict[str, dict]:
    """The earlier ``batch.csv``'s scene, trace and figures of its ok (or kept) jobs by
    name, as it wrote them (a figure that is not a number, or a column it did not have
    yet, left empty); none where it is missing or unreadable (its folders are then kept
    without them)."""
    try:
        with open(path, encoding="utf-8", newline="") as fh:
            rows = list(csv.DictReader(fh))
    except (OSError, UnicodeDecodeError, csv.Error):
        return {}
    return {row["name"]: {**{key: row.get(key) or None for key in INPUTS},
                          **{key: row.get(key) if _is_number(row.get(key)) else None
                             for key in MEASURES}}
            for row in rows if row.get("status") in ("ok", EARLIER) and row.get("name")}


def _is_number(text) -> bool:
    try:
        return math.isfinite(float(text))
    except (TypeError, ValueError):
        return False


def _link_tree(src: Path, dst: Path) -> None:
    """A copy of folder ``src`` at ``dst`` made of hard links (copies where the file system
    has none)."""
    shutil.copytree(src, dst, symlinks=True, copy_function=_link)


def _carry_users_files(src: Path, dst: Path) -> None:
    """Hard-link into job folder ``dst`` what earlier job folder ``src`` holds that is not
    a run's output (the user's files and folders)."""
    for entry in os.scandir(src):
        if is_run_output(entry) or os.path.lexists(dst / entry.name):
            continue
        if entry.is_dir(follow_symlinks=False):
            _link_tree(Path(entry.path), dst / entry.name)
        else:
            _link(entry.path, dst / entry.name)


def _link(src, dst) -> None:
    try:
        os.link(src, dst, follow_symlinks=False)
    except OSError:
        shutil.copy2(src, dst, follow_symlinks=False)

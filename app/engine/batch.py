"""Many replays at once: a manifest of jobs, run over this machine's cores or a Dask cluster.

Manifest grammar (CSV with a header; ``#`` lines are comments)::

    scene,trace[,renderer][,rate_hz][,block][,format][,name]

``scene`` and ``trace`` as ``frictex replay`` takes them (a file, relative to the
manifest's folder, or a bundled name, never a file of that name in the current folder:
one that is neither is a problem of its line, with the library's "did you mean" hint),
confined as the files a texture file names are
(``textures.outside``): in the manifest's folder or below, links followed, unless
``--allow-outside`` (``FRICTEX_ALLOW_OUTSIDE=1``) lifts it, so that a stranger's manifest
cannot make a batch read any file of the machine; a '..' or a link leading out is
refused, and an absolute path unless the file it names lies in the folder (a script
that writes a manifest beside its traces, as ``frictex bench`` does, may write their
absolute paths); ``renderer`` empty means the file's own;
``rate_hz`` (default 10000), ``block`` (default 5 ms of samples: 50 at 10 kHz) and ``format`` (csv, npz, parquet;
default csv) as the replay's options, within the same bounds as on the command line
(``--rate`` 100 to 1e6 Hz, ``--block`` 1 to 100000 samples); ``name`` the job's output
folder under the batch's ``--out`` (default: ``<row number>-<scene stem>-<trace stem>``,
the stems' other characters as ``_``), unique whatever the case of its letters (``dup``
and ``DUP`` are one name: one folder on macOS and Windows)::

    rate_hz := a number as trace files write it (ASCII decimal: 10000, 2.5e4)
    block   := DIGITS                                   # ASCII 0-9
    name    := (letter | digit) { letter | digit | "." | "_" | "-" }   # ASCII, at most 64
               except a name in RESERVED: batch.csv, batch.csv.partial (any case)

A name is thus a plain folder name and a plain cell of ``batch.csv``: no path separator,
no control character, no line break, never ``.`` or ``..``, never a file the batch
writes itself (:data:`RESERVED`). Cells may be quoted as CSV
allows; a line ends at a line feed (a carriage return before it is dropped).

The manifest is read as the trace reader reads traces (``textures.library.read_utf8``):
a regular UTF-8 file of at most MAX_MANIFEST_BYTES, without NUL bytes, lines of at most
MAX_LINE_BYTES; a FIFO or a device is refused before anything is read. Errors name the
file and the line, and show values escaped and cut (``device.safe_text``). Every problem
of a manifest is reported at once, one line each (at most MAX_PROBLEMS_SHOWN, then how
many more), as ``frictex validate`` reports a texture file's: a bad header alone stops
the reading, since the rows cannot be read without it. No job runs unless every row is
good.

Every job writes its replay outputs into its folder; the batch writes ``batch.csv``,
one row per job (:data:`RESULT_COLUMNS`):

- ``job`` (its row among the jobs, from 0), ``name``, ``scene`` and ``trace`` (the
  manifest's line's text, a file as it names it; an ``earlier`` row's are the
  earlier batch's, what its folder holds), ``status``: ``ok``, ``failed``
  (``error`` says why), ``interrupted`` (the batch was stopped before the job finished:
  ``error`` says whether it had started) or ``earlier`` (a stopped batch kept an earlier
  batch's folder of that name: below);
- ``output_s``: seconds of output the job wrote; ``wall_s``: the job's wall time in its
  worker, from its start to its outputs in place, start-up included (reading the scene
  and the trace, loading the compiled kernels); ``x_realtime``: ``output_s / wall_s``;
  ``x_realtime_end_to_end``: the replay's own factor (``timings`` in its
  ``summary.json``), which leaves the start-up out, so it is the larger of the two;
- ``clamps`` (the inversion's clamped samples, all guards), ``actuator_limited``
  (samples where an actuator limit changed the actuation's solution: the summary's
  ``counts.actuator_limited``), ``modal_capped`` (samples where two fingers could not be
  given independent amplitudes: ``counts.modal_capped``, empty where the summary has
  none, one from before version 6: not counted, which is not none capped),
  ``modal_unserved`` (finger samples touching beyond the fingers a modal scene's modes
  serve: ``counts.modal_unserved``, empty likewise for a summary from before version 7)
  and ``warnings`` (how many; the texts are in the job's ``summary.json``).

A job that is not ``ok`` has these numeric cells empty (an ``earlier`` one the earlier
batch's figures). A failed job does not stop the others, whatever it raised: an
unexpected exception (a bug in frictex or in a plugin renderer) is its ``failed`` row,
``internal error (...)`` and the exception's type and message, its traceback on stderr
(a Dask worker's log on a cluster).

The output folder. ``--out`` is new, empty, or an earlier batch's: nothing in it but
``batch.csv`` (and ``batch.csv.partial``), job folders (a folder with a replay's
``summary.json``) and the staging leftovers of killed replays (``.<name>.frictex-*``);
anything else is refused before a job runs, as is an ``--out`` on a file system that
holds no files (/proc), in a replay's words. The batch replaces it as a whole when it
ends (``app.engine.batch_folder``): until then it holds the earlier batch untouched,
whatever stops the batch (SIGKILL included; a full disk, which names ``--out``); then
``batch.csv`` and exactly the folders
of the jobs it lists ``ok`` (or ``earlier``, below). An earlier job folder that holds a
file not a run's output (the user's) is kept as it is and named in a warning.

Ctrl-C (or SIGTERM, SIGHUP) stops a batch within one to two seconds: no job starts after
it, each running one ends as an interrupted replay ends, and the new ``--out`` holds the
jobs that finished (``ok``, or ``failed``), every earlier job folder it did not replace,
kept and listed with status ``earlier`` (the earlier ``batch.csv``'s figures; ``job``
empty for a name the new manifest does not have; a failed job's row stays ``failed``,
its error saying the earlier folder was kept), and the rest ``interrupted``; the
command then exits as an interrupted replay does (130 for Ctrl-C, 128 + the signal
otherwise). Stopping a rerun deletes nothing that was complete. On a Dask cluster the jobs
running are given a few seconds (``fanout.DASK_STOP_S``) to finish; one still running
then is listed ``interrupted`` and runs on to its end on its worker (Dask cannot stop
it), a warning says so, and what it writes never reaches ``--out``. A text cell that would start with ``=``, ``+``, ``-``, ``@``, a tab or a
carriage return (an error that starts with a scene named ``=HYPERLINK(...)``) is written
behind a single quote, so that a spreadsheet shows it as text, never runs it (OWASP's
rule for CSV injection).
"""

from __future__ import annotations

import csv
import math
import os
import re
import sys
import time
import traceback
from dataclasses import dataclass
from pathlib import Path

from frictex.app.engine.limits import BLOCK_SIZES, OUTPUT_RATES_HZ
from frictex.app.engine.tables import FORMATS
from frictex.device.errors import FrictexError, InputError
from frictex.device.safe_text import printable, quoted
from frictex.rendering.input.trace_file import CR_ONLY, MAX_LINE_BYTES, NUMBER, describe_header
from frictex.textures.errors import TextureError
from frictex.textures.library import UnreadableText, bundled_file, file_problem, read_utf8
from frictex.textures.outside import HOW, outside_allowed, allowing_outside, leads_out

COLUMNS = ("scene", "trace", "renderer", "rate_hz", "block", "format", "name")
RESULT_COLUMNS = ("job", "name", "scene", "trace", "status", "error", "output_s", "wall_s",
                  "x_realtime", "x_realtime_end_to_end", "clamps", "actuator_limited",
                  "modal_capped", "modal_unserved", "warnings")
#: the cells of ``batch.csv`` that say which replay a job folder holds
INPUTS = ("scene", "trace")
#: the numeric cells of ``batch.csv``, empty for a job that is not ``ok``
MEASURES = RESULT_COLUMNS[RESULT_COLUMNS.index("output_s"):]
#: the files a batch writes in its ``--out`` beside the job folders: no job's name
RESULTS, RESULTS_PARTIAL = "batch.csv", "batch.csv.partial"
RESERVED = (RESULTS, RESULTS_PARTIAL)
#: Largest manifest read (bytes): about 10,000 jobs
MAX_MANIFEST_BYTES = 1 << 20
#: a job name (the module docstring's grammar)
NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]{0,63}")
_DIGITS = re.compile(r"[0-9]+")
#: longest error kept in a ``batch.csv`` cell (characters, escaped)
MAX_ERROR_SHOWN = 500
#: most problems of a manifest reported one by one (then how many more)
MAX_PROBLEMS_SHOWN = 50


@dataclass(frozen=True)
class Job:
    """One replay of a batch (units as ``frictex replay``'s options): ``scene`` and
    ``trace`` a file's absolute path or a bundled name; ``written`` the two as the
    manifest's line writes them (None: as ``scene`` and ``trace``), for ``batch.csv``;
    ``allow_outside`` whether its texture files may name files outside their folder
    (``--allow-outside`` where the manifest was read: :func:`run_job` carries it to the
    worker, whose environment on a Dask cluster is not this process's)."""

    index: int
    scene: str
    trace: str
    renderer: str | None
    rate_hz: float
    block: int | None
    fmt: str
    name: str
    written: tuple[str, str] | None = None
    allow_outside: bool = False


class ManifestError(InputError):
    """A manifest that cannot be read: every problem found, each one line naming the file,
    the line and the field (``error_lines``, which the command line prints one by one);
    the message is all of them, joined by "; "."""

    def __init__(self, *problems: str):
        self.error_lines = problems
        super().__init__("; ".join(problems))


class _Problems:
    """The problems found so far in the manifest ``path``, each one line."""

    def __init__(self, path: Path):
        self.path = path
        self.lines: list[str] = []

    def add(self, line: str) -> None:
        self.lines.append(line)

    def check(self, function, *args):
        """``function(*args)``, or None with its ManifestError's problems kept."""
        try:
            return function(*args)
        except ManifestError as exc:
            self.lines.extend(exc.error_lines)
            return None

    def raise_any(self) -> None:
        """A ManifestError of every problem kept (at most :data:`MAX_PROBLEMS_SHOWN`, then
        a line saying how many more), if any."""
        if len(self.lines) > MAX_PROBLEMS_SHOWN:
            more = len(self.lines) - MAX_PROBLEMS_SHOWN
            raise ManifestError(*self.lines[:MAX_PROBLEMS_SHOWN],
                                f"{self.path}: {more} more problems")
        if self.lines:
            raise ManifestError(*self.lines)


def read_manifest(path: Path, renderers: tuple[str, ...]) -> list[Job]:
    """The jobs of a manifest file (see the module docstring); raises ManifestError with
    every problem of the file."""
    path = Path(path)
    problems = _Problems(path)
    lines = _content_lines(path, _manifest_text(path), problems)
    rows = [(n, problems.check(_row, line, f"{path}:{n}")) for n, line in lines]
    n_header, first = rows[0]
    header = None if first is None else problems.check(_header, first, f"{path}:{n_header}")
    if header is None:  # the rows cannot be read without their header
        problems.raise_any()
    jobs = _jobs(path, header, rows[1:], renderers, problems)
    problems.raise_any()
    if not jobs:
        raise ManifestError(f"{path}: a header but no jobs")
    return jobs


def _manifest_text(path: Path) -> str:
    """The manifest's text, read as UTF-8 within :data:`MAX_MANIFEST_BYTES`."""
    try:
        return read_utf8(path, MAX_MANIFEST_BYTES)
    except UnreadableText as exc:
        where = f"{path}:{exc.line}" if exc.line is not None else f"{path}"
        raise ManifestError(f"{where}: {exc}; expected a CSV manifest of jobs") from None


def _content_lines(path: Path, text: str, problems: _Problems) -> list[tuple[int, str]]:
    """The (line number, line) pairs of ``text`` that are neither blank nor comments;
    at least one. A line too long, or holding a bare carriage return (a file of CR line
    endings, whose lines all run into one), is a problem, and left out."""
    lines = []
    for n, line in enumerate(text.split("\n"), 1):
        line = line.removesuffix("\r")
        if "\r" in line.rstrip("\r"):
            problems.add(f"{path}:{n}: {CR_ONLY}")
        elif len(line.encode("utf-8")) >= MAX_LINE_BYTES:
            problems.add(f"{path}:{n}: line longer than {MAX_LINE_BYTES} bytes; expected "
                         f"a CSV row of a few fields")
        elif line.strip() and not line.lstrip().startswith("#"):
            lines.append((n, line))
    if not lines:
        problems.add(f"{path}: no header and no jobs (expected a CSV header "
                     f"{','.join(COLUMNS[:2])},...)")
        problems.raise_any()
    return lines


def _header(row: list[str], where: str) -> list[str]:
    """The column names of the header ``row``: known ones, each once, scene and trace
    among them."""
    header = [h.strip() for h in row]
    unknown = [h for h in header if h not in COLUMNS]
    if unknown or not {"scene", "trace"} <= set(header):
        raise ManifestError(f"{where}: not a manifest header ({describe_header(header)}); "
                            f"expected scene,trace and optionally {','.join(COLUMNS[2:])}")
    twice = next((h for k, h in enumerate(header) if h in header[:k]), None)
    if twice is not None:
        raise ManifestError(f"{where}: header names column {twice} twice "
                            f"(each column once)")
    return header


def _jobs(path: Path, header: list[str], rows: list[tuple[int, list[str] | None]],
          renderers: tuple[str, ...], problems: _Problems) -> list[Job]:
    """One job per data row (line number, fields; None for a row that is not CSV), names
    unique regardless of case (each is a folder, and macOS and Windows fold case); the
    problems of every row kept in ``problems``."""
    jobs, names = [], {}
    for index, (line_no, row) in enumerate(rows):
        where = f"{path}:{line_no}"
        if row is None:
            continue
        if len(row) != len(header):
            problems.add(f"{where}: {len(row)} fields, expected {len(header)} "
                         f"({','.join(header)})")
            continue
        cell = dict(zip(header, (c.strip() for c in row)))
        job, name = _job(index, cell, path.parent, renderers, where, problems)
        if name is None:
            continue
        # a row with other problems still holds its name, so that a clash is said at once
        earlier = names.get(name.casefold())
        if earlier is not None:
            problems.add(f"{where}: name {quoted(name)} is used by an earlier job"
                         + ("" if earlier == name else
                            f" as {quoted(earlier)} (names must differ in more than case)"))
        names.setdefault(name.casefold(), name)
        if job is not None:
            jobs.append(job)
    return jobs


def _row(line: str, where: str) -> list[str]:
    """The CSV fields of one manifest line."""
    try:
        return next(csv.reader([line], strict=True))
    except csv.Error as exc:
        raise ManifestError(f"{where}: not a CSV row ({exc})") from None


def _number(cell: dict, key: str, default, bounds: tuple, unit: str, where: str):
    """Field ``key`` (a :data:`NUMBER`, or for ``block`` digits) within ``bounds``, the
    command line's; ``default`` when empty."""
    text = cell.get(key) or ""
    if not text:
        return default
    whole = key == "block"
    low, high = bounds
    if (_DIGITS if whole else NUMBER).fullmatch(text) is None:
        raise ManifestError(f"{where}: {key} {quoted(text)} is not "
                            f"{'a whole number (ASCII digits)' if whole else 'an ASCII decimal number'}"
                            f"; expected {low:g} to {high:g} {unit}")
    value = int(text) if whole else float(text)
    if not (math.isfinite(value) and low <= value <= high):
        raise ManifestError(f"{where}: {key} {quoted(text)}: expected {low:g} to {high:g} {unit} "
                            f"(as the command line's option)")
    return value


def _job(index: int, cell: dict, base: Path, renderers, where: str,
         problems: _Problems) -> tuple[Job | None, str | None]:
    """The job of one row, or None with each of its problems kept in ``problems``; and its
    name (None where the name is the problem)."""
    before = len(problems.lines)
    paths = {key: problems.check(_path, key, cell.get(key), base, where)
             for key in ("scene", "trace")}
    renderer = cell.get("renderer") or None
    if renderer is not None and renderer not in renderers:
        problems.add(f"{where}: renderer {quoted(renderer)}: expected one of "
                     f"{', '.join(renderers)} or empty")
    fmt = cell.get("format") or "csv"
    if fmt not in FORMATS:
        problems.add(f"{where}: format {quoted(fmt)}: expected one of {', '.join(FORMATS)}")
    rate_hz = problems.check(_number, cell, "rate_hz", 10_000.0, OUTPUT_RATES_HZ, "Hz", where)
    block = problems.check(_number, cell, "block", None, BLOCK_SIZES, "samples", where)
    name = problems.check(_name, cell, index, where)
    if len(problems.lines) > before:
        return None, name
    return Job(index, paths["scene"], paths["trace"], renderer, rate_hz, block, fmt, name,
               written=(cell["scene"], cell["trace"]), allow_outside=outside_allowed()), name


def _name(cell: dict, index: int, where: str) -> str:
    """The job's name: the ``name`` field, or made of the row number and the stems; a
    :data:`NAME`, not one of :data:`RESERVED`."""
    name = cell.get("name") or f"{index:04d}-{_stem(cell['scene'])}-{_stem(cell['trace'])}"
    if NAME.fullmatch(name) is None:
        raise ManifestError(f"{where}: name {quoted(name)}: expected a plain folder name (ASCII "
                            f"letters, digits, '.', '_' and '-', starting with a letter or a "
                            f"digit, at most 64)")
    if name.casefold() in RESERVED:
        raise ManifestError(f"{where}: name {quoted(name)} is a file the batch writes in its "
                            f"--out ({', '.join(RESERVED)}): name the job otherwise")
    return name


def _stem(spec: str) -> str:
    """A job name part: the file name without its .toml or .csv, or the bundled name; other
    characters than a name's (:data:`NAME`) as ``_``, at most 28 characters."""
    name = Path(spec).name
    for suffix in (".toml", ".csv"):
        name = name.removesuffix(suffix)
    return re.sub(r"[^A-Za-z0-9._-]", "_", name)[:28] or "job"


def _path(key: str, spec: str | None, base: Path, where: str) -> str:
    """The ``scene`` or ``trace`` field ``spec``: the file relative to the manifest's
    folder ``base`` (its real path, absolute) where such a file exists, else a bundled
    name, as given (:func:`run_job` finds it where the job runs, never a file of that
    name in the current folder); a ManifestError if it is empty, is neither (with the library's "did you mean" hint),
    or, unless allowed, leads outside ``base`` (module docstring)."""
    if not spec:
        raise ManifestError(f"{where}: {key} is empty")
    how = None if outside_allowed() else _leads_out(base, spec)
    if how is not None:
        raise ManifestError(f"{where}: {key} {quoted(spec)} {how}: a manifest names files in "
                            f"its own folder or below, or bundled scenes and traces ({HOW})")
    candidate = base / spec
    try:
        if candidate.exists():
            problem = file_problem(candidate)  # a folder, a FIFO, a device
            if problem is not None:
                raise ManifestError(f"{where}: {key} {quoted(spec)}: {problem}; expected a "
                                    f"{'texture' if key == 'scene' else 'trace CSV'} file")
            return os.path.realpath(candidate)
        bundled_file(spec, key)
    except TextureError as exc:
        raise ManifestError(f"{where}: {key} {exc}") from None
    except OSError as exc:  # a name too long for the file system
        raise ManifestError(f"{where}: {key} {quoted(spec)}: "
                            f"{exc.strerror or 'cannot be read'}") from None
    return spec


def _leads_out(base: Path, spec: str) -> str | None:
    """``textures.outside.leads_out``, but an absolute path is judged by the file it
    names (links followed): out only where that lies outside ``base``."""
    if not os.path.isabs(spec):
        return leads_out(base, spec)
    root, real = os.path.realpath(base), os.path.realpath(spec)
    if os.path.commonpath([root, real]) != root:
        return "is an absolute path outside the manifest's folder"
    return None


def run_job(job: Job, out_dir: str) -> dict:
    """Replay one job into ``out_dir/job.name`` (a scene or trace that is no absolute path
    is a bundled name: the bundled file, whatever the current folder holds); never raises
    for the job's own errors, whatever they are (a signal's ``KeyboardInterrupt`` or
    ``SystemExit`` passes): returns its result row (``status`` "ok", or "failed" with the
    error and empty measures; a job's unexpected exception, a bug, as :func:`_bug` says
    it), plain values that any worker can send back. Run the jobs of a batch with
    ``app.engine.fanout.fan_out(functools.partial(run_job, out_dir=...), jobs)``."""
    start = time.perf_counter()
    try:
        return _ok(job, _replay(job, out_dir), start)
    except (FrictexError, ValueError, OSError) as exc:  # its values already escaped
        return not_ok(job, "failed", printable(exc, MAX_ERROR_SHOWN))
    except Exception as exc:  # noqa: BLE001 - a bug of this job's (frictex's or a plugin's)
        return not_ok(job, "failed", _bug(job, exc))


def _replay(job: Job, out_dir: str) -> dict:
    """The job's replay (``app.engine.replay.run_replay``): its summary."""
    from frictex.app.engine.replay import run_replay
    scene, trace = (spec if os.path.isabs(spec) else str(bundled_file(spec, kind))
                    for spec, kind in ((job.scene, "scene"), (job.trace, "trace")))
    with allowing_outside(job.allow_outside):
        return run_replay(scene, trace, Path(out_dir) / job.name, rate_hz=job.rate_hz,
                          fmt=job.fmt, block_size=job.block, render_override=job.renderer,
                          progress=False)


def _ok(job: Job, doc: dict, start: float) -> dict:
    """The result row of a job whose replay wrote summary ``doc``, begun at
    ``time.perf_counter()`` ``start`` (s)."""
    wall_s = time.perf_counter() - start
    output_s = doc["output"]["duration_s"]
    return {**_identity(job), "status": "ok", "error": "",
            "output_s": output_s, "wall_s": wall_s,
            "x_realtime": output_s / wall_s if wall_s > 0 else None,
            "x_realtime_end_to_end": doc["timings"]["x_realtime_end_to_end"],
            "clamps": sum(doc["clamps"].values()),
            "actuator_limited": doc["counts"]["actuator_limited"],
            "modal_capped": doc["counts"].get("modal_capped"),  # before version 6: not counted
            "modal_unserved": doc["counts"].get("modal_unserved"),  # before version 7: not counted
            "warnings": len(doc["warnings"])}


def _bug(job: Job, exc: Exception) -> str:
    """A job's unexpected exception ``exc`` as the command line reports an internal error:
    its traceback on stderr (where the job ran: a Dask worker's log), then a line asking
    for a report; returns the job's error, the exception's type and message (text only:
    an exception may not survive the way back from a worker process)."""
    traceback.print_exception(exc, file=sys.stderr)
    print(f"frictex: internal error in job {job.name}: please report it with the traceback "
          f"above and the job's manifest line", file=sys.stderr)
    what = "".join(traceback.format_exception_only(exc)).strip()
    return printable(f"internal error (a bug in frictex or a plugin; traceback on stderr): "
                     f"{what}", MAX_ERROR_SHOWN)


def not_ok(job: Job, status: str, error: str) -> dict:
    """The result row of a job that did not finish: ``status`` ("failed" or
    "interrupted"), ``error``, every measure empty."""
    return {**_identity(job), "status": status, "error": error, **dict.fromkeys(MEASURES)}


def _identity(job: Job) -> dict:
    """The cells of a job's ``batch.csv`` row that say which job it is and what it replays."""
    scene, trace = job.written or (job.scene, job.trace)
    return {"job": job.index, "name": job.name, "scene": scene, "trace": trace}


#: bytes a ``batch.csv`` row takes at most, for the room check: its error (up to
#: MAX_ERROR_SHOWN characters, 4 bytes each at most in UTF-8) and its other cells
ROW_BYTES = 4 * MAX_ERROR_SHOWN + 1024


def write_results(out_dir: Path, rows: list[dict]) -> Path:
    """``batch.csv``: one row per job (see the module docstring), written all or nothing."""
    path = Path(out_dir) / RESULTS
    partial = path.with_name(RESULTS_PARTIAL)
    try:
        with open(partial, "w", encoding="utf-8", newline="") as fh:
            writer = csv.writer(fh, lineterminator="\n")
            writer.writerow(RESULT_COLUMNS)
            writer.writerows([_cell(row[name]) for name in RESULT_COLUMNS] for row in rows)
        os.replace(partial, path)
    finally:
        partial.unlink(missing_ok=True)
    return path


#: first characters that make a spreadsheet read a cell as a formula (OWASP CSV injection)
FORMULA_STARTS = ("=", "+", "-", "@", "\t", "\r")


def _cell(value):
    """A ``batch.csv`` cell: None empty, floats to 4 decimals; text that a spreadsheet would take for
    a formula (starting with one of :data:`FORMULA_STARTS`) behind a single quote."""
    if value is None:
        return ""
    if isinstance(value, float):
        return f"{value:.4f}"
    if isinstance(value, str) and value.startswith(FORMULA_STARTS):
        return "'" + value
    return value

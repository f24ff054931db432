"""Many replays at once: a manifest of jobs, run over this machine's cores or a Dask cluster.

Manifest grammar (CSV with a header; ``#`` lines are comments)::

    scene,trace[,renderer][,rate_hz][,block][,format][,name]

``scene`` and ``trace`` as ``frictex replay`` takes them (a file, relative to the
manifest's folder, or a bundled name); ``renderer`` empty means the file's own;
``rate_hz`` (default 10000), ``block`` (default 5 ms of samples: 50 at 10 kHz) and ``format`` (csv, npz, parquet;
default csv) as the replay's options, within the same bounds as on the command line
(``--rate`` 100 to 1e6 Hz, ``--block`` 1 to 100000 samples); ``name`` the job's output
folder under the batch's ``--out`` (default: ``<row number>-<scene stem>-<trace stem>``,
the stems' other characters as ``_``), unique::

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
file and the line, and show values escaped and cut (``device.safe_text``).

Every job writes its replay outputs into its folder; the batch writes ``batch.csv``,
one row per job (:data:`RESULT_COLUMNS`):

- ``job`` (its row among the jobs, from 0), ``name``, ``status``: ``ok``, ``failed``
  (``error`` says why), ``interrupted`` (the batch was stopped before the job finished:
  ``error`` says whether it had started) or ``earlier`` (a stopped batch kept an earlier
  batch's folder of that name: below);
- ``output_s``: seconds of output the job wrote; ``wall_s``: the job's wall time in its
  worker, from its start to its outputs in place, start-up included (reading the scene
  and the trace, loading the compiled kernels); ``x_realtime``: ``output_s / wall_s``;
  ``x_realtime_end_to_end``: the replay's own factor (``timings`` in its
  ``summary.json``), which leaves the start-up out, so it is the larger of the two;
- ``clamps`` (the inversion's clamped samples, all guards) and ``warnings`` (how many;
  the texts are in the job's ``summary.json``).

A job that is not ``ok`` has these numeric cells empty (an ``earlier`` one the earlier
batch's figures). A failed job does not stop the others.

The output folder. ``--out`` is new, empty, or an earlier batch's: nothing in it but
``batch.csv`` (and ``batch.csv.partial``), job folders (a folder with a replay's
``summary.json``) and the staging leftovers of killed replays (``.<name>.frictex-*``);
anything else is refused before a job runs. The batch replaces it as a whole when it
ends (``app.engine.batch_folder``): until then it holds the earlier batch untouched,
whatever stops the batch (SIGKILL included); then ``batch.csv`` and exactly the folders
of the jobs it lists ``ok`` (or ``earlier``, below). An earlier job folder that holds a
file not a run's output (the user's) is kept as it is and named in a warning.

Ctrl-C (or SIGTERM, SIGHUP) stops a batch within about a second: no job starts after
it, each running one ends as an interrupted replay ends, and the new ``--out`` holds the
jobs that finished (``ok``, or ``failed``), every earlier job folder it did not replace,
kept and listed with status ``earlier`` (the earlier ``batch.csv``'s figures; ``job``
empty for a name the new manifest does not have), and the rest ``interrupted``; the
command then exits as an interrupted replay does (130 for Ctrl-C, 128 + the signal
otherwise). Stopping a rerun deletes nothing that was complete. On a Dask cluster jobs
already running finish on their workers (Dask cannot stop them) though ``batch.csv``
lists them ``interrupted``. A text cell that would start with ``=``, ``+``, ``-``, ``@``, a tab or a
carriage return (an error that starts with a scene named ``=HYPERLINK(...)``) is written
behind a single quote, so that a spreadsheet shows it as text, never runs it (OWASP's
rule for CSV injection).
"""

from __future__ import annotations

import csv
import math
import os
import re
import time
from dataclasses import dataclass
from pathlib import Path

from frictex.app.engine.limits import BLOCK_SIZES, OUTPUT_RATES_HZ
from frictex.app.engine.tables import FORMATS
from frictex.device.errors import FrictexError, InputError
from frictex.device.safe_text import escape, quoted
from frictex.rendering.input.trace_file import MAX_LINE_BYTES, NUMBER, describe_header
from frictex.textures.library import UnreadableText, read_utf8

COLUMNS = ("scene", "trace", "renderer", "rate_hz", "block", "format", "name")
RESULT_COLUMNS = ("job", "name", "status", "error", "output_s", "wall_s", "x_realtime",
                  "x_realtime_end_to_end", "clamps", "warnings")
#: the numeric cells of ``batch.csv``, empty for a job that is not ``ok``
MEASURES = RESULT_COLUMNS[4:]
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


@dataclass(frozen=True)
class Job:
    """One replay of a batch (units as ``frictex replay``'s options)."""

    index: int
    scene: str
    trace: str
    renderer: str | None
    rate_hz: float
    block: int | None
    fmt: str
    name: str


class ManifestError(InputError):
    """A manifest that cannot be read: names the file, the line and the field."""


def read_manifest(path: Path, renderers: tuple[str, ...]) -> list[Job]:
    """The jobs of a manifest file (see the module docstring); raises ManifestError."""
    path = Path(path)
    lines = _content_lines(path, _manifest_text(path))
    rows = [_row(line, f"{path}:{n}") for n, line in lines]
    header = _header(rows[0], f"{path}:{lines[0][0]}")
    jobs = _jobs(path, header, [n for n, _ in lines[1:]], rows[1:], renderers)
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


def _content_lines(path: Path, text: str) -> list[tuple[int, str]]:
    """The (line number, line) pairs of ``text`` that are neither blank nor comments;
    at least one."""
    lines = []
    for n, line in enumerate(text.split("\n"), 1):
        line = line.removesuffix("\r")
        if len(line.encode("utf-8")) >= MAX_LINE_BYTES:
            raise ManifestError(f"{path}:{n}: line longer than {MAX_LINE_BYTES} bytes; expected "
                                f"a CSV row of a few fields")
        if line.strip() and not line.lstrip().startswith("#"):
            lines.append((n, line))
    if not lines:
        raise ManifestError(f"{path}: no header and no jobs (expected a CSV header "
                            f"{','.join(COLUMNS[:2])},...)")
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


def _jobs(path: Path, header: list[str], line_nos: list[int], rows: list[list[str]],
          renderers: tuple[str, ...]) -> list[Job]:
    """One job per data row (line numbers ``line_nos``), names unique."""
    jobs, names = [], set()
    for line_no, row in zip(line_nos, rows):
        where = f"{path}:{line_no}"
        if len(row) != len(header):
            raise ManifestError(f"{where}: {len(row)} fields, expected {len(header)} "
                                f"({','.join(header)})")
        cell = dict(zip(header, (c.strip() for c in row)))
        job = _job(len(jobs), cell, path.parent, renderers, where)
        if job.name in names:
            raise ManifestError(f"{where}: name {quoted(job.name)} is used by an earlier job")
        names.add(job.name)
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


def _job(index: int, cell: dict, base: Path, renderers, where: str) -> Job:
    for key in ("scene", "trace"):
        if not cell.get(key):
            raise ManifestError(f"{where}: {key} is empty")
    renderer = cell.get("renderer") or None
    if renderer is not None and renderer not in renderers:
        raise ManifestError(f"{where}: renderer {quoted(renderer)}: expected one of "
                            f"{', '.join(renderers)} or empty")
    fmt = cell.get("format") or "csv"
    if fmt not in FORMATS:
        raise ManifestError(f"{where}: format {quoted(fmt)}: expected one of {', '.join(FORMATS)}")
    name = _name(cell, index, where)
    return Job(index, _resolve(cell["scene"], base), _resolve(cell["trace"], base), renderer,
               _number(cell, "rate_hz", 10_000.0, OUTPUT_RATES_HZ, "Hz", where),
               _number(cell, "block", None, BLOCK_SIZES, "samples", where), fmt, name)


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


def _resolve(spec: str, base: Path) -> str:
    """A path relative to the manifest's folder where such a file exists, else as given
    (a bundled name, or a path the replay will report as missing)."""
    candidate = base / spec
    try:
        return str(candidate) if candidate.exists() else spec
    except OSError:  # a name too long for the file system: the replay reports it
        return spec


def run_job(job: Job, out_dir: str) -> dict:
    """Replay one job into ``out_dir/job.name``; never raises for the job's own errors:
    returns its result row (``status`` "ok", or "failed" with the error and empty
    measures). Run the jobs of a batch with
    ``app.engine.fanout.fan_out(functools.partial(run_job, out_dir=...), jobs)``."""
    from frictex.app.engine.replay import run_replay
    start = time.perf_counter()
    try:
        doc = run_replay(job.scene, job.trace, Path(out_dir) / job.name, rate_hz=job.rate_hz,
                         fmt=job.fmt, block_size=job.block, render_override=job.renderer,
                         progress=False)
    except (FrictexError, ValueError, OSError) as exc:
        return not_ok(job, "failed", escape(exc, MAX_ERROR_SHOWN))
    wall_s = time.perf_counter() - start
    output_s = doc["output"]["duration_s"]
    return {"job": job.index, "name": job.name, "status": "ok", "error": "",
            "output_s": output_s, "wall_s": wall_s,
            "x_realtime": output_s / wall_s if wall_s > 0 else None,
            "x_realtime_end_to_end": doc["timings"]["x_realtime_end_to_end"],
            "clamps": sum(doc["clamps"].values()), "warnings": len(doc["warnings"])}


def not_ok(job: Job, status: str, error: str) -> dict:
    """The result row of a job that did not finish: ``status`` ("failed" or
    "interrupted"), ``error``, every measure empty."""
    return {"job": job.index, "name": job.name, "status": status, "error": error,
            **dict.fromkeys(MEASURES)}


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

"""Many replays at once: a manifest of jobs, run over this machine's cores or a Dask cluster.

Manifest grammar (CSV with a header; ``#`` lines are comments)::

    scene,trace[,renderer][,rate_hz][,block][,format][,name]

``scene`` and ``trace`` as ``frictex replay`` takes them (a file, relative to the
manifest's folder, or a bundled name); ``renderer`` empty means the file's own;
``rate_hz`` (default 10000), ``block`` (default 50) and ``format`` (csv, npz, parquet;
default csv) as the replay's options; ``name`` the job's output folder under the
batch's ``--out`` (default: ``<row number>-<scene stem>-<trace stem>``, names unique).

Every job writes its replay outputs into its folder; the batch writes ``batch.csv``:
one row per job with its status (``ok`` or ``failed``), error, output seconds, wall
seconds and end-to-end real-time factor, clamps and warnings. A failed job does not
stop the others.
"""

from __future__ import annotations

import csv
import os
import time
from dataclasses import dataclass
from pathlib import Path

from frictex.app.engine.tables import FORMATS
from frictex.device.errors import InputError

COLUMNS = ("scene", "trace", "renderer", "rate_hz", "block", "format", "name")
RESULT_COLUMNS = ("job", "name", "status", "error", "output_s", "wall_s",
                  "x_realtime_end_to_end", "clamps", "warnings")


@dataclass(frozen=True)
class Job:
    """One replay of a batch (units as ``frictex replay``'s options)."""

    index: int
    scene: str
    trace: str
    renderer: str | None
    rate_hz: float
    block: int
    fmt: str
    name: str


class ManifestError(InputError):
    """A manifest that cannot be read: names the file, the line and the field."""


def read_manifest(path: Path, renderers: tuple[str, ...]) -> list[Job]:
    """The jobs of a manifest file (see the module docstring); raises ManifestError."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise ManifestError(f"{path}: cannot read the manifest: {exc}") from None
    lines = [(n, line) for n, line in enumerate(text.splitlines(), 1)
             if line.strip() and not line.lstrip().startswith("#")]
    if not lines:
        raise ManifestError(f"{path}: no header and no jobs (expected a CSV header "
                            f"{','.join(COLUMNS[:2])},...)")
    rows = csv.reader([line for _, line in lines])
    header = [h.strip() for h in next(rows)]
    unknown = [h for h in header if h not in COLUMNS]
    if unknown or not {"scene", "trace"} <= set(header):
        raise ManifestError(f"{path}:{lines[0][0]}: header {','.join(header)}: expected "
                            f"scene,trace and optionally {','.join(COLUMNS[2:])}")
    jobs, names = [], set()
    for (line_no, _), row in zip(lines[1:], rows):
        where = f"{path}:{line_no}"
        if len(row) != len(header):
            raise ManifestError(f"{where}: {len(row)} fields, expected {len(header)} "
                                f"({','.join(header)})")
        cell = dict(zip(header, (c.strip() for c in row)))
        job = _job(len(jobs), cell, path.parent, renderers, where)
        if job.name in names:
            raise ManifestError(f"{where}: name {job.name!r} is used by an earlier job")
        names.add(job.name)
        jobs.append(job)
    if not jobs:
        raise ManifestError(f"{path}: a header but no jobs")
    return jobs


def _job(index: int, cell: dict, base: Path, renderers, where: str) -> Job:
    def number(key, kind, default, ok):
        text = cell.get(key) or ""
        if not text:
            return default
        try:
            value = kind(text)
        except ValueError:
            value = None
        if value is None or not ok(value):
            raise ManifestError(f"{where}: {key} {text!r}: expected a positive "
                                f"{'whole number' if kind is int else 'finite number'}")
        return value

    for key in ("scene", "trace"):
        if not cell.get(key):
            raise ManifestError(f"{where}: {key} is empty")
    renderer = cell.get("renderer") or None
    if renderer is not None and renderer not in renderers:
        raise ManifestError(f"{where}: renderer {renderer!r}: expected one of "
                            f"{', '.join(renderers)} or empty")
    fmt = cell.get("format") or "csv"
    if fmt not in FORMATS:
        raise ManifestError(f"{where}: format {fmt!r}: expected one of {', '.join(FORMATS)}")
    name = cell.get("name") or f"{index:04d}-{_stem(cell['scene'])}-{_stem(cell['trace'])}"
    if "/" in name or "\\" in name or name in (".", "..") or "\0" in name:
        raise ManifestError(f"{where}: name {name!r}: expected a plain folder name")
    return Job(index, _resolve(cell["scene"], base), _resolve(cell["trace"], base), renderer,
               number("rate_hz", float, 10_000.0, lambda v: 0 < v < float("inf")),
               number("block", int, 50, lambda v: v >= 1), fmt, name)


def _stem(spec: str) -> str:
    """A job name part: the file name without its .toml or .csv, or the bundled name."""
    name = Path(spec).name
    for suffix in (".toml", ".csv"):
        name = name.removesuffix(suffix)
    return name or "job"


def _resolve(spec: str, base: Path) -> str:
    """A path relative to the manifest's folder where such a file exists, else as given
    (a bundled name, or a path the replay will report as missing)."""
    candidate = base / spec
    return str(candidate) if candidate.exists() else spec


def run_job(job: Job, out_dir: str) -> dict:
    """Replay one job into ``out_dir/job.name``; never raises for the job's own errors:
    returns its result row (``status`` "ok" or "failed" with the error). Run the jobs of a
    batch with ``app.engine.fanout.fan_out(functools.partial(run_job, out_dir=...), jobs)``."""
    from frictex.app.engine.replay import run_replay
    start = time.perf_counter()
    row = {"job": job.index, "name": job.name, "status": "ok", "error": "", "output_s": 0.0,
           "wall_s": 0.0, "x_realtime_end_to_end": 0.0, "clamps": 0, "warnings": 0}
    try:
        doc = run_replay(job.scene, job.trace, Path(out_dir) / job.name, rate_hz=job.rate_hz,
                         fmt=job.fmt, block_size=job.block, render_override=job.renderer,
                         progress=False)
    except (ValueError, OSError) as exc:
        row.update(status="failed", error=str(exc))
    else:
        row.update(output_s=doc["output"]["duration_s"],
                   x_realtime_end_to_end=doc["timings"]["x_realtime_end_to_end"] or 0.0,
                   clamps=sum(doc["clamps"].values()), warnings=len(doc["warnings"]))
    row["wall_s"] = time.perf_counter() - start
    return row


def write_results(out_dir: Path, rows: list[dict]) -> Path:
    """``batch.csv``: one row per job (see the module docstring), written all or nothing."""
    path = Path(out_dir) / "batch.csv"
    partial = path.with_name(path.name + ".partial")
    try:
        with open(partial, "w", encoding="utf-8", newline="") as fh:
            writer = csv.writer(fh, lineterminator="\n")
            writer.writerow(RESULT_COLUMNS)
            writer.writerows([_cell(row[name]) for name in RESULT_COLUMNS] for row in rows)
        os.replace(partial, path)
    finally:
        partial.unlink(missing_ok=True)
    return path


def _cell(value):
    return f"{value:.4f}" if isinstance(value, float) else value

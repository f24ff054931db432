"""Trace files: recorded touch samples as CSV.

Grammar (DESIGN.md, "Trace files")::

    file    := header NEWLINE { row NEWLINE }
    header  := column { "," column }        # any order; names are case-sensitive
    required columns: t_s, finger, x_mm, y_mm
    optional columns: force_n (N, default 0.5), event (down | move | up)
    extra columns are ignored; blank lines and lines starting with '#' are skipped.

Rules checked here, once, at the boundary: numbers are finite, ``finger`` is a
non-negative integer, time never goes backwards (equal times are allowed: real
controllers re-report within the same timestamp), forces are >= 0, events are one of
the three words. The first sample of a finger (or the first after its ``up``) is a
``down`` whatever the file says. Errors raise :class:`TraceError` naming the file, the
line and the column.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

DEFAULT_FORCE_N = 0.5
REQUIRED = ("t_s", "finger", "x_mm", "y_mm")
EVENTS = ("down", "move", "up")
DOWN, MOVE, UP = 0, 1, 2


class TraceError(ValueError):
    """A trace file or trace data that cannot be used; the message says where and why."""


@dataclass(frozen=True, eq=False)
class Trace:
    """Touch samples in time order; all arrays have the same length n.

    t_s : float64 (n,) sample time (s), non-decreasing.
    finger : int64 (n,) finger id (>= 0).
    x_mm, y_mm : float64 (n,) position (mm, screen origin top-left, y down).
    force_n : float64 (n,) normal force (N).
    event : int8 (n,) DOWN, MOVE or UP.
    """

    t_s: np.ndarray
    finger: np.ndarray
    x_mm: np.ndarray
    y_mm: np.ndarray
    force_n: np.ndarray
    event: np.ndarray

    def __len__(self) -> int:
        return int(self.t_s.size)

    @property
    def fingers(self) -> tuple[int, ...]:
        return tuple(int(f) for f in np.unique(self.finger))

    @property
    def duration_s(self) -> float:
        return float(self.t_s[-1] - self.t_s[0]) if len(self) else 0.0

    def slice(self, lo: int, hi: int) -> "Trace":
        """Samples ``lo`` to ``hi`` (exclusive), as views of these arrays."""
        return Trace(*(getattr(self, name)[lo:hi] for name in _COLUMNS))

    def then(self, later: "Trace") -> "Trace":
        """These samples followed by ``later``'s (which continue them in time)."""
        return Trace(*(np.concatenate((getattr(self, name), getattr(later, name)))
                       for name in _COLUMNS))


_COLUMNS = ("t_s", "finger", "x_mm", "y_mm", "force_n", "event")


def make_trace(t_s, finger, x_mm, y_mm, force_n=None, event=None, where: str = "trace",
               normalise: bool = True) -> Trace:
    """Validate arrays and build a :class:`Trace`.

    With ``normalise`` (a whole recording) events are normalised as the module doc says;
    a batch of live samples continuing earlier ones passes ``normalise=False`` so that a
    finger's first sample in the batch is not taken for a new touch.
    """
    t = np.asarray(t_s, dtype=np.float64)
    n = t.size
    fing = np.asarray(finger)
    x = np.asarray(x_mm, dtype=np.float64)
    y = np.asarray(y_mm, dtype=np.float64)
    f = np.full(n, DEFAULT_FORCE_N) if force_n is None else np.asarray(force_n, dtype=np.float64)
    ev = np.full(n, MOVE, dtype=np.int8) if event is None else np.asarray(event, dtype=np.int8)
    for name, arr in (("finger", fing), ("x_mm", x), ("y_mm", y), ("force_n", f), ("event", ev)):
        if arr.shape != (n,):
            raise TraceError(f"{where}: column {name} has shape {arr.shape}, expected ({n},)")
    if n == 0:
        raise TraceError(f"{where}: no samples (expected at least one row of t_s,finger,x_mm,y_mm)")
    for name, arr in (("t_s", t), ("x_mm", x), ("y_mm", y), ("force_n", f)):
        bad = ~np.isfinite(arr)
        if bad.any():
            i = int(np.argmax(bad))
            raise TraceError(f"{where}: sample {i}: {name} is {float(arr[i])!r}, expected a finite number")
    steps = np.diff(t)
    if (steps < 0).any():
        i = int(np.argmax(steps < 0)) + 1
        raise TraceError(f"{where}: sample {i}: t_s goes back from {float(t[i - 1])!r} to {float(t[i])!r} s "
                         "(time must not decrease)")
    if (f < 0).any():
        i = int(np.argmax(f < 0))
        raise TraceError(f"{where}: sample {i}: force_n is {float(f[i])!r}, expected >= 0")
    fing_f = np.asarray(fing, dtype=np.float64)
    if (fing_f < 0).any() or (fing_f != np.floor(fing_f)).any():
        i = int(np.argmax((fing_f < 0) | (fing_f != np.floor(fing_f))))
        raise TraceError(f"{where}: sample {i}: finger is {fing[i].item()!r}, expected an integer >= 0")
    if ((ev < DOWN) | (ev > UP)).any():
        raise TraceError(f"{where}: event codes must be {DOWN}, {MOVE} or {UP}")
    fing_i = fing_f.astype(np.int64)
    if normalise:
        ev = _normalise_events(fing_i, ev)
    return Trace(t, fing_i, x, y, f, ev)


def _normalise_events(finger: np.ndarray, event: np.ndarray,
                      down: set[int] | None = None) -> np.ndarray:
    """Make the first sample of each finger, and the first after an ``up``, a ``down``.

    ``down`` (updated in place) holds the fingers touching before these samples, for a
    trace read in chunks; None means none are.
    """
    down = set() if down is None else down
    ev = event.copy()
    for fid in np.unique(finger).tolist():
        idx = np.flatnonzero(finger == fid)
        e = ev[idx]
        prev_up = np.concatenate(([fid not in down], e[:-1] == UP))
        e[prev_up & (e != UP)] = DOWN
        ev[idx] = e
        if e[-1] == UP:
            down.discard(fid)
        else:
            down.add(fid)
    return ev


def _parse_float(text: str, path: str, line: int, column: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise TraceError(f"{path}:{line}: column {column}: {text!r} is not a number") from None
    if not math.isfinite(value):
        raise TraceError(f"{path}:{line}: column {column}: {text!r} is not a finite number")
    return value


class _RowParser:
    """Data rows to arrays, chunk by chunk, carrying across chunks what spans them:
    the last time (time must not decrease) and which fingers are touching."""

    def __init__(self, names: list[str], where: str):
        self.names = names
        self.where = where
        self.col = {name: names.index(name) for name in names}
        self.last_t = -math.inf
        self.down: set[int] = set()

    def parse(self, numbered_rows: list[tuple[int, list[str]]]) -> Trace:
        where, col = self.where, self.col
        n = len(numbered_rows)
        t = np.empty(n)
        finger = np.empty(n, dtype=np.int64)
        x = np.empty(n)
        y = np.empty(n)
        force = np.full(n, DEFAULT_FORCE_N)
        event = np.full(n, MOVE, dtype=np.int8)
        has_force, has_event = "force_n" in col, "event" in col
        last_t = self.last_t
        for k, (line, row) in enumerate(numbered_rows):
            if len(row) < len(self.names):
                raise TraceError(f"{where}:{line}: {len(row)} fields, expected {len(self.names)} "
                                 f"({','.join(self.names)})")
            t[k] = _parse_float(row[col["t_s"]], where, line, "t_s")
            fv = _parse_float(row[col["finger"]], where, line, "finger")
            if fv < 0 or fv != int(fv):
                raise TraceError(f"{where}:{line}: column finger: {row[col['finger']]!r} "
                                 "is not an integer >= 0")
            finger[k] = int(fv)
            x[k] = _parse_float(row[col["x_mm"]], where, line, "x_mm")
            y[k] = _parse_float(row[col["y_mm"]], where, line, "y_mm")
            if has_force and row[col["force_n"]].strip():
                force[k] = _parse_float(row[col["force_n"]], where, line, "force_n")
                if force[k] < 0:
                    raise TraceError(f"{where}:{line}: column force_n: {float(force[k])!r} N "
                                     "is negative")
            if has_event and row[col["event"]].strip():
                word = row[col["event"]].strip()
                if word not in EVENTS:
                    raise TraceError(f"{where}:{line}: column event: {word!r} is not one of "
                                     f"{', '.join(EVENTS)}")
                event[k] = EVENTS.index(word)
            if t[k] < last_t:
                raise TraceError(f"{where}:{line}: t_s goes back from {float(last_t)!r} to "
                                 f"{float(t[k])!r} s (time must not decrease)")
            last_t = t[k]
        self.last_t = last_t
        trace = make_trace(t, finger, x, y, force, event, where, normalise=False)
        return Trace(trace.t_s, trace.finger, trace.x_mm, trace.y_mm, trace.force_n,
                     _normalise_events(trace.finger, trace.event, self.down))


def _chunks(lines, where: str, chunk_rows: int):
    """Traces of at most ``chunk_rows`` samples from an iterable of text lines."""
    parser = None
    batch: list[tuple[int, list[str]]] = []
    samples = 0
    for number, text in enumerate(lines, start=1):
        if not text.strip() or text.lstrip().startswith("#"):
            continue
        if parser is None:
            names = [h.strip() for h in next(csv.reader([text]))]
            missing = [c for c in REQUIRED if c not in names]
            if missing:
                raise TraceError(f"{where}:{number}: header lacks column(s) {', '.join(missing)} "
                                 f"(got {','.join(names)}; required {','.join(REQUIRED)})")
            parser = _RowParser(names, where)
            continue
        batch.append((number, next(csv.reader([text]))))
        if len(batch) == chunk_rows:
            samples += len(batch)
            yield parser.parse(batch)
            batch = []
    if parser is None:
        raise TraceError(f"{where}: empty trace (expected a header line with {','.join(REQUIRED)})")
    if batch:
        samples += len(batch)
        yield parser.parse(batch)
    if samples == 0:
        raise TraceError(f"{where}: header but no samples")


def iter_trace(path: str | Path, chunk_rows: int = 65_536):
    """Read and validate a trace CSV in chunks of ``chunk_rows`` samples (a generator of
    :class:`Trace`), so that a trace of any length is read in bounded memory."""
    path = Path(path)
    try:
        with open(path, encoding="utf-8", newline="") as fh:
            yield from _chunks(fh, str(path), chunk_rows)
    except FileNotFoundError:
        raise TraceError(f"{path}: no such trace file") from None
    except IsADirectoryError:
        raise TraceError(f"{path}: is a folder, not a trace file") from None
    except UnicodeDecodeError as exc:
        raise TraceError(f"{path}: not a text file ({exc.reason} at byte {exc.start})") from None
    except OSError as exc:
        raise TraceError(f"{path}: cannot read trace ({exc.strerror})") from None


def concat_traces(chunks) -> Trace:
    """One :class:`Trace` from consecutive chunks."""
    chunks = list(chunks)
    return Trace(*(np.concatenate([getattr(c, name) for c in chunks])
                   for name in ("t_s", "finger", "x_mm", "y_mm", "force_n", "event")))


def read_trace(path: str | Path) -> Trace:
    """Read and validate a whole trace CSV (see the module docstring for the grammar)."""
    return concat_traces(iter_trace(path))


def parse_trace(text: str, where: str = "<trace>") -> Trace:
    """Parse trace CSV text; ``where`` names the source in error messages."""
    return concat_traces(_chunks(text.splitlines(), where, 65_536))


def format_trace(trace: Trace, comment: str | None = None) -> str:
    """The CSV text of a trace (all columns, full float64 precision via repr),
    after an optional ``# comment`` line."""
    out = [f"# {line}" for line in comment.splitlines()] if comment else []
    out.append("t_s,finger,x_mm,y_mm,force_n,event")
    for t, fid, x, y, f, e in zip(trace.t_s.tolist(), trace.finger.tolist(), trace.x_mm.tolist(),
                                  trace.y_mm.tolist(), trace.force_n.tolist(), trace.event.tolist()):
        out.append(f"{t!r},{fid},{x!r},{y!r},{f!r},{EVENTS[e]}")
    return "\n".join(out) + "\n"


def write_trace(path: str | Path, trace: Trace, comment: str | None = None) -> None:
    """Write a trace CSV that :func:`read_trace` reads back exactly."""
    Path(path).write_text(format_trace(trace, comment), encoding="utf-8")

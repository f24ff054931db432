"""Trace files: recorded touch samples as CSV.

Grammar (DESIGN.md, "Trace files")::

    file    := [BOM] header NEWLINE { row NEWLINE }   # UTF-8; a leading UTF-8 BOM is dropped
    header  := column { "," column }        # any order; names are case-sensitive, each once
    required columns: t_s, finger, x_mm, y_mm
    optional columns: force_n (N, default 0.5), event (down | move | up)
    extra columns are ignored; blank lines and lines starting with '#' are skipped;
    a line holds at most MAX_LINE_BYTES bytes.
    number  := [SPACES] ["+" | "-"] ( DIGITS ["." [DIGITS]] | "." DIGITS )
               [ ("e" | "E") ["+" | "-"] DIGITS ] [SPACES]
    DIGITS  := { "0".."9" }-   SPACES := { " " | TAB }-     # ASCII only (:data:`NUMBER`)

Python's ``float`` also takes Unicode digits (``"\u0662\u0661"`` is 21), underscores
(``"2_2"`` is 22), ``nan`` and ``inf`` and Unicode spaces: none of these is a number here.

Rules checked here, once, at the boundary (every error names the file, the line and the
column, shows the value and what was expected):

- numbers are finite and within stated ranges, so that nothing later can overflow:
  |t_s| <= MAX_TIME_S (1e10 s: Unix times fit), |x_mm|, |y_mm| <= MAX_COORD_MM (1e5 mm),
  0 <= force_n <= MAX_FORCE_N (1000 N); ``finger`` is an integer id from 0 to
  MAX_FINGER_ID (2^31 - 1, the range of Linux tracking ids);
- events are one of the three words; the first sample of a finger (or the first after
  its ``up``) is a ``down`` whatever the file says; at most MAX_TOUCHING (20) fingers
  touch at once (a finger touches from its down to its up);
- time order. Real logs interleave two fingers' events and so step back a little:
  samples up to REORDER_TOLERANCE_S (5 ms) earlier than the latest time before them are
  moved into time order (a stable sort: equal times keep their file order); samples
  further back are dropped (so are samples that would go before the MAX_HELD_ROWS rows
  a reader holds back, in a file crowding more rows than that into 5 ms). Both are
  counted (:class:`TimeOrder`) for the replay's summary. ``strict=True`` refuses any step
  back instead.

Only regular files are opened (``textures.library.file_problem``): a FIFO or a device
is refused before anything blocks.

Errors never carry a line of a file that is not a trace: a header without the required
columns is described (its number of fields, and those of its names that are plain
column names), and every value shown is escaped and cut to
``device.safe_text.MAX_SHOWN`` characters (``device.safe_text.quoted``).
"""

from __future__ import annotations

import codecs
import csv
import difflib
import io
import math
import re
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, NoReturn

import numpy as np
import numpy.typing as npt

from frictex.textures.library import file_problem
from frictex.device.errors import InputError
# a number as trace files (and manifests, device logs) write it: the module docstring's
# grammar, shared by every text format (batch.py takes NUMBER from here)
from frictex.device.numbers import NUMBER, ascii_float  # noqa: F401
from frictex.device.safe_text import quoted

DEFAULT_FORCE_N = 0.5
REQUIRED = ("t_s", "finger", "x_mm", "y_mm")
EVENTS = ("down", "move", "up")
DOWN, MOVE, UP = 0, 1, 2
_EVENT_CODES = {word: code for code, word in enumerate(EVENTS)}

MAX_TIME_S = 1e10
MAX_COORD_MM = 1e5
MAX_FORCE_N = 1e3
MAX_FINGER_ID = 2**31 - 1
MAX_TOUCHING = 20
MAX_LINE_BYTES = 4096
REORDER_TOLERANCE_S = 0.005
#: Rows held back at most while waiting for rows that may go before them (memory bound
#: for a file whose rows crowd into one tolerance window; a 1 kHz screen puts 5 there).
MAX_HELD_ROWS = 65_536

#: What a carriage return that is not part of a CRLF means, and what to do (batch
#: manifests say it too): Python's csv module would ask for "universal-newline mode".
CR_ONLY = ("a line ends in a bare CR (a carriage return without a line feed, as old Mac "
           "files end their lines); save the file with LF or CRLF line endings")
#: a carriage return with more of its line after it (a run of them before a line feed, or
#: at the end, only ends a line)
_BARE_CR = re.compile(rb"\r(?=[^\r\n])")

#: column -> (lowest, highest, unit) accepted
RANGES = {"t_s": (-MAX_TIME_S, MAX_TIME_S, "s"), "x_mm": (-MAX_COORD_MM, MAX_COORD_MM, "mm"),
          "y_mm": (-MAX_COORD_MM, MAX_COORD_MM, "mm"), "force_n": (0.0, MAX_FORCE_N, "N"),
          "finger": (0, MAX_FINGER_ID, "finger id")}


class TraceError(InputError):
    """A trace file or trace data that cannot be used; the message says where and why."""


@dataclass(frozen=True, eq=False)
class Trace:
    """Touch samples in time order; all arrays have the same length n.

    t_s : float64 (n,) sample time (s), non-decreasing.
    finger : int64 (n,) finger id (>= 0).
    x_mm, y_mm : float64 (n,) position (mm, screen origin top-left, y down).
    force_n : float64 (n,) normal force (N).
    event : int8 (n,) DOWN, MOVE or UP.

    Each field is held as a read-only array (a view of what was given, lists made
    arrays): a Trace is not changed through it. :func:`make_trace` copies its inputs
    too, so that changing them afterwards changes no trace. A field that is None or a
    single value is refused here; the rules on the values are checked where a trace
    built by hand is used.
    """

    t_s: npt.NDArray[np.float64]
    finger: npt.NDArray[np.int64]
    x_mm: npt.NDArray[np.float64]
    y_mm: npt.NDArray[np.float64]
    force_n: npt.NDArray[np.float64]
    event: npt.NDArray[np.int8]

    def __post_init__(self) -> None:
        for name in _COLUMNS:
            object.__setattr__(self, name, _read_only(name, getattr(self, name)))

    def __len__(self) -> int:
        return int(self.t_s.size)

    @property
    def fingers(self) -> tuple[int, ...]:
        """The finger numbers in the trace, ascending."""
        return tuple(np.unique(self.finger).tolist())

    @property
    def duration_s(self) -> float:
        return float(self.t_s[-1] - self.t_s[0]) if len(self) else 0.0

    def slice(self, lo: int, hi: int) -> "Trace":
        """Samples ``lo`` to ``hi`` (exclusive), as views of these arrays."""
        return Trace(*(getattr(self, name)[lo:hi] for name in _COLUMNS))


_COLUMNS = ("t_s", "finger", "x_mm", "y_mm", "force_n", "event")


def read_only_view(array: np.ndarray) -> np.ndarray:
    """A read-only view of ``array`` (O(1)): no copy, and the array's own flags are left
    as they are (its owner may still write into it)."""
    view = array.view()
    view.setflags(write=False)
    return view


def _read_only(name: str, values) -> np.ndarray:
    """Field ``name`` of a :class:`Trace` as a read-only array (lists made arrays); None
    or a single value is refused (the rest is checked where the trace is used)."""
    if values is None:
        raise TraceError(f"trace: {name} is None: expected one number per sample, shape (n,)")
    try:
        array = np.asarray(values)
    except (TypeError, ValueError):  # a ragged nesting
        raise TraceError(f"trace: {name} is not an array of numbers: expected one number "
                         "per sample, shape (n,)") from None
    if array.ndim == 0:  # numpy makes a number, a generator or a set a 0-d array
        raise TraceError(f"trace: {name}: expected an array or list of one number per "
                         f"sample, got {type(values).__name__}")
    return read_only_view(array)


def make_trace(t_s, finger, x_mm, y_mm, force_n=None, event=None, where: str = "trace",
               normalise: bool = True) -> Trace:
    """Validate arrays and build a :class:`Trace` (the module docstring's rules; time
    must not decrease).

    With ``normalise`` (a whole recording) events are normalised and the fingers touching
    at once counted, as the module doc says; a batch of live samples continuing earlier
    ones passes ``normalise=False`` so that a finger's first sample in the batch is not
    taken for a new touch.
    """
    # copies (np.array), so that the caller changing its arrays later changes no trace
    t = np.array(t_s, dtype=np.float64)
    n = t.size
    fing = np.asarray(finger)  # copied by the cast to int64 below
    x = np.array(x_mm, dtype=np.float64)
    y = np.array(y_mm, dtype=np.float64)
    f = np.full(n, DEFAULT_FORCE_N) if force_n is None else np.array(force_n, dtype=np.float64)
    ev = np.full(n, MOVE, dtype=np.int8) if event is None else np.array(event, dtype=np.int8)
    for name, arr in (("finger", fing), ("x_mm", x), ("y_mm", y), ("force_n", f), ("event", ev)):
        if arr.shape != (n,):
            raise TraceError(f"{where}: column {name} has shape {arr.shape}, expected ({n},)")
    if n == 0:
        raise TraceError(f"{where}: no samples (expected at least one row of t_s,finger,x_mm,y_mm)")
    fing_f = np.asarray(fing, dtype=np.float64)
    for name, arr in (("t_s", t), ("x_mm", x), ("y_mm", y), ("force_n", f), ("finger", fing_f)):
        lo, hi, unit = RANGES[name]
        bad = ~((arr >= lo) & (arr <= hi))  # NaN fails both
        if bad.any():
            i = int(np.argmax(bad))
            raise TraceError(f"{where}: sample {i}: {name} is {arr[i].item()!r}, expected "
                             f"{_range_text(name)}")
    if (fing_f != np.floor(fing_f)).any():
        i = int(np.argmax(fing_f != np.floor(fing_f)))
        raise TraceError(f"{where}: sample {i}: finger is {fing[i].item()!r}, expected "
                         f"{_range_text('finger')}")
    steps = np.diff(t)
    if (steps < 0).any():
        i = int(np.argmax(steps < 0)) + 1
        raise TraceError(f"{where}: sample {i}: t_s goes back from {float(t[i - 1])!r} to {float(t[i])!r} s "
                         "(time must not decrease)")
    if ((ev < DOWN) | (ev > UP)).any():
        i = int(np.argmax((ev < DOWN) | (ev > UP)))
        raise TraceError(f"{where}: sample {i}: event is {int(ev[i])}, expected {DOWN} (down), "
                         f"{MOVE} (move) or {UP} (up)")
    fing_i = fing_f.astype(np.int64)
    if normalise:
        ev = _normalise_events(fing_i, ev, set(), where)
    return Trace(t, fing_i, x, y, f, ev)


def _range_text(name: str) -> str:
    lo, hi, unit = RANGES[name]
    if name == "finger":
        return f"an integer from 0 to {MAX_FINGER_ID} (32-bit ids, as Linux tracking ids)"
    return f"a number from {lo:g} to {hi:g} {unit}"


def _touch_steps(finger: np.ndarray, event: np.ndarray, down: set[int]) -> tuple[np.ndarray, np.ndarray]:
    """Normalised events and the number of fingers touching after each sample.

    A finger's first sample, or its first after an ``up``, becomes a ``down`` (unless it
    is itself an ``up``). ``down`` (updated in place) holds the fingers touching before
    these samples, for a trace read in chunks.
    """
    before = len(down)
    # each finger's samples side by side (stable: in time order), so that "the finger's
    # previous sample" is the one before in this order: n log n, however many ids
    order = np.argsort(finger, kind="stable")
    f, e = finger[order], event[order].copy()
    first = np.ones(f.size, dtype=bool)
    first[1:] = f[1:] != f[:-1]
    lifted = np.empty(f.size, dtype=bool)
    lifted[1:] = e[:-1] == UP
    lifted[first] = ~np.isin(f[first], np.fromiter(down, dtype=np.int64, count=len(down)))
    starts = lifted & (e != UP)
    e[starts] = DOWN
    ev = np.empty_like(e)
    ev[order] = e
    change = np.empty(f.size, dtype=np.int64)
    change[order] = starts.astype(np.int64) - (~lifted & (e == UP))
    last = np.ones(f.size, dtype=bool)
    last[:-1] = first[1:]
    for fid, lifts in zip(f[last].tolist(), (e[last] == UP).tolist()):
        if lifts:
            down.discard(fid)
        else:
            down.add(fid)
    return ev, before + np.cumsum(change)


def _normalise_events(finger: np.ndarray, event: np.ndarray, down: set[int], where: str,
                      lines: np.ndarray | None = None) -> np.ndarray:
    """:func:`_touch_steps`' events; TraceError where more than MAX_TOUCHING fingers touch."""
    ev, touching = _touch_steps(finger, event, down)
    if touching.size and touching.max() > MAX_TOUCHING:
        i = int(np.argmax(touching > MAX_TOUCHING))
        place = f"{where}:{lines[i]}" if lines is not None else f"{where}: sample {i}"
        raise TraceError(f"{place}: {int(touching[i])} fingers touch at once (finger "
                         f"{int(finger[i])} comes down while the others have no up event); "
                         f"at most {MAX_TOUCHING} are accepted")
    return ev


def most_touching(trace: Trace) -> int:
    """The largest number of fingers touching at the same time."""
    return int(_touch_steps(trace.finger, trace.event, set())[1].max(initial=0))


@dataclass
class TimeOrder:
    """What reading a trace did about time going back (counts grow as chunks are read).

    tolerance_s : samples at most this much earlier than the latest time before them were
        moved into time order (``reordered``); samples further back were ``dropped``
        (the first at line ``first_dropped_line``).
    """

    tolerance_s: float = REORDER_TOLERANCE_S
    reordered: int = 0
    dropped: int = 0
    first_dropped_line: int | None = None

    def as_dict(self) -> dict:
        """``{"tolerance_s", "reordered", "dropped"}`` for ``summary.json``."""
        return {"tolerance_s": self.tolerance_s, "reordered": self.reordered,
                "dropped": self.dropped}

    def warnings(self) -> list[str]:
        """One sentence per thing done, for the replay's summary (empty if time never went back)."""
        out = []
        if self.reordered:
            out.append(f"{self.reordered} touch samples were up to {self.tolerance_s * 1e3:g} ms "
                       f"earlier than the sample before them and were sorted into time order")
        if self.dropped:
            out.append(f"{self.dropped} touch samples went back in time by more than "
                       f"{self.tolerance_s * 1e3:g} ms and were dropped (the first at line "
                       f"{self.first_dropped_line}; --strict refuses such a trace)")
        return out


def _parse_number(text: str, path: str, line: int, column: str) -> float:
    """A field as a float within ``RANGES[column]``."""
    if NUMBER.fullmatch(text) is None:
        if text.strip(" \t").lower().lstrip("+-") not in ("nan", "inf", "infinity"):
            raise TraceError(f"{path}:{line}: column {column}: {quoted(text)} is not a number "
                             f"(expected ASCII decimal, e.g. 12, -0.5 or 1.5e-3)")
        value = math.inf
    else:
        value = float(text)
    lo, hi, _ = RANGES[column]
    if not math.isfinite(value):
        raise TraceError(f"{path}:{line}: column {column}: {quoted(text)} is not a finite number")
    if not lo <= value <= hi or (column == "finger" and value != int(value)):
        raise TraceError(f"{path}:{line}: column {column}: {quoted(text)} is not "
                         f"{_range_text(column)}")
    return value


class _RowParser:
    """Data rows to time-ordered traces, chunk by chunk, carrying across chunks what
    spans them: the latest time, the samples still within the reordering tolerance of
    it (a later row may belong before them; at most ``max_held``, so that memory stays
    bounded even if a whole file shares one time), and which fingers are touching."""

    def __init__(self, names: list[str], where: str, order: TimeOrder, strict: bool,
                 max_held: int):
        self.names = names
        self.where = where
        self.col = {name: names.index(name) for name in names}
        self.order = order
        self.strict = strict
        self.max_held = max_held
        self.latest = -math.inf
        self.released = -math.inf  # the latest time handed out: nothing may come before it
        self.held: list[np.ndarray] | None = None  # t, finger, x, y, force, event, line
        self.down: set[int] = set()

    def parse(self, batch: list["_Rows"], final: bool = False) -> Trace | None:
        """The samples of ``batch`` (consecutive rows, in file order) that no later row can
        precede (all of them if ``final``), in time order; None if there are none yet."""
        cols = self._rows(batch)
        if self.held is not None:
            cols = [np.concatenate(pair) for pair in zip(self.held, cols)]
        if np.any(cols[0][1:] < cols[0][:-1]):  # a trace's rows are nearly always in order
            order = np.argsort(cols[0], kind="stable")
            cols = [c[order] for c in cols]
        cut = cols[0].size if final else max(cols[0].size - self.max_held, int(np.searchsorted(
            cols[0], self.latest - self.order.tolerance_s, side="right")))
        self.held = [c[cut:] for c in cols]
        if cut == 0:
            return None
        self.released = float(cols[0][cut - 1])
        t, finger, x, y, force, event, lines = (c[:cut] for c in cols)
        trace = make_trace(t, finger, x, y, force, event, self.where, normalise=False)
        return Trace(trace.t_s, trace.finger, trace.x_mm, trace.y_mm, trace.force_n,
                     _normalise_events(trace.finger, trace.event, self.down, self.where, lines))

    def _rows(self, batch: list["_Rows"]) -> list[np.ndarray]:
        """Columns of the rows kept (time order decided, not yet sorted): t, finger, x, y,
        force, event, line. Values are parsed column by column and range-checked per
        column; the first problem in file order is the one reported (found row by row,
        only when a column does not parse)."""
        batch = batch or [_Rows(np.zeros(0, dtype=np.int64), None, list)]
        lines = np.concatenate([piece.lines for piece in batch])
        try:
            parts = [piece.columns or self._columns(piece.fields(), piece.plain_ascii)
                     for piece in batch]
        except (ValueError, IndexError, KeyError):
            self._first_row_problem(_numbered_rows(batch))
        t, fv, x, y, force, event = (np.concatenate(part) for part in zip(*parts))
        first_bad = self._first_bad_value(t, fv, x, y, force)
        self._time_order(t[:first_bad], lines[:first_bad])
        if first_bad < t.size:
            self._row_problem(*_numbered_rows(batch)[first_bad])
        keep = self._keep(t, lines)
        cols = (t, fv.astype(np.int64), x, y, force, event, lines)
        return list(cols) if keep.all() else [a[keep] for a in cols]

    def _columns(self, rows: list[list[str]], plain_ascii: bool = False) -> tuple[np.ndarray, ...]:
        """t, finger, x, y, force, event of well-formed rows (:func:`ascii_float` on each
        field, as the row-by-row check does; plain ``float`` where the rows are
        ``plain_ascii``, which then takes the same numbers); raises ValueError, IndexError
        or KeyError on the first field that is not (the caller then finds and reports it)."""
        col, n = self.col, len(rows)
        if n and set(map(len, rows)) != {len(self.names)}:
            raise IndexError
        number = float if plain_ascii else ascii_float
        t, fv, x, y = (np.fromiter(map(number, (row[col[name]] for row in rows)),
                                   dtype=np.float64, count=n) for name in REQUIRED)
        force = np.full(n, DEFAULT_FORCE_N)
        if "force_n" in col:
            i = col["force_n"]
            given = [k for k, row in enumerate(rows) if row[i].strip(" \t")]
            force[given] = np.fromiter(map(number, (rows[k][i] for k in given)),
                                       dtype=np.float64, count=len(given))
        event = np.full(n, MOVE, dtype=np.int8)
        if "event" in col:
            i = col["event"]
            words = [row[i].strip(" \t") for row in rows]
            given = [k for k, word in enumerate(words) if word]
            event[given] = [_EVENT_CODES[words[k]] for k in given]
        return t, fv, x, y, force, event

    def _first_row_problem(self, numbered_rows) -> NoReturn:
        """Raise the TraceError of the first row in file order that holds a problem: a
        row shorter or longer than the header, a field that is not a number or an event, or (before it) a value out
        of range or a step back in time under ``strict``."""
        for k, (line, row) in enumerate(numbered_rows):
            try:
                self._columns([row])
            except (ValueError, IndexError, KeyError):
                head = numbered_rows[:k]
                if head:
                    t, fv, x, y, force, _ = self._columns([r for _, r in head])
                    first_bad = self._first_bad_value(t, fv, x, y, force)
                    if first_bad < k:
                        self._row_problem(*head[first_bad])
                    self._time_order(t, np.array([ln for ln, _ in head], dtype=np.int64))
                self._row_problem(line, row)
        # the rows failed together but none alone: a bug here, not a bad file
        raise AssertionError(f"{self.where}: rows {numbered_rows[0][0]} to {numbered_rows[-1][0]} "
                             f"failed to parse together, but no row has a problem")

    @staticmethod
    def _first_bad_value(t, fv, x, y, force) -> int:
        """Index of the first row with a value out of its range (``len(t)`` if none)."""
        bad = np.zeros(t.size, dtype=bool)
        for name, arr in (("t_s", t), ("finger", fv), ("x_mm", x), ("y_mm", y), ("force_n", force)):
            lo, hi, _ = RANGES[name]
            bad |= ~((arr >= lo) & (arr <= hi))  # NaN fails both
        bad |= fv != np.floor(fv)
        return int(np.argmax(bad)) if bad.any() else t.size

    def _row_problem(self, line: int, row: list[str]):
        """Raise the TraceError of a row known to hold a problem."""
        where = self.where
        if len(row) != len(self.names):
            raise TraceError(f"{where}:{line}: {len(row)} fields, expected {len(self.names)} as "
                             f"the header has ({describe_header(self.names)})")
        for name in ("t_s", "finger", "x_mm", "y_mm", "force_n"):
            if name in self.col and (name != "force_n" or row[self.col[name]].strip(" \t")):
                _parse_number(row[self.col[name]], where, line, name)
        word = row[self.col["event"]].strip(" \t")
        raise TraceError(f"{where}:{line}: column event: {quoted(word)} is not one of "
                         f"{', '.join(EVENTS)}")

    def _time_order(self, t: np.ndarray, lines: np.ndarray) -> None:
        """With ``strict``, raise at the first row earlier than a row before it."""
        if not self.strict or t.size == 0:
            return
        before = np.maximum.accumulate(np.concatenate(([self.latest], t)))[:-1]
        back = t < before
        if back.any():
            i = int(np.argmax(back))
            raise TraceError(f"{self.where}:{lines[i]}: t_s goes back from {float(before[i])!r} "
                             f"to {float(t[i])!r} s (time must not decrease in a strict read: "
                             "--strict, strict=True)")

    def _keep(self, t: np.ndarray, lines: np.ndarray) -> np.ndarray:
        """Which rows are kept: those at most the tolerance earlier than the latest time
        before them (and not before what was handed out); counts the rest as dropped."""
        before = np.maximum.accumulate(np.concatenate(([self.latest], t)))[:-1]
        back = t < before
        keep = t >= np.maximum(before - self.order.tolerance_s, self.released)
        keep |= ~back
        self.order.reordered += int(np.count_nonzero(back & keep))
        dropped = np.flatnonzero(~keep)
        if dropped.size:
            self.order.dropped += int(dropped.size)
            if self.order.first_dropped_line is None:
                self.order.first_dropped_line = int(lines[dropped[0]])
        if t.size:
            self.latest = max(self.latest, float(t.max()))
        return keep


#: bytes read from a trace file at a time
_READ_BYTES = 1 << 22


def _blocks(fh, where: str):
    """The lines of a binary file in blocks: (number of the block's first line, the
    block's lines, each ended by its line break but the file's last line may have none,
    how many lines). UTF-8, a leading BOM dropped, lines of at most MAX_LINE_BYTES (the
    line break included), no NUL bytes.

    Each block is read and checked at once; the lines before a problem are handed out
    before the problem's error. A file that ends with a line break and fits one read is
    one block, the bytes read and never copied.
    """
    number, rest = 0, b""
    block = _without_bom(fh.read(max(_READ_BYTES, len(codecs.BOM_UTF8))), where) or fh.read(_READ_BYTES)
    while True:
        data = rest + block if rest else block
        cut = data.rfind(b"\n") + 1 if block else len(data)
        if block and cut == 0 and len(data) <= MAX_LINE_BYTES:
            rest, block = data, fh.read(_READ_BYTES)  # a line longer than a block so far
            continue
        end, rest = (cut, data[cut:]) if cut else (len(data), b"")
        if not end:
            return
        body = data[:end]  # no copy when end is the whole of data
        ended = body.endswith(b"\n")
        count = _line_breaks(body) + (not ended)
        bad = _first_bad_line(body, count)
        if bad == count:  # the whole block is good: handed out as it is, not split
            yield number + 1, body, count
        else:
            raws = body.split(b"\n", bad + 1)
            if bad:
                yield number + 1, b"\n".join(raws[:bad]) + b"\n", bad
            _line_problem(raws[bad], number + bad + 1, where, ended or bad < count - 1)
        number += count
        block = fh.read(_READ_BYTES)


def _line_breaks(body: bytes) -> int:
    """How many line breaks ``body`` holds (numpy counts several times faster than
    ``bytes.count``, which looks at a byte at a time)."""
    return int(np.count_nonzero(np.frombuffer(body, dtype=np.uint8) == 0x0A))


def _without_bom(head: bytes, where: str) -> bytes:
    """The file's first bytes without a UTF-8 BOM; a UTF-16 one is refused."""
    if head.startswith((codecs.BOM_UTF16_LE, codecs.BOM_UTF16_BE)):
        raise TraceError(f"{where}: UTF-16 text (it starts with a UTF-16 byte order "
                         f"mark); save it as UTF-8: trace files are UTF-8 CSV")
    return head[len(codecs.BOM_UTF8):] if head.startswith(codecs.BOM_UTF8) else head


def _first_bad_line(body: bytes, count: int) -> int:
    """Index among the ``count`` lines of ``body`` (each ended by a line break, the last
    one maybe not) of the first line too long, holding a NUL byte, a bare CR or not
    UTF-8; ``count`` if none."""
    bad = count
    long = _first_long_line(body)
    if long >= 0:
        bad = body.count(b"\n", 0, long)
    nul = body.find(0)
    if nul >= 0:
        bad = min(bad, body.count(b"\n", 0, nul))
    cr = _bare_cr(body)
    if cr >= 0:
        bad = min(bad, body.count(b"\n", 0, cr))
    if body.isascii():  # UTF-8, and no 2 MB string to build and drop
        return bad
    try:
        body.decode("utf-8")
    except UnicodeDecodeError as exc:
        bad = min(bad, body.count(b"\n", 0, exc.start))
    return bad


def _first_long_line(body: bytes) -> int:
    """Offset in ``body`` of the first line longer than MAX_LINE_BYTES, its break
    included, or -1. Each step looks at the next MAX_LINE_BYTES bytes from a line's start
    for the last line break among them: none means the line is too long. Two steps go at
    least MAX_LINE_BYTES further, so no byte is looked at more than twice."""
    start = 0
    while len(body) - start > MAX_LINE_BYTES:
        brk = body.rfind(b"\n", start, start + MAX_LINE_BYTES)
        if brk < 0:
            return start
        start = brk + 1
    return -1


def _bare_cr(data: bytes) -> int:
    """Offset in ``data`` of the first carriage return with more of its line after it
    (:data:`_BARE_CR`), or -1."""
    if b"\r" not in data or data.count(b"\r") == data.count(b"\r\n") + data.endswith(b"\r"):
        return -1  # the usual cases (none, or CRLF files), decided at C speed
    found = _BARE_CR.search(data)
    return found.start() if found else -1


def _line_problem(raw: bytes, number: int, where: str, had_break: bool):
    """Raise the error of a line known to be too long, binary, not UTF-8 or holding a
    bare CR. Of a line too long only its first MAX_LINE_BYTES are looked at. Binary
    content is named first (a binary file's bytes hold carriage returns and few line
    feeds), then a bare CR (lines that end in CR only make the file one long line: that,
    not its length, is the problem to name)."""
    head = raw[:MAX_LINE_BYTES]
    nul = head.find(0)
    if nul >= 0:
        raise TraceError(f"{where}:{number}: binary content (a NUL byte at column "
                         f"{nul + 1}); expected CSV text")
    try:  # a character cut at the end of a long line's head is not an error
        codecs.getincrementaldecoder("utf-8")().decode(head, final=len(raw) <= MAX_LINE_BYTES)
    except UnicodeDecodeError as exc:
        raise TraceError(f"{where}:{number}: not UTF-8 text (byte {head[exc.start]:#04x} at "
                         f"column {exc.start + 1}); trace files are UTF-8 CSV") from None
    if _bare_cr(head) >= 0:
        raise TraceError(f"{where}:{number}: {CR_ONLY}")
    if len(raw) + had_break > MAX_LINE_BYTES:
        raise TraceError(f"{where}:{number}: line longer than {MAX_LINE_BYTES} bytes; "
                         f"expected CSV rows of a few numbers")
    raise AssertionError(f"line {number} has no problem")


def _fields(text: str, where: str, number: int) -> list[str]:
    """The CSV fields of one line (without its line break)."""
    body = text.rstrip("\r\n")
    if '"' not in body and "\r" not in body:  # no quoting: what the csv module splits
        return body.split(",")
    try:
        return next(csv.reader([text]))
    except csv.Error as exc:
        raise TraceError(f"{where}:{number}: not a CSV row ({exc})") from None


@dataclass(frozen=True, eq=False)
class _Rows:
    """Consecutive data rows of a trace file.

    lines : int64 (n,) their line numbers.
    columns : (t, finger, x, y, force, event) parsed at once from a plain block, or None.
    fields : a function giving each row's fields (for a plain block, split only when a
        row's problem is to be named).
    plain_ascii : every byte of the rows is printable ASCII other than ``_``, or a tab:
        ``float`` then takes exactly the :data:`NUMBER` s (and the words nan and inf,
        which the range check refuses).
    """

    lines: np.ndarray
    columns: tuple | None
    fields: Callable[[], list[list[str]]]
    plain_ascii: bool = False

    def split(self, k: int) -> tuple["_Rows", "_Rows"]:
        """The first ``k`` rows and the rest."""
        halves = []
        for part in (slice(0, k), slice(k, None)):
            cols = None if self.columns is None else tuple(c[part] for c in self.columns)
            halves.append(_Rows(self.lines[part], cols, lambda part=part: self.fields()[part],
                                self.plain_ascii))
        return halves[0], halves[1]


def _numbered_rows(batch: list[_Rows]) -> list[tuple[int, list[str]]]:
    """(line number, fields) of every row of ``batch``."""
    return [pair for piece in batch for pair in zip(piece.lines.tolist(), piece.fields())]


#: until pyarrow is imported, a block of fewer lines is split line by line: for a small
#: file, importing it (about 0.1 s) would cost more than its parser saves (4 us a line)
_PLAIN_MIN_LINES = 8192
#: least bytes Arrow parses as one block (many rows, so a row never spans two)
_ARROW_BLOCK = 1 << 16


def _plain_columns(data: bytes, start: int, count: int, col: dict[str, int],
                   width: int) -> tuple | None:
    """(t, finger, x, y, force, event) of ``count`` lines of data rows (``data`` from
    offset ``start``, each line ended by a line break but maybe the last), parsed at once
    by Arrow's CSV reader when the block is plain: no quotes, comments or blank lines,
    every row of ``width`` fields (the header's), every number a float Arrow parses and
    every event word known. Lines end in LF or CRLF, as Arrow reads them: :func:`_blocks`
    refused a bare CR. None
    otherwise: the caller then splits the rows line by line, which names any problem.

    Arrow accepts a subset of what ``float`` does and gives the same value (the correctly
    rounded double; ``tests/test_trace_file.py`` checks it), so a block parses here to
    the same columns as line by line.
    """
    if count < _PLAIN_MIN_LINES and "pyarrow" not in sys.modules:
        return None
    if data.find(b'"', start) >= 0 or data.find(b"#", start) >= 0:
        return None
    if data.count(b",", start, _line_end(data, start)) + 1 != width:
        return None  # Arrow holds every row to the first row's width
    import pyarrow as pa
    from pyarrow import csv as pa_csv
    # Arrow needs a line break to see a row's end; a block that has it is not copied
    rows = (pa.py_buffer(data)[start:] if data.endswith(b"\n")
            else pa.py_buffer(data[start:] + b"\n"))
    names = list(REQUIRED) + [c for c in ("force_n", "event") if c in col]
    types = {f"f{col[name]}": pa.dictionary(pa.int32(), pa.string()) if name == "event"
             else pa.float64() for name in names}
    try:
        table = pa_csv.read_csv(
            rows,
            # a few blocks parsed on Arrow's threads (the cores); in order, as one
            read_options=pa_csv.ReadOptions(autogenerate_column_names=True, use_threads=True,
                                            block_size=max(rows.size // 4 + 2, _ARROW_BLOCK)),
            parse_options=pa_csv.ParseOptions(quote_char=False, escape_char=False,
                                              ignore_empty_lines=False),
            convert_options=pa_csv.ConvertOptions(column_types=types, include_columns=list(types),
                                                  null_values=[], strings_can_be_null=False,
                                                  check_utf8=False))
    except pa.ArrowInvalid:  # a blank line or a ragged row, a number or text it refuses
        return None
    t, fv, x, y = (table.column(f"f{col[name]}").to_numpy() for name in REQUIRED)
    force = (table.column(f"f{col['force_n']}").to_numpy() if "force_n" in col
             else np.full(count, DEFAULT_FORCE_N))
    event = np.full(count, MOVE, dtype=np.int8)
    if "event" in col:
        codes = []
        for part in table.column(f"f{col['event']}").chunks:
            words = [word.strip(" \t") for word in part.dictionary.to_pylist()]
            if not set(words) <= set(EVENTS) | {""}:
                return None
            lookup = np.array([_EVENT_CODES.get(word, MOVE) for word in words], dtype=np.int8)
            codes.append(lookup[part.indices.to_numpy()])
        event = np.concatenate(codes)
    # read-only views of Arrow's buffers: the parser concatenates (copies) every column
    return tuple(np.asarray(c, dtype=np.float64) for c in (t, fv, x, y, force)) + (event,)


def _chunks(blocks, where: str, chunk_rows: int, order: TimeOrder, strict: bool,
            header: list[str] | None = None):
    """Traces of about ``chunk_rows`` samples from :func:`_blocks`' blocks of lines; the
    header's column names added to ``header`` once read."""
    parser = None
    batch: list[_Rows] = []
    held = samples = 0
    for first, data, count in blocks:
        start = 0  # offset of the block's first data row
        if parser is None:
            parser, skipped = _header(data, first, where, order, strict)
            if parser is not None and header is not None:
                header.extend(parser.names)
            if parser is None or skipped == count:
                continue
            for _ in range(skipped):
                start = data.index(b"\n", start) + 1
            first, count = first + skipped, count - skipped
        piece = _block_rows(data, start, first, count, parser, where)
        batch.append(piece)
        held += piece.lines.size
        while held >= chunk_rows:
            head, batch = _take(batch, chunk_rows)
            held -= chunk_rows
            chunk = parser.parse(head)
            if chunk is not None:
                samples += len(chunk)
                yield chunk
    if parser is None:
        raise TraceError(f"{where}: empty trace (expected a header line with {','.join(REQUIRED)})")
    chunk = parser.parse(batch, final=True)
    if chunk is not None:
        samples += len(chunk)
        yield chunk
    if samples == 0:
        raise TraceError(f"{where}: header but no samples")


def _header(data: bytes, first: int, where: str, order: TimeOrder, strict: bool):
    """(the parser of the header line among a block's lines, how many lines up to and
    including it), or (None, 0) if the block has only blank and comment lines."""
    for k, text in enumerate(_lines(data)):
        if not text.strip() or text.lstrip().startswith("#"):
            continue
        names = [h.strip(" \t") for h in _fields(text, where, first + k)]
        missing = [c for c in REQUIRED if c not in names]
        if missing:
            raise TraceError(f"{where}:{first + k}: not a trace header: it lacks column(s) "
                             f"{', '.join(missing)} ({describe_header(names)}; expected a "
                             f"first line naming {','.join(REQUIRED)})")
        twice = next((name for k, name in enumerate(names) if name and name in names[:k]), None)
        if twice is not None:
            raise TraceError(f"{where}:{first + k}: header names column {quoted(twice)} twice "
                             f"(each column once)")
        return _RowParser(names, where, order, strict, MAX_HELD_ROWS), k + 1
    return None, 0


#: a header field shown in an error: a plain column name of at most 32 characters
def _line_end(data: bytes, start: int) -> int:
    """Offset of the end of the line of ``data`` that starts at ``start`` (its break)."""
    end = data.find(b"\n", start)
    return len(data) if end < 0 else end


def _lines(data: bytes):
    """The lines of ``data`` (UTF-8, joined by b"\\n"), decoded one at a time: the header
    is near the start of a block of a megabyte."""
    start = 0
    while (end := data.find(b"\n", start)) >= 0:
        yield data[start:end].decode("utf-8")
        start = end + 1
    yield data[start:].decode("utf-8")


_COLUMN_NAME = re.compile(r"[A-Za-z][A-Za-z0-9_]{0,31}")
#: most column names an error lists
_NAMES_SHOWN = 8


def describe_header(names: list[str]) -> str:
    """What a header line holds, for an error, without printing the line: the number of
    fields and the first :data:`_NAMES_SHOWN` of them that are plain column names
    (:data:`_COLUMN_NAME`); a line of another file (``/etc/shadow``) shows none of its text."""
    plain = [name for name in names if _COLUMN_NAME.fullmatch(name)]
    count = f"{len(names)} field{'s' * (len(names) != 1)}"
    if not plain:
        return f"{count}, {'not a column name' if len(names) == 1 else 'none a column name'}"
    shown = plain[:_NAMES_SHOWN] + ([f"{len(plain) - _NAMES_SHOWN} more column names"]
                                    if len(plain) > _NAMES_SHOWN else [])
    others = len(names) - len(plain)
    if others:
        shown.append(f"{others} that {'is not a column name' if others == 1 else 'are not column names'}")
    return f"{count}: {', '.join(shown[:-1])} and {shown[-1]}" if len(shown) > 1 else f"{count}: {shown[0]}"


#: columns ``frictex trace import`` writes beside those read, for the record: the raw
#: pressure and contact size of an Android log (``rendering.input.trace_import``)
RECORDED_COLUMNS = ("pressure", "touch_major")


def ignored_columns(names: list[str]) -> str | None:
    """A warning naming a header's columns that frictex does not read (they are ignored),
    each with the column it may misspell (``force_N``: did you mean force_n?); None if it
    reads them all, or ignores only :data:`RECORDED_COLUMNS`. As :func:`describe_header`,
    only plain column names are shown, the other fields counted."""
    extra = [name for name in names if name not in _COLUMNS + RECORDED_COLUMNS]
    if not extra:
        return None
    plain = [name for name in extra if _COLUMN_NAME.fullmatch(name)]
    shown = [name + _misspelt(name) for name in plain[:_NAMES_SHOWN]]
    if len(plain) > _NAMES_SHOWN:
        shown.append(f"{len(plain) - _NAMES_SHOWN} more")
    others = len(extra) - len(plain)
    if others:
        shown.append(f"{others} {'field that is' if others == 1 else 'fields that are'} not a "
                     "column name")
    return (f"trace: {len(extra)} {'column' if len(extra) == 1 else 'columns'} frictex does not "
            f"read, ignored: {', '.join(shown)} (it reads {', '.join(_COLUMNS)})")


def _misspelt(name: str) -> str:
    """" (did you mean C?)" where ``name`` is close to a column C frictex reads, else ""."""
    near = difflib.get_close_matches(name.lower(), _COLUMNS, n=1, cutoff=0.75)
    return f" (did you mean {near[0]}?)" if near else ""


def _block_rows(data: bytes, start: int, first: int, count: int, parser: "_RowParser",
                where: str) -> _Rows:
    """The data rows of a block of ``count`` lines (``data`` from offset ``start``) from
    line ``first``: parsed at once if the block is plain (:func:`_plain_columns`), else
    split line by line skipping blank and comment lines."""
    def split_rows():  # (line number, fields) of the data rows
        return [(first + k, _fields(text, where, first + k))
                for k, text in enumerate(data[start:].decode("utf-8").split("\n"))
                if text.strip() and not text.lstrip().startswith("#")]

    columns = _plain_columns(data, start, count, parser.col, len(parser.names))
    if columns is not None:  # every line a row: split only to name a row's problem
        lines = np.arange(first, first + count, dtype=np.int64)
        return _Rows(lines, columns, lambda: [row for _, row in split_rows()])
    numbered = split_rows()
    lines = np.fromiter((line for line, _ in numbered), dtype=np.int64, count=len(numbered))
    plain_ascii = not data[start:].translate(None, _PLAIN_ASCII_BYTES)
    return _Rows(lines, None, lambda: [row for _, row in numbered], plain_ascii)


#: the bytes of a block whose fields ``float`` reads as :data:`NUMBER` reads them
_PLAIN_ASCII_BYTES = bytes(range(0x20, 0x7F)).replace(b"_", b"") + b"\t\n"


def _take(batch: list[_Rows], n: int) -> tuple[list[_Rows], list[_Rows]]:
    """The first ``n`` rows of ``batch`` and the rest."""
    head, rest = [], list(batch)
    while n:
        piece = rest.pop(0)
        if piece.lines.size > n:
            piece, after = piece.split(n)
            rest.insert(0, after)
        head.append(piece)
        n -= piece.lines.size
    return head, rest


class TraceReader:
    """A trace CSV read and validated in chunks of about ``chunk_rows`` samples: an
    iterator of :class:`Trace`, so that a trace of any length is read in bounded memory.

    ``order`` (:class:`TimeOrder`) counts the samples sorted or dropped because time went
    back; it is final once the iterator is exhausted. ``strict`` refuses any step back.
    ``columns``: the header's column names, once read.
    """

    def __init__(self, path: str | Path, chunk_rows: int = 65_536, strict: bool = False,
                 tolerance_s: float = REORDER_TOLERANCE_S):
        self.path = Path(path)
        self.order = TimeOrder(tolerance_s)
        self.columns: list[str] = []
        self._chunks = self._read(chunk_rows, strict)

    def __iter__(self) -> "TraceReader":
        return self

    def __next__(self) -> Trace:
        return next(self._chunks)

    def warnings(self) -> list[str]:
        """What reading did about time going back (:meth:`TimeOrder.warnings`) and the
        header's columns it ignored (:func:`ignored_columns`), one sentence each."""
        ignored = ignored_columns(self.columns)
        return self.order.warnings() + ([ignored] if ignored else [])

    def _read(self, chunk_rows: int, strict: bool):
        path = self.path
        problem = file_problem(path)
        if problem is not None:
            raise TraceError(f"{path}: {problem}; expected a trace CSV file")
        try:
            with open(path, "rb") as fh:
                yield from _chunks(_blocks(fh, str(path)), str(path), chunk_rows, self.order,
                                   strict, self.columns)
        except OSError as exc:
            raise TraceError(f"{path}: cannot read trace ({exc.strerror or exc})") from None


def iter_trace(path: str | Path, chunk_rows: int = 65_536, strict: bool = False) -> TraceReader:
    """Read and validate a trace CSV in chunks (see :class:`TraceReader`)."""
    return TraceReader(path, chunk_rows, strict)


def concat_traces(chunks) -> Trace:
    """One :class:`Trace` from consecutive chunks."""
    chunks = list(chunks)
    return Trace(*(np.concatenate([getattr(c, name) for c in chunks]) for name in _COLUMNS))


def read_trace(path: str | Path, strict: bool = False) -> Trace:
    """Read and validate a whole trace CSV (see the module docstring for the grammar)."""
    return concat_traces(iter_trace(path, strict=strict))


def parse_trace(text: str, where: str = "<trace>", strict: bool = False) -> Trace:
    """Parse trace CSV text; ``where`` names the source in error messages."""
    blocks = _blocks(io.BytesIO(_utf8(text)), where)
    return concat_traces(_chunks(blocks, where, 65_536, TimeOrder(), strict))


def _utf8(text: str) -> bytes:
    """``text`` as UTF-8, a lone surrogate kept as bytes for the reader to refuse by its
    line as not UTF-8: the byte it stands for (text read with ``errors="surrogateescape"``),
    else its own encoding."""
    try:
        return text.encode("utf-8", errors="surrogateescape")
    except UnicodeEncodeError:
        return text.encode("utf-8", errors="surrogatepass")


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

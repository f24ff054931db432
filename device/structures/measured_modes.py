"""Measured mode shapes: sampled tables (a vibrometer scan, seed 000 Fig. 10) made smooth.

A device may give its mode shapes measured rather than modelled: deflection of each
mode sampled at positions along the structure. They are interpolated by not-a-knot cubic
splines (continuous slope and curvature, exact on cubics), so node positions and the
modal matrix vary smoothly as a finger moves. Outside the scanned span the end values
are held (never extrapolated); :meth:`MeasuredModes.outside` marks such positions so the
caller can count them. The table is scaled to 1 at its largest deflection: the unit
cancels (the commands at the actuators and the amplitudes under the fingers do not depend
on it), and a scan in metres (1e-9) or one of 1e-100 keeps the modal solve within the
range where its closed form is finite (below ~1e-77 its terms overflowed to NaN).

File grammar (CSV)::

    file   := header NEWLINE { row NEWLINE }
    header := "x_mm" { "," mode_name }          # 1 to MAX_MODES (26) distinct mode names
    row    := x { "," deflection }              # finite numbers, any consistent unit,
                                                # not all 0
    number := ASCII decimal: [sign] digits [. digits] [e [sign] digits], spaces or tabs
              around (device/numbers.py, the grammar of every frictex text format)
    blank lines and lines starting with '#' are skipped; x strictly increasing;
    at least 4 rows. A regular UTF-8 file of at most MAX_TABLE_BYTES (1 MiB).
"""

from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline

from frictex.device.numbers import NUMBER
from frictex.device.safe_files import UnsafeFile, read_bytes
from frictex.device.safe_text import escape, escape_path, quoted
from frictex.device.structures.beam import MAX_MODES, ModesError

MIN_SAMPLES = 4
#: Largest mode table read (bytes): a scan of thousands of points fits.
MAX_TABLE_BYTES = 1 << 20
#: Longest cell shown in an error (characters, escaped): a number is shorter, and a row of
#: something that is not a mode table is described, not printed.
MAX_CELL_SHOWN = 24


@dataclass(frozen=True, eq=False)
class MeasuredModes:
    """Mode shapes sampled at ``positions_mm`` (k,), ``shapes`` (k, p), one column per mode,
    scaled to 1 at the largest |deflection| (the module docstring)."""

    positions_mm: np.ndarray
    shapes: np.ndarray
    names: tuple[str, ...]
    source: str = "<table>"

    def __post_init__(self):
        x = np.asarray(self.positions_mm, dtype=np.float64)
        s = np.asarray(self.shapes, dtype=np.float64)
        where = f"mode table {self.source}"
        if x.ndim != 1 or x.size < MIN_SAMPLES:
            raise ModesError(f"{where}: need at least {MIN_SAMPLES} positions, got {x.size}")
        if s.ndim != 2 or s.shape[0] != x.size or s.shape[1] != len(self.names) or s.shape[1] < 1:
            raise ModesError(f"{where}: shapes must be ({x.size}, {len(self.names)}) "
                             f"(positions x modes), got {s.shape}")
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(s))):
            raise ModesError(f"{where}: positions and shapes must be finite numbers")
        peak = float(np.max(np.abs(s))) if s.size else 0.0
        if peak == 0.0:
            raise ModesError(f"{where}: every deflection is 0: no mode moves the structure")
        bad = np.flatnonzero(np.diff(x) <= 0)
        if bad.size:
            raise ModesError(f"{where}: positions must increase strictly; "
                             f"x = {x[bad[0] + 1]:g} mm follows {x[bad[0]]:g} mm")
        s = s / peak
        object.__setattr__(self, "positions_mm", x)
        object.__setattr__(self, "shapes", s)
        object.__setattr__(self, "_spline", CubicSpline(x, s, axis=0, bc_type="not-a-knot"))

    @classmethod
    def from_csv(cls, path, max_bytes: int = MAX_TABLE_BYTES) -> "MeasuredModes":
        """Read a mode table (grammar in the module docstring) from a regular UTF-8 file of
        at most ``max_bytes`` (``device.safe_files``); errors name file and line."""
        try:
            data = read_bytes(path, max_bytes)
        except UnsafeFile as exc:
            raise ModesError(f"{escape_path(path)}: {exc}") from None
        try:
            text = data.decode("utf-8-sig")
        except UnicodeDecodeError as exc:
            raise ModesError(f"{escape_path(path)}: not UTF-8 text (byte {data[exc.start]:#04x} at "
                             f"offset {exc.start}); expected a CSV mode table") from None
        return cls.from_text(text, escape_path(path))

    @classmethod
    def from_text(cls, text: str, source: str = "<table>") -> "MeasuredModes":
        """A mode table from its text; errors start with ``source`` and the line, and
        describe a row that does not fit rather than print it."""
        if "\0" in text:
            raise ModesError(f"{source}: holds a NUL byte: binary content, not a CSV mode table")
        try:
            rows = [(i, r) for i, r in enumerate(csv.reader(io.StringIO(text, newline="")), start=1)
                    if r and not r[0].lstrip().startswith("#")]
        except csv.Error as exc:  # e.g. a field over csv's 128 KiB limit
            raise ModesError(f"{source}: not a CSV mode table ({escape(exc)})") from None
        if not rows or rows[0][1][0].strip() != "x_mm" or len(rows[0][1]) < 2:
            raise ModesError(f"{source}: line {rows[0][0] if rows else 1}: header must be "
                             f"'x_mm,<mode>[,<mode>...]'")
        if len(rows[0][1]) - 1 > MAX_MODES:
            raise ModesError(f"{source}: line {rows[0][0]}: {len(rows[0][1]) - 1} mode columns; "
                             f"expected at most {MAX_MODES}")
        names = tuple(c.strip() for c in rows[0][1][1:])
        bad_name = next((n for n in names if not n or not n.isprintable()), None)
        if bad_name is not None:
            raise ModesError(f"{source}: line {rows[0][0]}: mode name {quoted(bad_name)} is empty "
                             f"or holds control characters; expected printable names")
        twice = next((n for i, n in enumerate(names) if n in names[:i]), None)
        if twice is not None:
            raise ModesError(f"{source}: line {rows[0][0]}: mode name {quoted(twice)} appears twice; "
                             f"expected distinct names")
        values = [cls._row(source, line, row, len(names) + 1) for line, row in rows[1:]]
        table = np.array(values).reshape(-1, len(names) + 1)
        return cls(table[:, 0], table[:, 1:], names, source=source)

    @staticmethod
    def _row(source: str, line: int, row: list[str], width: int) -> list[float]:
        if len(row) != width:
            raise ModesError(f"{source}: line {line}: expected {width} values, got {len(row)}")
        column = next((i for i, v in enumerate(row) if NUMBER.fullmatch(v) is None), None)
        if column is not None:
            word = row[column].strip().lower().lstrip("+-")
            if word in ("nan", "inf", "infinity"):
                raise ModesError(f"{source}: line {line}: values must be finite; value "
                                 f"{column + 1} is {quoted(row[column], MAX_CELL_SHOWN)}")
            raise ModesError(f"{source}: line {line}: value {column + 1} ({quoted(row[column], MAX_CELL_SHOWN)}) "
                             f"is not a number (ASCII decimal, e.g. -1.5e-3)")
        nums = [float(v) for v in row]
        if not all(math.isfinite(v) for v in nums):
            column = next(i for i, v in enumerate(nums) if not math.isfinite(v))
            raise ModesError(f"{source}: line {line}: values must be finite; value {column + 1} "
                             f"is {quoted(row[column], MAX_CELL_SHOWN)}")
        return nums

    def phi(self, x_mm) -> np.ndarray:
        """Interpolated shapes at ``x_mm`` (any shape) -> float64 (..., p); ends held outside."""
        x = np.clip(np.asarray(x_mm, dtype=np.float64), self.positions_mm[0], self.positions_mm[-1])
        return self._spline(x)

    def outside(self, x_mm) -> np.ndarray:
        """True where ``x_mm`` lies outside the scanned span (its value is the held end value)."""
        x = np.asarray(x_mm, dtype=np.float64)
        return (x < self.positions_mm[0]) | (x > self.positions_mm[-1])

    def nodes_mm(self, mode: int) -> np.ndarray:
        """Zeros (mm, increasing) of the interpolated shape of column ``mode`` (0-based)."""
        if not 0 <= mode < len(self.names):
            raise ModesError(f"mode index must be in 0..{len(self.names) - 1}, got {mode!r}")
        roots = CubicSpline(self.positions_mm, self.shapes[:, mode]).roots(extrapolate=False)
        return np.unique(roots)

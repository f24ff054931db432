"""Measured mode shapes: sampled tables (a vibrometer scan, seed 000 Fig. 10) made smooth.

A device may give its mode shapes measured rather than modelled: deflection of each
mode sampled at positions along the structure. They are interpolated by not-a-knot cubic
splines (continuous slope and curvature, exact on cubics), so node positions and the
modal matrix vary smoothly as a finger moves. Outside the scanned span the end values
are held (never extrapolated); :meth:`MeasuredModes.outside` marks such positions so the
caller can count them.

File grammar (CSV)::

    file   := header NEWLINE { row NEWLINE }
    header := "x_mm" { "," mode_name }          # at least one mode column
    row    := x { "," deflection }              # finite numbers, any consistent unit
    blank lines and lines starting with '#' are skipped; x strictly increasing;
    at least 4 rows.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.interpolate import CubicSpline

from frictex.device.structures.beam import ModesError

MIN_SAMPLES = 4


@dataclass(frozen=True, eq=False)
class MeasuredModes:
    """Mode shapes sampled at ``positions_mm`` (k,), ``shapes`` (k, p), one column per mode."""

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
        bad = np.flatnonzero(np.diff(x) <= 0)
        if bad.size:
            raise ModesError(f"{where}: positions must increase strictly; "
                             f"x = {x[bad[0] + 1]:g} mm follows {x[bad[0]]:g} mm")
        object.__setattr__(self, "positions_mm", x)
        object.__setattr__(self, "shapes", s)
        object.__setattr__(self, "_spline", CubicSpline(x, s, axis=0, bc_type="not-a-knot"))

    @classmethod
    def from_csv(cls, path) -> "MeasuredModes":
        """Read a mode table (grammar in the module docstring); errors name file and line."""
        path = Path(path)
        with path.open(newline="") as fh:
            rows = [(i, r) for i, r in enumerate(csv.reader(fh), start=1)
                    if r and not r[0].lstrip().startswith("#")]
        if not rows or rows[0][1][0].strip() != "x_mm" or len(rows[0][1]) < 2:
            raise ModesError(f"{path}: line {rows[0][0] if rows else 1}: header must be "
                             f"'x_mm,<mode>[,<mode>...]'")
        names = tuple(c.strip() for c in rows[0][1][1:])
        values = []
        for line, row in rows[1:]:
            if len(row) != len(names) + 1:
                raise ModesError(f"{path}: line {line}: expected {len(names) + 1} values, got {len(row)}")
            try:
                nums = [float(v) for v in row]
            except ValueError:
                raise ModesError(f"{path}: line {line}: {row!r} has a value that is not a number") from None
            if not all(math.isfinite(v) for v in nums):
                raise ModesError(f"{path}: line {line}: values must be finite, got {row!r}")
            values.append(nums)
        table = np.array(values).reshape(-1, len(names) + 1)
        return cls(table[:, 0], table[:, 1:], names, source=str(path))

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

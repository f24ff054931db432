"""Compare the CSV text of two traces as numbers, for golden files made by synthesis.

The synthesis is float64 arithmetic through numpy and scipy; another version of either,
or the same version on a processor with other vector instructions, may change the last
printed digit of a position (seen with numpy 2.4.6 on another machine, and for the
two-finger trace here). So comment lines, the header, finger ids and events must match
exactly, and the numbers to a relative 1e-12 (about 4 ulp at 17 significant digits; a
change in the synthesis itself moves them by far more).
"""

import csv
import math

RTOL = 1e-12


def _is_float(cell: str) -> bool:
    try:
        float(cell)
    except ValueError:
        return False
    return "." in cell or "e" in cell


def assert_same_trace_text(ours: str, theirs: str) -> None:
    """Raise AssertionError at the first line where two trace CSV texts differ beyond RTOL."""
    a, b = ours.splitlines(), theirs.splitlines()
    assert len(a) == len(b), f"{len(a)} lines against {len(b)}"
    for number, (row, want) in enumerate(zip(csv.reader(a), csv.reader(b)), 1):
        if not row or row[0].startswith("#") or not _is_float(want[0]):
            assert row == want, f"line {number}"
            continue
        assert len(row) == len(want), f"line {number}"
        for cell, expected in zip(row, want):
            if _is_float(expected):
                assert math.isclose(float(cell), float(expected), rel_tol=RTOL, abs_tol=RTOL), \
                    f"line {number}: {cell} against {expected}"
            else:
                assert cell == expected, f"line {number}"

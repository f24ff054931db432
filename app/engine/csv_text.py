"""CSV text of numeric columns, byte for byte what Python's ``"%.Nf" % value`` and
``"%d" % value`` give, at tens of millions of values per second.

Arrow's CSV writer prints floats as their shortest round-trip text (``0.6``), not with
the fixed decimals the replay's tables have always had (``0.600000``), so the digits are
written here by compiled kernels, in two passes over the values and no temporary array
of their size. The first (:func:`_scan`) decides each float's rounding exactly: a value
is scaled to integer units of 10**-N and rounded, unless its float64 product lies within
a few ulps of a half unit (where the product's own rounding could decide it), or beyond
2**53 units, or is not finite; such a value (rare: none in a typical table) is formatted
by Python and its text spliced in by the second pass (:func:`_write_rows`), which writes
every other value's digits.
"""

from __future__ import annotations

import numpy as np

from frictex.device.jit import njit

#: 2**53: above it a float64 no longer holds every whole number of units
_EXACT_UNITS = 2.0 ** 53
#: a product this close to a half unit, relative to its size, is undecided: 4 ulps
#: (an ulp of x >= 2**-1022 is at most x * 2**-52; below that no product is near a half)
_NEAR_HALF = 2.0 ** -50


def rows_text(columns: list[np.ndarray], formats: list[str]) -> memoryview:
    """The CSV lines (``\\n``-terminated, no header) of equal-length columns, as a view of
    the buffer the kernel wrote them into (a copy into ``bytes`` took a fifth of the time).

    ``formats[j]`` is ``"%d"`` (int64 column) or ``"%.Nf"`` (float64 column, 0 <= N <= 15).
    """
    n = len(columns[0])
    is_int = np.array([fmt == "%d" for fmt in formats], dtype=np.bool_)
    decimals = np.array([-1 if fmt == "%d" else int(fmt[2:-1]) for fmt in formats],
                        dtype=np.int64)
    floats = _stacked([c for c, i in zip(columns, is_int) if not i], np.float64, n)
    ints = _stacked([c for c, i in zip(columns, is_int) if i], np.int64, n)
    source = np.zeros(len(formats), dtype=np.int64)  # each column's row in floats or ints
    source[is_int] = np.arange(len(ints))
    source[~is_int] = np.arange(len(floats))
    float_decimals = decimals[~is_int]
    largest, undecided = _scan(floats, float_decimals)
    width = 1  # bytes a row may take: the newline, then per column the widest value
    for k, digits in enumerate(float_decimals.tolist()):
        width += 3 + digits + _digits(int(largest[k]) // 10 ** digits)  # comma, sign, point
    for row in ints:
        width += 2 + _digits(np.abs(row).max(initial=0))  # comma, sign
    float_column = np.flatnonzero(~is_int)
    special_at, special_text = [], []
    for k, i in undecided.tolist():
        j = int(float_column[k])
        special_at.append(i * len(formats) + j)
        special_text.append((formats[j] % floats[k, i]).encode("ascii"))
    order = np.argsort(np.array(special_at, dtype=np.int64), kind="stable")
    at = np.array(special_at, dtype=np.int64)[order]
    texts = [special_text[k] for k in order.tolist()]
    offsets = np.zeros(len(texts) + 1, dtype=np.int64)
    offsets[1:] = np.cumsum([len(t) for t in texts])
    blob = np.frombuffer(b"".join(texts), dtype=np.uint8) if texts else np.zeros(0, np.uint8)
    out = np.empty(n * width + int(offsets[-1]), dtype=np.uint8)
    used = _write_rows(floats, ints, is_int, source, decimals, at, offsets, blob, out)
    return memoryview(out[:used])


def _stacked(columns: list[np.ndarray], dtype, n: int) -> np.ndarray:
    """The columns as the rows of one C-contiguous array (0 rows if none)."""
    if not columns:
        return np.zeros((0, n), dtype=dtype)
    return np.ascontiguousarray(np.stack(columns), dtype=dtype)


def _digits(value) -> int:
    """Decimal digits of a whole number >= 0."""
    return len(str(int(value)))


#: "00" to "99" as ASCII bytes: two digits per division when writing a number
_PAIRS = np.frombuffer("".join(f"{k:02d}" for k in range(100)).encode("ascii"), dtype=np.uint8)
#: 10**k for k = 0 .. 18 (int64)
_POWERS = np.array([10 ** k for k in range(19)], dtype=np.int64)


@njit(cache=True, nogil=True)
def _scan(floats, decimals):
    """Per float column (row ``k`` of ``floats``, ``decimals[k]`` decimals): the largest
    whole number of units among the values decided here, and the (column, row) pairs of
    the undecided values, which Python formats (see the module)."""
    nf, n = floats.shape
    largest = np.zeros(nf, dtype=np.int64)
    undecided = []
    for k in range(nf):
        scale = float(_POWERS[decimals[k]])
        top = 0.0
        for i in range(n):
            scaled = np.abs(floats[k, i]) * scale
            if not (scaled < _EXACT_UNITS) or (
                    np.abs(scaled - np.floor(scaled) - 0.5) <= scaled * _NEAR_HALF):
                undecided.append((k, i))
            elif scaled > top:
                top = scaled
        largest[k] = np.int64(np.rint(top))
    found = np.empty((len(undecided), 2), dtype=np.int64)
    for s in range(len(undecided)):
        found[s, 0] = undecided[s][0]
        found[s, 1] = undecided[s][1]
    return largest, found


@njit(cache=True, nogil=True)
def _write_uint(out, pos, value, min_digits):
    """Decimal digits of ``value`` >= 0, left-padded with zeros to ``min_digits``."""
    digits = 1
    while digits < 19 and value >= _POWERS[digits]:
        digits += 1
    if digits < min_digits:
        digits = min_digits
    end = pos + digits
    k = end
    while value >= 100:
        pair = value % 100
        value //= 100
        out[k - 1] = _PAIRS[2 * pair + 1]
        out[k - 2] = _PAIRS[2 * pair]
        k -= 2
    if value >= 10:
        out[k - 1] = _PAIRS[2 * value + 1]
        out[k - 2] = _PAIRS[2 * value]
        k -= 2
    else:
        out[k - 1] = 48 + value
        k -= 1
    while k > pos:  # zero padding
        out[k - 1] = 48
        k -= 1
    return end


@njit(cache=True, nogil=True)
def _write_rows(floats, ints, is_int, source, decimals, special_at, offsets, blob, out):
    ncol = is_int.size
    n = floats.shape[1] if floats.shape[0] else ints.shape[1]
    pos = 0
    s = 0
    for i in range(n):
        for j in range(ncol):
            if j:
                out[pos] = 44  # ,
                pos += 1
            if s < special_at.size and special_at[s] == i * ncol + j:
                for b in range(offsets[s], offsets[s + 1]):
                    out[pos] = blob[b]
                    pos += 1
                s += 1
                continue
            if is_int[j]:
                value = ints[source[j], i]
                if value < 0:
                    out[pos] = 45  # -
                    pos += 1
                    value = -value  # int64 ids are >= 0 in practice; -2**63 is refused upstream
                pos = _write_uint(out, pos, value, 1)
                continue
            d = decimals[j]
            x = floats[source[j], i]
            if np.signbit(x):
                out[pos] = 45
                pos += 1
            units = np.int64(np.rint(np.abs(x) * float(_POWERS[d])))
            whole = units // _POWERS[d]
            pos = _write_uint(out, pos, whole, 1)
            if d:
                out[pos] = 46  # .
                pos += 1
                pos = _write_uint(out, pos, units - whole * _POWERS[d], d)
        out[pos] = 10
        pos += 1
    return pos

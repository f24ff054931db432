"""The overlay's decimation against dense evaluation: scope traces reduced to pixel columns,
trails thinned to a vertex per pixel of path."""

import numpy as np
import pytest
from numpy.testing import assert_allclose

from frictex.rendering.visual.overlay import column_quads, column_spans, thin_polyline


def dense_spans(x, y, x0, columns):
    """Per column, min and max of the polyline evaluated at 400 points across the column
    (edges included) and at its own samples there, within the polyline's x range."""
    lo, hi, left = [], [], []
    for c in range(columns):
        a, b = x0 + c, x0 + c + 1
        grid = np.linspace(max(a, x[0]), min(b, x[-1]), 400)
        inside = (x >= a) & (x < b) if c < columns - 1 else (x >= a)
        if grid[0] > grid[-1] and not inside.any():
            continue
        values = np.concatenate((np.interp(grid, x, y) if grid[0] <= grid[-1] else [], y[inside]))
        if values.size:
            left.append(a)
            lo.append(values.min())
            hi.append(values.max())
    return np.array(left), np.array(lo), np.array(hi)


@pytest.mark.parametrize("seed, samples, width", [(1, 6000, 800.0), (2, 50, 300.0),
                                                   (3, 3000, 123.5), (4, 2, 40.0)])
def test_column_spans_equal_the_polyline_sampled_densely(seed, samples, width):
    """Many samples per column (a 3 s scope at 2 kHz) and fewer than one (a sparse trace):
    each column spans exactly what the polyline reaches in it."""
    rng = np.random.default_rng(seed)
    x0 = 17.25
    x = np.sort(rng.uniform(x0, x0 + width, samples))
    y = np.cumsum(rng.normal(0.0, 3.0, samples)) + 100.0
    left, lo, hi = column_spans(x, y, x0, width)
    ref_left, ref_lo, ref_hi = dense_spans(x, y, x0, int(np.ceil(width)))
    assert_allclose(left, ref_left)
    # the dense grid finds an extreme at a column's edge to 1/400 of a column's change
    assert_allclose(lo, ref_lo, atol=0.05 * np.abs(np.diff(y)).max())
    assert_allclose(hi, ref_hi, atol=0.05 * np.abs(np.diff(y)).max())
    assert (lo <= hi).all() and len(left) <= np.ceil(width)


def test_thinned_polyline_keeps_its_breaks_and_a_vertex_per_pixel():
    """2,000 samples 0.1 px apart with two breaks: the kept vertices are about 1 px apart
    along the path, both ends of each break are kept, and no kept segment crosses one."""
    t = np.arange(2000)
    points = np.column_stack((0.1 * t, 50.0 + 10.0 * np.sin(t / 300.0)))
    joined = np.ones(1999, dtype=bool)
    joined[[500, 1200]] = False
    kept, kept_joined = thin_polyline(points, joined, 1.0)
    assert kept[0] == 0 and kept[-1] == 1999
    assert {500, 501, 1200, 1201} <= set(kept.tolist())
    assert 150 < kept.size < 260  # about 210 px of path
    gaps = np.flatnonzero(~kept_joined)
    assert [(kept[k], kept[k + 1]) for k in gaps] == [(500, 501), (1200, 1201)]
    step = np.hypot(*np.diff(points[kept], axis=0).T)[kept_joined]
    assert step.max() < 1.5


def test_column_quads_join_flat_runs_and_cover_each_column_span():
    left = 10.0 + np.arange(7)
    top = np.array([5.0, 5.0, 5.0, 3.0, 3.0, 7.0, 5.0])
    bottom = np.array([6.0, 6.0, 6.0, 9.0, 9.0, 8.0, 6.0])
    quads = column_quads(left, top, bottom, (1.0, 0.0, 0.0, 1.0)).reshape(-1, 6, 6)
    assert len(quads) == 4  # columns 0-2, 3-4, 5 and 6
    boxes = [(q[:, 0].min(), q[:, 0].max(), q[:, 1].min(), q[:, 1].max()) for q in quads]
    for c in range(7):
        centre = left[c] + 0.5
        (box,) = [b for b in boxes if b[0] < centre < b[1]]
        assert box[2:] == (top[c], bottom[c])
    assert boxes[0][:2] == (10.0, 13.0) and boxes[-1][:2] == (16.0, 17.0)
    assert (quads[:, :, 2:] == (1.0, 0.0, 0.0, 1.0)).all()

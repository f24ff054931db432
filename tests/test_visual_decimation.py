"""The overlay's decimation against dense evaluation: scope traces reduced to time bins (a
pixel column each), trails thinned to a vertex per pixel of path."""

import numpy as np
import pytest
from numpy.testing import assert_allclose

from frictex.rendering.visual.overlay import thin_polyline
from frictex.rendering.visual.scope_ring import bin_spans


def dense_spans(t, v, bin_s, first, count):
    """Per time bin, min and max of the polyline evaluated at 400 points across the bin
    (edges included) and at its own samples there, within the polyline's time range;
    NaN where it does not reach."""
    lo, hi = np.full(count, np.nan), np.full(count, np.nan)
    for k in range(count):
        a, b = (first + k) * bin_s, (first + k + 1) * bin_s
        grid = np.linspace(max(a, t[0]), min(b, t[-1]), 400)
        inside = (t >= a) & (t < b)
        values = np.concatenate((np.interp(grid, t, v) if grid[0] <= grid[-1] else [], v[inside]))
        if values.size:
            lo[k], hi[k] = values.min(), values.max()
    return lo, hi


@pytest.mark.parametrize("seed, samples, bins", [(1, 6000, 800), (2, 50, 300), (3, 3000, 123),
                                                 (4, 2, 40)])
def test_bin_spans_equal_the_polyline_sampled_densely(seed, samples, bins):
    """Many samples per bin (a 3 s scope at 2 kHz on 800 columns) and fewer than one (a
    sparse trace), bins before and after the trace included: each bin spans exactly what
    the polyline reaches in it."""
    rng = np.random.default_rng(seed)
    t = np.sort(rng.uniform(1.0, 4.0, samples))
    v = np.cumsum(rng.normal(0.0, 3.0, samples)) + 100.0
    bin_s = 3.5 / bins
    first = int(0.8 / bin_s)
    lo, hi = bin_spans(t, v, bin_s, first, bins)
    ref_lo, ref_hi = dense_spans(t, v, bin_s, first, bins)
    assert (np.isnan(lo) == np.isnan(ref_lo)).all() and np.isnan(lo).any()
    step = 0.05 * np.abs(np.diff(v)).max()  # the grid finds an edge's value to 1/400 of a bin
    assert_allclose(lo, ref_lo, atol=step)
    assert_allclose(hi, ref_hi, atol=step)


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

"""The overlay's decimation against dense evaluation: scope traces reduced to time bins (a
pixel column each), trails thinned to a vertex per pixel of path."""

import numpy as np
import pytest
from hypothesis import given, strategies as st
from numpy.testing import assert_allclose

from frictex.rendering.visual.overlay import BlockRecord, OverlayState, segment_triangles
from frictex.rendering.visual.scope_ring import bin_spans
from frictex.rendering.visual.trail import (TRAIL_BREAK_MM, TRAIL_BREAK_MM_S, TrailPath,
                                            thin_polyline)
from frictex.rendering.visual.viewport import fit_viewport
from frictex.textures.model import Display

DISPLAY = Display(108.0, 64.8, 800, 480)


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


polylines = st.integers(1, 60).flatmap(lambda n: st.tuples(
    st.lists(st.tuples(st.sampled_from([0.0, 0.3, 1.0, 2.5, np.nan]), st.sampled_from([0.0, -0.7, 1.0])),
             min_size=n, max_size=n),
    st.lists(st.booleans(), min_size=n - 1, max_size=n - 1)))


@given(polylines)
def test_thinning_equals_its_definition_written_with_arrays(polyline):
    """Steps of 0 to 2.7 px (repeated points included, and NaN: every vertex after it
    kept) with random breaks: the kept vertices and the joins between them are what the
    definition gives computed over whole arrays (path length marks, both ends of each
    break, the break count)."""
    steps, joined = polyline
    points = np.cumsum(np.array(steps, dtype=np.float64), axis=0)
    joined = np.array(joined, dtype=bool)
    length = np.concatenate(([0.0], np.cumsum(np.hypot(*np.diff(points, axis=0).T))))
    keep = np.zeros(len(points), dtype=bool)
    keep[[0, -1]] = True
    keep[1:] |= np.diff(np.floor(length / 1.0)) != 0
    keep[:-1] |= ~joined
    keep[1:] |= ~joined
    breaks = np.concatenate(([0], np.cumsum(~joined)))
    kept, kept_joined = thin_polyline(points, joined, 1.0)
    assert kept.tolist() == np.flatnonzero(keep).tolist()
    assert kept_joined.tolist() == (breaks[kept[1:]] == breaks[kept[:-1]]).tolist()


@given(polylines, st.sampled_from([1.0, 3.0, 5.5]))
def test_segment_quads_are_each_drawn_segments_width_around_it(polyline, width):
    """Each kept segment longer than zero (not NaN) becomes two triangles whose corners
    lie width/2 either side of its ends, perpendicular to it, in its ends' colours."""
    steps, keep = polyline
    points = np.cumsum(np.array(steps, dtype=np.float64), axis=0)
    keep = np.array(keep, dtype=bool)
    rgba = np.random.default_rng(len(points)).uniform(size=(len(points), 4))
    tris = segment_triangles(points, rgba, width, keep).reshape(-1, 6, 6)
    drawn = np.flatnonzero(keep & (np.hypot(*np.diff(points, axis=0).T) > 1e-9))
    assert len(tris) == drawn.size
    for quad, i in zip(tris, drawn):
        d = points[i + 1] - points[i]
        normal = np.array([-d[1], d[0]]) / np.hypot(*d) * width / 2
        ends = points[[i, i, i + 1, i + 1, i, i + 1]]
        sides = np.array([1, -1, 1, 1, -1, -1])[:, None]
        assert_allclose(quad[:, :2], ends + sides * normal, rtol=0, atol=1e-12)
        assert_allclose(quad[:, 2:], rgba[[i, i, i + 1, i + 1, i, i + 1]], rtol=0, atol=0)


def wandering_stroke(seed, n=8000):
    """A 2 kHz stroke (t s, contact, x and y mm): a random walk of ~0.03 mm steps, lifted
    for 0.15 s and jumping 40 mm while touching."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) / 2000.0
    x = 50.0 + np.cumsum(rng.normal(0.0, 0.02, n))
    y = 30.0 + np.cumsum(rng.normal(0.0, 0.02, n))
    contact = np.ones(n)
    contact[1000:1300] = 0.0
    x[5000:] += 40.0
    return t, contact, x, y


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_trail_taken_in_stretches_draws_each_joined_step_once_within_a_pixel(seed):
    """The stroke taken in 150 stretches of random length, each from a history of the
    last 3 s (as frames see it): the drawn segments cover every joined step of the
    samples exactly once and no other, each within 1 px of the samples it stands for,
    with about as few vertices as thinning the whole stroke at once."""
    t, contact, x, y = wandering_stroke(seed)
    vp = fit_viewport(DISPLAY, 800, 480)
    path = TrailPath(vp)
    ends = np.sort(np.random.default_rng(seed).choice(np.arange(1, t.size), 150, replace=False))
    for end in [*ends.tolist(), t.size]:
        kept = slice(max(0, end - 6000), end)
        path.take(t[kept], contact[kept], x[kept], y[kept])
    points, times, joined = path.since(-np.inf)
    at = np.searchsorted(t, times)
    assert_allclose(times, t[at], rtol=0, atol=0)
    assert_allclose(points, np.column_stack(vp.to_px(x[at], y[at])), rtol=0, atol=1e-9)
    drawn = np.zeros(t.size - 1, dtype=int)
    sample_px = np.column_stack(vp.to_px(x, y))
    for a, b in zip(at[:-1][joined], at[1:][joined]):
        drawn[a:b] += 1
        chord = sample_px[b] - sample_px[a]
        offset = sample_px[a:b + 1] - sample_px[a]
        distance = np.abs(chord[0] * offset[:, 1] - chord[1] * offset[:, 0]) / max(
            np.hypot(*chord), 1e-12)
        assert distance.max() < 1.0
    step_mm = np.hypot(np.diff(x), np.diff(y))  # a step is drawn touching at both ends, not a jump
    expected = ((contact[:-1] > 0) & (contact[1:] > 0)
                & ((step_mm <= TRAIL_BREAK_MM) | (step_mm <= TRAIL_BREAK_MM_S * np.diff(t))))
    assert expected.sum() < t.size - 300 and (drawn == expected).all()
    whole = thin_polyline(sample_px, expected, 1.0)[0]
    assert times.size <= whole.size + ends.size + 1


def test_a_trail_forgets_vertices_before_the_one_that_starts_its_window():
    t, contact, x, y = wandering_stroke(4)
    path = TrailPath(fit_viewport(DISPLAY, 800, 480))
    path.take(t, contact, x, y)
    all_times = path.since(-np.inf)[1].copy()
    points, times, joined = path.since(2.0)
    first = np.searchsorted(all_times, 2.0) - 1
    assert times[0] == all_times[first] < 2.0 <= times[1]
    assert_allclose(times, all_times[first:], rtol=0, atol=0)
    assert len(points) == len(times) == len(joined) + 1
    assert path.since(-np.inf)[1][0] == times[0]


def test_trails_drawn_in_a_new_viewport_equal_those_drawn_there_from_the_start():
    """A window resized 2 s before a stroke ends: its last second of trail is drawn in
    the new viewport's pixels, as by an overlay that drew each frame there."""
    t, contact, x, y = wandering_stroke(5, n=6000)
    small, large = fit_viewport(DISPLAY, 800, 480), fit_viewport(DISPLAY, 1920, 1080)
    resized, fresh = OverlayState(), OverlayState()
    one = lambda a: a[None, :]
    for lo in range(0, t.size, 33):
        part = slice(lo, lo + 33)
        record = BlockRecord(t[part], (0,), one(contact[part] > 0), one(x[part]), one(y[part]),
                             one(np.ones(t[part].size)), one(np.zeros(t[part].size)))
        resized.add(record)
        fresh.add(record)
        resized.trail_triangles(small if lo < 2000 else large)
        expected = fresh.trail_triangles(large)
    tris = resized.trail_triangles(large)
    assert len(tris) > 100
    assert_allclose(tris, expected, rtol=0, atol=1e-9)

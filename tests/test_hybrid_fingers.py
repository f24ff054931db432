"""The hybrid renderer's state follows the fingers touching, not every id ever used.

A touch screen that numbers its touches (TUIO session ids, evdev tracking ids) gives
each touch a new finger id; a long demo sees thousands. The tracker forgets a finger
once its lift is out; the hybrid renderer must too, and forgetting must change nothing
(an id that comes back is a new touch, which restarts the finger anyway)."""

import numpy as np
from hypothesis import given, settings, strategies as st
from numpy.testing import assert_allclose, assert_array_equal

from frictex.rendering.input.trace_file import DOWN, MOVE, UP, make_trace
from frictex.rendering.layers.hybrid import HybridRenderer, HybridState
from frictex.rendering.pipeline import build_pipeline
from frictex.rendering.tracking.tracks import apply_index, track
from scenes import grating_scene

RATE = 10_000.0
TOUCHES = 1_000


def one_touch_ids(touches: int, overlap: bool = True):
    """``touches`` strokes of 6 samples at 100 Hz along x, each with its own finger id
    (0, 1, 2, ...); with ``overlap`` each starts halfway through the one before, so two
    fingers touch at once part of the time."""
    rows = []
    step = 0.03 if overlap else 0.07
    rng = np.random.default_rng(27)  # positions off the grating's edges (see the split test)
    for fid in range(touches):
        t0 = fid * step
        x0 = rng.uniform(5.0, 60.0)
        for j in range(6):
            event = DOWN if j == 0 else UP if j == 5 else MOVE
            rows.append((t0 + 0.01 * j, fid, x0 + 2.0 * j + rng.normal(0.0, 0.05), 30.0, event))
    rows.sort(key=lambda r: r[0])
    t, finger, x, y, event = (np.array(c) for c in zip(*rows))
    return make_trace(t, finger, x, y, None, np.asarray(event, dtype=np.int8))


def blocks_of(trace, config, block_size):
    """(index0, samples or None) of every block from the first sample to the last."""
    applied = apply_index(trace.t_s, config)
    total = int(applied[-1] // block_size) + 2  # and one block after the last lift
    for k in range(total):
        lo, hi = np.searchsorted(applied, [k * block_size, (k + 1) * block_size])
        yield k * block_size, trace.slice(lo, hi) if hi > lo else None


def test_state_holds_only_the_fingers_of_the_block_after_1000_one_touch_ids():
    scene = grating_scene(5.0, render="hybrid")
    trace = one_touch_ids(TOUCHES)
    p = build_pipeline(scene, rate_hz=RATE, t0_s=float(trace.t_s[0]))
    renderer = HybridRenderer(scene.layers[0], RATE)
    tracker, state = p.initial_state().tracker, renderer.initial_state()
    largest = 0
    for index0, samples in blocks_of(trace, p.tracker_config, p.block_size):
        block, tracker = track(index0, p.block_size, samples, tracker, p.tracker_config)
        _, _, state = renderer.render(block, state)
        assert set(state.fingers) == set(block.ids)
        assert len(state.fingers) <= len(tracker.fingers) + (0 if samples is None
                                                             else len(set(samples.finger)))
        largest = max(largest, len(state.fingers))
    assert tracker.fingers == {} and state.fingers == {}
    assert largest <= 3  # two touching at once, and one that lifted in the block


def test_forgetting_lifted_fingers_changes_no_output():
    """The same blocks rendered with every finger ever seen carried along (as before
    the state was bounded) give the same mu' bit for bit."""
    scene = grating_scene(5.0, render="hybrid")
    trace = one_touch_ids(200)
    p = build_pipeline(scene, rate_hz=RATE, t0_s=float(trace.t_s[0]))
    renderer = HybridRenderer(scene.layers[0], RATE)
    tracker = p.initial_state().tracker
    bounded, everything = renderer.initial_state(), renderer.initial_state()
    seen = 0
    for index0, samples in blocks_of(trace, p.tracker_config, p.block_size):
        block, tracker = track(index0, p.block_size, samples, tracker, p.tracker_config)
        mu_a, covers_a, bounded = renderer.render(block, bounded)
        mu_b, covers_b, new = renderer.render(block, everything)
        everything = HybridState(fingers={**everything.fingers, **new.fingers})
        assert_array_equal(mu_a, mu_b)
        assert_array_equal(covers_a, covers_b)
        seen = max(seen, len(everything.fingers))
    assert seen == 200 and bounded.fingers == {}


def _pipeline_run(scene, trace, splits):
    """mu' of every finger id (rows) at every output sample, -1 where it does not touch,
    of the pipeline run in calls split at the blocks ``splits``."""
    p = build_pipeline(scene, rate_hz=RATE, t0_s=float(trace.t_s[0]))
    applied = apply_index(trace.t_s, p.tracker_config)
    total = int(applied[-1] // p.block_size) + 1
    bounds = [0, *(s for s in splits if s < total), total]
    state = p.initial_state()
    mu = np.full((int(trace.finger.max()) + 1, total * p.block_size), -1.0)
    for lo, hi in zip(bounds[:-1], bounds[1:]):
        a, b = np.searchsorted(applied, [lo * p.block_size, hi * p.block_size])
        out, state = p.process(lo, trace.slice(a, b) if b > a else None, state, n_blocks=hi - lo)
        cols = slice(out.index0, out.index0 + out.t_s.size)
        for row, fid in enumerate(out.finger_ids):
            mu[fid, cols] = np.where(out.contact[row], out.mu_target[row], -1.0)
    return mu


@settings(max_examples=8, derandomize=True, deadline=None)
@given(splits=st.lists(st.integers(1, 250), max_size=8, unique=True).map(sorted))
def test_any_split_of_many_one_touch_ids_equals_one_call(splits):
    """Bit for bit on every sample that plays a level; the touches' positions are drawn,
    not round numbers: a phase landing exactly on a square grating's edge may round to
    either side depending on where a call starts its sums (it did, one sample, on x =
    10.2 mm at 200 mm/s). A sample straddling an edge plays its sides in proportion
    (``rendering.layers.band_limit``), so the phase's own rounding (1e-16 cycle, split
    or not) shows there: within 1e-16 x 0.4 / (1 / 65536, the shortest interval that is
    not played as a point) = 3e-12; 1e-11."""
    scene = grating_scene(5.0, render="hybrid")
    trace = one_touch_ids(40)
    whole = _pipeline_run(scene, trace, ())
    assert (whole > 0).any(axis=1).all()  # every touch was rendered
    split = _pipeline_run(scene, trace, splits)
    level = np.isin(whole, (-1.0, 0.6, 1.0))
    assert_array_equal(split[level], whole[level])
    assert_allclose(split, whole, rtol=0, atol=1e-11)

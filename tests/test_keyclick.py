"""Key-click state machine (seed 004, Fig. 5): one phase flip per press, at the right force,
no flicker from force noise; any split into blocks gives the same states."""

import numpy as np
from hypothesis import given, settings, strategies as st
from numpy.testing import assert_array_equal

from frictex.rendering.input.press_synth import press_trace
from frictex.rendering.layers.keyclick import CLICKED, IDLE, ON, button_states

PRESS, CLICK, RELEASE = 0.5, 0.8, 0.4


def reference(force, inside, dwell):
    """Per-sample loop written from the state diagram, independent of the vectorised code."""
    runs = [0, 0, 0]
    pressed = clicked = False
    out = []
    for f, ins in zip(force, inside):
        conds = (ins and f >= PRESS, ins and f >= CLICK, (not ins) or not f >= RELEASE)
        runs = [r + 1 if c else 0 for r, c in zip(runs, conds)]
        if runs[2] >= dwell:
            pressed = clicked = False
        else:
            pressed |= runs[0] >= dwell
            clicked |= runs[1] >= dwell
        out.append(CLICKED if clicked else ON if pressed else IDLE)
    return np.array(out)


def noisy_presses(seed=3, noise_n=0.03, rate=10_000.0):
    """The bundled press shape at touch rate, held to the output rate (as the tracker does)."""
    trace = press_trace(seed=seed, noise_n=noise_n)
    t = np.arange(0.0, trace.t_s[-1] + 0.05, 1 / rate)
    idx = np.clip(np.searchsorted(trace.t_s, t, side="right") - 1, 0, len(trace) - 1)
    return t, trace.force_n[idx], trace


def test_one_flip_per_press_matching_the_reference_machine():
    t, force, trace = noisy_presses()
    inside = np.ones(t.size, bool)
    dwell = 100  # 10 ms at 10 kHz: one touch sample must confirm
    states, clicks, _ = button_states(force, inside, PRESS, CLICK, RELEASE, dwell)
    assert_array_equal(states, reference(force, inside, dwell))
    assert clicks.sum() == 3                                   # three presses in the trace
    flips = np.flatnonzero(np.diff(states.astype(int)) > 0)
    changes = np.flatnonzero(np.diff(states.astype(int)))
    # each press: idle -> on -> clicked -> idle, nothing else (no flicker)
    assert_array_equal(np.diff(states.astype(int))[changes], [1, 1, -2] * 3)
    for i in flips[1::2] + 1:                           # the click samples
        assert np.all(force[i - dwell + 1:i + 1] >= CLICK) and force[i - dwell] < CLICK
    # the noise does cross the press threshold back and forth: without the hysteresis band
    # and the dwell the same machine flickers
    assert np.count_nonzero(np.diff((trace.force_n >= PRESS).astype(int))) > 6
    bare, bare_clicks, _ = button_states(force, inside, PRESS, CLICK, PRESS, 1)
    assert np.count_nonzero(np.diff(bare.astype(int))) > 9


def test_a_single_noisy_sample_does_not_click_or_release():
    force = np.full(3000, 0.6)
    force[1000:1050] = 0.9    # a 5 ms spike past the click threshold
    force[2000:2050] = 0.3    # a 5 ms dip below release
    states, clicks, _ = button_states(force, np.ones(3000, bool), PRESS, CLICK, RELEASE, 100)
    assert clicks.sum() == 0 and np.all(states[100:] == ON)


def test_fast_press_clicks_once_and_leaving_the_button_releases():
    force = np.concatenate([np.zeros(200), np.full(800, 1.0), np.full(400, 1.0)])
    inside = np.concatenate([np.ones(1000, bool), np.zeros(400, bool)])
    states, clicks, _ = button_states(force, inside, PRESS, CLICK, RELEASE, 50)
    assert clicks.sum() == 1
    assert states[249] == CLICKED and states[248] == IDLE  # both thresholds confirmed together
    assert states[1049] == IDLE and states[1048] == CLICKED


def test_nan_force_counts_as_no_press():
    force = np.full(500, np.nan)
    states, clicks, _ = button_states(force, np.ones(500, bool), PRESS, CLICK, RELEASE, 1)
    assert clicks.sum() == 0 and np.all(states == IDLE)


@settings(derandomize=True, max_examples=25, deadline=None)
@given(st.lists(st.integers(0, 27_000), min_size=1, max_size=6))
def test_any_split_gives_the_same_states(cuts):
    t, force, _ = noisy_presses(seed=5)
    inside = np.ones(t.size, bool)
    whole, clicks, _ = button_states(force, inside, PRESS, CLICK, RELEASE, 100)
    edges = [0, *sorted(c for c in cuts if c < t.size), t.size]
    state, parts, flips = None, [], []
    for a, b in zip(edges, edges[1:]):
        s, c, state = button_states(force[a:b], inside[a:b], PRESS, CLICK, RELEASE, 100, state)
        parts.append(s)
        flips.append(c)
    assert_array_equal(np.concatenate(parts), whole)
    assert_array_equal(np.concatenate(flips), clicks)


def _press_clicks(over: int) -> int:
    """Clicks of a 100 Hz press on the bundled ring's button (0.6 N) with ``over`` touch
    samples at 0.85 N, past its 0.8 N click, in the middle."""
    import frictex
    force = np.array([0.1] * 5 + [0.6] * 20 + [0.85] * over + [0.6] * (20 - over + 1)
                     + [0.1] * 5)
    n = force.size
    event = np.full(n, frictex.MOVE)
    event[0], event[-1] = frictex.DOWN, frictex.UP
    trace = frictex.make_trace(np.arange(n) / 100.0, np.zeros(n, int), np.full(n, 70.0),
                               np.full(n, 15.0), force, event)
    return frictex.replay("keyclick-ring", trace).summary.forces["0"]["clicks"]


def test_one_noisy_touch_sample_does_not_click_the_bundled_button():
    """A touch sample's force holds until the next (10 ms at 100 Hz), which met the
    bundled scenes' dwell of 10 ms: one 0.85 N sample clicked (the push reversed) with the
    press going on at 0.6 N. Their dwell is now 15 ms: a second sample confirms."""
    assert _press_clicks(1) == 0
    assert _press_clicks(2) == 1

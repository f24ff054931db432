"""Per-finger layer selection: touch order, positional selectors, and composition with masks."""

import argparse
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from hypothesis.extra.numpy import arrays
from numpy.testing import assert_array_equal

from frictex.rendering.compose import compose
from frictex.device.actuation.base import touch_rank
from frictex.rendering.input.trace_file import read_trace
from frictex.rendering.input.trace_import import add_import_arguments, run_import
from frictex.rendering.tracking.finger_select import (HYSTERESIS_MM, SelectionState, finger_masks,
                                              select_fingers)
from frictex.rendering.tracking.tracks import TrackerConfig, TrackerState, track

INF = np.inf


def block(contact, start, x=None, y=None):
    contact = np.asarray(contact, dtype=bool)
    shape = contact.shape
    return SimpleNamespace(contact=contact, touch_start=np.asarray(start, dtype=np.float64) * np.ones(shape),
                           x_pred=np.zeros(shape) if x is None else np.asarray(x, dtype=np.float64),
                           y_pred=np.zeros(shape) if y is None else np.asarray(y, dtype=np.float64))


def test_fingers_are_numbered_by_touch_down_and_renumbered_when_one_lifts():
    # rows: finger touching since 2 s, since 1 s, since 3 s; the 1 s finger lifts at sample 2
    contact = [[1, 1, 1], [1, 1, 0], [1, 1, 1]]
    start = [[2.0] * 3, [1.0] * 3, [3.0] * 3]
    assert_array_equal(touch_rank(np.asarray(contact, bool), np.asarray(start)),
                       [[1, 1, 0], [0, 0, -1], [2, 2, 1]])


def test_equal_touch_down_times_are_ordered_by_row():
    rank = touch_rank(np.ones((3, 1), bool), np.array([[5.0], [5.0], [4.0]]))
    assert_array_equal(rank[:, 0], [1, 2, 0])


def test_number_selectors_pick_one_finger_or_none():
    b = block([[1, 1, 0], [1, 0, 0]], [[0.0], [0.5]])
    one, two, three, any_ = finger_masks(["1", "2", "3", "any"], b)
    assert_array_equal(one, [[1, 1, 0], [0, 0, 0]])
    assert_array_equal(two, [[0, 0, 0], [1, 0, 0]])
    assert not three.any()
    assert any_ is None


def test_all_any_builds_no_mask():
    assert finger_masks(["any", "any"], block([[1]], [[0.0]])) == [None, None]


def test_left_and_right_most_swap_as_fingers_cross():
    x = np.array([np.linspace(10, 50, 5), np.linspace(50, 10, 5)])  # cross at sample 2
    b = block(np.ones((2, 5)), [[0.0], [1.0]], x=x)
    left, right = finger_masks(["left-most", "right-most"], b)
    # at sample 2 they tie: each role stays with its holder until the other is
    # HYSTERESIS_MM beyond it (sample 3, 20 mm beyond)
    assert_array_equal(left, [[1, 1, 1, 0, 0], [0, 0, 0, 1, 1]])
    assert_array_equal(right, [[0, 0, 0, 1, 1], [1, 1, 1, 0, 0]])
    # with no holder the tie goes to finger 1 (first down)
    tie = block(np.ones((2, 1)), [[0.0], [1.0]], x=[[30.0], [30.0]])
    assert_array_equal(finger_masks(["right-most"], tie)[0], [[1], [0]])


def test_top_and_bottom_most_use_y_pointing_down():
    b = block(np.ones((2, 1)), [[0.0], [1.0]], y=[[10.0], [40.0]])
    top, bottom = finger_masks(["top-most", "bottom-most"], b)
    assert_array_equal(top[:, 0], [True, False])
    assert_array_equal(bottom[:, 0], [False, True])


def test_fingers_not_touching_are_never_selected():
    x = np.array([[5.0, 5.0], [50.0, 50.0]])
    b = block([[0, 1], [1, 1]], [[0.0], [1.0]], x=x)
    (left,) = finger_masks(["left-most"], b)
    assert_array_equal(left, [[0, 1], [1, 0]])  # sample 0: the only finger touching is the left-most


@settings(derandomize=True, max_examples=60, deadline=None)
@given(st.integers(1, 4).flatmap(lambda f: st.tuples(
    arrays(bool, (f, 6)), arrays(np.float64, (f, 1), elements=st.sampled_from([0.0, 0.5, 1.0])),
    arrays(np.float64, (f, 6), elements=st.floats(0, 100)))))
def test_selectors_agree_with_a_direct_count(case):
    contact, start, x = case
    b = block(contact, start, x=x)
    rank = touch_rank(b.contact, b.touch_start)
    masks = finger_masks(["1", "2", "left-most", "right-most"], b, hysteresis_mm=0.0)
    held = finger_masks(["left-most", "right-most"], b)  # default hysteresis
    for k in range(contact.shape[1]):
        rows = np.flatnonzero(contact[:, k])
        # numbers: a permutation of 0..m-1 in order of (start time, row)
        expected = sorted(rows, key=lambda r: (start[r, 0], r))
        assert_array_equal(rank[expected, k], np.arange(rows.size))
        assert (rank[~contact[:, k], k] == -1).all()
        for mask, nth in ((masks[0], 0), (masks[1], 1)):
            assert_array_equal(np.flatnonzero(mask[:, k]), expected[nth:nth + 1])
        for mask, pick in ((masks[2], np.min), (masks[3], np.max)):
            chosen = np.flatnonzero(mask[:, k])
            assert chosen.size == (1 if rows.size else 0)
            if rows.size:
                assert x[chosen[0], k] == pick(x[rows, k])
        # with hysteresis: one touching finger, within HYSTERESIS_MM of the extreme
        for mask, sign in ((held[0], 1.0), (held[1], -1.0)):
            chosen = np.flatnonzero(mask[:, k])
            assert chosen.size == (1 if rows.size else 0)
            if rows.size:
                assert contact[chosen[0], k]
                assert sign * x[chosen[0], k] <= (sign * x[rows, k]).min() + HYSTERESIS_MM


def test_compose_applies_a_layer_only_where_its_mask_selects():
    contact = np.ones((2, 3), bool)
    covers = np.ones((2, 3), bool)
    layers = [(np.full((2, 3), 0.8), covers), (np.full((2, 3), 0.5), covers)]
    masks = [np.array([[1, 1, 0], [0, 0, 1]], bool), None]
    mu = compose(layers, ["multiply", "multiply"], contact, masks)
    assert_array_equal(mu, [[0.4, 0.4, 0.5], [0.5, 0.5, 0.4]])


def _tracks(x, contact=None):
    """Two fingers' blocks with ids and touch ids (x (2, n) mm, y fixed)."""
    x = np.asarray(x, dtype=np.float64)
    contact = np.ones(x.shape, bool) if contact is None else np.asarray(contact, bool)
    return SimpleNamespace(ids=(0, 1), touch_id=np.ones(x.shape, np.int64), contact=contact,
                           touch_start=np.array([[0.0], [1.0]]) * np.ones(x.shape),
                           x_pred=x, y_pred=np.zeros(x.shape))


def test_a_crossing_hands_the_role_over_once_the_other_finger_is_hysteresis_beyond():
    """Finger 0 at 40 mm still, finger 1 from 46 mm towards -x at 20 mm/s (10 kHz): finger
    0 is left-most until finger 1 is HYSTERESIS_MM left of it, at t = (6 + 3) / 20 s."""
    t = np.arange(8000) / 1e4
    x = np.array([np.full(t.size, 40.0), 46.0 - 20.0 * t])
    left = select_fingers(["left-most"], _tracks(x))[0][0]
    switch = np.flatnonzero(left[1])[0]
    assert abs(t[switch] - (6.0 + HYSTERESIS_MM) / 20.0) <= 1e-4
    assert left[0, :switch].all() and left[1, switch:].all() and not left[0, switch:].any()


def test_roles_carried_between_blocks_equal_one_call():
    """Fingers wobbling within the hysteresis across each other: any split into blocks
    with the state carried gives the same masks as one call (and no swap at all)."""
    rng = np.random.default_rng(3)
    n = 600
    x = np.array([np.full(n, 40.0), 40.5 + rng.uniform(-2.0, 2.0, n)])
    whole, _ = select_fingers(["left-most", "right-most"], _tracks(x))
    state, parts = SelectionState(), []
    for lo, hi in ((0, 7), (7, 250), (250, 251), (251, n)):
        masks, state = select_fingers(["left-most", "right-most"], _tracks(x[:, lo:hi]), state)
        parts.append(masks)
    for i in range(2):
        assert_array_equal(np.concatenate([p[i] for p in parts], axis=1), whole[i])
    assert np.ptp(np.argmax(whole[0], axis=0)) == 0  # never swapped


REFDATA = Path(__file__).resolve().parents[2] / "shared" / "refdata" / "android-getevent"
TABLET = ["--x-range", "0", "1600", "--y-range", "0", "900", "--width-mm", "217", "--height-mm", "136"]


@pytest.mark.skipif(not REFDATA.is_dir(), reason=f"refdata Android getevent logs not found at {REFDATA}")
def test_two_fingers_side_by_side_on_the_tablet_keep_their_roles(tmp_path):
    """refdata Tablet/tablet-two-finger-drag.txt (one finger above the other, their x
    within 0-7 mm): plain left-most (no hysteresis) swaps the roles 9 times in 1.5 s;
    with the default hysteresis the role changes once, when the fingers part by 4 mm."""
    out = tmp_path / "drag.csv"
    parser = argparse.ArgumentParser()
    add_import_arguments(parser)
    assert run_import(parser.parse_args([str(REFDATA / "Tablet/tablet-two-finger-drag.txt"),
                                         "-o", str(out)] + TABLET),
                      lambda path, text: Path(path).write_text(text)) == 0
    trace = read_trace(out)
    cfg = TrackerConfig(t0_s=float(trace.t_s[0]))
    fingers, _ = track(0, int((trace.duration_s + 0.05) * cfg.rate_hz), trace, TrackerState(), cfg)
    both = fingers.contact.all(axis=0)
    assert both.sum() / cfg.rate_hz > 1.4

    def swaps(hysteresis_mm):
        left = select_fingers(["left-most"], fingers, SelectionState(), hysteresis_mm)[0][0]
        return int(np.count_nonzero(np.diff(np.argmax(left[:, both], axis=0))))

    # independently: where the plain rule (smaller x) changes its mind
    plain = np.count_nonzero(np.diff((fingers.x_pred[1] < fingers.x_pred[0])[both]))
    assert swaps(0.0) == plain == 9
    assert swaps(HYSTERESIS_MM) == 1

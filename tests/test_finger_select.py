"""Per-finger layer selection: touch order, positional selectors, and composition with masks."""

from types import SimpleNamespace

import numpy as np
from hypothesis import given, settings, strategies as st
from hypothesis.extra.numpy import arrays
from numpy.testing import assert_array_equal

from rendering.compose import compose
from device.actuation.base import touch_rank
from rendering.tracking.finger_select import finger_masks

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
    assert_array_equal(left, [[1, 1, 1, 0, 0], [0, 0, 0, 1, 1]])   # the tie goes to finger 1 (first down)
    assert_array_equal(right, [[0, 0, 1, 1, 1], [1, 1, 0, 0, 0]])


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
    masks = finger_masks(["1", "2", "left-most", "right-most"], b)
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


def test_compose_applies_a_layer_only_where_its_mask_selects():
    contact = np.ones((2, 3), bool)
    covers = np.ones((2, 3), bool)
    layers = [(np.full((2, 3), 0.8), covers), (np.full((2, 3), 0.5), covers)]
    masks = [np.array([[1, 1, 0], [0, 0, 1]], bool), None]
    mu = compose(layers, ["multiply", "multiply"], contact, masks)
    assert_array_equal(mu, [[0.4, 0.4, 0.5], [0.5, 0.5, 0.4]])

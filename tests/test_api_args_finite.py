"""An infinite argument without an upper bound is refused as not finite: "expected more
than 0" alone is what inf is."""

import math

import pytest

import frictex
from frictex._args import real


def test_replay_says_max_gap_must_be_finite():
    with pytest.raises(frictex.InputError,
                       match=r"^max_gap_s=inf: expected a finite number more than 0 \(s\)$"):
        frictex.replay("grating-5mm", "swipe-40mms-50hz", max_gap_s=math.inf)


@pytest.mark.parametrize("value, bounds, positive, expected", [
    (math.inf, None, True, "a finite number more than 0 (s)"),
    (math.inf, (1.0, math.inf), False, "a finite number at least 1 s"),
    (math.inf, None, False, "a finite number"),
    (math.nan, None, True, "more than 0 (s)"),
    (-math.inf, None, True, "more than 0 (s)"),
    (math.inf, (0.0, 5.0), False, "0 to 5 s"),
])
def test_the_message_says_finite_only_where_inf_is_within_the_words(value, bounds, positive,
                                                                     expected):
    with pytest.raises(frictex.InputError) as caught:
        real("t", value, "s", bounds, positive=positive)
    assert str(caught.value) == f"t={value!r}: expected {expected}"

"""Verdicts on speed targets from paired rounds (``app.measure.ratio_claim``), against a
t interval on the rounds' log ratios computed here from the t table."""

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from frictex.app.measure.ratio_claim import ratio_claim

#: Student's t, 97.5 % quantile, for 3 and 7 degrees of freedom (printed tables)
T_975 = {3: 3.182446, 7: 2.364624}


def _interval(ratios):
    logs = np.log(ratios)
    half = T_975[len(ratios) - 1] * logs.std(ddof=1) / math.sqrt(len(ratios))
    return math.exp(logs.mean()), math.exp(logs.mean() - half), math.exp(logs.mean() + half)


def test_the_geometric_mean_and_its_interval_match_the_t_table():
    ratios = [0.91, 1.05, 0.98, 1.12, 0.87, 1.01, 0.95, 1.08]
    geomean, low, high = _interval(ratios)
    for at_most in (True, False):
        claim = ratio_claim(ratios, 1.2, at_most)
        assert (claim.geomean, claim.low, claim.high) == (
            pytest.approx(geomean, rel=1e-6), pytest.approx(low, rel=1e-6),
            pytest.approx(high, rel=1e-6))
        assert claim.rounds == 8
    assert high < 1.2  # so at most 1.2x holds, and at least 1.2x is refuted
    assert ratio_claim(ratios, 1.2, at_most=True).verdict == "holds"
    assert ratio_claim(ratios, 1.2, at_most=False).verdict == "does not hold"


def test_an_interval_across_the_target_shows_nothing_whatever_the_median():
    ratios = [1.62, 1.31, 1.58, 1.55]  # three of four rounds over 1.5x
    geomean, low, high = _interval(ratios)
    assert low < 1.5 < high
    claim = ratio_claim(ratios, 1.5, at_most=False)
    assert claim.verdict == "not shown"
    figure = claim.figure("replay", "batch", 1.5, at_most=False)
    assert figure.label == "batch, target at least 1.5x (geometric mean of 4 rounds)"
    assert figure.value == pytest.approx(geomean)
    assert figure.unit == f"x (95 % interval {low:.2f}-{high:.2f}x): not shown"


def test_a_verdict_prints_the_whole_interval_not_only_the_end_that_does_not_decide_it():
    ratios = [0.7978, 0.9114, 0.9318, 0.8794]  # the batch's four pairs: 0.79-0.98x
    figure = ratio_claim(ratios, 1.5, at_most=False).figure("replay", "batch", 1.5,
                                                             at_most=False)
    assert figure.unit == "x (95 % interval 0.79-0.98x): does not hold"
    assert figure.value == pytest.approx(0.8786, abs=1e-4)


@pytest.mark.parametrize("ratios", [[], [1.1]])
def test_fewer_than_two_rounds_give_no_interval_and_no_verdict(ratios):
    claim = ratio_claim(ratios, 1.2, at_most=True)
    assert claim.verdict == "not shown"
    assert math.isnan(claim.low) and math.isnan(claim.high)
    assert "nan" not in claim.figure("s", "L", 1.2, at_most=True).unit


@pytest.mark.parametrize("bad", [0.0, -1.0, math.nan, math.inf])
def test_a_ratio_that_is_no_ratio_is_refused(bad):
    with pytest.raises(ValueError, match="positive and finite"):
        ratio_claim([1.0, bad], 1.2, at_most=True)


@given(st.lists(st.floats(0.05, 20.0), min_size=2, max_size=12), st.floats(0.5, 3.0))
def test_the_two_sides_of_a_target_never_both_hold(ratios, target):
    at_most = ratio_claim(ratios, target, at_most=True)
    at_least = ratio_claim(ratios, target, at_most=False)
    assert at_most.low <= at_most.geomean <= at_most.high or at_most.low == at_most.high
    assert not (at_most.verdict == "holds" and at_least.verdict == "holds")
    assert (at_most.verdict == "holds") == (at_least.verdict == "does not hold")

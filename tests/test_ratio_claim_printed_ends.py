"""A printed interval end settles the side of the target it lies on
(``app.measure.ratio_claim.end_text``): an upper end of 1.996 against "at most 2x" holds
and must not print as 2.00, one of 2.004 is not shown and must not print as 2.00 either."""

import math

import pytest

from frictex.app.measure.ratio_claim import end_text, ratio_claim

#: Student's t, 97.5 % quantile, 3 degrees of freedom (printed tables)
T_975_3 = 3.182446


def _rounds_with_upper_end(high: float) -> list[float]:
    """Four ratios whose 95 % interval's upper end is ``high`` (geometric mean 1.96)."""
    logs = [-1.0, -1.0, 1.0, 1.0]  # mean 0, sample sd 2/sqrt(3)
    half_unit = T_975_3 * (2.0 / math.sqrt(3.0)) / 2.0
    scale = (math.log(high) - math.log(1.96)) / half_unit
    return [1.96 * math.exp(scale * x) for x in logs]


@pytest.mark.parametrize("high, verdict, printed", [(1.996, "holds", "1.996x"),
                                                    (2.004, "not shown", "2.004x")])
def test_an_upper_end_beside_the_target_prints_on_its_own_side(high, verdict, printed):
    claim = ratio_claim(_rounds_with_upper_end(high), 2.0, at_most=True)
    assert claim.high == pytest.approx(high, rel=1e-6)
    figure = claim.figure("replay", "batch", 2.0, at_most=True)
    assert figure.unit.endswith(f"-{printed}): {verdict}")


def test_an_end_away_from_the_target_keeps_two_decimals():
    assert end_text(1.93, 2.0) == "1.93"
    assert end_text(0.9812, 1.5) == "0.98"


def test_an_end_on_the_target_prints_as_the_target():
    assert end_text(2.0, 2.0) == "2.00"


def test_a_small_time_keeps_two_significant_digits():
    assert end_text(0.04731, 0.15) == "0.047"
    assert end_text(0.3412, 0.5) == "0.34"

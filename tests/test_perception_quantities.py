"""The protocol page says which quantity of a depth each of the perception check and the
simulated participant sets against a Weber fraction, and its example holds: depths 0.3
and 0.35 on grating-5mm are under the check's 0.11 (mu' 0.7 and 0.65) and above the
participant's (contrasts 0.3 and 0.35)."""

import pytest

from frictex.app.experiment.observer import p_choose_larger
from frictex.app.experiment.protocol_doc import render
from frictex.rendering.perception import compare_values


def test_the_page_names_the_quantity_each_judges():
    """Before, the page said nothing of it, and `validate --perception` warned of a pair
    that a 2afc run with simulated:weber=0.11,lapse=0 answered 77 of 100 correct."""
    page = " ".join(render().split())
    assert "compares the friction levels the two stimuli play" in page
    assert "dmu'/mu' of the higher, with the Weber fraction 0.11" in page
    assert "The simulated participant judges the contrast felt (max - min of mu', the depth " \
           "itself)" in page
    assert "play mu' 0.7 and 0.65, 7.14 % apart, and are warned of" in page


def test_the_pages_example_holds():
    found = compare_values("depth", 0.3, 0.35, "x")  # grating-5mm: mu_high 1
    assert found is not None and found.value == pytest.approx(0.05 / 0.7, rel=1e-9)
    assert p_choose_larger(0.35 / 0.3, 0.11, 0.0) > 0.75

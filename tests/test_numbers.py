"""device/numbers.py: the one ASCII number grammar of frictex's text formats."""

import math
import re

import pytest
from hypothesis import given, settings, strategies as st

from frictex.device.numbers import NUMBER, ascii_float

#: the grammar written out independently of the module's possessive pattern
_PLAIN = re.compile(r"[ \t]*[+-]?([0-9]+(\.[0-9]*)?|\.[0-9]+)([eE][+-]?[0-9]+)?[ \t]*", re.ASCII)


@pytest.mark.parametrize("text, value", [("12", 12.0), (" -0.5\t", -0.5), ("1.5e-3", 1.5e-3),
                                         (".5", 0.5), ("5.", 5.0), ("+2E2", 200.0)])
def test_the_ascii_forms_are_read(text, value):
    assert ascii_float(text) == value


@pytest.mark.parametrize("text", ["0_00.000001", "2_2", "\u0662\u0661", "\u0661.5", "nan", "inf",
                                  "-Infinity", "1e", "e5", ".", "", " ", "\u20031", "1\u00a0",
                                  "0x10", "1,5", "--1", "1e+-2"])
def test_what_float_alone_would_take_is_refused(text):
    with pytest.raises(ValueError):
        ascii_float(text)


@settings(max_examples=300, derandomize=True)
@given(st.text(alphabet=st.sampled_from("0123456789+-.eE _\t\u0660\u0661x"), max_size=12))
def test_exactly_the_grammar_is_taken(text):
    """Text taken is text of the grammar, read as float reads it; the rest is refused."""
    if _PLAIN.fullmatch(text):
        assert NUMBER.fullmatch(text)
        value = ascii_float(text)
        assert value == float(text) or (math.isnan(value) and math.isnan(float(text)))
    else:
        with pytest.raises(ValueError):
            ascii_float(text)


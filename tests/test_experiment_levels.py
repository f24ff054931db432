"""Levels a protocol compares: none the reference, each on the side its method can
compare, each named apart from the reference and the others (stimulus names keep 10
significant digits)."""

import pytest

from frictex.app.experiment.protocol import ProtocolError, load_protocol
from frictex.app.experiment.scheduler import Scheduler

BASE = """format = 1
method = "{method}"
repetitions = 2

[stimuli]
scene = "grating-5mm"
vary = "{vary}"
reference = {reference}
{levels}
"""


def protocol(tmp_path, method="2afc", vary="depth", reference="0.3", levels="levels = [0.4]",
             extra=""):
    path = tmp_path / "p.toml"
    path.write_text(BASE.format(method=method, vary=vary, reference=reference, levels=levels)
                    + extra, encoding="utf-8")
    return path


def test_same_different_compares_levels_below_the_reference(tmp_path):
    p = load_protocol(protocol(tmp_path, "same-different", levels="levels = [0.2, 0.4]"))
    assert p.stimuli.levels == (0.2, 0.4)
    plan = Scheduler(p, 1).plan
    below = [t for t in plan if t.value == pytest.approx(0.2)]
    assert len(below) == 8  # AB, BA, AA, BB twice each
    assert min(t.difference for t in below) == pytest.approx(-0.1, abs=1e-12)


@pytest.mark.parametrize("method, words", [
    ("2afc", "0.3 is not above the reference 0.3"),
    ("same-different", "0.3 is the reference itself"),
    ("magnitude", "0.3 is the reference, which is rated as one of the stimuli: a level "
                  "given twice"),
])
def test_a_level_that_is_the_reference_is_refused(tmp_path, method, words):
    with pytest.raises(ProtocolError, match=r"p\.toml:9: stimuli\.levels\[1\]: " + words):
        load_protocol(protocol(tmp_path, method, levels="levels = [0.3, 0.5]"))


def test_2afc_levels_stay_above_the_reference(tmp_path):
    with pytest.raises(ProtocolError, match="0.2 is not above the reference 0.3: 2afc asks"):
        load_protocol(protocol(tmp_path, "2afc", levels="levels = [0.2]"))


@pytest.mark.parametrize("levels, words", [
    ("levels = [0.3000000000001]", r"stimuli\.levels\[1\]: 0\.3000000000001 is named "
                                   r"depth=0\.3, as the reference is"),
    ("levels = [0.5, 0.50000000000001]", r"stimuli\.levels\[2\]: 0\.50000000000001 is named "
                                         r"depth=0\.5, as level 0\.5 is"),
])
def test_levels_named_as_the_reference_or_each_other_are_refused(tmp_path, levels, words):
    with pytest.raises(ProtocolError, match=words):
        load_protocol(protocol(tmp_path, "2afc", levels=levels))


def test_a_staircase_min_named_as_the_reference_is_refused(tmp_path):
    table = "\n[staircase]\nstart = 0.1\nmin = 1e-12\nmax = 0.5\n"
    with pytest.raises(ProtocolError, match=r"staircase\.min: a difference of 1e-12: the "
                                            r"comparison is named depth=0\.3"):
        load_protocol(protocol(tmp_path, "staircase", levels="", extra=table))
    ok = load_protocol(protocol(tmp_path, "staircase", levels="", extra=table.replace(
        "1e-12", "0.003")))
    assert ok.staircase.min == 0.003

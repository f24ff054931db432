"""The claims' three verdicts: holds, does not hold, not shown (``report_claims``)."""

import json
import math

import pytest

from frictex.app.measure.report_claims import (HOLDS, NOT_SHOWN, REFUTED, Claim, claims,
                                               count_line, verdict)
from frictex.app.measure.report_seeds import Draws
from frictex.device.errors import InputError


def _draws(hybrid: list[float], sht: list[float]) -> Draws:
    """One grating, fast swipes only, two renderers: the 0.6 mm spectral claim
    'auto (hybrid) <= sht' on these per-draw values."""
    per = {name: {"time_error": v, "spectral_error": v, "alignment_error_mm": v,
                  "chatter": [None] * len(v)} for name, v in (("hybrid", hybrid), ("sht", sht))}
    return Draws(len(hybrid), ["fast"], ["hybrid", "sht"], {"grating-0.6mm": {"fast": per}})


def _fine(hybrid, sht) -> Claim:
    (found,) = [c for c in claims(_draws(hybrid, sht)) if c.group == "auto on fine gratings"]
    return found


def test_an_interval_below_zero_holds():
    c = _fine([0.10, 0.11, 0.12, 0.10], [0.20, 0.22, 0.21, 0.20])
    assert c.high < 0 and c.passed and c.verdict == HOLDS


def test_an_interval_wholly_on_the_losing_side_does_not_hold():
    c = _fine([0.30, 0.31, 0.33, 0.30], [0.20, 0.22, 0.21, 0.20])
    assert c.low > 0 and not c.passed and c.verdict == REFUTED


def test_an_interval_straddling_zero_is_not_shown():
    c = _fine([0.20, 0.25, 0.15, 0.22], [0.21, 0.20, 0.21, 0.20])
    assert c.low < 0 < c.high and not c.passed and c.verdict == NOT_SHOWN


def test_verdict_rule_at_its_edges():
    assert verdict(True, -1.0) == HOLDS
    assert verdict(False, 1e-9) == REFUTED
    assert verdict(False, 0.0) == NOT_SHOWN  # the interval touches the bound: unsettled
    assert verdict(False, math.nan) == NOT_SHOWN  # fewer than two draws: no interval


def test_count_line_counts_each_verdict():
    found = [_fine([0.1, 0.11, 0.12], [0.2, 0.22, 0.21]),
             _fine([0.3, 0.31, 0.33], [0.2, 0.22, 0.21]),
             _fine([0.2, 0.25, 0.15], [0.21, 0.2, 0.21]),
             _fine([0.3, 0.32, 0.31], [0.2, 0.2, 0.2])]
    assert count_line(found) == "1 of 4 claims hold, 2 do not, 1 not shown"


def test_report_json_keeps_passed_adds_verdict_and_reads_old_claims():
    from dataclasses import asdict
    c = _fine([0.30, 0.31, 0.33, 0.30], [0.20, 0.22, 0.21, 0.20])
    doc = json.loads(json.dumps(asdict(c)))
    assert doc["passed"] is False and doc["verdict"] == REFUTED
    assert Claim(**doc) == c
    old = {k: v for k, v in doc.items() if k != "verdict"}  # report.json before verdicts
    assert Claim(**old).verdict == REFUTED


def test_a_verdict_that_contradicts_passed_is_refused():
    with pytest.raises(InputError, match="contradicts"):
        Claim("g", "s", "human", "m", "t", -1.0, -2.0, -0.5, 8, False, HOLDS)
    with pytest.raises(InputError, match="expected one of"):
        Claim("g", "s", "human", "m", "t", -1.0, -2.0, -0.5, 8, True, "maybe")
